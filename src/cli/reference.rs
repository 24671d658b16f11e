//! `dibench reference`: a high-sample reference, whole or one shard of it.

use super::{Common, check_image_memory, load_with, parse_seconds, pool};
use crate::error::Result;
use crate::harness::{reference, shard};
use crate::strategy;
use clap::Args;

#[derive(Args, Debug)]
pub struct ReferenceArgs {
    #[command(flatten)]
    pub common: Common,
    /// Samples per pixel (default 8192).
    #[arg(long, conflicts_with = "time", value_parser = clap::value_parser!(u64).range(1..), allow_negative_numbers = true)]
    pub spp: Option<u64>,
    /// Render whole passes for this many seconds instead of a fixed spp.
    #[arg(long, value_parser = parse_seconds, allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// Render only shard i of n (passes i, i+n, ... of --spp) into <out>/<scene>/reference/
    /// shards/, for a cluster job array; `dibench merge` then writes the reference.
    #[arg(long, conflicts_with = "time", allow_hyphen_values = true)]
    pub shard: Option<String>,
}

pub fn run(a: ReferenceArgs) -> Result<()> {
    let spec = a
        .shard
        .as_deref()
        .map(shard::ShardSpec::parse)
        .transpose()?;
    let (pool, threads) = pool(a.common.threads)?;
    let (scene, _) = load_with(&a.common)?;
    scene.scene.require_light_power()?;
    // The film, its mean and variance, and a checkpoint being written.
    check_image_memory(&scene, 3)?;
    let budget = match (a.spp, a.time) {
        (_, Some(t)) => reference::Budget::Time(t),
        (n, None) => reference::Budget::Spp(n.unwrap_or(8192)),
    };
    crate::output::check_output_dir(&a.common.out, "--out")?;
    if let Some(spec) = spec {
        let store = shard::store(&a.common.out, &scene.scene.name)?;
        let total = a.spp.unwrap_or(8192);
        for integrand in strategy::integrands(&scene) {
            let unit = store.lock(&shard::stem(integrand.name(), spec))?;
            let (film, meta) =
                pool.install(|| shard::render(&scene, integrand, total, a.common.seed, spec))?;
            let path = shard::save_shard(&unit, &film, &meta)?;
            println!(
                "shard {}/{}: {} ({} of {total} spp, {:.1} s, {threads} threads)",
                spec.index,
                spec.count,
                path.display(),
                meta.spp,
                meta.wall_time_s
            );
        }
        return Ok(());
    }
    let store = reference::store(&a.common.out, &scene.scene.name)?;
    for integrand in strategy::integrands(&scene) {
        // Locked while it renders: a concurrent `compare` waits for it instead of rendering
        // its own, and checkpoints of two processes never interleave.
        let unit = store.lock(integrand.name())?;
        let r = pool.install(|| {
            reference::render_progressive(
                &scene,
                integrand,
                budget,
                a.common.seed,
                threads,
                Some(&unit),
            )
        })?;
        let path = reference::save(&unit, &r.image, &r.variance, &r.meta)?;
        println!("reference: {} ({})", path.display(), r.meta);
    }
    Ok(())
}
