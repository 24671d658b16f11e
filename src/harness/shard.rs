//! A reference rendered across machines: shard i of n renders the passes i, i + n, i + 2n, …
//! below the total spp, with exactly the random streams a single-process reference uses for
//! those passes, and stores its film losslessly (f64 sums and Welford M2, not an f32 EXR).
//! `dibench merge` combines the n shards with Chan's formula into the ordinary reference
//! files, equal to a single-process render up to roundoff. `scripts/reference-slurm.sh` runs
//! the shards as a Slurm job array.

use super::reference::{ReferenceMeta, reference_dir, reference_stream_seed, save, strategy_for};
use super::{COMMIT, VERSION};
use crate::error::{Error, Result};
use crate::film::Film;
use crate::output::{write_bytes, write_json};
use crate::prepare::PreparedScene;
use crate::render::Renderer;
use crate::strategy::Integrand;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// `i/n` with 0 ≤ i < n.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShardSpec {
    pub index: u64,
    pub count: u64,
}

impl ShardSpec {
    pub fn parse(s: &str) -> Result<Self> {
        let bad = || Error::Usage(format!("--shard must be i/n with 0 <= i < n, got `{s}`"));
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            i.trim().parse::<u64>().map_err(|_| bad())?,
            n.trim().parse::<u64>().map_err(|_| bad())?,
        );
        if count == 0 || index >= count {
            return Err(bad());
        }
        Ok(ShardSpec { index, count })
    }
}

/// What a shard file holds besides the film.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ShardMeta {
    pub scene: String,
    pub integrand: String,
    pub scene_hash: String,
    pub width: u32,
    pub height: u32,
    pub total_spp: u64,
    pub seed: u64,
    pub index: u64,
    pub count: u64,
    /// Passes this shard rendered.
    pub spp: u64,
    pub strategy: String,
    pub backend: String,
    pub wall_time_s: f64,
    pub dibench_version: String,
    pub commit: String,
}

fn shard_dir(out: &Path, scene: &str) -> PathBuf {
    reference_dir(out, scene).join("shards")
}

fn stem(integrand: &str, s: ShardSpec) -> String {
    format!("{integrand}.{}-of-{}", s.index, s.count)
}

/// Renders shard `spec` of a `total_spp` reference of `integrand`.
pub fn render(
    scene: &PreparedScene,
    integrand: Integrand,
    total_spp: u64,
    seed: u64,
    spec: ShardSpec,
) -> Result<(Film, ShardMeta)> {
    if total_spp == 0 {
        return Err(Error::Usage("--spp must be at least 1".into()));
    }
    let strategy = strategy_for(scene, integrand)?;
    let mut renderer = Renderer::new(scene, strategy.as_ref(), reference_stream_seed(seed))?;
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    let start = Instant::now();
    for pass in (spec.index..total_spp).step_by(spec.count as usize) {
        if crate::interrupt::requested() {
            return Err(Error::Interrupted(format!(
                "shard {}/{} of the {} reference stopped at {} spp; nothing stored",
                spec.index,
                spec.count,
                integrand.name(),
                film.spp
            )));
        }
        renderer.add_pass_with_stream(&mut film, pass);
    }
    let meta = ShardMeta {
        scene: scene.scene.name.clone(),
        integrand: integrand.name().to_string(),
        scene_hash: scene.scene.content_hash.clone(),
        width: scene.scene.width,
        height: scene.scene.height,
        total_spp,
        seed,
        index: spec.index,
        count: spec.count,
        spp: film.spp,
        strategy: strategy.name().to_string(),
        backend: scene.tracer.name().to_string(),
        wall_time_s: start.elapsed().as_secs_f64(),
        dibench_version: VERSION.to_string(),
        commit: COMMIT.to_string(),
    };
    Ok((film, meta))
}

/// Writes `<out>/<scene>/reference/shards/<integrand>.<i>-of-<n>.bin` (little-endian f64:
/// every pixel's sum, then every pixel's M2, tile-major as in `Film`) and its `.json`, the
/// JSON last. Returns the JSON's path.
pub fn save_shard(out: &Path, film: &Film, meta: &ShardMeta) -> Result<PathBuf> {
    let dir = shard_dir(out, &meta.scene);
    let spec = ShardSpec {
        index: meta.index,
        count: meta.count,
    };
    let mut bytes = Vec::with_capacity(film.sum.len() * 48);
    for px in film.sum.iter().chain(film.m2.iter()) {
        for v in px {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    write_bytes(
        &dir.join(format!("{}.bin", stem(&meta.integrand, spec))),
        &bytes,
    )?;
    let json = dir.join(format!("{}.json", stem(&meta.integrand, spec)));
    write_json(&json, meta)?;
    Ok(json)
}

/// A shard's JSON path, film and metadata.
type LoadedShard = (PathBuf, Film, ShardMeta);

fn load_shard(json: &Path) -> Result<(Film, ShardMeta)> {
    let text = std::fs::read_to_string(json).map_err(|e| Error::io(json, e))?;
    let meta: ShardMeta = serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: json.to_path_buf(),
        message: e.to_string(),
    })?;
    let bin = json.with_extension("bin");
    let bytes = std::fs::read(&bin).map_err(|e| Error::io(&bin, e))?;
    let mut film = Film::new(meta.width, meta.height);
    let want = film.sum.len() * 2 * 3 * 8;
    if bytes.len() != want {
        return Err(Error::Parse {
            path: bin,
            message: format!(
                "{} bytes, expected {want} for {}x{}",
                bytes.len(),
                meta.width,
                meta.height
            ),
        });
    }
    let mut vals = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")));
    let n = film.sum.len();
    for px in film.sum.iter_mut().chain(film.m2.iter_mut()).take(2 * n) {
        for v in px.iter_mut() {
            *v = vals.next().expect("length checked");
        }
    }
    film.spp = meta.spp;
    Ok((film, meta))
}

/// Merges every complete set of shards under `<out>/<scene>/reference/shards/` into the
/// ordinary reference files of its integrand. All n shards of a set must be present and agree
/// on scene content, resolution, seed and total spp; anything else is an error naming the
/// file. Returns the reference EXRs written.
pub fn merge(out: &Path, scene: &str) -> Result<Vec<PathBuf>> {
    let dir = shard_dir(out, scene);
    let entries = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    let mut jsons: Vec<PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    jsons.sort();
    if jsons.is_empty() {
        return Err(Error::Usage(format!(
            "{}: no shards to merge",
            dir.display()
        )));
    }
    let mut sets: Vec<(String, Vec<LoadedShard>)> = Vec::new();
    for j in jsons {
        let (film, meta) = load_shard(&j)?;
        match sets.iter_mut().find(|(k, _)| *k == meta.integrand) {
            Some((_, v)) => v.push((j, film, meta)),
            None => sets.push((meta.integrand.clone(), vec![(j, film, meta)])),
        }
    }
    let mut written = Vec::new();
    for (integrand, mut shards) in sets {
        shards.sort_by_key(|s| s.2.index);
        let first = shards[0].2.clone();
        for (path, _, m) in &shards {
            let same = m.scene_hash == first.scene_hash
                && (m.width, m.height) == (first.width, first.height)
                && (m.seed, m.total_spp, m.count) == (first.seed, first.total_spp, first.count)
                && m.strategy == first.strategy;
            if !same {
                return Err(Error::Parse {
                    path: path.clone(),
                    message: format!(
                        "shard does not match {}: scene hash, resolution, seed, total spp, shard count and strategy must agree",
                        stem(
                            &first.integrand,
                            ShardSpec {
                                index: first.index,
                                count: first.count
                            }
                        )
                    ),
                });
            }
        }
        let have: Vec<u64> = shards.iter().map(|s| s.2.index).collect();
        let missing: Vec<String> = (0..first.count)
            .filter(|i| !have.contains(i))
            .map(|i| i.to_string())
            .collect();
        if !missing.is_empty() || have.len() as u64 != first.count {
            return Err(Error::Usage(format!(
                "{}: {integrand} shards {} of {} missing (or duplicated)",
                dir.display(),
                missing.join(","),
                first.count
            )));
        }
        let mut film = Film::new(first.width, first.height);
        let mut wall = 0.0;
        for (_, f, m) in &shards {
            film.merge(f);
            wall += m.wall_time_s;
        }
        let meta = ReferenceMeta {
            scene: first.scene.clone(),
            integrand: integrand.clone(),
            scene_hash: first.scene_hash.clone(),
            width: first.width,
            height: first.height,
            spp: film.spp,
            seed: first.seed,
            strategy: first.strategy.clone(),
            backend: first.backend.clone(),
            threads: 0,
            wall_time_s: wall,
            noise_floor_rmse: Some((film.mean_sample_variance() / film.spp as f64).sqrt()),
            dibench_version: VERSION.to_string(),
            commit: COMMIT.to_string(),
        };
        written.push(save(out, &film.mean(), &film.variance_of_mean(), &meta)?);
    }
    Ok(written)
}
