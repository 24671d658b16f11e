//! Environment light: radiance from infinitely far away, looked up and importance-sampled in
//! the representation and by the sampler a strategy's `LightMethods::env` names
//! (`crate::env`). Like a directional light it is distant: its shadow rays are unbounded.

use super::bounds::{Bounds, DistantBounds};
use super::{
    LaneQuery, LaneSamples, Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, keep,
    sample_lane_by_lane,
};
use crate::env::{EnvMethod, EnvSampler, Environment, ImportanceMap, Repr};
use crate::simd::{self, Isa, Kernel, Lanes, V3, Vector};
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
        struct LatLong<'a>(
            &'a ImportanceMap,
            EnvSampler,
            &'a LaneQuery<'a>,
            u32,
            &'a mut LaneSamples,
        );
        impl Kernel for LatLong<'_> {
            type Out = bool;
            /// The lanes of `active` written whole rows at a time; false for a black map.
            #[inline(always)]
            fn run<L: Lanes>(self) -> bool {
                let (active, out) = (self.3, self.4);
                let (u0, u1) = (L::V::load(self.2.u[0]), L::V::load(self.2.u[1]));
                let Some(s) = self.0.sample_latlong_lanes::<L::V>(self.1, u0, u1, active) else {
                    return false;
                };
                let zero = V3::<L::V>::splat(Vec3::ZERO);
                keep(active, V3::<L::V>::load(&s.wi), &mut out.wi);
                keep(active, V3::<L::V>::load(&s.radiance), &mut out.radiance);
                keep(active, zero, &mut out.point);
                keep(active, zero, &mut out.normal);
                keep(active, zero, &mut out.point_error);
                let pdf = L::V::select(active, L::V::load(&s.pdf), L::V::load(&out.pdf));
                pdf.store(&mut out.pdf);
                out.valid = (out.valid & !active) | s.valid;
                out.distant |= active;
                true
            }
        }
        let map = self.env.map(Repr::LatLong);
        if !simd::run(isa, LatLong(map, m.env.sampler, q, active, out)) {
            out.valid &= !active; // a black map: nothing to sample
        }
    }

    /// By direction: the environment has no points.
    fn pdf(&self, _ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        match at {
            LightHit::Direction(w) => self.pdf_env(w, m.env),
            LightHit::Surface { .. } => 0.0,
        }
    }
}
