//! Light sources with their samplers and pdfs side by side, one file per light type, behind
//! one [`Light`] interface; a [`LightSet`] holds a scene's lights and picks among them with a
//! [`LightSelector`] (pbrt-v4 keeps selection apart from the lights in the same way). Every
//! sampler returns its pdf in solid angle at the shading point, the measure of the
//! direct-illumination integral, or reports a delta light.

pub mod bounds;
pub mod environment;
pub mod mesh;
pub mod quad;
pub mod selector;
pub mod sphere;

crate::plugin::registry! {
    /// Every light type a scene file names by a table array of its own (`[[spot_light]]`), in
    /// listing order (the order their lights take in a scene's light list). Lights that are the
    /// surface of a shape (`emission` on a quad, sphere or mesh) and the environment are part
    /// of their shape's or the environment's description instead.
    pub static LIGHT_TYPES: LightType = [
        point::POINT,
        spot::SPOT,
        directional::DIRECTIONAL,
        linear_spot::LINEAR_SPOT,
    ];
}

use crate::env::{EnvMethod, Environment, Repr};
use crate::geometry::Ray;
use crate::math::offset_ray_origin;
use crate::simd::{self, Isa, Soa3, V3, Vector, Vector64, WIDTH};
use bounds::Bounds;
use glam::Vec3;
use selector::{LightSelector, SELECTORS, SelectorType};
use std::sync::{Arc, OnceLock};

/// A kind of light as the scene format names it: the table array `[[name]]` and how one of
/// its tables becomes a light. One file declares it beside its `impl Light`, and one line in
/// [`LIGHT_TYPES`] registers it; nothing else in the crate names it.
pub struct LightType {
    /// The scene file's table array (`spot_light` for `[[spot_light]]`).
    pub name: &'static str,
    pub describe: &'static str,
    /// The fields it reads, for error messages.
    pub fields: &'static [&'static str],
    /// Builds the light from its table; fields it does not read are reported by the caller.
    pub parse: fn(&mut crate::scene::params::Params) -> crate::error::Result<Arc<dyn LightSpec>>,
    /// Its χ² cases (sample/pdf pairs), for the χ² suite and `dibench warp`; none for a delta
    /// light.
    pub chi2_cases: fn() -> Vec<crate::chi2::WarpEntry>,
}

impl std::fmt::Debug for LightType {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// A light as parsed, before the scene is known: a distant light's power depends on the size
/// of the scene it falls on, so the light is placed once the scene is bounded.
pub trait LightSpec: Send + Sync + std::fmt::Debug {
    /// The light for a scene whose bounding sphere has radius `scene_radius` (> 0).
    fn place(&self, scene_radius: f32) -> Box<dyn Light>;
}

/// The type named `name`.
pub fn light_type(name: &str) -> Option<&'static LightType> {
    LIGHT_TYPES.iter().copied().find(|t| t.name == name)
}

/// One sample of incident light at a shading point.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point to the light point.
    pub wi: Vec3,
    /// The sampled point on the light and the light's normal there, oriented towards the
    /// shading point (zero for a point light).
    pub point: Vec3,
    pub normal: Vec3,
    /// Absolute per-axis error bound of `point`, to offset the shadow ray's far end by.
    pub point_error: Vec3,
    /// Incident radiance along -wi; for a delta light, the irradiance at normal incidence I/d².
    pub radiance: Vec3,
    /// Solid-angle pdf; 1 for a delta light.
    pub pdf: f32,
    /// A light at infinity (directional): the shadow ray is unbounded and `point` unused.
    pub distant: bool,
}

/// Unit direction and squared distance from p to a sampled light point q; None when q is p
/// itself (a shading point on the light's own surface can draw its own position: a
/// measure-zero event that carries no light, and would otherwise divide zero by zero).
pub fn direction_to(p: Vec3, q: Vec3) -> Option<(Vec3, f32)> {
    let d = q - p;
    let d2 = d.length_squared();
    (d2 > 0.0).then(|| (d / d2.sqrt(), d2))
}

/// How quads are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum QuadMethod {
    /// Uniform by area.
    Area,
    /// Uniform in solid angle (spherical rectangle, Ureña et al. 2013).
    SolidAngle,
}

/// How spheres are sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SphereMethod {
    /// Uniform by area over the whole sphere (back-facing samples count as misses).
    Area,
    /// Uniform by area over the cap visible from the shading point.
    Cap,
    /// Uniform in the cone of directions the sphere subtends.
    Cone,
}

/// How emissive meshes are sampled, after a triangle is chosen in proportion to its area.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshMethod {
    /// Uniform by area on the triangle.
    Area,
    /// Uniform in the triangle's solid angle (spherical triangle, Arvo 1995).
    SolidAngle,
}

impl QuadMethod {
    pub const ALL: [QuadMethod; 2] = [QuadMethod::Area, QuadMethod::SolidAngle];

    /// The name part a strategy that picks this method gets (`light-quad-sa`).
    pub fn name(self) -> &'static str {
        match self {
            QuadMethod::Area => "quad-area",
            QuadMethod::SolidAngle => "quad-sa",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            QuadMethod::Area => "quads uniform by area",
            QuadMethod::SolidAngle => {
                "quads uniform in solid angle (spherical rectangle, Ureña et al. 2013)"
            }
        }
    }
}

impl SphereMethod {
    pub const ALL: [SphereMethod; 3] = [SphereMethod::Area, SphereMethod::Cap, SphereMethod::Cone];

    pub fn name(self) -> &'static str {
        match self {
            SphereMethod::Area => "sphere-area",
            SphereMethod::Cap => "sphere-cap",
            SphereMethod::Cone => "sphere-cone",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            SphereMethod::Area => "spheres uniform by area over the whole sphere",
            SphereMethod::Cap => "spheres uniform by area over the visible cap",
            SphereMethod::Cone => "spheres uniform in the subtended cone",
        }
    }
}

impl MeshMethod {
    pub const ALL: [MeshMethod; 2] = [MeshMethod::Area, MeshMethod::SolidAngle];

    pub fn name(self) -> &'static str {
        match self {
            MeshMethod::Area => "mesh-area",
            MeshMethod::SolidAngle => "mesh-sa",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            MeshMethod::Area => "mesh triangles uniform by area",
            MeshMethod::SolidAngle => {
                "mesh triangles uniform in solid angle (spherical triangle, Arvo 1995)"
            }
        }
    }
}

/// The sampler used for each shape of area light, and how the environment is sampled (its
/// representation is the integrand's: see [`Self::with_env_repr`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightMethods {
    pub quad: QuadMethod,
    pub sphere: SphereMethod,
    pub mesh: MeshMethod,
    pub env: EnvMethod,
}

impl LightMethods {
    /// The lecture's baseline: area sampling for quads and meshes, the cone for spheres.
    pub const BASIC: LightMethods = LightMethods {
        quad: QuadMethod::Area,
        sphere: SphereMethod::Cone,
        mesh: MeshMethod::Area,
        env: EnvMethod::LATLONG_CDF,
    };
    /// The lowest-variance sampler of each kind: solid angle everywhere.
    pub const SOLID_ANGLE: LightMethods = LightMethods {
        quad: QuadMethod::SolidAngle,
        sphere: SphereMethod::Cone,
        mesh: MeshMethod::SolidAngle,
        env: EnvMethod::LATLONG_CDF,
    };
}

/// One override of [`LightMethods::BASIC`]: a light-sampling variant's distinguishing part.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MethodOverride {
    Quad(QuadMethod),
    Sphere(SphereMethod),
    Mesh(MeshMethod),
}

impl MethodOverride {
    /// Every single-shape override that differs from the basic method, in listing order.
    pub fn all() -> Vec<MethodOverride> {
        let b = LightMethods::BASIC;
        let quads = QuadMethod::ALL
            .into_iter()
            .filter(|&m| m != b.quad)
            .map(MethodOverride::Quad);
        let spheres = SphereMethod::ALL
            .into_iter()
            .filter(|&m| m != b.sphere)
            .map(MethodOverride::Sphere);
        let meshes = MeshMethod::ALL
            .into_iter()
            .filter(|&m| m != b.mesh)
            .map(MethodOverride::Mesh);
        quads.chain(spheres).chain(meshes).collect()
    }

    pub fn name(self) -> &'static str {
        match self {
            MethodOverride::Quad(m) => m.name(),
            MethodOverride::Sphere(m) => m.name(),
            MethodOverride::Mesh(m) => m.name(),
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            MethodOverride::Quad(m) => m.describe(),
            MethodOverride::Sphere(m) => m.describe(),
            MethodOverride::Mesh(m) => m.describe(),
        }
    }

    /// The shape whose lights this override concerns.
    pub fn shape(self) -> LightShape {
        match self {
            MethodOverride::Quad(_) => LightShape::Quad,
            MethodOverride::Sphere(_) => LightShape::Sphere,
            MethodOverride::Mesh(_) => LightShape::Mesh,
        }
    }

    /// `methods` with this override applied.
    pub fn apply(self, mut methods: LightMethods) -> LightMethods {
        match self {
            MethodOverride::Quad(m) => methods.quad = m,
            MethodOverride::Sphere(m) => methods.sphere = m,
            MethodOverride::Mesh(m) => methods.mesh = m,
        }
        methods
    }
}

impl LightMethods {
    /// These methods with the environment looked up and sampled in representation `repr`.
    pub fn with_env_repr(mut self, repr: Repr) -> Self {
        self.env.repr = repr;
        self
    }
}

/// The shading points of a packet's lanes that one light is sampled for at once (structure of
/// arrays): what [`LightCtx`] and the three sample numbers are per lane. It borrows the rows
/// where they already are (the packet's points and normals, the pass's sample numbers): a copy
/// per packet was a `memcpy` of 576 bytes, 2.7 % of a cornell `light` pass (docs/tracer.md,
/// stop 47).
#[derive(Clone, Copy, Debug)]
pub struct LaneQuery<'a> {
    pub p: &'a Soa3,
    pub n: &'a Soa3,
    /// `u[k][lane]`: the sample numbers [`Light::sample`] takes.
    pub u: [&'a [f32; WIDTH]; 3],
}

impl LaneQuery<'_> {
    pub fn ctx(&self, lane: usize) -> LightCtx {
        LightCtx {
            p: self.p.get(lane),
            n: self.n.get(lane),
        }
    }
}

/// Owned rows of a [`LaneQuery`], for callers that fill a query lane by lane (tests, benches).
#[derive(Clone, Copy, Debug, Default)]
pub struct LaneQueryRows {
    pub p: Soa3,
    pub n: Soa3,
    pub u: [[f32; WIDTH]; 3],
}

impl LaneQueryRows {
    pub fn ctx(&self, lane: usize) -> LightCtx {
        self.query().ctx(lane)
    }

    pub fn query(&self) -> LaneQuery<'_> {
        LaneQuery {
            p: &self.p,
            n: &self.n,
            u: [&self.u[0], &self.u[1], &self.u[2]],
        }
    }
}

/// The shading points of a packet's lanes, without sample numbers.
#[derive(Clone, Copy, Debug, Default)]
pub struct LanePoints {
    pub p: Soa3,
    pub n: Soa3,
}

impl LanePoints {
    pub fn ctx(&self, lane: usize) -> LightCtx {
        LightCtx {
            p: self.p.get(lane),
            n: self.n.get(lane),
        }
    }
}

/// [`LightSample`]s of 16 lanes (structure of arrays); `valid` marks the lanes that have one.
#[derive(Clone, Copy, Debug, Default)]
pub struct LaneSamples {
    pub valid: u32,
    /// Lanes whose sample is at infinity ([`LightSample::distant`]).
    pub distant: u32,
    pub wi: Soa3,
    pub point: Soa3,
    pub normal: Soa3,
    pub point_error: Soa3,
    pub radiance: Soa3,
    pub pdf: [f32; WIDTH],
}

impl LaneSamples {
    /// Stores `s` as lane `lane`'s sample, or marks the lane as having none.
    pub fn set(&mut self, lane: usize, s: Option<LightSample>) {
        let bit = 1 << lane;
        let Some(s) = s else {
            self.valid &= !bit;
            return;
        };
        self.valid |= bit;
        self.distant = if s.distant {
            self.distant | bit
        } else {
            self.distant & !bit
        };
        self.wi.set(lane, s.wi);
        self.point.set(lane, s.point);
        self.normal.set(lane, s.normal);
        self.point_error.set(lane, s.point_error);
        self.radiance.set(lane, s.radiance);
        self.pdf[lane] = s.pdf;
    }

    /// Lane `lane`'s sample, if it has one.
    pub fn get(&self, lane: usize) -> Option<LightSample> {
        (self.valid >> lane & 1 != 0).then(|| LightSample {
            wi: self.wi.get(lane),
            point: self.point.get(lane),
            normal: self.normal.get(lane),
            point_error: self.point_error.get(lane),
            radiance: self.radiance.get(lane),
            pdf: self.pdf[lane],
            distant: self.distant >> lane & 1 != 0,
        })
    }
}

/// Stores lanes `m` of `new` into `old`, keeping its other lanes.
#[inline(always)]
pub(crate) fn keep<V: Vector<WIDTH>>(m: u32, new: V3<V>, old: &mut Soa3) {
    V3::select(m, new, V3::load(old)).store(old)
}

/// The solid-angle pdf of a point uniform by area on a flat light (unit normal `normal`, area
/// `area`) at each lane of `at`: d²/(A·cos θ_l) where the light faces the viewpoint, 0
/// elsewhere; the scalar `pdf_area` of quads and mesh triangles, the same operations in the
/// same order. Lanes whose point is their viewpoint (which no hit is) hold values that mean
/// nothing.
#[inline(always)]
pub(crate) fn flat_area_pdf_lanes<V: Vector<WIDTH>>(
    normal: V3<V>,
    area: V,
    at: &SurfaceLanes,
) -> V {
    let zero = V::splat(0.0);
    let d = V3::<V>::load(&at.q) - V3::load(&at.from.p);
    let d2 = d.dot(d);
    let cos_l = normal.dot(d).neg().div(d2.sqrt());
    zero.lt_select(cos_l, d2.div(area.mul(cos_l)), zero)
}

/// f64 lanes rounded to f32 lanes. A function, not a closure: a closure is not always inlined
/// into the ISA's entry, and outside it its vector operations are calls.
#[inline(always)]
pub(crate) fn f32s<V: Vector<WIDTH>, D: Vector64<WIDTH>>(x: D) -> V {
    let mut a = [0.0f32; WIDTH];
    x.to_f32(&mut a);
    V::load(&a)
}

/// f32 lanes, exactly as f64 lanes.
#[inline(always)]
pub(crate) fn d64<V: Vector<WIDTH>, D: Vector64<WIDTH>>(x: V) -> D {
    let mut a = [0.0f32; WIDTH];
    x.store(&mut a);
    D::from_f32(&a)
}

/// How many f32 a light's [`LaneKernel`] record holds.
pub const LANE_RECORD: usize = 16;

/// Records of 16 lanes' lights, `records[k][lane]`: field k of lane `lane`'s light.
pub type LaneRecords = [[f32; WIDTH]; LANE_RECORD];

/// One light's record, a cache line of its own (a table of them reads one line per lane).
#[derive(Clone, Copy, Debug, PartialEq)]
#[repr(C, align(64))]
pub struct LaneRecord(pub [f32; LANE_RECORD]);

impl LaneRecord {
    pub const ZERO: LaneRecord = LaneRecord([0.0; LANE_RECORD]);
}

/// The records of 16 lanes' lights (`rows[lane]`) as [`LaneRecords`], field by field: each
/// record read whole, four fields at a time, and transposed in registers
/// ([`Vector::load_records`]). Written field by field lane by lane, the 256 scalar copies were
/// 5.5 % of a mesh_light `light` pass (docs/tracer.md, stop 48).
pub fn gather_records(isa: Isa, rows: &[&LaneRecord; WIDTH], out: &mut LaneRecords) {
    struct Gather<'a>(&'a [&'a LaneRecord; WIDTH], &'a mut LaneRecords);
    impl simd::Kernel for Gather<'_> {
        type Out = ();
        #[inline(always)]
        fn run<L: simd::Lanes>(self) {
            let Gather(rows, out) = self;
            for quad in 0..LANE_RECORD / 4 {
                let q: [&[f32; 4]; WIDTH] = std::array::from_fn(|lane| {
                    let r = &rows[lane].0;
                    r[4 * quad..4 * quad + 4].try_into().expect("four fields")
                });
                let v = L::V::load_records(&q);
                for (k, v) in v.into_iter().enumerate() {
                    v.store(&mut out[4 * quad + k]);
                }
            }
        }
    }
    simd::run(isa, Gather(rows, out));
}

/// Rows `k..k + 3` of a record as f32 lanes.
#[inline(always)]
pub(crate) fn record_rows<V: Vector<WIDTH>>(r: &LaneRecords, k: usize) -> V3<V> {
    V3 {
        x: V::load(&r[k]),
        y: V::load(&r[k + 1]),
        z: V::load(&r[k + 2]),
    }
}

/// Rows `k..k + 3` of a record, exactly, as f64 lanes.
#[inline(always)]
pub(crate) fn record_rows_d<D: Vector64<WIDTH>>(r: &LaneRecords, k: usize) -> [D; 3] {
    [
        D::from_f32(&r[k]),
        D::from_f32(&r[k + 1]),
        D::from_f32(&r[k + 2]),
    ]
}

/// The fewest lanes a pdf kernel over lanes ([`LaneKernel::pdf`], a triangle's
/// [`Light::pdf_lanes`]) is run for; fewer are taken one at a time. Its f64 spherical triangle
/// over 16 lanes, with the records' gather, executes about as many instructions as five lanes'
/// scalar pdfs on AVX2 (3,600 against 755 a lane; `scripts/instructions.sh` on many_mesh and
/// mesh_light, docs/tracer.md, stop 56), whatever the number of lanes it has to answer.
pub const MIN_PDF_KERNEL_LANES: u32 = 5;

/// A kernel that samples the lanes of a packet together although each lane has its own light
/// of one type (mesh triangles: every lane picks its own triangle, so sampling per light,
/// [`Light::sample_lanes`], would run one lane at a time). Each light hands over its
/// parameters as a record ([`Light::lane_record`]); lights answering the same kernel (the same
/// `&'static`, compared by address) are sampled by one call.
pub struct LaneKernel {
    pub name: &'static str,
    /// Lane i of `out`, for each lane of `active`, is what [`Light::sample`] of the light whose
    /// record is lane i of `records` returns, bit for bit (other lanes are left as they were).
    pub sample: fn(Isa, &LaneRecords, &LaneQuery, u32, &LightMethods, &mut LaneSamples),
    /// The sampler's pdf beside it: lane i of `out`, for each lane of `active`, is
    /// [`Light::pdf`] of the light whose record is lane i of `records` at lane i of `at`, bit
    /// for bit (other lanes are left as they were). The MIS weight of emission probes whose
    /// lanes hit different lights of this type (an emissive mesh's triangles).
    pub pdf: fn(Isa, &LaneRecords, &SurfaceLanes, u32, &LightMethods, &mut [f32; WIDTH]),
}

impl LaneKernel {
    /// The same kernel: identity is the static's address.
    pub fn is(&self, other: &LaneKernel) -> bool {
        std::ptr::eq(self, other)
    }
}

impl std::fmt::Debug for LaneKernel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// [`Light::sample`] lane by lane: what [`Light::sample_lanes`] does for a light without a
/// kernel over lanes, and for the methods a light's kernel does not cover.
pub fn sample_lane_by_lane<T: Light + ?Sized>(
    light: &T,
    q: &LaneQuery,
    active: u32,
    m: &LightMethods,
    out: &mut LaneSamples,
) {
    for lane in 0..WIDTH {
        if active >> lane & 1 != 0 {
            let u = [q.u[0][lane], q.u[1][lane], q.u[2][lane]];
            out.set(lane, light.sample(&q.ctx(lane), u, m));
        }
    }
}

/// Surface points on one light seen from the shading points of a packet's lanes (structure of
/// arrays): what [`Light::pdf_lanes`] takes.
#[derive(Clone, Copy, Debug, Default)]
pub struct SurfaceLanes {
    /// The shading points' positions and normals.
    pub from: LanePoints,
    /// The points on the light.
    pub q: Soa3,
    /// The light's part each point is on ([`LightHit::Surface`]'s `local`).
    pub local: [u32; WIDTH],
}

impl SurfaceLanes {
    /// Lane `lane` of `self` as a scalar query: where it is seen from, and what it hit.
    pub fn get(&self, lane: usize) -> (LightCtx, LightHit) {
        let hit = LightHit::Surface {
            q: self.q.get(lane),
            local: self.local[lane],
        };
        (self.from.ctx(lane), hit)
    }

    pub fn set(&mut self, lane: usize, ctx: &LightCtx, q: Vec3, local: u32) {
        self.from.p.set(lane, ctx.p);
        self.from.n.set(lane, ctx.n);
        self.q.set(lane, q);
        self.local[lane] = local;
    }
}

/// The lanes (bit i = lane i) whose entry in `values` is `v`: which lanes chose one light.
#[inline]
pub fn lanes_holding<T: PartialEq>(values: &[T; WIDTH], v: T) -> u32 {
    let mut mask = 0;
    for (lane, x) in values.iter().enumerate() {
        if *x == v {
            mask |= 1 << lane;
        }
    }
    mask
}

/// [`Light::pdf_lanes`] lane by lane: the scalar [`Light::pdf`] of each lane of `active`.
pub fn pdf_lane_by_lane<T: Light + ?Sized>(
    light: &T,
    at: &SurfaceLanes,
    active: u32,
    m: &LightMethods,
    out: &mut [f32; WIDTH],
) {
    for (lane, o) in out.iter_mut().enumerate() {
        if active >> lane & 1 != 0 {
            let (ctx, hit) = at.get(lane);
            *o = light.pdf(&ctx, hit, m);
        }
    }
}

/// pbrt-v4's ShadowEpsilon: a shadow segment stops this fraction short of the (offset) light
/// point.
pub const SHADOW_EPSILON: f32 = 1e-4;

impl LightSample {
    /// The unoccluded-test segment from a shading point (already offset) to the sample, with the
    /// light end offset off the light's own surface so the light does not shadow itself.
    pub fn shadow_ray(&self, origin: Vec3) -> Option<Ray> {
        if self.distant {
            // Unbounded, along the light's direction. (Until the stress suite's exact shading
            // points exposed it, this fell through to a segment towards `point` = the world
            // origin: directional shadows were tested against the wrong segment.)
            return Some(Ray::new(origin, self.wi, f32::INFINITY));
        }
        // The far end steps off the light's surface towards the shading point, past its own
        // error box (pbrt-v4 `SpawnRayTo`).
        let towards = if self.normal.dot(origin - self.point) >= 0.0 {
            self.normal
        } else {
            -self.normal
        };
        let target = offset_ray_origin(self.point, self.point_error, towards);
        let d = target - origin;
        let dist = d.length();
        if dist == 0.0 {
            return None;
        }
        Some(Ray::new(origin, d / dist, dist * (1.0 - SHADOW_EPSILON)))
    }
}

/// What a light knows of the point it is sampled from: the position and the shading normal
/// (flipped to the viewer's side), as pbrt-v4's `LightSampleContext`. Selectors that weigh
/// lights by orientation use the normal: dibench's surfaces reflect into the hemisphere about
/// it only, so a light wholly below it provably adds nothing; zero means no orientation (a
/// point that receives from every direction). Every light sampler uses `p`.
#[derive(Clone, Copy, Debug)]
pub struct LightCtx {
    pub p: Vec3,
    pub n: Vec3,
}

/// The geometry a light is sampled on: which methods apply and what the lecture's strategies
/// say about it. A new light type on an existing shape keeps the shape's samplers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightShape {
    /// A point (point and spot lights): a delta light.
    Point,
    /// A single direction from infinitely far away (directional light): a delta light.
    Direction,
    Quad,
    Sphere,
    Mesh,
    /// Every direction, from infinitely far away.
    Environment,
}

impl LightShape {
    pub fn name(self) -> &'static str {
        match self {
            LightShape::Point => "point",
            LightShape::Direction => "directional",
            LightShape::Quad => "quad",
            LightShape::Sphere => "sphere",
            LightShape::Mesh => "mesh",
            LightShape::Environment => "environment",
        }
    }

    /// Only light sampling can reach it: no sampled direction hits a point or one direction.
    pub fn is_delta(self) -> bool {
        matches!(self, LightShape::Point | LightShape::Direction)
    }
}

/// Where a traced ray found a light: a point on an emitting primitive (`local` names the
/// light's own part, e.g. a mesh triangle), or a direction for the environment.
#[derive(Clone, Copy, Debug)]
pub enum LightHit {
    Surface { q: Vec3, local: u32 },
    Direction(Vec3),
}

/// A light source: its power for selection, its samplers by method with their pdfs, and the
/// radiance it emits. Implementations live one per file beside this one.
pub trait Light: Send + Sync + std::fmt::Debug {
    fn shape(&self) -> LightShape;

    /// Radiant power [W], luminance-weighted, for power-proportional light selection.
    fn power(&self) -> f32;

    fn is_delta(&self) -> bool {
        self.shape().is_delta()
    }

    /// What light selection knows of this light: its bounds if it is at a finite place, its
    /// irradiance if it is at infinity (see [`bounds`]).
    fn bounds(&self) -> Bounds;

    /// A sample of this light seen from `ctx`, by the method `m` selects for its shape.
    /// u[0..2] place the sample; u[2] is not the light's (a [`LightSet`] spends it on the low
    /// bits of the selection number); None when the sample carries no light (the back of a
    /// one-sided emitter).
    fn sample(&self, ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample>;

    /// [`Self::sample`] for the lanes of `active` (bit i = lane i) at once, on the lane layer's
    /// `isa`: lane i of `out` is what [`Self::sample`] returns for lane i, bit for bit (other
    /// lanes are left as they were). The default samples lane by lane; a light with a
    /// kernel over lanes overrides it for the methods the kernel covers (#19 part B).
    fn sample_lanes(
        &self,
        _isa: Isa,
        q: &LaneQuery,
        active: u32,
        m: &LightMethods,
        out: &mut LaneSamples,
    ) {
        sample_lane_by_lane(self, q, active, m, out)
    }

    /// A kernel that samples lanes of different lights of this type at once under the methods
    /// `m`, with this light's record for it; None (the default) where it has none: the light is
    /// then sampled through [`Self::sample_lanes`] for the lanes that chose it.
    fn lane_record(&self, _m: &LightMethods) -> Option<(&'static LaneKernel, [f32; LANE_RECORD])> {
        None
    }

    /// Solid-angle pdf with which [`Self::sample`] (same method) produces the direction to
    /// `at`. 0 for delta lights: no direction found by another strategy can reach them.
    fn pdf(&self, ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32;

    /// [`Self::pdf`] for the lanes of `active` at once, on the lane layer's `isa`: lane i of
    /// `out` is the pdf of surface point `at[i]` (part `local[i]`) seen from `q.ctx(i)`, bit
    /// for bit as [`Self::pdf`] (`q.u` is not read; other lanes of `out` are kept). The
    /// default is lane by lane; a light with a kernel over lanes overrides it (the MIS weight
    /// of emission probes that hit it, #19 part B).
    fn pdf_lanes(
        &self,
        _isa: Isa,
        at: &SurfaceLanes,
        active: u32,
        m: &LightMethods,
        out: &mut [f32; WIDTH],
    ) {
        pdf_lane_by_lane(self, at, active, m, out)
    }

    /// Radiance leaving part `local` of the light at a point with outward geometric normal
    /// `n` towards direction `w` (unit, pointing away from the light). Zero for lights without
    /// a surface.
    fn emitted(&self, _n: Vec3, _w: Vec3, _local: u32) -> Vec3 {
        Vec3::ZERO
    }

    /// `m` with the methods this light cannot be sampled by replaced by ones it can (a
    /// quad that is not a rectangle has no spherical-rectangle sampler).
    fn usable_methods(&self, m: LightMethods) -> LightMethods {
        m
    }
}

/// Which light (and which part of it, e.g. a mesh triangle) a primitive emits as.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EmitterRef {
    pub light: u32,
    pub local: u32,
}

/// A scene's lights and the selectors over them (built on first use: a light BVH over a
/// million lights is not built for a strategy that never asks for it).
pub struct LightSet {
    lights: Vec<Box<dyn Light>>,
    environment: Option<(usize, Arc<Environment>)>,
    selectors: Vec<OnceLock<Result<Box<dyn LightSelector>, String>>>,
}

impl std::fmt::Debug for LightSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LightSet")
            .field("lights", &self.lights)
            .finish_non_exhaustive()
    }
}

impl LightSet {
    /// `environment`: the index in `lights` of the environment light and its maps.
    pub fn new(
        lights: Vec<Box<dyn Light>>,
        environment: Option<(usize, Arc<Environment>)>,
    ) -> Self {
        LightSet {
            lights,
            environment,
            selectors: SELECTORS.iter().map(|_| OnceLock::new()).collect(),
        }
    }

    pub fn lights(&self) -> &[Box<dyn Light>] {
        &self.lights
    }

    pub fn len(&self) -> usize {
        self.lights.len()
    }

    pub fn is_empty(&self) -> bool {
        self.lights.is_empty()
    }

    pub fn get(&self, i: usize) -> &dyn Light {
        self.lights[i].as_ref()
    }

    /// True if some light has shape `shape`.
    pub fn has(&self, shape: LightShape) -> bool {
        self.lights.iter().any(|l| l.shape() == shape)
    }

    pub fn has_delta(&self) -> bool {
        self.lights.iter().any(|l| l.is_delta())
    }

    /// `m` as every light of the set can use it (see [`Light::usable_methods`]); resolved
    /// once when a strategy is bound to a scene.
    pub fn usable_methods(&self, m: LightMethods) -> LightMethods {
        self.lights.iter().fold(m, |m, l| l.usable_methods(m))
    }

    /// The environment light's index, if the scene has one.
    pub fn environment_index(&self) -> Option<usize> {
        self.environment.as_ref().map(|(i, _)| *i)
    }

    /// The environment in every representation, if the scene has one.
    pub fn environment(&self) -> Option<&Arc<Environment>> {
        self.environment.as_ref().map(|(_, e)| e)
    }

    /// The selector of type `kind` over these lights, built on first use; Err says why it
    /// cannot select among them (no light with positive power, too many lights for an O(n)
    /// selector, a type not in `SELECTORS`).
    pub fn selector(&self, kind: &'static SelectorType) -> Result<&dyn LightSelector, String> {
        // Built selectors are kept one per registered type; a type from outside the registry
        // has no slot (and is refused, not a panic).
        let Some(k) = SELECTORS.iter().position(|s| std::ptr::eq(*s, kind)) else {
            return Err(format!(
                "light selector `{}` is not registered in lights::selector::SELECTORS",
                kind.name
            ));
        };
        match self.selectors[k].get_or_init(|| (kind.build)(&self.lights)) {
            Ok(s) => Ok(s.as_ref()),
            Err(why) => Err(why.clone()),
        }
    }

    /// Picks a light with `sel` and samples it by `m`; the returned pdf includes the
    /// selection probability.
    pub fn sample(
        &self,
        sel: &dyn LightSelector,
        ctx: &LightCtx,
        u_select: f32,
        u: [f32; 3],
        m: &LightMethods,
    ) -> Option<(usize, LightSample)> {
        let (i, pmf) = sel.sample(ctx, selection_number(u_select, u[2]))?;
        let mut s = self.lights[i].sample(ctx, u, m)?;
        s.pdf *= pmf;
        Some((i, s))
    }

    /// The pdf with which [`Self::sample`] produces the direction to `at` on light `light`
    /// (selection probability included).
    pub fn pdf(
        &self,
        sel: &dyn LightSelector,
        ctx: &LightCtx,
        light: usize,
        at: LightHit,
        m: &LightMethods,
    ) -> f32 {
        sel.pmf(ctx, light) * self.lights[light].pdf(ctx, at, m)
    }

    /// Each light's own pdf ([`Light::pdf_lanes`], no selection pmf) of the lanes of `active`
    /// that hit it, lane i's point on light `light[i]`, into `out` (other lanes are kept).
    pub fn pdf_lanes_by_light(
        &self,
        isa: Isa,
        light: &[u32; WIDTH],
        at: &SurfaceLanes,
        active: u32,
        m: &LightMethods,
        out: &mut [f32; WIDTH],
    ) {
        let mut rest = active;
        while rest != 0 {
            let i = light[rest.trailing_zeros() as usize];
            let mask = lanes_holding(light, i) & active;
            rest &= !mask;
            self.lights[i as usize].pdf_lanes(isa, at, mask, m, out);
        }
    }

    /// The pdf with which [`Self::sample`] produces direction `wi` towards the environment;
    /// 0 without one.
    pub fn env_pdf(
        &self,
        sel: &dyn LightSelector,
        ctx: &LightCtx,
        wi: Vec3,
        m: &LightMethods,
    ) -> f32 {
        match self.environment_index() {
            Some(i) => self.pdf(sel, ctx, i, LightHit::Direction(wi), m),
            None => 0.0,
        }
    }

    /// Radiance the environment sends along -`dir` in representation `repr` (zero without one).
    pub fn env_radiance(&self, repr: Repr, dir: Vec3) -> Vec3 {
        match self.environment() {
            Some(env) => env.radiance(repr, dir),
            None => Vec3::ZERO,
        }
    }

    /// Radiance emitter `e` sends from a point with outward geometric normal `ng` towards `w`.
    pub fn emitted(&self, e: EmitterRef, ng: Vec3, w: Vec3) -> Vec3 {
        self.lights[e.light as usize].emitted(ng, w, e.local)
    }
}

/// One selection number in [0, 1) with 48 random bits from two 24-bit sample dimensions: `hi`
/// on its 2^-24 grid plus `lo` below it. With one f32, each of a million equally likely lights
/// would get 16 or 17 multiples of 2^-24 — a pmf off by 6 % — and a tree descent that
/// rescales u at every level has no bits left after 24 binary choices (sampling.md,
/// pitfall 18).
pub fn selection_number(hi: f32, lo: f32) -> f64 {
    const GRID: f64 = 16_777_216.0;
    // floor by truncation (sample numbers are non-negative, below 2^24 on the grid): one
    // conversion instead of a call to libm's floor without SSE4.1.
    (hi as f64 * GRID) as i64 as f64 / GRID + lo as f64 / GRID
}

/// [`selection_number`] of 16 lanes at once, bit for bit, on `isa` (lane by lane
/// it was 2 % of a mesh_light pass: scalar conversions outside any ISA kernel; docs/tracer.md,
/// stop 47).
pub fn selection_numbers(isa: Isa, hi: &[f32; WIDTH], lo: &[f32; WIDTH], out: &mut [f64; WIDTH]) {
    struct Numbers<'a>(&'a [f32; WIDTH], &'a [f32; WIDTH], &'a mut [f64; WIDTH]);
    impl simd::Kernel for Numbers<'_> {
        type Out = ();
        #[inline(always)]
        fn run<L: simd::Lanes>(self) {
            selection_number_lanes::<L::D>(self.0, self.1).to_f64(self.2);
        }
    }
    simd::run(isa, Numbers(hi, lo, out));
}

/// [`selection_number`] over f64 lanes. The floor of x = hi·2²⁴ (0 ≤ x < 2²⁴) without a floor
/// instruction: x + 2⁵² − 2⁵² is x rounded to the nearest integer (exact in f64 below 2⁵²),
/// one less where that rounded up. The divisions by 2²⁴ are exact products.
#[inline(always)]
fn selection_number_lanes<D: Vector64<WIDTH>>(hi: &[f32; WIDTH], lo: &[f32; WIDTH]) -> D {
    const GRID: f64 = 16_777_216.0;
    let x = D::from_f32(hi).mul(D::splat(GRID));
    let big = D::splat(4_503_599_627_370_496.0);
    let near = x.add(big).sub(big);
    let floor = near.sub(x.lt_select(near, D::splat(1.0), D::splat(0.0)));
    let unit = D::splat(1.0 / GRID);
    floor.mul(unit).add(D::from_f32(lo).mul(unit))
}

/// What the lights' lane tests share: a light's samples over lanes against its scalar ones.
#[cfg(test)]
pub(crate) mod lane_tests {
    use super::*;
    use crate::sampling::stream::{ONE_MINUS_EPSILON, SampleStream};

    fn bits(s: Option<LightSample>) -> Option<([u32; 16], bool)> {
        s.map(|s| {
            let mut b = [0u32; 16];
            for (k, v) in [s.wi, s.point, s.normal, s.point_error, s.radiance]
                .iter()
                .flat_map(|v| v.to_array())
                .chain([s.pdf])
                .enumerate()
            {
                b[k] = v.to_bits();
            }
            (b, s.distant)
        })
    }

    /// Lane `lane`'s sample numbers in round `round`: u at 0 and just below 1 among random ones.
    pub(crate) fn set_numbers(
        q: &mut LaneQueryRows,
        lane: usize,
        round: usize,
        rng: &mut SampleStream,
    ) {
        let [u0, u1] = rng.next_2d();
        let special = [0.0, ONE_MINUS_EPSILON, u0, u1];
        q.u[0][lane] = special[(lane + round) % 4];
        q.u[1][lane] = special[(lane + 2 * round) % 4];
        q.u[2][lane] = rng.next_2d()[0];
    }

    /// Every lane in even rounds, a random mask in odd ones.
    pub(crate) fn active_lanes(round: usize, rng: &mut SampleStream) -> u32 {
        if round.is_multiple_of(2) {
            u32::MAX >> (32 - WIDTH)
        } else {
            (rng.next_2d()[0] * (1u32 << WIDTH) as f32) as u32
        }
    }

    /// `light.sample_lanes` of lanes `active` equals `light.sample` lane by lane, bit for bit,
    /// on every ISA, and lanes outside `active` keep what they held.
    pub(crate) fn assert_lanes_are_the_scalar_samples<T: Light>(
        light: &T,
        q: &LaneQuery,
        active: u32,
        m: &LightMethods,
        label: &str,
    ) {
        let marker = LightSample {
            wi: Vec3::X,
            point: Vec3::Y,
            normal: Vec3::Z,
            point_error: Vec3::ONE,
            radiance: Vec3::splat(7.0),
            pdf: 3.0,
            distant: true,
        };
        for isa in Isa::available() {
            let mut out = LaneSamples::default();
            for lane in 0..WIDTH {
                out.set(lane, Some(marker));
            }
            light.sample_lanes(isa, q, active, m, &mut out);
            for lane in 0..WIDTH {
                let want = if active >> lane & 1 != 0 {
                    light.sample(&q.ctx(lane), [q.u[0][lane], q.u[1][lane], q.u[2][lane]], m)
                } else {
                    Some(marker)
                };
                assert_eq!(
                    bits(out.get(lane)),
                    bits(want),
                    "{isa:?} {label} lane {lane} p {:?}",
                    q.p.get(lane)
                );
            }
        }
    }

    /// Where the pdf kernel over records ([`LaneKernel::pdf`]) leaves [`Light::pdf`] of lane
    /// i's light `lights[i]` at `at`'s lane i, on some ISA, for a lane of `active`, or where
    /// it writes a lane outside `active`; None where it is the scalar pdf bit for bit on every
    /// ISA. The records are the lights' own ([`Light::lane_record`]), then changed by `alter`
    /// (identity but for a negative control).
    pub(crate) fn record_pdf_mismatch<T: Light>(
        lights: &[T],
        at: &SurfaceLanes,
        active: u32,
        m: &LightMethods,
        alter: impl Fn(&mut LaneRecords),
    ) -> Option<String> {
        const MARKER: f32 = -3.5;
        assert_eq!(lights.len(), WIDTH);
        let mut records: LaneRecords = [[0.0; WIDTH]; LANE_RECORD];
        let mut kernel: Option<&'static LaneKernel> = None;
        for (lane, light) in lights.iter().enumerate() {
            let (k, r) = light.lane_record(m).expect("a light with a kernel");
            assert!(kernel.is_none_or(|o| o.is(k)), "one kernel for every lane");
            kernel = Some(k);
            for (row, v) in records.iter_mut().zip(r) {
                row[lane] = v;
            }
        }
        alter(&mut records);
        let kernel = kernel.expect("sixteen lanes");
        for isa in Isa::available() {
            let mut out = [MARKER; WIDTH];
            (kernel.pdf)(isa, &records, at, active, m, &mut out);
            for (lane, got) in out.iter().enumerate() {
                let want = if active >> lane & 1 != 0 {
                    let (ctx, hit) = at.get(lane);
                    lights[lane].pdf(&ctx, hit, m)
                } else {
                    MARKER
                };
                if got.to_bits() != want.to_bits() {
                    return Some(format!(
                        "{isa:?} lane {lane}: {got} against {want}, p {:?}, q {:?}",
                        at.from.p.get(lane),
                        at.q.get(lane)
                    ));
                }
            }
        }
        None
    }

    /// `light.pdf_lanes` of lanes `active` equals `light.pdf` lane by lane, bit for bit, on
    /// every ISA, and lanes outside `active` keep what they held.
    pub(crate) fn assert_lane_pdfs_are_the_scalar_ones<T: Light>(
        light: &T,
        at: &SurfaceLanes,
        active: u32,
        m: &LightMethods,
        label: &str,
    ) {
        const MARKER: f32 = -3.5;
        for isa in Isa::available() {
            let mut out = [MARKER; WIDTH];
            light.pdf_lanes(isa, at, active, m, &mut out);
            for (lane, got) in out.iter().enumerate() {
                let want = if active >> lane & 1 != 0 {
                    let (ctx, hit) = at.get(lane);
                    light.pdf(&ctx, hit, m)
                } else {
                    MARKER
                };
                assert_eq!(
                    got.to_bits(),
                    want.to_bits(),
                    "{isa:?} {label} lane {lane}: {got} against {want}, p {:?}, q {:?}",
                    at.from.p.get(lane),
                    at.q.get(lane)
                );
            }
        }
    }
}

#[cfg(test)]
mod selection_number_tests {
    use super::*;
    use crate::sampling::stream::{ONE_MINUS_EPSILON, SampleStream};

    /// Sample numbers that test the floor: on the 2⁻²⁴ grid, just below grid points, finer
    /// than the grid near 0 (subnormals included), 0 and the largest below 1, and random
    /// f32 bits in [0, 1).
    fn numbers() -> Vec<f32> {
        let mut v = vec![0.0, ONE_MINUS_EPSILON, f32::MIN_POSITIVE, 1e-30, 1e-40, 0.5];
        let mut rng = SampleStream::new(5, 6, 7, 8);
        for _ in 0..4000 {
            let grid = (rng.next_1d() * 16_777_216.0).floor() / 16_777_216.0;
            let below = f32::from_bits(grid.to_bits().saturating_sub(1));
            let any = f32::from_bits((rng.next_1d() * 1_065_353_216.0) as u32);
            v.extend([grid, below, any, rng.next_1d() * 1e-6]);
        }
        v.retain(|x| (0.0..1.0).contains(x));
        v
    }

    /// `numbers` against `selection_number` lane by lane, bit for bit, on every ISA.
    fn lanes_match(
        f: impl Fn(Isa, &[f32; WIDTH], &[f32; WIDTH], &mut [f64; WIDTH]),
    ) -> Result<(), String> {
        let v = numbers();
        for (k, hi) in v.chunks_exact(WIDTH).enumerate() {
            let hi: [f32; WIDTH] = hi.try_into().unwrap();
            let lo: [f32; WIDTH] = std::array::from_fn(|l| v[(k * 7 + l * 3) % v.len()]);
            for isa in Isa::available() {
                let mut got = [0.0; WIDTH];
                f(isa, &hi, &lo, &mut got);
                for l in 0..WIDTH {
                    let want = selection_number(hi[l], lo[l]);
                    if got[l].to_bits() != want.to_bits() {
                        return Err(format!(
                            "{isa:?}: hi {:e} lo {:e}: {} against {want}",
                            hi[l], lo[l], got[l]
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The lanes' floor is the scalar truncation. Control: rounding to the nearest grid point
    /// instead of down is caught.
    #[test]
    fn lanes_are_the_scalar_numbers() {
        lanes_match(selection_numbers).unwrap();
        let rounded = |_: Isa, hi: &[f32; WIDTH], lo: &[f32; WIDTH], out: &mut [f64; WIDTH]| {
            const GRID: f64 = 16_777_216.0;
            for l in 0..WIDTH {
                out[l] = (hi[l] as f64 * GRID).round() / GRID + lo[l] as f64 / GRID;
            }
        };
        let e = lanes_match(rounded).unwrap_err();
        eprintln!("caught: {e}");
    }
}

#[cfg(test)]
mod gather_records_tests {
    use super::*;

    /// Distinct values per (lane, field), NaN payloads and negative zero included, so a field
    /// or lane out of place, or a value changed by a float operation, shows.
    fn record(lane: usize) -> LaneRecord {
        LaneRecord(std::array::from_fn(|k| match (lane + k) % 7 {
            0 => -0.0,
            1 => f32::from_bits(0x7fc0_0000 | (lane * 16 + k) as u32),
            _ => (lane * 100 + k) as f32 + 0.25,
        }))
    }

    /// Every ISA's gather is the field-by-field copy, bit for bit, whichever records the lanes
    /// share; the control (the lanes' records in the wrong order) is caught.
    #[test]
    fn gather_is_the_lane_by_lane_copy_on_every_isa() {
        let table: Vec<LaneRecord> = (0..WIDTH).map(record).collect();
        let bits = |r: &LaneRecords| r.map(|row| row.map(f32::to_bits));
        for pick in [
            std::array::from_fn(|l| l),
            std::array::from_fn(|l| (l * 5 + 3) % WIDTH),
            [7; WIDTH],
        ] {
            let rows: [&LaneRecord; WIDTH] = std::array::from_fn(|l| &table[pick[l]]);
            let want: LaneRecords = std::array::from_fn(|k| std::array::from_fn(|l| rows[l].0[k]));
            for isa in Isa::available() {
                let mut got = [[1.0; WIDTH]; LANE_RECORD];
                gather_records(isa, &rows, &mut got);
                assert_eq!(bits(&got), bits(&want), "{isa:?}, lanes' records {pick:?}");
                // Control: the lanes' records reversed must not pass.
                let mut reversed = rows;
                reversed.reverse();
                if pick != [7; WIDTH] {
                    gather_records(isa, &reversed, &mut got);
                    assert_ne!(bits(&got), bits(&want), "control, {isa:?}");
                }
            }
        }
    }
}
