//! High-sample reference images, stored with the metadata that decides whether `compare` may
//! reuse them: same scene content hash and resolution, and at least the requested spp.

use super::{COMMIT, VERSION, progress_bar, render_spp};
use crate::error::{Error, Result};
use crate::film::Image;
use crate::math::mix64;
use crate::output::{read_exr, write_exr, write_json};
use crate::prepare::PreparedScene;
use crate::render::Renderer;
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
    pub dibench_version: String,
    pub commit: String,
}

pub fn reference_dir(out: &Path, scene: &str) -> PathBuf {
    out.join(scene).join("reference")
}

/// The reference's random streams are salted so that they never coincide with the streams of
/// a compared run of the same strategy and seed: an error measured against a correlated
/// reference would be too small.
fn reference_stream_seed(seed: u64) -> u64 {
    mix64(seed) ^ 0x5245_4645_5245_4e43
}

pub fn render(
    scene: &PreparedScene,
    integrand: Integrand,
    spp: u64,
    seed: u64,
    threads: usize,
) -> Result<(Image, ReferenceMeta)> {
    if spp == 0 {
        return Err(Error::Usage("--spp must be at least 1".into()));
    }
    let strategy = reference_strategy(scene, integrand).ok_or_else(|| {
        Error::Usage(format!(
            "scene `{}`: no strategy can render a {} reference",
            scene.scene.name,
            integrand.name()
        ))
    })?;
    let renderer = Renderer::new(scene, strategy.as_ref(), reference_stream_seed(seed));
    let bar = progress_bar(
        spp,
        format!("reference {} {}", scene.scene.name, integrand.name()),
        "{prefix} [{bar:30}] {pos}/{len} spp, eta {eta}",
    );
    let start = Instant::now();
    let image = render_spp(
        &renderer,
        scene.scene.width,
        scene.scene.height,
        spp,
        |_| bar.inc(1),
    );
    bar.finish_and_clear();
    let meta = ReferenceMeta {
        scene: scene.scene.name.clone(),
        integrand: integrand.name().to_string(),
        scene_hash: scene.scene.content_hash.clone(),
        width: scene.scene.width,
        height: scene.scene.height,
        spp,
        seed,
        strategy: strategy.name().to_string(),
        backend: scene.tracer.name().to_string(),
        threads,
        wall_time_s: start.elapsed().as_secs_f64(),
        dibench_version: VERSION.to_string(),
        commit: COMMIT.to_string(),
    };
    Ok((image, meta))
}

pub fn save(out: &Path, image: &Image, meta: &ReferenceMeta) -> Result<PathBuf> {
    let dir = reference_dir(out, &meta.scene);
    let exr = dir.join(format!("{}.exr", meta.integrand));
    write_exr(&exr, image)?;
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
