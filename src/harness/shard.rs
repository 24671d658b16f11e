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
use crate::output::store::{Locked, NewFile, Store};
use crate::prepare::PreparedScene;
use crate::render::{Renderer, group_size};
use crate::strategy::Integrand;
use serde::{Deserialize, Serialize};
use std::io::Write;
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
    /// The machine that rendered the shard ([`super::cpu_model`]). Absent in shards stored
    /// before.
    #[serde(default)]
    pub cpu: Option<String>,
}

/// The shard store of `scene` under `out`, `<out>/<scene>/reference/shards/` (created if
/// missing): one unit per shard, named by [`stem`].
pub fn store(out: &Path, scene: &str) -> Result<Store> {
    Store::open(&reference_dir(out, scene).join("shards"))
}

/// The unit name of shard `s` of `integrand`'s reference.
pub fn stem(integrand: &str, s: ShardSpec) -> String {
    format!("{integrand}.{}-of-{}", s.index, s.count)
}

/// Passes below `total` that shard `s` renders: `index`, `index + count`, …
fn passes(total: u64, s: ShardSpec) -> u64 {
    if s.index >= total {
        0
    } else {
        (total - 1 - s.index) / s.count + 1
    }
}

/// Renders shard `spec` of a `total_spp` reference of `integrand`.
pub fn render(
    scene: &PreparedScene,
    integrand: Integrand,
    total_spp: u64,
    seed: u64,
    spec: ShardSpec,
) -> Result<(Film, ShardMeta)> {
    super::options::check_at_least_one("--spp", total_spp)?;
    let strategy = strategy_for(scene, integrand)?;
    let mut renderer = Renderer::new(scene, strategy.as_ref(), reference_stream_seed(seed))?;
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    let start = Instant::now();
    let _polling = crate::interrupt::polling();
    // This shard's passes are index, index + count, … below total_spp.
    let mut next = spec.index;
    while next < total_spp {
        if crate::interrupt::requested() {
            return Err(Error::Interrupted(format!(
                "shard {}/{} of the {} reference stopped at {} spp; nothing stored",
                spec.index,
                spec.count,
                integrand.name(),
                film.spp
            )));
        }
        // In groups (Renderer::add_passes_with_streams): the same film as pass by pass.
        let per_pass = (film.spp > 0).then(|| start.elapsed().as_secs_f64() / film.spp as f64);
        let left = (total_spp - next).div_ceil(spec.count);
        let streams: Vec<u64> = (0..group_size(left, per_pass))
            .map(|i| next + i * spec.count)
            .collect();
        renderer.add_passes_with_streams(&mut film, &streams);
        next = next.saturating_add(streams.len() as u64 * spec.count);
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
        cpu: Some(super::cpu_model()),
    };
    Ok((film, meta))
}

/// Commits the shard as the content of `unit` (locked for writing): its film as
/// little-endian f64 (every pixel's sum, then every pixel's M2, tile-major as in `Film`) and
/// its metadata. Returns the manifest's path.
pub fn save_shard(unit: &Locked, film: &Film, meta: &ShardMeta) -> Result<PathBuf> {
    let mut bytes = Vec::with_capacity(film.sum.len() * 48);
    for px in film.sum.iter().chain(film.m2.iter()) {
        for v in px {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
    }
    unit.commit(
        meta,
        vec![NewFile {
            role: "film",
            ext: "bin",
            write: Box::new(|f, p| f.write_all(&bytes).map_err(|e| Error::io(p, e))),
        }],
    )
}

/// The machines of a merged reference's shards, in shard order: each distinct one once,
/// joined by " | " (a description has a ";" of its own), and "unrecorded" for shards stored
/// before the machine was.
fn machines<'a>(cpus: impl Iterator<Item = Option<&'a str>>) -> String {
    let mut seen: Vec<&str> = Vec::new();
    for cpu in cpus.map(|c| c.unwrap_or("unrecorded")) {
        if !seen.contains(&cpu) {
            seen.push(cpu);
        }
    }
    seen.join(" | ")
}

/// A shard's manifest path, film and metadata.
type LoadedShard = (PathBuf, Film, ShardMeta);

/// The shard in `unit`, its metadata checked against itself and its film's size before the
/// film is allocated; None when nothing is committed there.
fn load_shard(unit: &Locked) -> Result<Option<LoadedShard>> {
    let Some(stored) = unit.read::<ShardMeta>()? else {
        return Ok(None);
    };
    let (meta, json) = (stored.meta.clone(), stored.manifest.clone());
    let lie = |message: String| Error::Parse {
        path: json.clone(),
        message,
    };
    if meta.count == 0 || meta.index >= meta.count {
        return Err(lie(format!(
            "shard {}/{}: the index must be below the count",
            meta.index, meta.count
        )));
    }
    let spec = ShardSpec {
        index: meta.index,
        count: meta.count,
    };
    if meta.spp != passes(meta.total_spp, spec) {
        return Err(lie(format!(
            "claims {} spp, but shard {}/{} of {} spp has {}",
            meta.spp,
            meta.index,
            meta.count,
            meta.total_spp,
            passes(meta.total_spp, spec)
        )));
    }
    if !(1..=crate::scene::MAX_IMAGE_SIDE).contains(&meta.width)
        || !(1..=crate::scene::MAX_IMAGE_SIDE).contains(&meta.height)
    {
        return Err(lie(format!(
            "claims a {}×{} image (sides must be in 1..={})",
            meta.width,
            meta.height,
            crate::scene::MAX_IMAGE_SIDE
        )));
    }
    let (bin, bytes) = stored.file("film")?;
    let pixels = crate::film::TileLayout::new(meta.width, meta.height).tile_count() as u64 * 16;
    let want = pixels * 2 * 3 * 8;
    if bytes.len() as u64 != want {
        return Err(Error::Parse {
            path: bin.to_path_buf(),
            message: format!(
                "{} bytes, expected {want} for the {}×{} film its manifest {} claims",
                bytes.len(),
                meta.width,
                meta.height,
                json.display()
            ),
        });
    }
    crate::bounded::check_memory(
        || format!("{}: a {}×{} film", json.display(), meta.width, meta.height),
        want,
    )?;
    let mut film = Film::new(meta.width, meta.height);
    let mut vals = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().expect("8 bytes")));
    for px in film.sum.iter_mut().chain(film.m2.iter_mut()) {
        for v in px.iter_mut() {
            *v = vals.next().expect("length checked");
            if !v.is_finite() {
                return Err(Error::Parse {
                    path: bin.to_path_buf(),
                    message: "holds a non-finite value".into(),
                });
            }
        }
    }
    film.spp = meta.spp;
    Ok(Some((json, film, meta)))
}

/// Merges every complete set of shards under `<out>/<scene>/reference/shards/` into the
/// reference of its integrand. Every shard must be for the scene's current content and
/// resolution (else an error naming the scene and the shard), and all n shards of a set must be
/// present and agree on seed, total spp and strategy; anything else is an error naming the
/// file. Returns the reference manifests written.
pub fn merge(out: &Path, scene: &crate::scene::Scene) -> Result<Vec<PathBuf>> {
    let dir = reference_dir(out, &scene.name).join("shards");
    if !dir.is_dir() {
        return Err(Error::Usage(format!(
            "{}: no shards to merge",
            dir.display()
        )));
    }
    let shards = store(out, &scene.name)?;
    let stems = shards.stems()?;
    let mut locks = Vec::new();
    for stem in &stems {
        locks.push(shards.lock_shared(stem)?);
    }
    let mut sets: Vec<(String, Vec<LoadedShard>)> = Vec::new();
    for unit in &locks {
        let Some((j, film, meta)) = load_shard(unit)? else {
            continue;
        };
        if meta.scene_hash != scene.content_hash
            || (meta.width, meta.height) != (scene.width, scene.height)
        {
            return Err(Error::Parse {
                path: j,
                message: format!(
                    "this shard was rendered for other content of scene `{}` ({}; {}×{} then, \
                     {}×{} now): the scene or a file it uses changed since; render the shards again",
                    scene.name,
                    scene.path.display(),
                    meta.width,
                    meta.height,
                    scene.width,
                    scene.height
                ),
            });
        }
        match sets.iter_mut().find(|(k, _)| *k == meta.integrand) {
            Some((_, v)) => v.push((j, film, meta)),
            None => sets.push((meta.integrand.clone(), vec![(j, film, meta)])),
        }
    }
    if sets.is_empty() {
        return Err(Error::Usage(format!(
            "{}: no shards to merge",
            dir.display()
        )));
    }
    let references = super::reference::store(out, &scene.name)?;
    let mut written = Vec::new();
    for (integrand, mut shards) in sets {
        shards.sort_by_key(|s| s.2.index);
        let first = shards[0].2.clone();
        for (path, _, m) in &shards {
            let same = (m.seed, m.total_spp, m.count) == (first.seed, first.total_spp, first.count)
                && m.strategy == first.strategy;
            if !same {
                return Err(Error::Parse {
                    path: path.clone(),
                    message: format!(
                        "shard does not match {}: seed, total spp, shard count and strategy must agree",
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
        // At most ten named: a count read from a file may be anything up to 2^64.
        let missing: Vec<String> = (0..first.count)
            .filter(|i| !have.contains(i))
            .take(10)
            .map(|i| i.to_string())
            .collect();
        let duplicated = have.windows(2).any(|w| w[0] == w[1]);
        if !missing.is_empty() || duplicated {
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
            cpu: Some(machines(shards.iter().map(|s| s.2.cpu.as_deref()))),
        };
        let unit = references.lock(&integrand)?;
        written.push(save(&unit, &film.mean(), &film.variance_of_mean(), &meta)?);
    }
    Ok(written)
}

#[cfg(test)]
mod tests {
    use super::machines;

    /// A merged reference names each machine of its shards once, in shard order, and shards
    /// stored before the machine was recorded as "unrecorded" (control: one machine alone is
    /// itself, not a list).
    #[test]
    fn a_merged_reference_names_its_shards_machines() {
        let (a, b) = (
            "AMD EPYC (family 25, model 1, stepping 1; avx2)",
            "Xeon (avx512)",
        );
        assert_eq!(machines([Some(a), Some(a)].into_iter()), a);
        assert_eq!(
            machines([Some(b), Some(a), Some(b), None].into_iter()),
            format!("{b} | {a} | unrecorded")
        );
    }
}
