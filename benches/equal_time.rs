//! The equal-time comparison on the bench scenes as a bench target: `cargo bench --bench
//! equal_time` renders a reference per scene, runs every applicable strategy
//! DIBENCH_BENCH_RUNS times (default 5) for DIBENCH_BENCH_TIME seconds (default 0.25) on the
//! packet backend, writes the run directories (results.csv, summary.csv) under
//! target/tmp/equal_time/, and prints each strategy's predicted equal-time RMSE
//! (per-sample variance × cost per sample / budget, plus the reference noise floor) beside the
//! measured one with its 95 % interval.

use dibench::harness::compare;
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::strategy::{applicable, integrands};
use dibench::tracer::backends;
use std::path::PathBuf;

const SCENES: [&str; 2] = ["cornell", "sphere_light"];
const REFERENCE_SPP: u64 = 2048;

fn env_or<T: std::str::FromStr>(key: &str, default: T) -> T {
    std::env::var(key)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // `cargo bench` passes --bench; `cargo test --benches` passes nothing and expects speed.
    if !std::env::args().any(|a| a == "--bench") {
        return Ok(());
    }
    let time_s: f64 = env_or("DIBENCH_BENCH_TIME", 0.25);
    let runs: u32 = env_or("DIBENCH_BENCH_RUNS", 5);
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("equal_time");
    let threads = rayon::current_num_threads();
    for name in SCENES {
        let scene = Scene::load(&Scene::resolve(name)?)?;
        let scene = PreparedScene::with_tracer(scene, |g| {
            backends::build("packet", g).expect("the packet backend always builds")
        });
        let (strategies, skipped) = applicable(&scene);
        for k in &skipped {
            eprintln!("{name}: skipping `{}`: {}", k.name, k.reason);
        }
        let mut images = Vec::new();
        let store = dibench::harness::reference::store(&out, &scene.scene.name)?;
        for integrand in integrands(&scene) {
            images.push(compare::Reference::load_or_render(
                &store,
                &scene,
                integrand,
                compare::Need::Spp(REFERENCE_SPP),
                1,
                threads,
            )?);
        }
        let opts = compare::CompareOptions {
            budget: compare::Budget::Time(time_s),
            seed: 1,
            threads,
            runs,
            isa: dibench::simd::Isa::detect()?.name().to_string(),
            samplers: Vec::new(),
        };
        let references = compare::References { images };
        let run_dir = compare::create_run_dir(&out, &scene.scene.name, 1)?;
        let report = compare::run(&scene, &strategies, skipped, &references, &run_dir, &opts)?;
        println!(
            "equal_time/{name}: {runs} runs × {time_s} s, {}",
            report.run_dir.display()
        );
        println!(
            "  {:<18} {:>12} {:>12} {:>10}",
            "strategy", "predicted", "measured", "±95%"
        );
        for r in &report.summary {
            println!(
                "  {:<18} {:>12.4e} {:>12.4e} {:>10.2e}",
                r.strategy,
                r.predicted_rmse.unwrap_or(f64::NAN),
                r.rmse_mean,
                r.rmse_ci95.unwrap_or(0.0)
            );
        }
    }
    Ok(())
}
