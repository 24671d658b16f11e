//! Direct-illumination strategies. A [`Strategy`] is a value composed of parts — an estimator
//! (direction, light or MIS sampling, ambient occlusion), the light-sampling methods it
//! overrides, the environment sampler it pins, the light selector, the lobe-selection policy —
//! and its name is derived from those parts. Bound to a scene ([`Strategy::bind`]) it becomes
//! an [`Estimator`], with everything that depends on the scene resolved once: the usable
//! light methods, the selector, the environment representation of its integrand.
//!
//! An estimator turns a shading point into at most one shadow probe and one emission probe;
//! the renderer traces the probes as packets. A strategy never sees the tracer.

pub mod ambient_occlusion;
pub mod direction;
pub mod estimate;
pub mod light_sampling;
pub mod mis;

use crate::bsdf::{Bsdf, LocalBsdf};
use crate::env::{EnvMethod, EnvSampler, Repr};
use crate::geometry::Ray;
use crate::lights::{LaneRecords, LaneSamples, LightCtx};
use crate::math::{Frame, offset_ray_origin, offset_ray_origin_lanes};
use crate::prepare::{PreparedScene, SceneView, SurfaceHit};
use crate::sampling::{Dims, Layout, PacketDims};
use crate::simd::{Soa3, V3, Vector, WIDTH};
use crate::tracer::{LANES, RayPacket};
use glam::Vec3;

/// A surface point about to be shaded, with the normal flipped to the viewer's side (surfaces
/// are two-sided reflectors) and the origin already offset for rays leaving on that side.
#[derive(Clone, Copy, Debug)]
pub struct ShadingPoint<'a> {
    pub p: Vec3,
    pub origin: Vec3,
    pub n: Vec3,
    /// Unit direction towards the viewer (world space).
    pub wo: Vec3,
    /// The material in the shading frame about `n`.
    pub bsdf: LocalBsdf<'a>,
    /// Scan-line index of the pixel this point was seen through; `u32::MAX` for a point not
    /// seen through the camera (a closed-form check's).
    pub pixel: u32,
}

impl<'a> ShadingPoint<'a> {
    /// An exact point (no error to step over: rays start at `p` itself) seen along
    /// `view_dir` (unit, pointing at the surface): a point given by a test or stress case.
    pub fn new(p: Vec3, ng: Vec3, view_dir: Vec3, bsdf: &'a Bsdf) -> Self {
        Self::with_error(p, Vec3::ZERO, ng, view_dir, bsdf)
    }

    /// A computed surface point whose coordinates are known to within `p_error` per axis.
    pub fn with_error(p: Vec3, p_error: Vec3, ng: Vec3, view_dir: Vec3, bsdf: &'a Bsdf) -> Self {
        let n = if ng.dot(view_dir) < 0.0 { ng } else { -ng };
        let frame = Frame::from_normal(n);
        let wo = -view_dir;
        ShadingPoint {
            p,
            origin: offset_ray_origin(p, p_error, n),
            n,
            wo,
            bsdf: LocalBsdf {
                frame,
                wo: frame.to_local(wo),
                bsdf,
            },
            pixel: u32::MAX,
        }
    }

    /// A shading point of lane `lane` of [`ShadingLanes`] (as [`Self::with_error`] makes it).
    pub fn from_lanes(g: &ShadingLanes, lane: usize, p: Vec3, bsdf: &'a Bsdf) -> Self {
        let n = g.n.get(lane);
        ShadingPoint {
            p,
            origin: g.origin.get(lane),
            n,
            wo: g.wo.get(lane),
            bsdf: LocalBsdf {
                frame: Frame {
                    s: g.s.get(lane),
                    t: g.t.get(lane),
                    n,
                },
                wo: g.wo_local.get(lane),
                bsdf,
            },
            pixel: u32::MAX,
        }
    }

    /// What a light sampler or selector is told about this point.
    pub fn light_ctx(&self) -> LightCtx {
        LightCtx {
            p: self.p,
            n: self.n,
        }
    }
}

/// The geometry [`ShadingPoint::with_error`] derives, for 16 lanes: the normal flipped to the
/// viewer, its frame, the direction to the viewer (world and local) and the offset origin.
#[derive(Clone, Copy, Debug, Default)]
pub struct ShadingLanes {
    pub n: Soa3,
    pub s: Soa3,
    pub t: Soa3,
    pub wo: Soa3,
    pub wo_local: Soa3,
    pub origin: Soa3,
}

impl ShadingLanes {
    /// [`ShadingPoint::with_error`] over lanes, bit for bit, written into `g` (every field,
    /// every lane).
    #[inline(always)]
    pub fn compute<V: Vector<WIDTH>>(
        p: V3<V>,
        p_error: V3<V>,
        ng: V3<V>,
        view_dir: V3<V>,
        g: &mut ShadingLanes,
    ) {
        let n = V3::select(ng.dot(view_dir).lt(V::splat(0.0)), ng, -ng);
        let (s, t) = Frame::from_normal_lanes(n);
        let wo = -view_dir;
        let wo_local = V3 {
            x: wo.dot(s),
            y: wo.dot(t),
            z: wo.dot(n),
        };
        n.store(&mut g.n);
        s.store(&mut g.s);
        t.store(&mut g.t);
        wo.store(&mut g.wo);
        wo_local.store(&mut g.wo_local);
        offset_ray_origin_lanes(p, p_error, n).store(&mut g.origin);
    }
}

/// A packet of up to 16 shading points, in lanes: parts written over lanes read the rows
/// (`p`, `geo`) and move no point in or out of a struct; a part that shades lane by lane asks
/// for a lane's [`ShadingPoint`] ([`Self::point`]), built from the lanes when it is asked for.
/// Only the lanes of `mask` hold a point; the others hold finite values that nothing reads.
#[derive(Clone, Debug)]
pub struct ShadingPacket<'a> {
    /// The points' positions (`ShadingPoint::p`).
    pub p: Soa3,
    pub geo: ShadingLanes,
    /// Each point's material (Some in every lane of `mask`).
    pub bsdf: [Option<&'a Bsdf>; LANES],
    /// Each point's pixel (`ShadingPoint::pixel`).
    pub pixel: [u32; LANES],
    /// The lanes that hold a point.
    pub mask: u32,
}

impl Default for ShadingPacket<'_> {
    fn default() -> Self {
        ShadingPacket {
            p: Soa3::default(),
            geo: ShadingLanes::default(),
            bsdf: [None; LANES],
            pixel: [u32::MAX; LANES],
            mask: 0,
        }
    }
}

impl<'a> ShadingPacket<'a> {
    /// The packet of `points` (a test's or a closed-form check's packet; the renderer
    /// computes the lanes directly).
    pub fn from_points(points: &[Option<ShadingPoint<'a>>; LANES]) -> Self {
        let mut packet = ShadingPacket::default();
        for (lane, sp) in points.iter().enumerate() {
            let Some(sp) = sp else { continue };
            packet.mask |= 1 << lane;
            packet.p.set(lane, sp.p);
            packet.bsdf[lane] = Some(sp.bsdf.bsdf);
            packet.pixel[lane] = sp.pixel;
            let g = &mut packet.geo;
            g.n.set(lane, sp.n);
            g.s.set(lane, sp.bsdf.frame.s);
            g.t.set(lane, sp.bsdf.frame.t);
            g.wo.set(lane, sp.wo);
            g.wo_local.set(lane, sp.bsdf.wo);
            g.origin.set(lane, sp.origin);
        }
        packet
    }

    /// Lane `lane`'s point; None outside `mask`.
    #[inline(always)]
    pub fn point(&self, lane: usize) -> Option<ShadingPoint<'a>> {
        if self.mask >> lane & 1 == 0 {
            return None;
        }
        let bsdf = self.bsdf[lane].expect("a material in every lane with a point");
        let mut sp = ShadingPoint::from_lanes(&self.geo, lane, self.p.get(lane), bsdf);
        sp.pixel = self.pixel[lane];
        Some(sp)
    }

    /// The points of the lanes of `mask`, with their lanes, in lane order.
    #[inline(always)]
    pub fn points(&self) -> impl Iterator<Item = (usize, ShadingPoint<'a>)> + '_ {
        (0..LANES).filter_map(|lane| Some((lane, self.point(lane)?)))
    }

    /// What a light sampler or selector is told about lane `lane`'s point.
    #[inline(always)]
    pub fn light_ctx(&self, lane: usize) -> LightCtx {
        LightCtx {
            p: self.p.get(lane),
            n: self.geo.n.get(lane),
        }
    }

    /// Calls `each(material, lanes)` once for each material among the lanes of `mask`, with
    /// the lanes that hold it (a pixel's samples mostly share one).
    #[inline(always)]
    pub fn each_material(&self, mask: u32, mut each: impl FnMut(&'a Bsdf, u32)) {
        let mut rest = mask & self.mask;
        while rest != 0 {
            let Some(bsdf) = self.bsdf[rest.trailing_zeros() as usize] else {
                rest &= rest - 1;
                continue;
            };
            let mut same = 0u32;
            let mut m = rest;
            while m != 0 {
                let lane = m.trailing_zeros() as usize;
                m &= m - 1;
                if self.bsdf[lane].is_some_and(|b| std::ptr::eq(b, bsdf)) {
                    same |= 1 << lane;
                }
            }
            each(bsdf, same);
            rest &= !same;
        }
    }

    /// Lane `lane`'s material in its shading frame (what evaluating f needs, without the
    /// rest of the point).
    #[inline(always)]
    pub fn local_bsdf(&self, lane: usize) -> Option<LocalBsdf<'a>> {
        if self.mask >> lane & 1 == 0 {
            return None;
        }
        let g = &self.geo;
        Some(LocalBsdf {
            frame: Frame {
                s: g.s.get(lane),
                t: g.t.get(lane),
                n: g.n.get(lane),
            },
            wo: g.wo_local.get(lane),
            bsdf: self.bsdf[lane].expect("a material in every lane with a point"),
        })
    }
}

/// What one sample asks the tracer. The contribution is `shadow.value` if the shadow segment
/// is clear, plus `emission.weight · Le · w` for the emitter the emission ray hits first, with
/// w the estimator's [`Estimator::emission_weight`] (or [`Estimator::env_weight`] if it
/// escapes).
#[derive(Clone, Copy, Debug, Default)]
pub struct Probes {
    pub shadow: Option<ShadowProbe>,
    pub emission: Option<EmissionProbe>,
}

impl Probes {
    /// A sample that asks only whether a shadow segment is clear.
    pub fn shadow(probe: ShadowProbe) -> Self {
        Probes {
            shadow: Some(probe),
            emission: None,
        }
    }
}

/// A packet's [`Probes`], in lanes: the shadow segments and emission rays as the packets the
/// renderer traces, with what each adds. Lane i of `shadow` (bit i of `shadow_mask`) and of
/// `emission` (bit i of `emission_mask`) is lane i's probe; other lanes hold finite values
/// that nothing reads. An estimator written over lanes fills the rows; [`Self::set`] stores a
/// lane's `Probes`.
#[derive(Clone, Debug, Default)]
pub struct ProbePacket {
    pub shadow: RayPacket,
    pub shadow_value: Soa3,
    pub shadow_mask: u32,
    pub emission: RayPacket,
    pub emission_weight: Soa3,
    pub emission_pdf: [f32; LANES],
    pub emission_mask: u32,
    /// Scratch for the light samples an estimator draws on the way to its rows, kept with the
    /// packet so that it is not zeroed per packet (a `memset` of 1 KB, 2.1 % of a cornell
    /// `light` pass; docs/tracer.md, stop 47). Only the lanes of its `valid` mask are this
    /// packet's: every sampler writes each field of the lanes it draws for, and the light
    /// estimators' `shadow_rays` clears `valid` first.
    pub light_samples: LaneSamples,
    /// Scratch for the lights' lane records ([`crate::lights::LaneKernel`]), likewise kept
    /// (zeroing it was a 1 KB `memset` per packet, 0.75 % of a mesh_light MIS pass): only the
    /// lanes a kernel samples are read for their result, and those are written first.
    pub light_records: LaneRecords,
}

impl ProbePacket {
    /// Lane `lane`'s probes become `p`.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, p: Probes) {
        let bit = 1 << lane;
        match p.shadow {
            Some(s) => {
                self.shadow.set(lane, &s.ray);
                self.shadow_value.set(lane, s.value);
                self.shadow_mask |= bit;
            }
            None => self.shadow_mask &= !bit,
        }
        self.set_emission(lane, p.emission);
    }

    /// Lane `lane`'s emission probe becomes `e` (its shadow probe stays).
    #[inline(always)]
    pub fn set_emission(&mut self, lane: usize, e: Option<EmissionProbe>) {
        let bit = 1 << lane;
        match e {
            Some(e) => {
                self.emission.set(lane, &e.ray);
                self.emission_weight.set(lane, e.weight);
                self.emission_pdf[lane] = e.pdf;
                self.emission_mask |= bit;
            }
            None => self.emission_mask &= !bit,
        }
    }

    /// Lane `lane`'s probes.
    #[inline(always)]
    pub fn get(&self, lane: usize) -> Probes {
        Probes {
            shadow: self.shadow_probe(lane),
            emission: self.emission_probe(lane),
        }
    }

    #[inline(always)]
    pub fn shadow_probe(&self, lane: usize) -> Option<ShadowProbe> {
        (self.shadow_mask >> lane & 1 != 0).then(|| ShadowProbe {
            ray: self.shadow.get(lane),
            value: self.shadow_value.get(lane),
        })
    }

    #[inline(always)]
    pub fn emission_probe(&self, lane: usize) -> Option<EmissionProbe> {
        (self.emission_mask >> lane & 1 != 0).then(|| EmissionProbe {
            ray: self.emission.get(lane),
            weight: self.emission_weight.get(lane),
            pdf: self.emission_pdf[lane],
        })
    }

    /// No lane has a probe.
    #[inline(always)]
    pub fn clear(&mut self) {
        self.shadow_mask = 0;
        self.emission_mask = 0;
    }
}

#[derive(Clone, Copy, Debug)]
pub struct ShadowProbe {
    pub ray: Ray,
    pub value: Vec3,
}

#[derive(Clone, Copy, Debug)]
pub struct EmissionProbe {
    pub ray: Ray,
    pub weight: Vec3,
    /// Solid-angle pdf the direction was sampled with (for MIS).
    pub pdf: f32,
}

/// The quantity a strategy estimates: each has its own reference image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Integrand {
    /// Emission seen by the camera plus reflected direct illumination, with the environment
    /// (if any) in this representation: resampling makes each a slightly different radiance
    /// function, so each has its own reference.
    Direct(Repr),
    /// (1/π)∫ V(ω) cos θ dω with occluders within the scene's AO distance.
    AmbientOcclusion,
}

impl Integrand {
    /// Direct illumination with the environment in its source (lat/long) representation.
    pub const DIRECT: Integrand = Integrand::Direct(Repr::LatLong);

    /// Every integrand, in listing order.
    pub const ALL: [Integrand; 5] = [
        Integrand::Direct(Repr::LatLong),
        Integrand::Direct(Repr::Cube),
        Integrand::Direct(Repr::Octahedral),
        Integrand::Direct(Repr::Healpix),
        Integrand::AmbientOcclusion,
    ];

    pub fn name(&self) -> &'static str {
        match self {
            Integrand::Direct(Repr::LatLong) => "direct",
            Integrand::Direct(Repr::Cube) => "direct-cube",
            Integrand::Direct(Repr::Octahedral) => "direct-octa",
            Integrand::Direct(Repr::Healpix) => "direct-healpix",
            Integrand::AmbientOcclusion => "ao",
        }
    }

    /// Emission seen by the camera counts (every integrand but AO).
    pub fn is_direct(&self) -> bool {
        matches!(self, Integrand::Direct(_))
    }

    /// The representation this integrand looks the environment up in.
    pub fn env_repr(&self) -> Repr {
        match self {
            Integrand::Direct(r) => *r,
            Integrand::AmbientOcclusion => Repr::LatLong,
        }
    }
}

/// A strategy as listed, named and compared. See the module documentation.
pub trait Strategy: Send + Sync {
    /// The name results are reported under, derived from the strategy's parts; it also keys
    /// the random streams, so two strategies never share samples.
    fn name(&self) -> String;

    /// One-line description for listings.
    fn describe(&self) -> String;

    fn integrand(&self) -> Integrand {
        Integrand::DIRECT
    }

    /// The estimator for `scene` (the view of this strategy's integrand), or why the strategy
    /// does not apply: it would be biased there, or identical to another strategy.
    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String>;
}

/// A strategy bound to a scene.
pub trait Estimator: Send + Sync {
    /// Which sample dimension feeds what, in the order [`Self::sample`] reads them (after the
    /// camera's two). A sample generator may stratify the pairs it names.
    fn layout(&self) -> Layout;

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes;

    /// The probes of a packet of shading points, written into `out` (cleared by the caller:
    /// the lanes without a point get none), reading each lane's dimensions from `u` and
    /// leaving `u` past the most any lane read. The default shades lane by lane through
    /// [`Self::sample`]; an estimator written over lanes overrides it, reading whole rows of
    /// `u` ([`PacketDims::take`]) and the points' lanes ([`ShadingPacket::geo`]) and writing
    /// the probes' rows.
    fn sample_packet(&self, packet: &ShadingPacket, u: &mut PacketDims, out: &mut ProbePacket) {
        let mut used = 0;
        for (lane, sp) in packet.points() {
            let mut d = u.lane(lane);
            out.set(lane, self.sample(&sp, &mut d));
            used = used.max(d.used());
        }
        u.skip(used);
    }

    /// Weight of the emission an emission probe found at `hit` (MIS overrides).
    fn emission_weight(
        &self,
        _sp: &ShadingPoint,
        _probe: &EmissionProbe,
        _hit: &SurfaceHit,
    ) -> f32 {
        1.0
    }

    /// [`Self::emission_weight`] of the emission probes of the lanes that have a hit in
    /// `hits` (the renderer's emitting surfaces; the other lanes are not read and weigh 1),
    /// lane by lane unless overridden.
    fn emission_weight_packet(
        &self,
        packet: &ShadingPacket,
        probes: &ProbePacket,
        hits: &[Option<SurfaceHit>; LANES],
    ) -> [f32; LANES] {
        let mut out = [1.0f32; LANES];
        for (lane, o) in out.iter_mut().enumerate() {
            if let Some(hit) = &hits[lane]
                && let Some(probe) = probes.emission_probe(lane)
                && let Some(sp) = packet.point(lane)
            {
                *o = self.emission_weight(&sp, &probe, hit);
            }
        }
        out
    }

    /// Weight of environment radiance found by an emission probe that escaped (MIS overrides).
    fn env_weight(&self, _sp: &ShadingPoint, _probe: &EmissionProbe) -> f32 {
        1.0
    }

    /// [`Self::env_weight`] of the emission probes of lanes `mask`, whose rays' directions are
    /// `dirs` (the renderer's packet of escaped rays), lane by lane unless overridden; lanes
    /// outside `mask` are not read.
    fn env_weight_packet(
        &self,
        packet: &ShadingPacket,
        probes: &ProbePacket,
        _dirs: &Soa3,
        mask: u32,
    ) -> [f32; LANES] {
        let mut out = [1.0f32; LANES];
        for (lane, o) in out.iter_mut().enumerate() {
            if mask >> lane & 1 != 0
                && let (Some(sp), Some(probe)) = (packet.point(lane), probes.emission_probe(lane))
            {
                *o = self.env_weight(&sp, &probe);
            }
        }
        out
    }

    /// An image-space estimator (spatial resampling, say) needs every pixel's shading point
    /// of a pass before it shades any: the renderer then traces the whole pass's camera rays
    /// first and calls [`Self::begin_pass`] with them. Per-point estimators leave this false.
    fn wants_pass_points(&self) -> bool {
        false
    }

    /// Every pixel's shading point of the coming pass, in scan-line order (None where the
    /// camera ray missed); called only when [`Self::wants_pass_points`] is true.
    fn begin_pass(&mut self, _pass: &PassPoints) {}
}

/// A pass's shading points, one per pixel in scan-line order.
pub struct PassPoints<'a> {
    pub width: u32,
    pub height: u32,
    pub points: Vec<Option<ShadingPoint<'a>>>,
}

/// A strategy left out of a run, and why.
#[derive(Clone, Debug, serde::Serialize)]
pub struct Skipped {
    pub name: String,
    pub reason: String,
}

/// The environment (representation, sampler) pairs, in listing order.
pub fn env_methods() -> impl Iterator<Item = EnvMethod> {
    Repr::ALL.into_iter().flat_map(|repr| {
        EnvSampler::ALL
            .into_iter()
            .map(move |sampler| EnvMethod { repr, sampler })
    })
}

/// The name part of an environment method: `latlong-cdf`, `octa-hier`, ...
pub fn env_method_name(m: EnvMethod) -> String {
    format!("{}-{}", m.repr.name(), m.sampler.name())
}

/// Every strategy dibench knows, in listing order, built from the parts: the direction
/// samplers, BSDF sampling with each other GGX sampler and with lobes chosen by albedo, light
/// sampling with each single-shape method override, both MIS heuristics, power-heuristic MIS
/// with each BSDF-sampling variant, both AO estimators, then light sampling and MIS pinned to
/// each environment method.
pub fn registry() -> Vec<Box<dyn Strategy>> {
    use direction::{DirectionKind, DirectionSampling};
    use light_sampling::LightSampling;
    use mis::{Heuristic, Mis};
    let mut v: Vec<Box<dyn Strategy>> = Vec::new();
    for k in DirectionKind::ALL {
        v.push(Box::new(DirectionSampling::new(k)));
    }
    for s in crate::bsdf::BsdfSampling::variants() {
        v.push(Box::new(DirectionSampling::bsdf(s)));
    }
    v.push(Box::new(LightSampling::basic()));
    for o in crate::lights::MethodOverride::all() {
        v.push(Box::new(LightSampling::with_override(o)));
    }
    for h in Heuristic::ALL {
        v.push(Box::new(Mis::new(h)));
    }
    v.push(Box::new(Mis::by_area(Heuristic::Power)));
    for s in crate::bsdf::BsdfSampling::variants() {
        v.push(Box::new(Mis::with_sampling(Heuristic::Power, s)));
    }
    for cosine in [false, true] {
        v.push(Box::new(ambient_occlusion::AmbientOcclusion { cosine }));
    }
    for m in env_methods() {
        v.push(Box::new(LightSampling::env(m)));
    }
    for m in env_methods() {
        v.push(Box::new(Mis::env(m)));
    }
    // Light selection as an axis: light sampling and MIS (power) with every other selector.
    for &selector in crate::lights::selector::SELECTORS.iter().skip(1) {
        v.push(Box::new(LightSampling::with_selector(selector)));
        v.push(Box::new(Mis {
            selector,
            ..Mis::new(Heuristic::Power)
        }));
    }
    v
}

pub fn by_name(name: &str) -> Option<Box<dyn Strategy>> {
    registry().into_iter().find(|s| s.name() == name)
}

/// True if `s` applies to `scene`.
pub fn applies(s: &dyn Strategy, scene: &PreparedScene) -> Result<(), String> {
    s.bind(scene.view(s.integrand())).map(|_| ())
}

/// The strategy a reference for `integrand` is rendered with: the lowest-variance unbiased
/// one that applies.
pub fn reference_strategy(
    scene: &PreparedScene,
    integrand: Integrand,
) -> Option<Box<dyn Strategy>> {
    use light_sampling::LightSampling;
    use mis::{Heuristic, Mis};
    let env_mis = |repr| {
        Box::new(Mis::env(EnvMethod {
            repr,
            sampler: EnvSampler::Cdf,
        })) as Box<dyn Strategy>
    };
    let order: Vec<Box<dyn Strategy>> = match integrand {
        Integrand::Direct(Repr::LatLong) => vec![
            Box::new(Mis::new(Heuristic::Power)),
            env_mis(Repr::LatLong),
            Box::new(LightSampling::basic()),
        ],
        Integrand::Direct(r) => vec![env_mis(r)],
        Integrand::AmbientOcclusion => {
            vec![Box::new(ambient_occlusion::AmbientOcclusion {
                cosine: true,
            })]
        }
    };
    order
        .into_iter()
        .find(|s| applies(s.as_ref(), scene).is_ok())
}

/// The integrands a scene has (the set its references are made for).
pub fn integrands(scene: &PreparedScene) -> Vec<Integrand> {
    Integrand::ALL
        .into_iter()
        .filter(|&i| reference_strategy(scene, i).is_some())
        .collect()
}

/// Splits `strategies` into the ones that apply to the scene and the ones that do not.
pub fn split_applicable(
    strategies: Vec<Box<dyn Strategy>>,
    scene: &PreparedScene,
) -> (Vec<Box<dyn Strategy>>, Vec<Skipped>) {
    let mut run = Vec::new();
    let mut skipped = Vec::new();
    for s in strategies {
        match applies(s.as_ref(), scene) {
            Ok(()) => run.push(s),
            Err(reason) => skipped.push(Skipped {
                name: s.name(),
                reason,
            }),
        }
    }
    (run, skipped)
}

/// Splits the registry into the strategies that apply to the scene and the ones that do not.
pub fn applicable(scene: &PreparedScene) -> (Vec<Box<dyn Strategy>>, Vec<Skipped>) {
    split_applicable(registry(), scene)
}
