//! Environment lighting: radiance arriving from infinitely far away, from a lat/long EXR
//! (`map`), resampled into four parameterizations of the sphere — lat/long, cube map,
//! equal-area octahedral, HEALPix — each an atlas of square tiles in [0, 1)² with its
//! direction ↔ (u, v) maps and Jacobian dω/(du dv) side by side (one file each).
//!
//! In each representation the radiance is piecewise constant over its own texels, and the
//! importance samplers (`cdf`: marginal/conditional; `hierarchical`: quadtree warping) choose a
//! texel with probability ∝ luminance · J(texel centre) and a point uniformly in it: so the
//! solid-angle pdf is p_uv / J(u, v), zero exactly where the radiance is zero, and lookup and
//! sampling share one reconstruction. Both samplers have the same pdf; they differ in cost and
//! in how they warp u.

pub mod cdf;
pub mod cube;
pub mod healpix;
pub mod hierarchical;
pub mod latlong;
pub mod map;
pub mod octahedral;
pub mod texels;

use glam::Vec3;
pub use texels::{EnvLanes, EnvSample, ImportanceMap, TexelMap};

/// Four 16-byte records (a texel's radiance and density, a pyramid node's four child sums) in
/// one aligned 64-byte cache line, so records read together can share a line.
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C, align(64))]
struct RecordLine([[f32; 4]; 4]);

/// The lines' records as one flat table, record k (slot k % 4 of line k / 4) at k: the form
/// [`crate::simd::Vector::load_records_at`] reads.
#[inline(always)]
fn record_table(lines: &[RecordLine]) -> &[[f32; 4]] {
    bytemuck::cast_slice(lines)
}

/// A parameterization of the sphere of directions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Repr {
    LatLong,
    Cube,
    Octahedral,
    Healpix,
}

impl Repr {
    pub const ALL: [Repr; 4] = [Repr::LatLong, Repr::Cube, Repr::Octahedral, Repr::Healpix];

    pub fn name(self) -> &'static str {
        match self {
            Repr::LatLong => "latlong",
            Repr::Cube => "cube",
            Repr::Octahedral => "octa",
            Repr::Healpix => "healpix",
        }
    }

    pub fn index(self) -> usize {
        self as usize
    }

    /// Square tiles side by side in the atlas.
    pub fn tiles(self) -> usize {
        match self {
            Repr::LatLong => 2,
            Repr::Cube => 6,
            Repr::Octahedral => 1,
            Repr::Healpix => 12,
        }
    }

    /// Tile side used for scenes: texel counts of 131k (lat/long 512×256, as the input maps),
    /// 98k (cube 6×128²), 65k (octahedral 256²) and 197k (HEALPix Nside 128).
    pub fn default_tile(self) -> usize {
        match self {
            Repr::LatLong => 256,
            Repr::Cube => 128,
            Repr::Octahedral => 256,
            Repr::Healpix => 128,
        }
    }

    pub fn dir_to_uv(self, w: Vec3) -> [f32; 2] {
        match self {
            Repr::LatLong => latlong::dir_to_uv(w),
            Repr::Cube => cube::dir_to_uv(w),
            Repr::Octahedral => octahedral::dir_to_uv(w),
            Repr::Healpix => healpix::dir_to_uv(w),
        }
    }

    pub fn uv_to_dir(self, uv: [f32; 2]) -> Vec3 {
        match self {
            Repr::LatLong => latlong::uv_to_dir(uv),
            Repr::Cube => cube::uv_to_dir(uv),
            Repr::Octahedral => octahedral::uv_to_dir(uv),
            Repr::Healpix => healpix::uv_to_dir(uv),
        }
    }

    /// dω/(du dv) at an atlas point.
    pub fn jacobian(self, uv: [f32; 2]) -> f32 {
        match self {
            Repr::LatLong => latlong::jacobian(uv),
            Repr::Cube => cube::jacobian(uv),
            Repr::Octahedral => octahedral::jacobian(uv),
            Repr::Healpix => healpix::jacobian(uv),
        }
    }
}

/// How texels are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum EnvSampler {
    /// Marginal/conditional CDF inversion.
    Cdf,
    /// Hierarchical warping down a mip pyramid.
    Hierarchical,
}

impl EnvSampler {
    pub const ALL: [EnvSampler; 2] = [EnvSampler::Cdf, EnvSampler::Hierarchical];

    pub fn name(self) -> &'static str {
        match self {
            EnvSampler::Cdf => "cdf",
            EnvSampler::Hierarchical => "hier",
        }
    }
}

/// One (representation, sampler) pair: how an environment light is looked up and sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct EnvMethod {
    pub repr: Repr,
    pub sampler: EnvSampler,
}

impl EnvMethod {
    pub const LATLONG_CDF: EnvMethod = EnvMethod {
        repr: Repr::LatLong,
        sampler: EnvSampler::Cdf,
    };
}

/// The environment in all four representations (built only for scenes that have one).
#[derive(Debug)]
pub struct Environment {
    maps: Vec<ImportanceMap>,
}

impl Environment {
    /// Resamples `radiance` (world direction → radiance) into every representation at its
    /// default resolution.
    pub fn build(radiance: &(dyn Fn(Vec3) -> Vec3 + Sync)) -> Self {
        Self::build_with(radiance, Repr::ALL.map(Repr::default_tile))
    }

    /// As [`Self::build`], with the tile side of each representation (in `Repr::ALL` order).
    pub fn build_with(radiance: &(dyn Fn(Vec3) -> Vec3 + Sync), tiles: [usize; 4]) -> Self {
        Environment {
            maps: Repr::ALL
                .iter()
                .zip(tiles)
                .map(|(&r, n)| ImportanceMap::new(TexelMap::resample(r, n, radiance)))
                .collect(),
        }
    }

    pub fn map(&self, repr: Repr) -> &ImportanceMap {
        &self.maps[repr.index()]
    }

    /// Radiance arriving from direction `w` (unit, pointing away from the scene).
    pub fn radiance(&self, repr: Repr, w: Vec3) -> Vec3 {
        self.map(repr).texels.lookup(w)
    }

    pub fn sample(&self, m: EnvMethod, u: [f32; 2]) -> Option<EnvSample> {
        self.map(m.repr).sample(m.sampler, u)
    }

    /// Solid-angle pdf of [`Self::sample`] (either sampler: they share it).
    pub fn pdf(&self, m: EnvMethod, w: Vec3) -> f32 {
        self.map(m.repr).pdf(w)
    }
}

/// χ² cases: one per (representation, sampler), on [`synthetic_environment`].
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    crate::strategy::env_methods()
        .map(|method| {
            let name = format!("env-{}", crate::strategy::env_method_name(method));
            crate::chi2::WarpEntry::new(
                name.clone(),
                "environment light importance sampling on a synthetic map (sun of relative strength `sun` + gradient + a black region), `tile` texels per tile side",
                &[("sun", 50.0), ("tile", 16.0)],
                &[&[], &[("sun", 1e4)], &[("sun", 0.0), ("tile", 32.0)]],
                move |p| chi2_case(p, &name, method),
            )
        })
        .collect()
}

/// A synthetic environment: a small bright sun, a sky gradient, and a black wedge (the sampler
/// must never go there, and its pdf there must be zero). Not symmetric in φ, so a map mirrored
/// in φ shows.
pub fn synthetic_environment(sun: f32) -> impl Fn(Vec3) -> Vec3 + Sync {
    let sun_dir = Vec3::new(0.5, 0.6, -0.4).normalize();
    move |w: Vec3| {
        if w.x > 0.2 && w.y < 0.0 {
            return Vec3::ZERO;
        }
        let sky = Vec3::new(0.3, 0.5, 1.0) * (1.2 + w.y) + Vec3::splat(0.2 * w.z.abs());
        let s = if w.dot(sun_dir) > 0.995 { sun } else { 0.0 };
        sky + Vec3::new(1.0, 0.9, 0.7) * s
    }
}

fn chi2_case(
    p: &crate::chi2::Params,
    name: &str,
    method: EnvMethod,
) -> Result<crate::chi2::WarpCase, String> {
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase, label, param};
    let (sun, tile) = (param(p, "sun"), p["tile"]);
    if sun.is_nan() || sun < 0.0 {
        return Err("sun must be non-negative".into());
    }
    if !((1.0..=512.0).contains(&tile) && tile.fract() == 0.0 && (tile as usize).is_power_of_two())
    {
        return Err("tile must be a power of two in 1..=512".into());
    }
    let n = tile as usize;
    let env = std::sync::Arc::new(Environment::build_with(&synthetic_environment(sun), [n; 4]));
    let env2 = env.clone();
    Ok(WarpCase {
        label: label(name, p),
        sample: Box::new(move |u| env.sample(method, [u[0], u[1]]).map(|s| (s.wi, s.pdf))),
        pdf: Box::new(move |w| env2.pdf(method, w) as f64),
        mismatch_slack: DEFAULT_SLACK,
        chart: Chart::sphere(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::stream::SampleStream;
    use crate::sampling::warp::sample_uniform_sphere;

    /// dir → uv → dir is the identity, and uv → dir → uv too (away from seams).
    #[test]
    fn maps_round_trip() {
        let mut rng = SampleStream::new(1, 2, 3, 4);
        for r in Repr::ALL {
            for _ in 0..20_000 {
                let w = sample_uniform_sphere(rng.next_2d());
                let back = r.uv_to_dir(r.dir_to_uv(w));
                assert!((back - w).length() < 2e-3, "{r:?}: {w} -> {back}");
                assert!((back.length() - 1.0).abs() < 1e-5, "{r:?}: not unit");
            }
        }
    }

    /// The stated Jacobian equals |∂ω/∂u × ∂ω/∂v| by central differences, and integrates to 4π.
    #[test]
    fn jacobians_match_finite_differences() {
        for r in Repr::ALL {
            let n = 96 * r.tiles();
            let (mut integral, mut worst) = (0.0f64, 0.0f64);
            let mut skipped = 0;
            for i in 0..n {
                for j in 0..96 {
                    let uv = [(i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / 96.0];
                    let h = 1e-3 / r.tiles() as f32;
                    let du = (r.uv_to_dir([uv[0] + h, uv[1]]) - r.uv_to_dir([uv[0] - h, uv[1]]))
                        .as_dvec3()
                        / (2.0 * h as f64);
                    let dv = (r.uv_to_dir([uv[0], uv[1] + 1e-3])
                        - r.uv_to_dir([uv[0], uv[1] - 1e-3]))
                    .as_dvec3()
                        / 2e-3;
                    let fd = du.cross(dv).length();
                    let jac = r.jacobian(uv) as f64;
                    // Skip the few points whose stencil straddles a seam or fold.
                    if (fd - jac).abs() > 0.5 * jac {
                        skipped += 1;
                        continue;
                    }
                    worst = worst.max((fd - jac).abs() / jac);
                    integral += jac / (n * 96) as f64;
                }
            }
            assert!(worst < 2e-2, "{r:?}: Jacobian off by {worst}");
            assert!(skipped < n * 96 / 100, "{r:?}: {skipped} stencils off");
            let four_pi = 4.0 * std::f64::consts::PI;
            assert!(
                (integral - four_pi).abs() < 1e-3 * four_pi,
                "{r:?}: ∫J = {integral}"
            );
        }
    }
}
