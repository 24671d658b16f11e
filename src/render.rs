//! One sample per pixel over the whole image, in 4×4 tiles: a 16-ray camera packet, then the
//! estimator's shadow and emission probes as two more packets. Parallel over tiles with rayon.
//! Passes are rendered in groups of up to 16 ([`Renderer::add_passes`]), whose packets hold
//! several passes' samples of fewer pixels, down to one pixel's 16 samples: the same film.
//!
//! A pass runs in two phases per tile — the camera phase (sample values, camera rays, shading
//! points) and the shading phase (probes, their packets, the radiance) — back to back, or, for
//! an image-space estimator, the camera phase of every tile first, then the estimator's
//! `begin_pass` with all shading points, then every tile's shading phase.

use crate::error::{Error, Result};
use crate::film::{Accumulation, Film, TILE, TileLayout};
use crate::geometry::sphere::Sphere;
use crate::geometry::triangle::Triangle;
use crate::geometry::{Hit, Ray};
use crate::prepare::{PreparedScene, SceneView, SurfaceHit};
use crate::sampling::generator::MAX_DIMENSIONS;
use crate::sampling::stream::name_id;
use crate::sampling::{GENERATORS, LaneValues, PacketDims, SampleGenerator, SampleKeys, Setup};
use crate::scene::Camera;
use crate::simd::{self, Isa, Lanes, Soa3, V3, Vector};
use crate::strategy::{
    EmissionProbe, Estimator, PassPoints, ProbePacket, ShadingLanes, ShadingPacket, ShadingPoint,
    Strategy,
};
use crate::tracer::{HitPacket, LANES, LaneMask, NO_HIT, RayPacket};
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
    /// The lane layer's instruction set (every ISA gives the same bits).
    isa: Isa,
}

/// A tile after its camera phase. Reused from tile to tile within a worker's share of a pass
/// (rayon's `for_each_init`): 2 KiB of sample values are not cleared and copied per tile.
struct CameraTile<'a> {
    radiance: [Vec3; LANES],
    /// The shading points, in lanes (the shading kernel writes them).
    packet: ShadingPacket<'a>,
    values: LaneValues,
}

impl CameraTile<'_> {
    fn new() -> Self {
        CameraTile {
            radiance: [Vec3::ZERO; LANES],
            packet: ShadingPacket::default(),
            values: [[0.0; LANES]; MAX_DIMENSIONS],
        }
    }
}

/// A worker's packets and lanes for a tile's two phases, reused from tile to tile: each is
/// written whole, or in the lanes that are read, before it is read, so nothing is cleared
/// per tile (clearing them was 4 % of a cornell `light` profile: docs/tracer.md, stop 36).
/// Lanes a tile does not use keep an earlier tile's finite values, which no lane reads.
#[derive(Default)]
struct TileScratch {
    cam: RayPacket,
    hits: HitPacket,
    lanes: HitLanes,
    /// The hit points' error bounds (the points and their geometry go to the tile).
    p_error: Soa3,
    /// The shading phase's probes (their shadow and emission packets) and the emission rays'
    /// hits.
    probes: ProbePacket,
    emit_hits: HitPacket,
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
            isa: Isa::detect().unwrap_or(Isa::Portable),
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
        if self.estimator.wants_pass_points() {
            let update = Accumulation::of_count(film.spp);
            let layout = film.layout;
            let mut tiles: Vec<CameraTile> = (0..layout.tile_count())
                .into_par_iter()
                .map_init(TileScratch::default, |scratch, t| {
                    let mut tile = CameraTile::new();
                    self.camera_phase(&layout, &tile_lanes(&layout, t, stream), &mut tile, scratch);
                    tile
                })
                .collect();
            let mut pass = PassPoints {
                width: layout.width,
                height: layout.height,
                points: vec![None; (layout.width * layout.height) as usize],
            };
            for (t, tile) in tiles.iter().enumerate() {
                for (lane, p) in tile.packet.points() {
                    if let Some((x, y)) = layout.lane_pixel(t, lane) {
                        pass.points[(y * layout.width + x) as usize] = Some(p);
                    }
                }
            }
            self.estimator.begin_pass(&pass);
            let this = &*self;
            film.sum
                .par_chunks_mut(16)
                .zip(film.m2.par_chunks_mut(16))
                .zip(tiles.par_iter_mut())
                .for_each_init(TileScratch::default, |scratch, ((sum, m2), tile)| {
                    this.shading_phase(tile, scratch);
                    update.add_tile(this.isa, sum, m2, &tile.radiance);
                });
            film.spp += 1;
        } else {
            self.add_passes_with_streams(film, &[stream]);
        }
    }

    /// Adds `count` (at most [`MAX_GROUP`]) passes to the film, numbered from its next pass:
    /// the same film, bit for bit, as `count` calls of [`Self::add_pass`].
    pub fn add_passes(&mut self, film: &mut Film, count: u64) {
        let first = film.spp;
        let streams: Vec<u64> = (first..first + count).collect();
        self.add_passes_with_streams(film, &streams);
    }

    /// Adds one pass per entry of `streams` (at most [`MAX_GROUP`]) with those sample
    /// indices, in order: the same film, bit for bit, as [`Self::add_pass_with_stream`] of
    /// each in turn (the `grouped_passes_equal_passes_one_by_one` test).
    ///
    /// A packet then holds samples of several passes of fewer pixels: a group of c passes
    /// (a power of two) fills each packet with c passes of 16/c neighbouring pixels, down
    /// to one pixel's 16 samples. A strategy's samples are unchanged; only their grouping
    /// into lanes is. Rays from one pixel's samples are about as coherent as rays get, which
    /// is what packets pay for: at 16 passes a bunny `light` pass is 1.2× as fast
    /// (docs/tracer.md, stop 42). Mitsuba 3's JIT variants put one pixel's samples in
    /// neighbouring lanes the same way. An image-space estimator, which needs every point of
    /// a pass before it shades any, takes its passes one by one.
    pub fn add_passes_with_streams(&mut self, film: &mut Film, streams: &[u64]) {
        assert!(
            streams.len() as u64 <= MAX_GROUP,
            "{} passes in one group",
            streams.len()
        );
        if self.estimator.wants_pass_points() {
            for &s in streams {
                self.add_pass_with_stream(film, s);
            }
            return;
        }
        let layout = film.layout;
        // Powers of two, largest first: 13 passes are groups of 8, 4 and 1. Per group, once
        // for every tile: each lane's pass, and each pass's film update.
        let mut groups = Vec::new();
        let mut offset = 0;
        while offset < streams.len() {
            let c = 1usize << (streams.len() - offset).ilog2();
            let of_group = &streams[offset..offset + c];
            let pass: [u64; LANES] = std::array::from_fn(|l| of_group[l & (c - 1)]);
            let update: Vec<Accumulation> = (0..c)
                .map(|j| Accumulation::of_count(film.spp + (offset + j) as u64))
                .collect();
            groups.push((c, pass, update));
            offset += c;
        }
        let this = &*self;
        film.sum
            .par_chunks_mut(16)
            .zip(film.m2.par_chunks_mut(16))
            .enumerate()
            .for_each_init(
                || (CameraTile::new(), TileScratch::default()),
                |(tile, scratch), (t, (sum, m2))| {
                    for (c, pass, update) in &groups {
                        let c = *c;
                        // radiance[j][pixel]: pass j of the group, the tile's pixels in order.
                        let mut radiance = [[Vec3::ZERO; LANES]; MAX_GROUP as usize];
                        for places in &BLOCK_PLACES[c.trailing_zeros() as usize][..c] {
                            let samples = LaneSamples::new(&layout, t, places, *pass);
                            if samples.active == 0 {
                                continue;
                            }
                            this.camera_phase(&layout, &samples, tile, scratch);
                            this.shading_phase(tile, scratch);
                            let got = &tile.radiance;
                            // Both indices are below 16 (c ≤ 16, slots of a 4×4 tile); the
                            // masks say so, so the copy has no bounds checks.
                            for (lane, &slot) in samples.places.slot.iter().enumerate() {
                                radiance[lane & (c - 1) & (LANES - 1)]
                                    [slot as usize & (LANES - 1)] = got[lane];
                            }
                        }
                        for (u, x) in update.iter().zip(&radiance) {
                            u.add_tile(this.isa, sum, m2, x);
                        }
                    }
                },
            );
        film.spp += streams.len() as u64;
    }

    /// Sample values, the camera packet, what the camera sees directly (emitters, the
    /// environment) and the shading points. Camera rays, hit points and shading frames are
    /// computed over lanes, bit for bit as the scalar [`camera_ray`], [`World::surface`] and
    /// [`ShadingPoint::with_error`] (the `camera_phase_matches_lane_by_lane` test).
    fn camera_phase(
        &self,
        shape: &TileLayout,
        samples: &LaneSamples,
        out: &mut CameraTile<'a>,
        scratch: &mut TileScratch,
    ) {
        let scene = self.scene;
        let world = &scene.world;
        let (w, h) = (shape.width, shape.height);
        out.radiance = [Vec3::ZERO; LANES];
        out.packet.mask = 0;
        let active = samples.active;
        // Each lane's pixel, as the key row the generator reads (values below 2³²), and its
        // coordinates: whole rows from the places' tables. An inactive lane's place lies
        // outside the image (finite coordinates no one reads) and its pixel is u32::MAX.
        let (x0, y0) = samples.origin;
        let pl = samples.places;
        let mut pixels = [0u64; LANES];
        for ((pixel, &dx), &dy) in pixels.iter_mut().zip(&pl.dx).zip(&pl.dy) {
            *pixel = (y0 + dy).wrapping_mul(w).wrapping_add(x0 + dx) as u64;
        }
        if active != LaneMask::MAX {
            for (lane, pixel) in pixels.iter_mut().enumerate() {
                if active >> lane & 1 == 0 {
                    *pixel = u32::MAX as u64;
                }
            }
        }
        // Exact: sides are at most MAX_IMAGE_SIDE, far below 2²⁴.
        let (fx0, fy0) = (x0 as f32, y0 as f32);
        let keys = SampleKeys::of_render(self.seed, self.strategy_id, pixels, samples.pass);
        self.generator
            .fill_lanes(&self.setup, &keys, active, self.dims, &mut out.values);
        let px = PixelLanes {
            x: pl.fx.map(|d| fx0 + d),
            y: pl.fy.map(|d| fy0 + d),
            u: [out.values[0], out.values[1]],
        };
        let TileScratch {
            cam,
            hits,
            lanes: g,
            p_error,
            ..
        } = scratch;
        simd::run(
            self.isa,
            CameraRays {
                camera: &scene.scene.camera,
                w,
                h,
                px: &px,
                out: cam,
            },
        );
        scene.tracer.intersect_packet_coherent(cam, active, hits);
        // Which lanes hit something and which escaped, without a branch per lane.
        let mut found = 0u32;
        for (lane, &prim) in hits.prim.iter().enumerate() {
            found |= ((prim != NO_HIT) as u32) << lane;
        }
        let hit_mask = found & active as u32;
        let escaped = active as u32 & !hit_mask;
        // The primitive every hit lane hit, if they share one: a packet of one pixel's
        // samples mostly does (passes in groups), and then its lookups are made once.
        let first = hits.prim[(hit_mask.trailing_zeros() as usize).min(LANES - 1)];
        let mut other = 0u32;
        for (lane, &prim) in hits.prim.iter().enumerate() {
            other |= ((prim != first) as u32) << lane;
        }
        let shared = (hit_mask != 0 && other & hit_mask == 0).then_some(first as usize);
        // What the hit points need, gathered into lanes: triangle vertices and barycentrics
        // (one triangle's rows at once where every lane hit it), or a sphere hit's point
        // (computed lane by lane: spheres are few). Lanes that did not hit get finite values
        // no one reads.
        g.given = 0;
        let shared_sphere = shared.and_then(|prim| world.geometry.sphere_index(prim as u32));
        match (shared, shared_sphere) {
            (Some(prim), None) => {
                let t = &world.geometry.triangles[prim];
                g.v = [Soa3::splat(t.v0), Soa3::splat(t.v1), Soa3::splat(t.v2)];
                (g.b1, g.b2) = (hits.u, hits.v);
                g.ng = Soa3::splat(world.triangle_normals[prim]);
            }
            (Some(_), Some(s)) => {
                // One sphere for every hit lane (one pixel's samples on a sphere light or a
                // ball): its points over lanes.
                simd::run(
                    self.isa,
                    SphereHits {
                        sphere: &world.geometry.spheres[s],
                        cam,
                        t: &hits.t,
                        mask: hit_mask,
                        g,
                    },
                );
            }
            (None, _) => {
                let mut rest = hit_mask;
                while rest != 0 {
                    let lane = rest.trailing_zeros() as usize;
                    rest &= rest - 1;
                    let prim = hits.prim[lane];
                    match world.geometry.sphere_index(prim) {
                        None => {
                            let t = &world.geometry.triangles[prim as usize];
                            g.v[0].set(lane, t.v0);
                            g.v[1].set(lane, t.v1);
                            g.v[2].set(lane, t.v2);
                            g.b1[lane] = hits.u[lane];
                            g.b2[lane] = hits.v[lane];
                            g.ng.set(lane, world.triangle_normals[prim as usize]);
                        }
                        Some(_) => {
                            let hit = Hit {
                                t: hits.t[lane],
                                prim,
                                u: hits.u[lane],
                                v: hits.v[lane],
                            };
                            let surf = world.surface(&cam.get(lane), &hit);
                            g.p.set(lane, surf.p);
                            g.p_error.set(lane, surf.p_error);
                            g.ng.set(lane, surf.ng);
                            g.given |= 1 << lane;
                        }
                    }
                }
            }
        }
        if self.direct && escaped != 0 {
            // The camera sees the environment (zero without one).
            let dirs = Soa3 {
                x: cam.dx,
                y: cam.dy,
                z: cam.dz,
            };
            self.view
                .add_env_radiance(self.isa, &dirs, None, escaped, &mut out.radiance);
        }
        if hit_mask == 0 {
            return;
        }
        let ShadingPacket {
            p,
            geo,
            bsdf,
            pixel: pixel_of,
            ..
        } = &mut out.packet;
        simd::run(
            self.isa,
            ShadingKernel {
                hits: g,
                cam,
                p,
                p_error,
                geo,
            },
        );
        let surface_of = |prim: usize| (world.prim_material[prim], world.prim_emitter[prim]);
        let shared_surface = shared.map(surface_of);
        for (lane, &pixel) in pixels.iter().enumerate() {
            if hit_mask & (1 << lane) == 0 {
                continue;
            }
            let (material, emitter) =
                shared_surface.unwrap_or_else(|| surface_of(hits.prim[lane] as usize));
            let p = p.get(lane);
            if self.direct && emitter.is_some() {
                let surf = SurfaceHit {
                    p,
                    p_error: p_error.get(lane),
                    ng: g.ng.get(lane),
                    material,
                    emitter,
                };
                out.radiance[lane] += self.view.emitted(&surf, cam.get(lane).dir);
            }
            bsdf[lane] = Some(&world.materials[material as usize]);
            pixel_of[lane] = pixel as u32;
        }
        out.packet.mask = hit_mask;
    }

    /// What the emission rays `mask` of `emit` see that can add radiance: the lanes whose
    /// closest hit is an emitter (`found`, their hits in `hits`) and, where the scene has an
    /// environment, the lanes that hit nothing (`escaped`, no hit in `hits`); other lanes of
    /// `hits` are not to be read. A ray whose closest hit is an emitter meets an emitter, so
    /// the emitters' own tracer first tells which rays meet one at all (an occlusion query of
    /// a tree of a few primitives); only those ask the scene for their closest hit. The others
    /// can only
    /// escape: with an environment the scene is asked whether anything lies on them (an
    /// occlusion query, which stops at its first hit), and without one they are done. The
    /// same answers as a closest-hit query of every lane, ties included, with any backend:
    /// every decision about an emitter is the scene's own closest hit.
    fn trace_emission(&self, emit: &RayPacket, mask: LaneMask, hits: &mut HitPacket) -> (u32, u32) {
        let scene = self.scene;
        let env = scene.lights.environment().is_some();
        let near = match &scene.emitters {
            Some(e) => e.tracer.occluded_packet(emit, mask) as u32,
            None => 0,
        };
        let (mut found, mut escaped) = (0u32, 0u32);
        if near != 0 {
            scene.tracer.intersect_packet(emit, near as LaneMask, hits);
        }
        for lane in 0..LANES {
            if near >> lane & 1 == 0 {
                hits.set(lane, None);
                continue;
            }
            match hits.get(lane) {
                Some(h) if scene.world.prim_emitter[h.prim as usize].is_some() => {
                    found |= 1 << lane
                }
                None if env => escaped |= 1 << lane,
                _ => {}
            }
        }
        let rest = if env { mask as u32 & !near } else { 0 };
        if rest != 0 {
            let blocked = scene.tracer.occluded_packet(emit, rest as LaneMask) as u32;
            escaped |= rest & !blocked;
        }
        (found, escaped)
    }

    /// The estimator's probes for the tile's points, traced as packets, added to the tile's
    /// radiance in place (a copy in and out was two `memcpy` calls per packet, 1.3 % of a
    /// cornell `light` pass: docs/tracer.md, stop 47).
    fn shading_phase(&self, tile: &mut CameraTile, scratch: &mut TileScratch) {
        let scene = self.scene;
        let CameraTile {
            radiance,
            packet,
            values,
        } = tile;
        let mut dims = PacketDims::new(&*values, 2, self.dims);
        let TileScratch {
            probes,
            emit_hits: ehits,
            ..
        } = scratch;
        probes.clear();
        self.estimator.sample_packet(&*packet, &mut dims, probes);
        // Only lanes with a point are traced, whatever an estimator left in the others.
        let shadow_mask = (probes.shadow_mask & packet.mask) as LaneMask;
        let emit_mask = (probes.emission_mask & packet.mask) as LaneMask;
        if shadow_mask != 0 {
            let blocked = scene.tracer.occluded_packet(&probes.shadow, shadow_mask);
            let mut clear = shadow_mask & !blocked;
            while clear != 0 {
                let lane = clear.trailing_zeros() as usize;
                clear &= clear - 1;
                radiance[lane] += probes.shadow_value.get(lane);
            }
        }
        if emit_mask != 0 {
            let emit = &probes.emission;
            let dirs = Soa3 {
                x: emit.dx,
                y: emit.dy,
                z: emit.dz,
            };
            // The environment's records of these directions, on their way while the rays
            // are traced (those that escape read them, from these texels).
            let texels = self.view.prefetch_env(self.isa, &dirs, emit_mask as u32);
            let (found, escaped) = self.trace_emission(emit, emit_mask, ehits);
            let mut env = [Vec3::ZERO; LANES];
            let mut env_weight = [0.0f32; LANES];
            if escaped != 0 {
                self.view
                    .add_env_radiance(self.isa, &dirs, texels.as_ref(), escaped, &mut env);
                env_weight = self
                    .estimator()
                    .env_weight_packet(&*packet, probes, &dirs, escaped);
            }
            // The emitting surfaces the rest found, weighted over lanes.
            let mut surfaces: [Option<SurfaceHit>; LANES] = [None; LANES];
            let mut le = [Vec3::ZERO; LANES];
            for lane in 0..LANES {
                if (found | escaped) >> lane & 1 == 0 {
                    continue;
                }
                let probe = probes
                    .emission_probe(lane)
                    .expect("an emission lane has a probe");
                match ehits.get(lane) {
                    Some(hit) => {
                        if let Some((surf, l)) = emitted_at(&self.view, &probe, &hit) {
                            surfaces[lane] = Some(surf);
                            le[lane] = l;
                        }
                    }
                    None => radiance[lane] += escape_weighted(&probe, env[lane], env_weight[lane]),
                }
            }
            if surfaces.iter().any(Option::is_some) {
                let w = self
                    .estimator()
                    .emission_weight_packet(&*packet, probes, &surfaces);
                for lane in 0..LANES {
                    if surfaces[lane].is_some() {
                        let weight = probes.emission_weight.get(lane);
                        radiance[lane] += weight * le[lane] * w[lane];
                    }
                }
            }
        }
    }
}

/// The most passes [`Renderer::add_passes`] renders together: a packet's lanes.
pub const MAX_GROUP: u64 = LANES as u64;

/// A group's predicted time at most: budgets and interrupts are looked at between groups.
const GROUP_SECONDS: f64 = 0.25;

/// The size of the next group of passes for [`Renderer::add_passes`]: at most
/// [`MAX_GROUP`] and `left` (at least 1), and, given the measured seconds `per_pass`, no more
/// than about a quarter of a second of passes, so that an interrupt or a budget is looked at
/// often. Without a measurement, one pass.
pub fn group_size(left: u64, per_pass: Option<f64>) -> u64 {
    let by_time = match per_pass {
        // A float-to-int cast saturates: a tiny pass time gives u64::MAX.
        Some(p) if p > 0.0 => (GROUP_SECONDS / p) as u64,
        _ => 1,
    };
    left.min(MAX_GROUP).min(by_time).max(1)
}

/// Which sample each lane of a camera packet takes: the pixel at place `slot` (4·dy + dx) of
/// the tile whose top left pixel is `origin`, in pass (sample index) `pass`, in the lanes of
/// `active`.
struct LaneSamples {
    origin: (u32, u32),
    places: &'static Places,
    pass: [u64; LANES],
    active: LaneMask,
}

impl LaneSamples {
    /// Lanes at `places` of tile `tile`, active where their pixel is in the image.
    fn new(layout: &TileLayout, tile: usize, places: &'static Places, pass: [u64; LANES]) -> Self {
        let origin = layout.tile_origin(tile);
        let inside =
            |dx: u32, dy: u32| origin.0 + dx < layout.width && origin.1 + dy < layout.height;
        let active = if inside(TILE - 1, TILE - 1) {
            LaneMask::MAX
        } else {
            (0..LANES)
                .filter(|&l| inside(places.dx[l], places.dy[l]))
                .fold(0, |m, l| m | 1 << l)
        };
        LaneSamples {
            origin,
            places,
            pass,
            active,
        }
    }
}

/// Each lane's place in its tile (`slot` = 4·dy + dx) and the place's offsets, as integers
/// and as floats: tables, so a packet's pixel rows are whole-row additions. (Split out of
/// `slot` lane by lane, they were 5 % of a sphere_light `light` pass.)
#[derive(Clone, Copy)]
struct Places {
    slot: [u8; LANES],
    dx: [u32; LANES],
    dy: [u32; LANES],
    fx: [f32; LANES],
    fy: [f32; LANES],
}

impl Places {
    const fn of(slot: [u8; LANES]) -> Places {
        let mut p = Places {
            slot,
            dx: [0; LANES],
            dy: [0; LANES],
            fx: [0.0; LANES],
            fy: [0.0; LANES],
        };
        let mut lane = 0;
        while lane < LANES {
            let s = slot[lane] as u32;
            p.dx[lane] = s % TILE;
            p.dy[lane] = s / TILE;
            p.fx[lane] = (s % TILE) as f32;
            p.fy[lane] = (s / TILE) as f32;
            lane += 1;
        }
        p
    }
}

/// A whole tile, lane = 4·dy + dx (the film's order within a tile).
static TILE_PLACES: Places = {
    let mut slot = [0u8; LANES];
    let mut lane = 0;
    while lane < LANES {
        slot[lane] = lane as u8;
        lane += 1;
    }
    Places::of(slot)
};

/// Tile `tile` of one pass: lane = 4·dy + dx, the film's order within a tile.
fn tile_lanes(layout: &TileLayout, tile: usize, pass: u64) -> LaneSamples {
    LaneSamples::new(layout, tile, &TILE_PLACES, [pass; LANES])
}

/// Lanes' places in the tile (4·dy + dx) for each group size c = 2^shift and packet `block`
/// of it: 16/c of the tile's pixels, each in c neighbouring lanes (lane = c·pixel + pass),
/// the pixels taken in Morton order, so a packet's pixels are a 4×4, 4×2, 2×2, 2×1 or 1×1
/// block. A table: computed lane by lane for every packet, they were 4 % of a sphere_light
/// pass.
const BLOCK_SLOTS: [[[u8; LANES]; LANES]; 5] = {
    let mut t = [[[0u8; LANES]; LANES]; 5];
    let mut shift = 0;
    while shift < 5 {
        let mut block = 0;
        while block < 1 << shift {
            let mut lane = 0;
            while lane < LANES {
                let m = block << (4 - shift) | lane >> shift;
                let (dx, dy) = (m & 1 | (m >> 1) & 2, (m >> 1) & 1 | (m >> 2) & 2);
                t[shift][block][lane] = (4 * dy + dx) as u8;
                lane += 1;
            }
            block += 1;
        }
        shift += 1;
    }
    t
};

/// [`BLOCK_SLOTS`] as [`Places`].
static BLOCK_PLACES: [[Places; LANES]; 5] = {
    const EMPTY: Places = Places::of([0; LANES]);
    let mut t = [[EMPTY; LANES]; 5];
    let mut shift = 0;
    while shift < 5 {
        let mut block = 0;
        while block < LANES {
            t[shift][block] = Places::of(BLOCK_SLOTS[shift][block]);
            block += 1;
        }
        shift += 1;
    }
    t
};

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

/// A tile's pixel coordinates and camera sample numbers, per lane.
struct PixelLanes {
    x: [f32; LANES],
    y: [f32; LANES],
    u: [[f32; LANES]; 2],
}

/// [`camera_ray`] over lanes, bit for bit.
struct CameraRays<'a> {
    camera: &'a Camera,
    w: u32,
    h: u32,
    px: &'a PixelLanes,
    out: &'a mut RayPacket,
}

impl simd::Kernel for CameraRays<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        type V<L> = <L as Lanes>::V;
        let c = self.camera;
        let (w, h) = (self.w as f32, self.h as f32);
        let aspect = V::<L>::splat(w / h);
        let tan = V::<L>::splat(c.tan_half_fov_y);
        let (one, two) = (V::<L>::splat(1.0), V::<L>::splat(2.0));
        let (x, y) = (V::<L>::load(&self.px.x), V::<L>::load(&self.px.y));
        let (u0, u1) = (V::<L>::load(&self.px.u[0]), V::<L>::load(&self.px.u[1]));
        let sx = two
            .mul(x.add(u0))
            .div(V::<L>::splat(w))
            .sub(one)
            .mul(aspect)
            .mul(tan);
        let sy = one.sub(two.mul(y.add(u1)).div(V::<L>::splat(h))).mul(tan);
        let d = V3::splat(c.forward) + V3::splat(c.right).scale(sx) + V3::splat(c.up).scale(sy);
        let d = d.scale(one.div(d.dot(d).sqrt()));
        let o = self.out;
        d.x.store(&mut o.dx);
        d.y.store(&mut o.dy);
        d.z.store(&mut o.dz);
        o.ox = [c.eye.x; LANES];
        o.oy = [c.eye.y; LANES];
        o.oz = [c.eye.z; LANES];
        o.tmax = [f32::INFINITY; LANES];
    }
}

/// What [`World::surface`] reads for a tile's hits, per lane: a triangle's vertices,
/// barycentrics and normal, or (lanes of `given`) a point already computed.
#[derive(Default)]
struct HitLanes {
    v: [Soa3; 3],
    b1: [f32; LANES],
    b2: [f32; LANES],
    ng: Soa3,
    p: Soa3,
    p_error: Soa3,
    given: u32,
}

/// [`World::surface`]'s point, error bound and normal for the lanes of `mask`, which hit
/// `sphere`, over lanes (bit for bit: [`Sphere::surface_lanes`]); marked as given.
///
/// [`World::surface`]: crate::prepare::World::surface
struct SphereHits<'a> {
    sphere: &'a Sphere,
    cam: &'a RayPacket,
    t: &'a [f32; LANES],
    mask: u32,
    g: &'a mut HitLanes,
}

impl simd::Kernel for SphereHits<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (cam, g, m) = (self.cam, self.g, self.mask);
        let [p, p_error, ng] = self.sphere.surface_lanes(
            cam.origin_lanes::<L::V>(),
            cam.dir_lanes(),
            L::V::load(self.t),
        );
        V3::select(m, p, V3::load(&g.p)).store(&mut g.p);
        V3::select(m, p_error, V3::load(&g.p_error)).store(&mut g.p_error);
        V3::select(m, ng, V3::load(&g.ng)).store(&mut g.ng);
        g.given |= m;
    }
}

/// Hit points, their error bounds and their shading geometry over lanes, written into the
/// tile's shading packet and the worker's scratch.
struct ShadingKernel<'a> {
    hits: &'a HitLanes,
    cam: &'a RayPacket,
    p: &'a mut Soa3,
    p_error: &'a mut Soa3,
    geo: &'a mut ShadingLanes,
}

impl simd::Kernel for ShadingKernel<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (g, cam) = (self.hits, self.cam);
        let v = [
            V3::<L::V>::load(&g.v[0]),
            V3::load(&g.v[1]),
            V3::load(&g.v[2]),
        ];
        let (tp, terr) = Triangle::point_lanes(v, L::V::load(&g.b1), L::V::load(&g.b2));
        let p = V3::select(g.given, V3::load(&g.p), tp);
        let p_error = V3::select(g.given, V3::load(&g.p_error), terr);
        ShadingLanes::compute(p, p_error, V3::load(&g.ng), cam.dir_lanes(), self.geo);
        p.store(self.p);
        p_error.store(self.p_error);
    }
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
    escape_weighted(probe, le, estimator.env_weight(sp, probe))
}

/// [`escape_contribution`] given the environment's radiance `le` along the probe's ray and
/// the estimator's weight `w` for it.
fn escape_weighted(probe: &EmissionProbe, le: Vec3, w: f32) -> Vec3 {
    if le == Vec3::ZERO {
        return Vec3::ZERO;
    }
    probe.weight * le * w
}

/// What an emission probe that hit `hit` adds: weight · Le · the estimator's MIS weight.
pub fn emission_contribution(
    view: &SceneView,
    estimator: &dyn Estimator,
    sp: &ShadingPoint,
    probe: &EmissionProbe,
    hit: &crate::geometry::Hit,
) -> Vec3 {
    match emitted_at(view, probe, hit) {
        Some((surf, le)) => probe.weight * le * estimator.emission_weight(sp, probe, &surf),
        None => Vec3::ZERO,
    }
}

/// The emitting surface an emission probe hit and the radiance Le it sends back along the
/// probe's ray; None where it sends none.
fn emitted_at(
    view: &SceneView,
    probe: &EmissionProbe,
    hit: &crate::geometry::Hit,
) -> Option<(SurfaceHit, Vec3)> {
    view.world.prim_emitter[hit.prim as usize]?;
    let surf = view.world.surface(&probe.ray, hit);
    let le = view.emitted(&surf, probe.ray.dir);
    (le != Vec3::ZERO).then_some((surf, le))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Scene;
    use crate::strategy::Integrand;

    impl<'a> Renderer<'a> {
        /// The camera phase lane by lane with the scalar functions: the reference the lane
        /// kernels are held to.
        fn camera_phase_lane_by_lane(
            &self,
            shape: &TileLayout,
            tile: usize,
            pass: u64,
            out: &mut CameraTile<'a>,
        ) {
            let scene = self.scene;
            let camera = &scene.scene.camera;
            let (w, h) = (shape.width, shape.height);
            out.radiance = [Vec3::ZERO; LANES];
            let mut points = [None; LANES];
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
            let keys = SampleKeys::of_render(
                self.seed,
                self.strategy_id,
                pixels.map(u64::from),
                [pass; LANES],
            );
            self.generator
                .fill_lanes(&self.setup, &keys, active, self.dims, &mut out.values);
            for (lane, &(x, y)) in coords.iter().enumerate() {
                if active & (1 << lane) != 0 {
                    let v = &out.values;
                    cam.set(
                        lane,
                        &camera_ray(camera, w, h, x, y, [v[0][lane], v[1][lane]]),
                    );
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
                points[lane] = Some(sp);
            }
            out.packet = ShadingPacket::from_points(&points);
        }
    }

    /// The emission rays' answer, with the emitters' own tracer in front, is the scene's
    /// closest hit, bit for bit: a lane is `found` exactly where its closest hit is an
    /// emitter, with that hit, and `escaped` exactly where it hits nothing and the scene has
    /// an environment. Camera rays (which see lights directly) and
    /// rays from surface points in random directions, with emitting quads, a sphere, a mesh
    /// and an environment beside an emitter.
    #[test]
    fn emission_rays_find_what_the_closest_hit_finds() {
        let mut scenes: Vec<(String, PreparedScene)> = ["cornell", "sphere_light", "mesh_light"]
            .iter()
            .map(|&n| {
                let s = Scene::load(&Scene::resolve(n).unwrap()).unwrap();
                (n.to_string(), PreparedScene::new(s))
            })
            .collect();
        let path = Scene::resolve("sphere_light").unwrap();
        let text = std::fs::read_to_string(&path).unwrap()
            + "\n[environment]\nconstant = [0.2, 0.3, 0.4]\n";
        let lit = PreparedScene::new(Scene::parse(&text, &path).unwrap());
        scenes.push(("sphere_light + environment".into(), lit));
        let (mut found_total, mut escaped_total) = (0, 0);
        for (name, scene) in &scenes {
            let env = scene.lights.environment().is_some();
            let strategy = crate::strategy::reference_strategy(scene, Integrand::DIRECT).unwrap();
            let r = Renderer::new(scene, strategy.as_ref(), 3).unwrap();
            // One scratch for every packet, as a worker reuses it.
            let mut hits = HitPacket::default();
            for set in crate::harness::raysets::generate(scene, 48, 48, 5) {
                if !matches!(set.class, "primary" | "incoherent") {
                    continue;
                }
                for (p, &m) in set.packets.iter().zip(&set.masks) {
                    let (found, escaped) = r.trace_emission(p, m, &mut hits);
                    for lane in 0..LANES {
                        if m >> lane & 1 == 0 {
                            continue;
                        }
                        let closest = scene.tracer.intersect(&p.get(lane));
                        let emits = closest
                            .is_some_and(|h| scene.world.prim_emitter[h.prim as usize].is_some());
                        assert_eq!(found >> lane & 1 != 0, emits, "{name} lane {lane}");
                        assert_eq!(
                            escaped >> lane & 1 != 0,
                            env && closest.is_none(),
                            "{name} lane {lane}"
                        );
                        if emits || escaped >> lane & 1 != 0 {
                            assert_eq!(hits.get(lane), closest, "{name} lane {lane}");
                        }
                    }
                    found_total += found.count_ones();
                    escaped_total += escaped.count_ones();
                }
            }
        }
        assert!(
            found_total > 100 && escaped_total > 100,
            "{found_total} {escaped_total}"
        );
    }

    /// Every tile's camera phase over lanes equals the lane-by-lane one bit for bit (points,
    /// frames, offset origins, what the camera sees directly, and the packet's lanes of the
    /// points: what estimators written over lanes read), on every ISA, in scenes with
    /// triangles, spheres, emitters seen by the camera and an environment, with partial tiles.
    #[test]
    fn camera_phase_matches_lane_by_lane() {
        let mut points = 0;
        for name in ["cornell", "sphere_light", "mesh_light", "env_venice_bunny"] {
            let mut scene = Scene::load(&Scene::resolve(name).unwrap()).unwrap();
            // A size that is not a multiple of the tile, so edge tiles have empty lanes.
            (scene.width, scene.height) = (30, 22);
            let scene = PreparedScene::new(scene);
            let strategy = crate::strategy::reference_strategy(&scene, Integrand::DIRECT).unwrap();
            let mut r = Renderer::new(&scene, strategy.as_ref(), 3).unwrap();
            let layout = TileLayout::new(30, 22);
            // One scratch and one tile for every tile, ISA and pass, as a worker reuses them.
            let mut scratch = TileScratch::default();
            let mut got = CameraTile::new();
            for isa in Isa::available() {
                r.isa = isa;
                for pass in [0, 7] {
                    for t in 0..layout.tile_count() {
                        let mut want = CameraTile::new();
                        r.camera_phase(
                            &layout,
                            &tile_lanes(&layout, t, pass),
                            &mut got,
                            &mut scratch,
                        );
                        r.camera_phase_lane_by_lane(&layout, t, pass, &mut want);
                        let text = |c: &CameraTile| {
                            let k = &c.packet;
                            let g = &k.geo;
                            let lanes: Vec<_> = (0..LANES)
                                .filter(|l| k.mask >> l & 1 != 0)
                                .map(|l| {
                                    let f = [&k.p, &g.n, &g.s, &g.t, &g.wo, &g.wo_local, &g.origin];
                                    f.map(|v| v.get(l))
                                })
                                .collect();
                            let points: Vec<_> = (0..LANES).map(|l| k.point(l)).collect();
                            format!("{:?} {points:?} {:b} {lanes:?}", c.radiance, k.mask)
                        };
                        assert_eq!(text(&got), text(&want), "{name} {isa:?} tile {t}");
                        points += want.packet.points().count();
                    }
                }
            }
        }
        assert!(points > 5000, "{points}");
    }
}

#[cfg(test)]
mod group_tests {
    use super::*;
    use crate::scene::Scene;
    use std::sync::{Arc, Mutex};

    /// The film's bits: every pixel's sum and M2, and the pass count.
    fn bits(film: &Film) -> (Vec<[u64; 3]>, Vec<[u64; 3]>, u64) {
        let b = |v: &Vec<[f64; 3]>| v.iter().map(|p| p.map(f64::to_bits)).collect();
        (b(&film.sum), b(&film.m2), film.spp)
    }

    /// One pass the plain way, written out independently of the groups: each tile's 16
    /// pixels in one packet in the film's lane order, then the film's update of the tile.
    fn pass_tile_by_tile(r: &Renderer, film: &mut Film, stream: u64) {
        let layout = film.layout;
        let update = Accumulation::of_count(film.spp);
        let (mut tile, mut scratch) = (CameraTile::new(), TileScratch::default());
        for (t, (sum, m2)) in film
            .sum
            .chunks_mut(16)
            .zip(film.m2.chunks_mut(16))
            .enumerate()
        {
            r.camera_phase(
                &layout,
                &tile_lanes(&layout, t, stream),
                &mut tile,
                &mut scratch,
            );
            r.shading_phase(&mut tile, &mut scratch);
            update.add_tile(r.isa, sum, m2, &tile.radiance);
        }
        film.spp += 1;
    }

    /// Passes rendered in groups make the film that passes one by one, tile by tile make, bit
    /// for bit: for groups of every size up to 16 (13 = 8 + 4 + 1; `add_pass` is a group of
    /// one), for a shard's strided passes, in scenes with quads, a sphere, a mesh light and an
    /// environment, at a size with partial tiles, for light, BSDF and MIS estimators (emission
    /// rays included). Control: a group's passes in reverse order make a different film, so
    /// the test sees which lane's sample went to which pass.
    #[test]
    fn grouped_passes_equal_passes_one_by_one() {
        let cases = [
            ("cornell", "light"),
            ("cornell", "mis-power"),
            ("sphere_light", "mis-power"),
            ("mesh_light", "cosine"),
            ("ggx_gold_bunny", "mis-power"),
            ("env_venice_bunny", "mis-env-latlong-cdf"),
        ];
        for (name, strategy) in cases {
            let mut scene = Scene::load(&Scene::resolve(name).unwrap()).unwrap();
            (scene.width, scene.height) = (30, 22);
            let scene = PreparedScene::new(scene);
            let strategy = crate::strategy::by_name(strategy).unwrap();
            let mut r = Renderer::new(&scene, strategy.as_ref(), 11).unwrap();
            // Passes 0..16 as 16, 16..29 as 13, 29..31 as 2, 31..32 as 1, 32..48 as 16.
            let mut want = Film::new(30, 22);
            for pass in 0..48 {
                pass_tile_by_tile(&r, &mut want, pass);
            }
            let mut got = Film::new(30, 22);
            for count in [16, 13, 2, 1, 16] {
                r.add_passes(&mut got, count);
            }
            let mut single = Film::new(30, 22);
            for _ in 0..48 {
                r.add_pass(&mut single);
            }
            assert!(
                bits(&single) == bits(&want),
                "{name} {} add_pass",
                strategy.name()
            );
            assert!(bits(&got) == bits(&want), "{name} {}", strategy.name());
            // A shard's passes 3, 8, 13, …: five at a time against one at a time.
            let streams: Vec<u64> = (0..10).map(|i| 3 + 5 * i).collect();
            let (mut one, mut five) = (Film::new(30, 22), Film::new(30, 22));
            for &s in &streams {
                pass_tile_by_tile(&r, &mut one, s);
            }
            r.add_passes_with_streams(&mut five, &streams[..5]);
            r.add_passes_with_streams(&mut five, &streams[5..]);
            assert!(
                bits(&five) == bits(&one),
                "{name} {} shard",
                strategy.name()
            );
            // Control: a group's passes in reverse order (each pass's sample in another
            // lane's place in the pixel's running sum) make a different film.
            let reversed: Vec<u64> = (0..16).rev().collect();
            let mut control = Film::new(30, 22);
            r.add_passes_with_streams(&mut control, &reversed);
            assert!(bits(&control) != got_16(&mut r), "{name} control");
        }
    }

    /// Passes 0..16 as one group.
    fn got_16(r: &mut Renderer) -> (Vec<[u64; 3]>, Vec<[u64; 3]>, u64) {
        let mut film = Film::new(30, 22);
        r.add_passes(&mut film, 16);
        bits(&film)
    }

    /// A strategy whose estimator is another's, made image-space: it asks for every pass's
    /// points first and records, per pass, how many it got and whether each sits at its own
    /// pixel.
    struct PassPointsOf(Box<dyn Strategy>, Arc<Mutex<Vec<(usize, bool)>>>);

    struct PassPointsEstimator<'s> {
        inner: Box<dyn Estimator + 's>,
        seen: Arc<Mutex<Vec<(usize, bool)>>>,
    }

    impl Strategy for PassPointsOf {
        /// The inner strategy's name: it keys the random streams, so the samples are the same.
        fn name(&self) -> String {
            self.0.name()
        }
        fn describe(&self) -> String {
            self.0.describe()
        }
        fn integrand(&self) -> crate::strategy::Integrand {
            self.0.integrand()
        }
        fn bind<'s>(
            &self,
            scene: SceneView<'s>,
        ) -> std::result::Result<Box<dyn Estimator + 's>, String> {
            Ok(Box::new(PassPointsEstimator {
                inner: self.0.bind(scene)?,
                seen: self.1.clone(),
            }))
        }
    }

    impl Estimator for PassPointsEstimator<'_> {
        fn layout(&self) -> crate::sampling::Layout {
            self.inner.layout()
        }
        fn sample(
            &self,
            sp: &ShadingPoint,
            u: &mut crate::sampling::Dims,
        ) -> crate::strategy::Probes {
            self.inner.sample(sp, u)
        }
        fn emission_weight(
            &self,
            sp: &ShadingPoint,
            probe: &EmissionProbe,
            hit: &SurfaceHit,
        ) -> f32 {
            self.inner.emission_weight(sp, probe, hit)
        }
        fn env_weight(&self, sp: &ShadingPoint, probe: &EmissionProbe) -> f32 {
            self.inner.env_weight(sp, probe)
        }
        fn wants_pass_points(&self) -> bool {
            true
        }
        fn begin_pass(&mut self, pass: &PassPoints) {
            let mut count = 0;
            let mut placed = pass.points.len() == (pass.width * pass.height) as usize;
            for (i, p) in pass.points.iter().enumerate() {
                if let Some(p) = p {
                    count += 1;
                    placed &= p.pixel as usize == i;
                }
            }
            self.seen.lock().unwrap().push((count, placed));
        }
    }

    /// An image-space estimator gets every pass's points, each at its own pixel, before it
    /// shades them, also when passes are asked for in groups, and makes the film that the
    /// same estimator shading point by point makes (the lane-by-lane default of
    /// `sample_packet` against the packet path). By hand: groups that skip the image-space
    /// path (no `begin_pass`), and points stored at transposed pixels, both fail it.
    #[test]
    fn an_image_space_estimator_gets_each_pass_and_the_same_film() {
        for (name, strategy) in [
            ("cornell", "mis-power"),
            ("env_venice_bunny", "mis-env-latlong-cdf"),
        ] {
            let mut scene = Scene::load(&Scene::resolve(name).unwrap()).unwrap();
            (scene.width, scene.height) = (30, 22);
            let scene = PreparedScene::new(scene);
            let seen = Arc::new(Mutex::new(Vec::new()));
            let wrapped = PassPointsOf(crate::strategy::by_name(strategy).unwrap(), seen.clone());
            let mut image_space = Renderer::new(&scene, &wrapped, 5).unwrap();
            let plain = Renderer::new(&scene, wrapped.0.as_ref(), 5).unwrap();
            let (mut got, mut want) = (Film::new(30, 22), Film::new(30, 22));
            for count in [5, 16, 1] {
                image_space.add_passes(&mut got, count);
            }
            for pass in 0..22 {
                pass_tile_by_tile(&plain, &mut want, pass);
            }
            assert!(bits(&got) == bits(&want), "{name}");
            let seen = seen.lock().unwrap();
            assert_eq!(seen.len(), 22, "{name}: one begin_pass per pass");
            assert!(
                seen.iter().all(|&(n, placed)| n > 300 && placed),
                "{name}: {seen:?}"
            );
        }
    }

    /// Group sizes stay within a packet, the passes left and about a quarter second, and are
    /// one pass until a pass has been timed.
    #[test]
    fn group_sizes_are_bounded() {
        assert_eq!(group_size(100, None), 1);
        assert_eq!(group_size(100, Some(0.001)), MAX_GROUP);
        assert_eq!(group_size(5, Some(0.001)), 5);
        assert_eq!(group_size(0, Some(0.001)), 1);
        assert_eq!(group_size(100, Some(0.05)), 5);
        assert_eq!(group_size(100, Some(10.0)), 1);
        assert_eq!(group_size(100, Some(0.0)), 1);
        assert_eq!(group_size(100, Some(f64::MIN_POSITIVE)), MAX_GROUP);
    }
}
