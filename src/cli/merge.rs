//! `dibench merge`: the shards of `reference --shard i/n` into the scene's reference files.

use crate::error::Result;
use crate::scene::Scene;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct MergeArgs {
    /// Scene file or name under scenes/ (names the results directory).
    pub scene: String,
    /// Output root holding <scene>/reference/shards/.
    #[arg(long, default_value = "results")]
    pub out: PathBuf,
}

pub fn run(a: MergeArgs) -> Result<()> {
    let scene = Scene::load(&Scene::resolve(&a.scene)?)?;
    for p in crate::harness::shard::merge(&a.out, &scene)? {
        println!("reference: {}", p.display());
    }
    Ok(())
}
