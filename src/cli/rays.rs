//! `dibench rays`: ray throughput of each backend (and ISA) on fixed ray sets.

use super::{load, parse_threads, pool};
use crate::error::{Error, Result};
use crate::harness::{rays, raysets};
use crate::simd::Isa;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct RaysArgs {
    /// Scene file, or the name of a scene in scenes/.
    #[arg(default_value = "bunny")]
    pub scene: String,
    /// Output root; the table goes to <out>/<scene>/rays.csv.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
    /// Comma-separated backends (obvhs, packet); packet runs at every available ISA.
    #[arg(long, value_delimiter = ',', default_value = "obvhs,packet")]
    pub backend: Vec<String>,
    /// Only this ISA for the packet backend (default: every ISA the CPU has).
    #[arg(long)]
    pub isa: Option<String>,
    /// Tracing threads (default 1: single-thread throughput).
    #[arg(long, default_value_t = 1, value_parser = parse_threads, allow_negative_numbers = true)]
    pub threads: usize,
    /// Image side of the ray sets, in pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=crate::scene::MAX_IMAGE_SIDE as i64), allow_negative_numbers = true)]
    pub size: u32,
    /// Timing rounds (best round is reported; order alternates between rounds).
    #[arg(long, default_value_t = 5, value_parser = parse_rounds, allow_negative_numbers = true)]
    pub rounds: usize,
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,
    /// Comma-separated ray classes to time (primary, shadow_area, shadow_distant, incoherent;
    /// default: all four).
    #[arg(long, value_delimiter = ',')]
    pub class: Vec<String>,
    /// What a packet's 16 camera rays are: `tile`, the centres of 4×4 pixels, or `pixel`, 16
    /// jittered samples of one pixel of a (size/4)² image, as a render traces them (its
    /// secondary rays then start within one pixel's footprint).
    #[arg(long, value_enum, default_value_t = raysets::Packing::Tile)]
    pub packets: raysets::Packing,
}

fn parse_rounds(s: &str) -> std::result::Result<usize, String> {
    match s.trim().parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        _ => Err(format!("expected a whole number from 1 to {}", usize::MAX)),
    }
}

pub fn run(a: RaysArgs) -> Result<()> {
    for b in &a.backend {
        if !rays::BACKENDS.contains(&b.as_str()) {
            return Err(rays::unknown_backend(b));
        }
    }
    for c in &a.class {
        if !raysets::CLASSES.iter().any(|(name, _)| name == c) {
            let known: Vec<&str> = raysets::CLASSES.iter().map(|(name, _)| *name).collect();
            return Err(Error::Usage(format!(
                "--class: unknown ray class `{c}` (known: {})",
                known.join(", ")
            )));
        }
    }
    let isas = match (&a.isa, std::env::var("DIBENCH_ISA")) {
        (Some(s), _) => vec![Isa::parse(s)?],
        (None, Ok(s)) if !s.is_empty() => vec![Isa::detect()?],
        _ => Isa::available(),
    };
    let (pool, threads) = pool(Some(a.threads))?;
    let scene = load(&a.scene)?;
    let name = scene.scene.name.clone();
    let path = a.out.join(&name).join("rays.csv");
    crate::output::check_output_dir(&a.out.join(&name), "--out")?;
    // Four sets of size² rays, with their packets and masks: about 256 bytes per ray.
    crate::bounded::check_memory(
        || format!("--size {}", a.size),
        crate::bounded::bytes(a.size as u64 * a.size as u64, 256),
    )?;
    let mut sets = rays::generate_packed(&scene, a.size, a.seed, a.packets);
    if !a.class.is_empty() {
        sets.retain(|s| a.class.iter().any(|c| c == s.class));
    }
    let subjects = rays::subjects(&scene, &a.backend, &isas)?;
    let rows =
        pool.install(|| rays::measure(&name, &sets, &subjects, a.rounds, threads, a.packets));
    crate::output::write_csv(&path, &rows)?;
    let report = rays::RaysReport {
        scene: name,
        threads,
        size: a.size,
        rounds: a.rounds,
        packing: a.packets,
        rows,
        csv: path,
        cpu: crate::harness::cpu_model(),
    };
    print!("{report}");
    Ok(())
}
