//! One sample per pixel over the whole image, in 4×4 tiles: a 16-ray camera packet, then the
//! strategy's shadow and emission probes as two more packets. Parallel over tiles with rayon.

use crate::film::{Film, TileLayout, accumulate};
use crate::geometry::Ray;
use crate::prepare::PreparedScene;
use crate::sampling::stream::{SampleStream, name_id};
use crate::scene::Camera;
use crate::strategy::{ShadingPoint, Strategy};
use crate::tracer::{HitPacket, LANES, LaneMask, RayPacket};
use glam::Vec3;
use rayon::prelude::*;

pub struct Renderer<'a> {
    pub scene: &'a PreparedScene,
    pub strategy: &'a dyn Strategy,
    pub seed: u64,
    strategy_id: u64,
}

impl<'a> Renderer<'a> {
    pub fn new(scene: &'a PreparedScene, strategy: &'a dyn Strategy, seed: u64) -> Self {
        Renderer {
            scene,
            strategy,
            seed,
            strategy_id: name_id(strategy.name()),
        }
    }

    /// Adds one sample per pixel to the film; pass `film.spp` numbers the random streams, so
    /// the result is independent of thread count and scheduling.
    pub fn add_pass(&self, film: &mut Film) {
        self.add_pass_with_stream(film, film.spp);
    }

    /// Adds one sample per pixel drawn from the random streams of pass `stream`, which need
    /// not be the film's next pass: shard i of n renders passes i, i + n, … (see
    /// `harness::shard`), and the merged film equals a sequential render's up to roundoff.
    pub fn add_pass_with_stream(&self, film: &mut Film, stream: u64) {
        let count = film.spp;
        let layout = film.layout;
        film.sum
            .par_chunks_mut(16)
            .zip(film.m2.par_chunks_mut(16))
            .enumerate()
            .for_each(|(tile, (sum, m2))| {
                let radiance = self.render_tile(&layout, tile, stream);
                for ((s, m), l) in sum.iter_mut().zip(m2.iter_mut()).zip(radiance.iter()) {
                    accumulate(s, m, count, [l.x as f64, l.y as f64, l.z as f64]);
                }
            });
        film.spp += 1;
    }

    fn render_tile(&self, shape: &TileLayout, tile: usize, pass: u64) -> [Vec3; LANES] {
        let scene = self.scene;
        let camera = &scene.scene.camera;
        let (w, h) = (shape.width, shape.height);
        let mut radiance = [Vec3::ZERO; LANES];
        let mut rngs: [Option<SampleStream>; LANES] = Default::default();
        let mut cam = RayPacket::default();
        let mut active: LaneMask = 0;
        for (lane, slot) in rngs.iter_mut().enumerate() {
            if let Some((x, y)) = shape.lane_pixel(tile, lane) {
                let pixel = y as u64 * w as u64 + x as u64;
                let mut rng = SampleStream::new(self.seed, self.strategy_id, pixel, pass);
                let ray = camera_ray(camera, w, h, x, y, rng.next_2d());
                cam.set(lane, &ray);
                *slot = Some(rng);
                active |= 1 << lane;
            }
        }
        let mut hits = HitPacket::default();
        scene
            .tracer
            .intersect_packet_coherent(&cam, active, &mut hits);

        let mut shadow = RayPacket::default();
        let mut shadow_value = [Vec3::ZERO; LANES];
        let mut shadow_mask: LaneMask = 0;
        let mut emit = RayPacket::default();
        let mut emit_probe = [None; LANES];
        let mut emit_mask: LaneMask = 0;
        let mut points: [Option<ShadingPoint>; LANES] = [None; LANES];
        let direct = self.strategy.integrand().is_direct();
        for lane in 0..LANES {
            let Some(rng) = rngs[lane].as_mut() else {
                continue;
            };
            let ray = cam.get(lane);
            let Some(hit) = hits.get(lane) else {
                // The camera sees the environment (zero without one).
                if direct {
                    radiance[lane] += scene.env_radiance(self.strategy.env_repr(), ray.dir);
                }
                continue;
            };
            let surf = scene.surface(&ray, &hit);
            if direct {
                radiance[lane] += scene.emitted(&surf, ray.dir);
            }
            let sp = ShadingPoint::with_error(
                surf.p,
                surf.p_error,
                surf.ng,
                ray.dir,
                scene.bsdfs[surf.material as usize],
            );
            let probes = self.strategy.sample(scene, &sp, rng);
            points[lane] = Some(sp);
            if let Some(s) = probes.shadow {
                shadow.set(lane, &s.ray);
                shadow_value[lane] = s.value;
                shadow_mask |= 1 << lane;
            }
            if let Some(e) = probes.emission {
                emit.set(lane, &e.ray);
                emit_probe[lane] = Some(e);
                emit_mask |= 1 << lane;
            }
        }
        if shadow_mask != 0 {
            let blocked = scene.tracer.occluded_packet(&shadow, shadow_mask);
            for lane in 0..LANES {
                if shadow_mask & !blocked & (1 << lane) != 0 {
                    radiance[lane] += shadow_value[lane];
                }
            }
        }
        if emit_mask != 0 {
            let mut ehits = HitPacket::default();
            scene.tracer.intersect_packet(&emit, emit_mask, &mut ehits);
            for lane in 0..LANES {
                let (Some(probe), Some(sp)) = (emit_probe[lane], points[lane]) else {
                    continue;
                };
                radiance[lane] += match ehits.get(lane) {
                    Some(hit) => emission_contribution(scene, self.strategy, &sp, &probe, &hit),
                    None => escape_contribution(scene, self.strategy, &sp, &probe),
                };
            }
        }
        radiance
    }
}

/// Pinhole camera ray through pixel (x, y) at sub-pixel offset `u` (a box filter).
pub fn camera_ray(c: &Camera, w: u32, h: u32, x: u32, y: u32, u: [f32; 2]) -> Ray {
    let aspect = w as f32 / h as f32;
    let sx = (2.0 * (x as f32 + u[0]) / w as f32 - 1.0) * aspect * c.tan_half_fov_y;
    let sy = (1.0 - 2.0 * (y as f32 + u[1]) / h as f32) * c.tan_half_fov_y;
    Ray::new(
        c.eye,
        (c.forward + c.right * sx + c.up * sy).normalize(),
        f32::INFINITY,
    )
}

/// What an emission probe that escaped the scene adds: weight · L_env · the strategy's MIS
/// weight, with the environment in the strategy's representation (zero without one).
pub fn escape_contribution(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    probe: &crate::strategy::EmissionProbe,
) -> Vec3 {
    let le = scene.env_radiance(strategy.env_repr(), probe.ray.dir);
    if le == Vec3::ZERO {
        return Vec3::ZERO;
    }
    probe.weight * le * strategy.env_weight(scene, sp, probe)
}

/// What an emission probe that hit `hit` adds: weight · Le · the strategy's MIS weight.
pub fn emission_contribution(
    scene: &PreparedScene,
    strategy: &dyn Strategy,
    sp: &ShadingPoint,
    probe: &crate::strategy::EmissionProbe,
    hit: &crate::geometry::Hit,
) -> Vec3 {
    if scene.prim_emitter[hit.prim as usize].is_none() {
        return Vec3::ZERO;
    }
    let surf = scene.surface(&probe.ray, hit);
    let le = scene.emitted(&surf, probe.ray.dir);
    if le == Vec3::ZERO {
        return Vec3::ZERO;
    }
    probe.weight * le * strategy.emission_weight(scene, sp, probe, &surf)
}
