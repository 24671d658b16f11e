//! High-sample reference images, stored with the metadata that decides whether `compare` may
//! reuse them: same scene content hash and resolution, and at least the requested spp.

use super::{COMMIT, VERSION, progress_bar};
use crate::error::{Error, Result};
use crate::film::{Film, Image};
use crate::math::mix64;
use crate::output::{read_exr, write_exr, write_json};
use crate::prepare::PreparedScene;
use crate::render::Renderer;
use crate::strategy::{Integrand, reference_strategy};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

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
}

pub fn reference_dir(out: &Path, scene: &str) -> PathBuf {
    out.join(scene).join("reference")
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

/// Renders a reference; with `checkpoint_out`, saves it (image, variance, JSON) at 64, 128,
/// 256, ... spp so an interrupted render keeps its latest power of two. A stored checkpoint
/// carries its own spp, so `compare` reuses it only when that is enough.
pub fn render_progressive(
    scene: &PreparedScene,
    integrand: Integrand,
    budget: Budget,
    seed: u64,
    threads: usize,
    checkpoint_out: Option<&Path>,
) -> Result<Rendered> {
    let (spp, time) = match budget {
        Budget::Spp(0) => return Err(Error::Usage("--spp must be at least 1".into())),
        Budget::Spp(n) => (n, None),
        Budget::Time(t) if !(t.is_finite() && t > 0.0) => {
            return Err(Error::Usage(format!(
                "--time must be a positive number of seconds, got {t}"
            )));
        }
        Budget::Time(t) => (u64::MAX, Some(Duration::from_secs_f64(t))),
    };
    let strategy = strategy_for(scene, integrand)?;
    let mut renderer = Renderer::new(scene, strategy.as_ref(), reference_stream_seed(seed))?;
    let bar = progress_bar(
        if time.is_some() { 0 } else { spp },
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
        noise_floor_rmse: Some((film.mean_sample_variance() / film.spp as f64).sqrt()),
        dibench_version: VERSION.to_string(),
        commit: COMMIT.to_string(),
    };
    let mut next_checkpoint = FIRST_CHECKPOINT_SPP;
    loop {
        if crate::interrupt::requested() {
            bar.finish_and_clear();
            let kept = match checkpoint_out {
                Some(_) if next_checkpoint > FIRST_CHECKPOINT_SPP => {
                    format!("; the {} spp checkpoint is stored", next_checkpoint / 2)
                }
                _ => "; nothing stored".to_string(),
            };
            return Err(Error::Interrupted(format!(
                "{} reference for `{}` stopped at {} spp{kept}",
                integrand.name(),
                scene.scene.name,
                film.spp
            )));
        }
        let done = match time {
            Some(t) => film.spp > 0 && start.elapsed() >= t,
            None => film.spp >= spp,
        };
        if done {
            break;
        }
        renderer.add_pass(&mut film);
        bar.inc(1);
        if let Some(out) = checkpoint_out
            && film.spp == next_checkpoint
        {
            save(out, &film.mean(), &film.variance_of_mean(), &meta_of(&film))?;
            next_checkpoint *= 2;
        }
    }
    bar.finish_and_clear();
    Ok(Rendered {
        image: film.mean(),
        variance: film.variance_of_mean(),
        meta: meta_of(&film),
    })
}

/// Writes `<integrand>.exr`, its per-pixel variance of the mean `<integrand>.variance.exr`,
/// and `<integrand>.json`; the JSON last, so a stored JSON always describes its images.
pub fn save(out: &Path, image: &Image, variance: &Image, meta: &ReferenceMeta) -> Result<PathBuf> {
    let dir = reference_dir(out, &meta.scene);
    let exr = dir.join(format!("{}.exr", meta.integrand));
    write_exr(&exr, image)?;
    write_exr(
        &dir.join(format!("{}.variance.exr", meta.integrand)),
        variance,
    )?;
    write_json(&dir.join(format!("{}.json", meta.integrand)), meta)?;
    Ok(exr)
}

/// A stored reference for exactly this scene content and resolution with at least `min_spp`.
pub fn load_matching(
    out: &Path,
    scene: &PreparedScene,
    integrand: Integrand,
    min_spp: u64,
) -> Result<Option<(Image, ReferenceMeta)>> {
    let dir = reference_dir(out, &scene.scene.name);
    let json = dir.join(format!("{}.json", integrand.name()));
    let Ok(text) = std::fs::read_to_string(&json) else {
        return Ok(None);
    };
    let meta: ReferenceMeta = serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: json.clone(),
        message: e.to_string(),
    })?;
    if meta.scene_hash != scene.scene.content_hash
        || meta.width != scene.scene.width
        || meta.height != scene.scene.height
        || meta.spp < min_spp
    {
        return Ok(None);
    }
    let image = read_exr(&dir.join(format!("{}.exr", integrand.name())))?;
    if image.width != meta.width || image.height != meta.height {
        return Ok(None);
    }
    Ok(Some((image, meta)))
}
