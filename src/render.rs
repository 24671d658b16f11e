//! One sample per pixel over the whole image, in 4×4 tiles: a 16-ray camera packet, then the
//! estimator's shadow and emission probes as two more packets. Parallel over tiles with rayon.
//!
//! A pass runs in two phases per tile — the camera phase (sample values, camera rays, shading
//! points) and the shading phase (probes, their packets, the radiance) — back to back, or, for
//! an image-space estimator, the camera phase of every tile first, then the estimator's
//! `begin_pass` with all shading points, then every tile's shading phase.

use crate::error::{Error, Result};
use crate::film::{Film, TileLayout, accumulate};
use crate::geometry::Ray;
use crate::prepare::{PreparedScene, SceneView};
use crate::sampling::generator::MAX_DIMENSIONS;
use crate::sampling::stream::name_id;
use crate::sampling::{Dims, GENERATORS, SampleGenerator, SampleKey, Setup};
use crate::scene::Camera;
use crate::strategy::{EmissionProbe, Estimator, PassPoints, Probes, ShadingPoint, Strategy};
use crate::tracer::{HitPacket, LANES, LaneMask, RayPacket};
use glam::Vec3;
use rayon::prelude::*;

pub struct Renderer<'a> {
    pub scene: &'a PreparedScene,
    pub view: SceneView<'a>,
    estimator: Box<dyn Estimator + 'a>,
    generator: &'a dyn SampleGenerator,
    /// What the generator knows of this render (layout, spp if fixed, image size).
    setup: Setup,
    pub seed: u64,
    strategy_id: u64,
    /// Camera dimensions plus the estimator's.
    dims: usize,
    direct: bool,
}

/// A tile after its camera phase. Reused from tile to tile within a worker's share of a pass
/// (rayon's `for_each_init`): 2 KiB of sample values are not cleared and copied per tile.
struct CameraTile<'a> {
    radiance: [Vec3; LANES],
    points: [Option<ShadingPoint<'a>>; LANES],
    values: [[f32; MAX_DIMENSIONS]; LANES],
}

impl CameraTile<'_> {
    fn new() -> Self {
        CameraTile {
            radiance: [Vec3::ZERO; LANES],
            points: [None; LANES],
            values: [[0.0; MAX_DIMENSIONS]; LANES],
        }
    }
}

impl<'a> Renderer<'a> {
    /// `strategy` bound to `scene`, drawing from the default (independent) generator; an error
    /// when the strategy does not apply there.
    pub fn new(scene: &'a PreparedScene, strategy: &dyn Strategy, seed: u64) -> Result<Self> {
        Self::with_generator(scene, strategy, seed, GENERATORS[0])
    }

    /// `strategy` drawing from `generator`, with no sample count known up front (a time
    /// budget); see [`Self::with_sampler`].
    pub fn with_generator(
        scene: &'a PreparedScene,
        strategy: &dyn Strategy,
        seed: u64,
        generator: &'a dyn SampleGenerator,
    ) -> Result<Self> {
        Self::with_sampler(scene, strategy, seed, generator, None)
    }

    /// `strategy` drawing from `generator`, told the number of passes `spp` the render will
    /// take when it is fixed (a stratified generator needs it); an error when the strategy does
    /// not apply or the generator cannot serve this render.
    pub fn with_sampler(
        scene: &'a PreparedScene,
        strategy: &dyn Strategy,
        seed: u64,
        generator: &'a dyn SampleGenerator,
        spp: Option<u64>,
    ) -> Result<Self> {
        let integrand = strategy.integrand();
        let view = scene.view(integrand);
        let name = strategy.name();
        let estimator = strategy.bind(view).map_err(|why| {
            Error::Usage(format!(
                "strategy `{name}` does not apply to scene `{}`: {why}",
                scene.scene.name
            ))
        })?;
        let setup = Setup::image(
            estimator.layout(),
            spp,
            scene.scene.width,
            scene.scene.height,
        );
        let dims = setup.layout.len();
        if dims > MAX_DIMENSIONS {
            return Err(Error::Usage(format!(
                "strategy `{name}` lays out {dims} sample dimensions; at most {MAX_DIMENSIONS} are supported"
            )));
        }
        generator
            .check(&setup)
            .map_err(|why| Error::Usage(format!("--sampler {}: {why}", generator.name())))?;
        Ok(Renderer {
            scene,
            view,
            estimator,
            generator,
            setup,
            seed,
            strategy_id: name_id(&name),
            dims,
            direct: integrand.is_direct(),
        })
    }

    pub fn generator(&self) -> &dyn SampleGenerator {
        self.generator
    }

    pub fn estimator(&self) -> &dyn Estimator {
        self.estimator.as_ref()
    }

    /// Adds one sample per pixel to the film; pass `film.spp` numbers the samples, so the
    /// result is independent of thread count and scheduling.
    pub fn add_pass(&mut self, film: &mut Film) {
        self.add_pass_with_stream(film, film.spp);
    }

    /// Adds one sample per pixel with sample index `stream`, which need not be the film's
    /// next pass: shard i of n renders passes i, i + n, … (see `harness::shard`), and the
    /// merged film equals a sequential render's up to roundoff.
    pub fn add_pass_with_stream(&mut self, film: &mut Film, stream: u64) {
        let count = film.spp;
        let layout = film.layout;
        if self.estimator.wants_pass_points() {
            let tiles: Vec<CameraTile> = (0..layout.tile_count())
                .into_par_iter()
                .map(|t| {
                    let mut tile = CameraTile::new();
                    self.camera_phase(&layout, t, stream, &mut tile);
                    tile
                })
                .collect();
            let mut pass = PassPoints {
                width: layout.width,
                height: layout.height,
                points: vec![None; (layout.width * layout.height) as usize],
            };
            for (t, tile) in tiles.iter().enumerate() {
                for (lane, p) in tile.points.iter().enumerate() {
                    if let Some((x, y)) = layout.lane_pixel(t, lane) {
                        pass.points[(y * layout.width + x) as usize] = *p;
                    }
                }
            }
            self.estimator.begin_pass(&pass);
            let this = &*self;
            film.sum
                .par_chunks_mut(16)
                .zip(film.m2.par_chunks_mut(16))
                .zip(tiles.par_iter())
                .for_each(|((sum, m2), tile)| {
                    let radiance = this.shading_phase(tile);
                    for ((s, m), l) in sum.iter_mut().zip(m2.iter_mut()).zip(radiance.iter()) {
                        accumulate(s, m, count, [l.x as f64, l.y as f64, l.z as f64]);
                    }
                });
        } else {
            let this = &*self;
            film.sum
                .par_chunks_mut(16)
                .zip(film.m2.par_chunks_mut(16))
                .enumerate()
                .for_each_init(CameraTile::new, |tile, (t, (sum, m2))| {
                    this.camera_phase(&layout, t, stream, tile);
                    let radiance = this.shading_phase(tile);
                    for ((s, m), l) in sum.iter_mut().zip(m2.iter_mut()).zip(radiance.iter()) {
                        accumulate(s, m, count, [l.x as f64, l.y as f64, l.z as f64]);
                    }
                });
        }
        film.spp += 1;
    }

    /// Sample values, the camera packet, what the camera sees directly (emitters, the
    /// environment) and the shading points.
    fn camera_phase(&self, shape: &TileLayout, tile: usize, pass: u64, out: &mut CameraTile<'a>) {
        let scene = self.scene;
        let camera = &scene.scene.camera;
        let (w, h) = (shape.width, shape.height);
        out.radiance = [Vec3::ZERO; LANES];
        out.points = [None; LANES];
        let mut cam = RayPacket::default();
        let mut active: LaneMask = 0;
        let mut pixels = [u32::MAX; LANES];
        let mut coords = [(0, 0); LANES];
        for (lane, (pixel_of, xy)) in pixels.iter_mut().zip(coords.iter_mut()).enumerate() {
            if let Some((x, y)) = shape.lane_pixel(tile, lane) {
                *pixel_of = y * w + x;
                *xy = (x, y);
                active |= 1 << lane;
            }
        }
        let keys = pixels.map(|pixel| SampleKey {
            seed: self.seed,
            strategy: self.strategy_id,
            pixel: pixel as u64,
            index: pass,
        });
        self.generator
            .fill_lanes(&self.setup, &keys, active, self.dims, &mut out.values);
        for (lane, &(x, y)) in coords.iter().enumerate() {
            if active & (1 << lane) != 0 {
                let v = &out.values[lane];
                cam.set(lane, &camera_ray(camera, w, h, x, y, [v[0], v[1]]));
            }
        }
        let mut hits = HitPacket::default();
        scene
            .tracer
            .intersect_packet_coherent(&cam, active, &mut hits);
        for (lane, &pixel) in pixels.iter().enumerate() {
            if active & (1 << lane) == 0 {
                continue;
            }
            let ray = cam.get(lane);
            let Some(hit) = hits.get(lane) else {
                // The camera sees the environment (zero without one).
                if self.direct {
                    out.radiance[lane] += self.view.env_radiance(ray.dir);
                }
                continue;
            };
            let surf = scene.world.surface(&ray, &hit);
            if self.direct {
                out.radiance[lane] += self.view.emitted(&surf, ray.dir);
            }
            let mut sp = ShadingPoint::with_error(
                surf.p,
                surf.p_error,
                surf.ng,
                ray.dir,
                &scene.world.materials[surf.material as usize],
            );
            sp.pixel = pixel;
            out.points[lane] = Some(sp);
        }
    }

    /// The estimator's probes for the tile's points, traced as packets.
    fn shading_phase(&self, tile: &CameraTile) -> [Vec3; LANES] {
        let scene = self.scene;
        let mut radiance = tile.radiance;
        let mut dims: [Dims; LANES] =
            std::array::from_fn(|lane| Dims::new(&tile.values[lane][2..self.dims]));
        let mut probes = [Probes::default(); LANES];
        self.estimator
            .sample_packet(&tile.points, &mut dims, &mut probes);

        let mut shadow = RayPacket::default();
        let mut shadow_mask: LaneMask = 0;
        let mut emit = RayPacket::default();
        let mut emit_mask: LaneMask = 0;
        for (lane, p) in probes.iter().enumerate() {
            if tile.points[lane].is_none() {
                continue;
            }
            if let Some(s) = p.shadow {
                shadow.set(lane, &s.ray);
                shadow_mask |= 1 << lane;
            }
            if let Some(e) = p.emission {
                emit.set(lane, &e.ray);
                emit_mask |= 1 << lane;
            }
        }
        if shadow_mask != 0 {
            let blocked = scene.tracer.occluded_packet(&shadow, shadow_mask);
            for (lane, p) in probes.iter().enumerate() {
                if shadow_mask & !blocked & (1 << lane) != 0
                    && let Some(s) = p.shadow
                {
                    radiance[lane] += s.value;
                }
            }
        }
        if emit_mask != 0 {
            let mut ehits = HitPacket::default();
            scene.tracer.intersect_packet(&emit, emit_mask, &mut ehits);
            for lane in 0..LANES {
                let (Some(probe), Some(sp)) = (probes[lane].emission, &tile.points[lane]) else {
                    continue;
                };
                radiance[lane] += match ehits.get(lane) {
                    Some(hit) => {
                        emission_contribution(&self.view, self.estimator(), sp, &probe, &hit)
                    }
                    None => escape_contribution(&self.view, self.estimator(), sp, &probe),
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

/// What an emission probe that escaped the scene adds: weight · L_env · the estimator's MIS
/// weight, with the environment in the view's representation (zero without one).
pub fn escape_contribution(
    view: &SceneView,
    estimator: &dyn Estimator,
    sp: &ShadingPoint,
    probe: &EmissionProbe,
) -> Vec3 {
    let le = view.env_radiance(probe.ray.dir);
    if le == Vec3::ZERO {
        return Vec3::ZERO;
    }
    probe.weight * le * estimator.env_weight(sp, probe)
}

/// What an emission probe that hit `hit` adds: weight · Le · the estimator's MIS weight.
pub fn emission_contribution(
    view: &SceneView,
    estimator: &dyn Estimator,
    sp: &ShadingPoint,
    probe: &EmissionProbe,
    hit: &crate::geometry::Hit,
) -> Vec3 {
    if view.world.prim_emitter[hit.prim as usize].is_none() {
        return Vec3::ZERO;
    }
    let surf = view.world.surface(&probe.ray, hit);
    let le = view.emitted(&surf, probe.ray.dir);
    if le == Vec3::ZERO {
        return Vec3::ZERO;
    }
    probe.weight * le * estimator.emission_weight(sp, probe, &surf)
}
