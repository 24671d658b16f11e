//! High-sample reference images, stored with the metadata that decides whether `compare` may
//! reuse them: same scene content hash and resolution, and at least the requested spp. Each
//! integrand's reference is one unit of the store `<out>/<scene>/reference/` (see
//! `output::store`): its image, its variance and its metadata are committed together, and the
//! unit is locked while it is rendered, so that concurrent runs render it once.

use super::{COMMIT, VERSION, progress_bar};
use crate::error::{Error, Result};
use crate::film::{Film, Image};
use crate::math::mix64;
use crate::output::store::{Locked, NewFile, Store};
use crate::output::{decode_exr, encode_exr};
use crate::prepare::PreparedScene;
use crate::render::{Renderer, group_size};
use crate::strategy::{Integrand, reference_strategy};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ReferenceMeta {
    pub scene: String,
    pub integrand: String,
    pub scene_hash: String,
    pub width: u32,
    pub height: u32,
    pub spp: u64,
    pub seed: u64,
    pub strategy: String,
    pub backend: String,
    pub threads: usize,
    pub wall_time_s: f64,
    /// √(mean over pixels and channels of the variance of the reference mean): the RMSE the
    /// reference's own noise adds to any image's measured RMSE (in expectation,
    /// E[RMSE²] = MSE against the truth + floor²). Absent in references stored before.
    #[serde(default)]
    pub noise_floor_rmse: Option<f64>,
    pub dibench_version: String,
    pub commit: String,
    /// The machine(s) that rendered it ([`crate::output::Provenance::cpu`]). Absent in
    /// references stored before.
    #[serde(default)]
    pub cpu: Option<String>,
}

impl ReferenceMeta {
    /// What the reference's EXR headers say of it (references use independent samples).
    pub fn provenance(&self) -> crate::output::Provenance {
        crate::output::Provenance {
            scene: self.scene.clone(),
            scene_hash: self.scene_hash.clone(),
            strategy: self.strategy.clone(),
            integrand: self.integrand.clone(),
            sampler: crate::sampling::GENERATORS[0].name().to_string(),
            content: "radiance".into(),
            spp: self.spp,
            render_time_s: self.wall_time_s,
            seed: self.seed,
            backend: self.backend.clone(),
            threads: self.threads,
            version: self.dibench_version.clone(),
            commit: self.commit.clone(),
            cpu: self.cpu.clone(),
        }
    }
}

/// How a reference was rendered, as `dibench reference` prints it after the file's path.
impl std::fmt::Display for ReferenceMeta {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} spp, {:.1} s, strategy {}, noise floor {:.3e} RMSE",
            self.spp,
            self.wall_time_s,
            self.strategy,
            self.noise_floor_rmse.unwrap_or(0.0)
        )
    }
}

pub fn reference_dir(out: &Path, scene: &str) -> PathBuf {
    out.join(scene).join("reference")
}

/// The reference store of `scene` under `out`, created if missing.
pub fn store(out: &Path, scene: &str) -> Result<Store> {
    Store::open(&reference_dir(out, scene))
}

/// The reference's random streams are salted so that they never coincide with the streams of
/// a compared run of the same strategy and seed: an error measured against a correlated
/// reference would be too small.
pub(crate) fn reference_stream_seed(seed: u64) -> u64 {
    mix64(seed) ^ 0x5245_4645_5245_4e43
}

/// The strategy that renders `integrand`'s reference, or an error naming the scene.
pub(crate) fn strategy_for(
    scene: &PreparedScene,
    integrand: Integrand,
) -> Result<Box<dyn crate::strategy::Strategy>> {
    reference_strategy(scene, integrand).ok_or_else(|| {
        Error::Usage(format!(
            "scene `{}`: no strategy can render a {} reference",
            scene.scene.name,
            integrand.name()
        ))
    })
}

/// How long a reference renders.
#[derive(Clone, Copy, Debug)]
pub enum Budget {
    Spp(u64),
    /// Whole passes until the time is spent (at least one).
    Time(f64),
    /// Whole passes until the noise floor is at most `target` (checked every few passes, after
    /// `pilot::MIN_PASSES`) or until `cap` seconds are spent; `expected_spp` sizes the
    /// progress bar.
    Floor {
        target: f64,
        cap: f64,
        expected_spp: u64,
    },
}

/// The first progressive checkpoint; later ones at 2×, 4×, ... (a crash loses at most half).
pub const FIRST_CHECKPOINT_SPP: u64 = 64;

/// A rendered reference: mean image, per-pixel variance of the mean, metadata.
pub struct Rendered {
    pub image: Image,
    pub variance: Image,
    pub meta: ReferenceMeta,
}

pub fn render(
    scene: &PreparedScene,
    integrand: Integrand,
    spp: u64,
    seed: u64,
    threads: usize,
) -> Result<Rendered> {
    render_progressive(scene, integrand, Budget::Spp(spp), seed, threads, None)
}

/// Renders a reference; with `checkpoints` (the unit, locked), commits it (image, variance,
/// JSON) at 64, 128, 256, ... spp so an interrupted render keeps its latest power of two. A
/// stored checkpoint carries its own spp, so `compare` reuses it only when that is enough.
pub fn render_progressive(
    scene: &PreparedScene,
    integrand: Integrand,
    budget: Budget,
    seed: u64,
    threads: usize,
    checkpoints: Option<&Locked>,
) -> Result<Rendered> {
    let strategy = strategy_for(scene, integrand)?;
    render_with(scene, strategy.as_ref(), budget, seed, threads, checkpoints)
}

/// [`render_progressive`] with a given strategy (its integrand is the reference's).
pub fn render_with(
    scene: &PreparedScene,
    strategy: &dyn crate::strategy::Strategy,
    budget: Budget,
    seed: u64,
    threads: usize,
    checkpoints: Option<&Locked>,
) -> Result<Rendered> {
    let integrand = strategy.integrand();
    // Validated here, where the budget is used, for every entry point.
    let (spp, time, floor) = match budget {
        Budget::Floor {
            target,
            cap,
            expected_spp,
        } => (
            expected_spp,
            Some(super::options::check_seconds("--reference-cap", cap)?),
            Some(target),
        ),
        Budget::Spp(n) => {
            super::options::check_at_least_one("--spp", n)?;
            (n, None, None)
        }
        Budget::Time(t) => (
            u64::MAX,
            Some(super::options::check_seconds("--time", t)?),
            None,
        ),
    };
    let mut renderer = Renderer::new(scene, strategy, reference_stream_seed(seed))?;
    let bar = progress_bar(
        if time.is_some() && floor.is_none() {
            0
        } else {
            spp
        },
        format!("reference {} {}", scene.scene.name, integrand.name()),
        "{prefix} [{bar:30}] {pos}/{len} spp, eta {eta}",
    );
    let start = Instant::now();
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    let meta_of = |film: &Film| ReferenceMeta {
        scene: scene.scene.name.clone(),
        integrand: integrand.name().to_string(),
        scene_hash: scene.scene.content_hash.clone(),
        width: scene.scene.width,
        height: scene.scene.height,
        spp: film.spp,
        seed,
        strategy: strategy.name(),
        backend: scene.tracer.name().to_string(),
        threads,
        wall_time_s: start.elapsed().as_secs_f64(),
        noise_floor_rmse: Some(noise_floor(film)),
        dibench_version: VERSION.to_string(),
        commit: COMMIT.to_string(),
        cpu: Some(super::cpu_model()),
    };
    let mut next_checkpoint = FIRST_CHECKPOINT_SPP;
    let mut saved = None;
    let _polling = crate::interrupt::polling();
    loop {
        if crate::interrupt::requested() {
            bar.finish_and_clear();
            let kept = match saved {
                Some(spp) => format!("; the {spp} spp checkpoint is stored"),
                None => "; no checkpoint of it stored".to_string(),
            };
            return Err(Error::Interrupted(format!(
                "{} reference for `{}` stopped at {} spp{kept}",
                integrand.name(),
                scene.scene.name,
                film.spp
            )));
        }
        let done = match (floor, time) {
            // The floor is an O(pixels) sum: looked at every 8 passes, a small share of them.
            (Some(target), Some(cap)) => {
                film.spp >= super::pilot::MIN_PASSES
                    && (start.elapsed() >= cap
                        || (film.spp.is_multiple_of(8) && noise_floor(&film) <= target))
            }
            (_, Some(t)) => film.spp > 0 && start.elapsed() >= t,
            (_, None) => film.spp >= spp,
        };
        if done {
            break;
        }
        // Passes go in groups (Renderer::add_passes), ending on every pass the loop looks
        // at: a checkpoint, a multiple of 8 where the floor is measured, the spp asked for.
        let elapsed = start.elapsed().as_secs_f64();
        let per_pass = (film.spp > 0).then(|| elapsed / film.spp as f64);
        let mut left = match checkpoints {
            Some(_) => next_checkpoint.saturating_sub(film.spp),
            None => u64::MAX,
        };
        if floor.is_some() {
            left = left.min(8 - film.spp % 8);
        } else if time.is_none() {
            left = left.min(spp.saturating_sub(film.spp));
        }
        if let (Some(t), Some(p)) = (time, per_pass) {
            left = left.min(((t.as_secs_f64() - elapsed) / p).ceil().max(1.0) as u64);
        }
        let count = group_size(left, per_pass);
        renderer.add_passes(&mut film, count);
        bar.inc(count);
        if let Some(unit) = checkpoints
            && film.spp == next_checkpoint
        {
            // A checkpoint never replaces a stored reference of this content with more
            // samples (reruns after kills would otherwise lose it); the final save does.
            let better_stored = unit.meta::<ReferenceMeta>()?.is_some_and(|m| {
                m.scene_hash == scene.scene.content_hash
                    && (m.width, m.height) == (scene.scene.width, scene.scene.height)
                    && m.spp > film.spp
            });
            if !better_stored {
                save(
                    unit,
                    &film.mean(),
                    &film.variance_of_mean(),
                    &meta_of(&film),
                )?;
                saved = Some(film.spp);
            }
            next_checkpoint = next_checkpoint.saturating_mul(2);
        }
    }
    bar.finish_and_clear();
    Ok(Rendered {
        image: film.mean(),
        variance: film.variance_of_mean(),
        meta: meta_of(&film),
    })
}

/// √(σ²/N): the RMSE the reference's noise adds to a measured RMSE (see `ReferenceMeta`).
pub fn noise_floor(film: &Film) -> f64 {
    (film.mean_sample_variance() / film.spp.max(1) as f64).sqrt()
}

/// Commits the reference (image, per-pixel variance of the mean, metadata) as the content of
/// the unit `unit` (locked for writing; named by the integrand); returns the manifest's path.
pub fn save(
    unit: &Locked,
    image: &Image,
    variance: &Image,
    meta: &ReferenceMeta,
) -> Result<PathBuf> {
    let provenance = meta.provenance();
    let of_variance = provenance.variance();
    unit.commit(
        meta,
        vec![
            NewFile {
                role: "image",
                ext: "exr",
                write: Box::new(|f, p| encode_exr(f, image, p, Some(&provenance))),
            },
            NewFile {
                role: "variance",
                ext: "variance.exr",
                write: Box::new(|f, p| encode_exr(f, variance, p, Some(&of_variance))),
            },
        ],
    )
}

/// The stored reference of `unit` if it is for exactly this scene content and resolution and
/// has at least `min_spp`; a damaged one is an error naming the file.
pub fn load_matching(
    unit: &Locked,
    scene: &PreparedScene,
    min_spp: u64,
) -> Result<Option<(Image, ReferenceMeta)>> {
    let Some(stored) = unit.read::<ReferenceMeta>()? else {
        return Ok(None);
    };
    let meta = stored.meta.clone();
    if meta.scene_hash != scene.scene.content_hash
        || meta.width != scene.scene.width
        || meta.height != scene.scene.height
        || meta.spp < min_spp
    {
        return Ok(None);
    }
    let (path, bytes) = stored.file("image")?;
    let (width, height, pixels) =
        decode_exr(bytes, path, |r, g, b| [r as f64, g as f64, b as f64])?;
    let bad = |message: String| Error::Parse {
        path: path.to_path_buf(),
        message,
    };
    if (width, height) != (meta.width as usize, meta.height as usize) {
        return Err(bad(format!(
            "{width}×{height} pixels, but its manifest says {}×{}",
            meta.width, meta.height
        )));
    }
    if let Some(k) = pixels.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(bad(format!("pixel {k} is not finite")));
    }
    let image = Image {
        width: meta.width,
        height: meta.height,
        pixels,
    };
    Ok(Some((image, meta)))
}

/// The stored per-pixel variance of the reference mean of `unit` (as [`load_matching`] found
/// it), checked to match the image's size and to be finite and non-negative.
pub fn load_variance(unit: &Locked, width: u32, height: u32) -> Result<Image> {
    let Some(stored) = unit.read::<ReferenceMeta>()? else {
        return Err(Error::Output {
            path: unit.manifest_path(),
            message: "the reference vanished while locked".into(),
        });
    };
    let (path, bytes) = stored.file("variance")?;
    let (w, h, pixels) = decode_exr(bytes, path, |r, g, b| [r as f64, g as f64, b as f64])?;
    let bad = |message: String| Error::Parse {
        path: path.to_path_buf(),
        message,
    };
    if (w, h) != (width as usize, height as usize) {
        return Err(bad(format!(
            "{w}×{h} pixels, but its image has {width}×{height}"
        )));
    }
    if let Some(k) = pixels
        .iter()
        .position(|p| !p.iter().all(|c| c.is_finite() && *c >= 0.0))
    {
        return Err(bad(format!(
            "pixel {k} is not a variance (negative or not finite)"
        )));
    }
    Ok(Image {
        width,
        height,
        pixels,
    })
}
