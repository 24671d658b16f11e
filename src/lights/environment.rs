//! Environment light: radiance from infinitely far away, looked up and importance-sampled in
//! the representation and by the sampler a strategy's `LightMethods::env` names
//! (`crate::env`). Like a directional light it is distant: its shadow rays are unbounded.

use super::bounds::{Bounds, DistantBounds};
use super::{
    LaneQuery, LaneSamples, Light, LightCtx, LightHit, LightMethods, LightSample, LightShape,
    sample_lane_by_lane,
};
use crate::env::{EnvLanes, EnvMethod, EnvSampler, Environment, ImportanceMap, Repr};
use crate::simd::{self, Isa, Kernel, Lanes, Soa3, Vector, WIDTH};
use glam::Vec3;
use std::sync::Arc;

#[derive(Clone, Debug)]
pub struct EnvironmentLight {
    pub env: Arc<Environment>,
    /// Radius of the scene's bounding sphere: the power reaching the scene is π r² ∫L dω.
    pub scene_radius: f32,
}

impl EnvironmentLight {
    pub fn sample_env(&self, u: [f32; 2], m: EnvMethod) -> Option<LightSample> {
        let s = self.env.sample(m, u)?;
        Some(LightSample {
            wi: s.wi,
            point: Vec3::ZERO,
            point_error: Vec3::ZERO,
            normal: Vec3::ZERO,
            radiance: s.radiance,
            pdf: s.pdf,
            distant: true,
        })
    }

    pub fn pdf_env(&self, wi: Vec3, m: EnvMethod) -> f32 {
        self.env.pdf(m, wi)
    }
}

impl Light for EnvironmentLight {
    fn shape(&self) -> LightShape {
        LightShape::Environment
    }

    /// Luminance-weighted power for light selection (pbrt-v4 `ImageInfiniteLight::Phi`).
    fn power(&self) -> f32 {
        let r = self.scene_radius as f64;
        (std::f64::consts::PI * r * r * self.env.map(Repr::LatLong).luminance_integral) as f32
    }

    fn bounds(&self) -> Bounds {
        Bounds::Distant(DistantBounds {
            to_light: None,
            irradiance: self.env.map(Repr::LatLong).luminance_integral as f32,
        })
    }

    fn sample(&self, _ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        self.sample_env([u[0], u[1]], m.env)
    }

    /// Over lanes for lat/long maps (by either sampler); lane by lane for the other
    /// representations, whose maps are scalar.
    fn sample_lanes(
        &self,
        isa: Isa,
        q: &LaneQuery,
        active: u32,
        m: &LightMethods,
        out: &mut LaneSamples,
    ) {
        if m.env.repr != Repr::LatLong {
            return sample_lane_by_lane(self, q, active, m, out);
        }
        struct LatLong<'a>(&'a ImportanceMap, EnvSampler, &'a LaneQuery, u32);
        impl Kernel for LatLong<'_> {
            type Out = Option<EnvLanes>;
            #[inline(always)]
            fn run<L: Lanes>(self) -> Option<EnvLanes> {
                let (u0, u1) = (L::V::load(&self.2.u[0]), L::V::load(&self.2.u[1]));
                self.0.sample_latlong_lanes::<L::V>(self.1, u0, u1, self.3)
            }
        }
        let map = self.env.map(Repr::LatLong);
        let Some(s) = simd::run(isa, LatLong(map, m.env.sampler, q, active)) else {
            out.valid &= !active; // a black map: nothing to sample
            return;
        };
        let keep = |from: &Soa3, to: &mut Soa3| {
            for lane in 0..WIDTH {
                if active >> lane & 1 != 0 {
                    to.set(lane, from.get(lane));
                }
            }
        };
        keep(&s.wi, &mut out.wi);
        keep(&s.radiance, &mut out.radiance);
        keep(&Soa3::default(), &mut out.point);
        keep(&Soa3::default(), &mut out.normal);
        keep(&Soa3::default(), &mut out.point_error);
        for lane in 0..WIDTH {
            if active >> lane & 1 != 0 {
                out.pdf[lane] = s.pdf[lane];
            }
        }
        out.valid = (out.valid & !active) | s.valid;
        out.distant |= active;
    }

    /// By direction: the environment has no points.
    fn pdf(&self, _ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        match at {
            LightHit::Direction(w) => self.pdf_env(w, m.env),
            LightHit::Surface { .. } => 0.0,
        }
    }
}
