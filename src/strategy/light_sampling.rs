//! Light sampling: a light chosen by the strategy's selector, a point on it by the method the
//! strategy uses for its shape, and one shadow ray. Estimator f·L·cos θ / (pmf·pdf_ω).
//! `light` uses the lecture's basic samplers; each variant overrides one shape's sampler or
//! pins the environment's representation and sampler.

use super::{
    Estimator, Integrand, ProbePacket, Probes, ShadingLanes, ShadingPacket, ShadingPoint,
    ShadowProbe, Strategy, env_method_name,
};
use crate::bsdf::BsdfSampling;
use crate::bsdf::lambert::diffuse_lanes;
use crate::env::EnvMethod;
use crate::geometry::Ray;
use crate::lights::selector::{LightSelector, SelectorType, default_selector};
use crate::lights::{
    LANE_RECORD, LaneKernel, LaneQuery, LaneRecord, LaneRecords, LaneSamples, MIN_PDF_KERNEL_LANES,
    SHADOW_EPSILON, gather_records, selection_numbers,
};
use crate::lights::{
    LightHit, LightMethods, LightSample, LightSet, LightShape, MethodOverride, SurfaceLanes,
    lanes_holding,
};
use crate::math::offset_ray_origin_lanes;
use crate::prepare::SceneView;
use crate::sampling::{Dimension, Dims, Layout, PacketDims};
use crate::simd::{self, Isa, Lanes, Soa3, V3, Vector, WIDTH};
use crate::tracer::LANES;
use glam::Vec3;

/// The light-sampling part of a layout: which light, where on it, and a third number for
/// lights with parts (a mesh's triangle).
pub const LIGHT_DIMS: [Dimension; 3] = [
    Dimension::one("light selection"),
    Dimension::pair("light point"),
    Dimension::one("light part"),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightSampling {
    /// The one shape whose basic sampler this variant replaces.
    pub method: Option<MethodOverride>,
    /// The environment representation and sampler this variant pins (its integrand is that
    /// representation's); None: the integrand's default, lat/long by CDF.
    pub env: Option<EnvMethod>,
    pub selector: &'static SelectorType,
}

impl LightSampling {
    pub fn basic() -> Self {
        LightSampling {
            method: None,
            env: None,
            selector: default_selector(),
        }
    }

    pub fn with_override(o: MethodOverride) -> Self {
        LightSampling {
            method: Some(o),
            ..Self::basic()
        }
    }

    pub fn with_selector(selector: &'static SelectorType) -> Self {
        LightSampling {
            selector,
            ..Self::basic()
        }
    }

    pub fn env(m: EnvMethod) -> Self {
        LightSampling {
            env: Some(m),
            ..Self::basic()
        }
    }

    pub fn methods(&self) -> LightMethods {
        let mut m = LightMethods::BASIC;
        if let Some(o) = self.method {
            m = o.apply(m);
        }
        if let Some(e) = self.env {
            m.env = e;
        }
        m
    }
}

/// Light sampling as bound to a scene: the lights, the selector built over them, and the
/// methods resolved once for this scene and integrand.
pub struct BoundLights<'s> {
    pub lights: &'s LightSet,
    /// Each light's kernel over lanes for these methods ([`Light::lane_record`]), asked once
    /// at bind: a packet reads a lane's kernel and record from here instead of a dynamic call
    /// per lane (5 % of a mesh_light pass; docs/tracer.md, stop 47).
    kernels: Vec<Option<&'static LaneKernel>>,
    /// Each light's record, one cache line each, read whole by [`gather_records`]
    /// ([`LaneRecord::ZERO`] for lights without a kernel).
    records: Vec<LaneRecord>,
    pub selector: &'s dyn LightSelector,
    pub methods: LightMethods,
    /// The lane layer's instruction set for [`Self::probe_packet`] (every ISA gives the same
    /// bits; `DIBENCH_ISA` picks one).
    pub isa: Isa,
}

/// What [`BoundLights::probe`] returns for one shading point: the shadow probe with its
/// unweighted value, the light sample (pdf with the selection's), its direction in the shading
/// frame, and the light's index.
pub type LightProbe = (ShadowProbe, LightSample, Vec3, usize);

/// The packet's per-lane inputs to the shadow-ray kernel, beside the light samples: the
/// selection pmfs and the points' lanes (origins and frames).
struct ShadowLanes<'a> {
    pmf: [f32; WIDTH],
    geo: &'a ShadingLanes,
}

/// The shadow-ray kernel's results: `valid` lanes have a probe.
#[derive(Default)]
struct ShadowRays {
    valid: u32,
    dir: Soa3,
    tmax: [f32; WIDTH],
    local: Soa3,
    pdf: [f32; WIDTH],
    /// cos θ / pdf, the factor of f·L in the estimate.
    factor: [f32; WIDTH],
}

/// The rest of [`BoundLights::probe`] after the light sample, over lanes: the cosine, the
/// shadow segment ([`LightSample::shadow_ray`]), the direction in the shading frame, the pdf
/// with the selection's and cos θ / pdf, in the scalar code's operations and order.
#[inline(always)]
fn shadow_lanes<V: Vector<WIDTH>>(q: &LaneQuery, ls: &LaneSamples, x: &ShadowLanes) -> ShadowRays {
    let zero = V::splat(0.0);
    let wi = V3::<V>::load(&ls.wi);
    let pdf = V::load(&ls.pdf).mul(V::load(&x.pmf));
    let cos = V3::load(q.n).dot(wi);
    let mut valid = ls.valid & !cos.le(zero);
    let distant = ls.distant;
    let unbounded = V::splat(f32::INFINITY);
    // Only the valid lanes' rays are read. Where they are all distant (an environment or a
    // directional light), none has an end point: the segment below, the end point's offset
    // and a division by the distance, would be thrown away by the selects.
    let (dir, tmax) = if valid & !distant == 0 {
        (wi, unbounded)
    } else {
        let origin = V3::load(&x.geo.origin);
        let point = V3::load(&ls.point);
        let normal = V3::load(&ls.normal);
        let facing = zero.le(normal.dot(origin - point));
        let towards = V3::select(facing, normal, -normal);
        let target = offset_ray_origin_lanes(point, V3::load(&ls.point_error), towards);
        let d = target - origin;
        let dist = d.dot(d).sqrt();
        valid &= distant | !dist.eq(zero);
        let tmax = dist.mul(V::splat(1.0 - SHADOW_EPSILON));
        (
            V3::select(distant, wi, d / dist),
            V::select(distant, unbounded, tmax),
        )
    };
    let local = V3 {
        x: wi.dot(V3::load(&x.geo.s)),
        y: wi.dot(V3::load(&x.geo.t)),
        z: cos,
    };
    let mut out = ShadowRays {
        valid,
        ..ShadowRays::default()
    };
    dir.store(&mut out.dir);
    tmax.store(&mut out.tmax);
    local.store(&mut out.local);
    pdf.store(&mut out.pdf);
    cos.div(pdf).store(&mut out.factor);
    out
}

/// Each shadow lane's unweighted value f·L·cos θ/pdf, handed to `each(lane, local, value)`
/// with the direction in the lane's shading frame. f is evaluated over lanes, once for each
/// material among the lanes ([`Bsdf::eval_lanes`]: a pixel's samples mostly share one), from
/// the packet's rows (no point is built).
#[inline(always)]
fn shadow_values(
    isa: Isa,
    packet: &ShadingPacket,
    r: &ShadowRays,
    ls: &LaneSamples,
    valid: u32,
    mut each: impl FnMut(usize, Vec3, Vec3),
) {
    let mut f = Soa3::default();
    packet.each_material(valid, |bsdf, lanes| {
        bsdf.eval_lanes(isa, &packet.geo.wo_local, &r.local, lanes, &mut f);
    });
    let mut rest = valid;
    while rest != 0 {
        let lane = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let local = r.local.get(lane);
        let value = f.get(lane) * ls.radiance.get(lane) * r.factor[lane];
        each(lane, local, value);
    }
}

/// How a light sample's value is weighted: 1 for light sampling alone, the MIS weight for
/// MIS, against the BSDF pdf of the sample's direction under [`Self::sampling`] (which the
/// caller works out over lanes, [`crate::bsdf::Bsdf::pdf_lanes`]). The same rule twice: lane
/// by lane, and over lanes for diffuse materials.
pub trait LightWeight {
    /// The BSDF sampling whose pdf the weight is against; None where the weight reads none
    /// (then `p_bsdf` is 0 and not worked out).
    fn sampling(&self) -> Option<BsdfSampling>;
    /// The weight of a light sample of light `light` with pdf `pdf` (selection included)
    /// against the BSDF pdf `p_bsdf` of its direction.
    fn lane(&self, pdf: f32, p_bsdf: f32, light: usize) -> f32;
    /// [`Self::lane`] over lanes for diffuse materials, whose BSDF pdf `p_bsdf` (the cosine
    /// density) is given; `delta` holds the lanes whose light is a delta light. Bit for bit
    /// `lane` in every lane it is asked for.
    fn diffuse_lanes<V: Vector<WIDTH>>(&self, pdf: V, p_bsdf: V, delta: u32) -> V;
    /// Whether [`Self::diffuse_lanes`] reads `delta` (else it is not worked out).
    const READS_DELTA: bool = true;
}

/// Light sampling alone: every weight is 1.
pub struct Unweighted;

impl LightWeight for Unweighted {
    fn sampling(&self) -> Option<BsdfSampling> {
        None
    }

    #[inline(always)]
    fn lane(&self, _: f32, _: f32, _: usize) -> f32 {
        1.0
    }

    #[inline(always)]
    fn diffuse_lanes<V: Vector<WIDTH>>(&self, _: V, _: V, _: u32) -> V {
        V::splat(1.0)
    }

    const READS_DELTA: bool = false;
}

/// The values of diffuse shadow lanes `mask` over lanes: f by [`diffuse_lanes`] times the
/// radiance times cos θ/pdf, then times the weight against [`diffuse_lanes`]' BSDF pdf: the
/// scalar operations in their order, so every lane is its scalar value bit for bit.
struct DiffuseValues<'a, W> {
    r: &'a ShadowRays,
    radiance: &'a Soa3,
    kd: &'a Soa3,
    mask: u32,
    delta: u32,
    weight: &'a W,
    out: &'a mut Soa3,
}

impl<W: LightWeight> simd::Kernel for DiffuseValues<'_, W> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (f, p_bsdf) = diffuse_lanes(V3::<L::V>::load(self.kd), L::V::load(&self.r.local.z));
        let value = (f * V3::load(self.radiance)).scale(L::V::load(&self.r.factor));
        let w = self
            .weight
            .diffuse_lanes::<L::V>(L::V::load(&self.r.pdf), p_bsdf, self.delta);
        V3::select(self.mask, value.scale(w), V3::load(self.out)).store(self.out);
    }
}

impl<'s> BoundLights<'s> {
    /// `methods` as the scene can use them, in the view's environment representation; Err
    /// when the selector cannot select (no light with positive power, too many lights).
    pub fn bind(
        scene: &SceneView<'s>,
        selector: &'static SelectorType,
        methods: LightMethods,
    ) -> Result<Self, String> {
        let selector = scene.lights.selector(selector)?;
        let methods = scene
            .lights
            .usable_methods(methods)
            .with_env_repr(scene.env);
        let (kernels, records) = (0..scene.lights.len())
            .map(|i| match scene.lights.get(i).lane_record(&methods) {
                Some((k, r)) => (Some(k), LaneRecord(r)),
                None => (None, LaneRecord::ZERO),
            })
            .unzip();
        Ok(BoundLights {
            lights: scene.lights,
            kernels,
            records,
            isa: Isa::detect().unwrap_or(Isa::Portable),
            selector,
            methods,
        })
    }

    /// The light-sampled part of an estimate (shared with MIS): the unweighted value
    /// f·L·cos/pdf with its shadow ray, the light sample (its direction also in the shading
    /// frame) and the light's index; or None.
    pub fn probe(&self, sp: &ShadingPoint, u: &mut Dims) -> Option<LightProbe> {
        let u_select = u.get_1d();
        let ul = u.get_3d();
        let (light, ls) =
            self.lights
                .sample(self.selector, &sp.light_ctx(), u_select, ul, &self.methods)?;
        let cos = sp.n.dot(ls.wi);
        if cos <= 0.0 {
            return None;
        }
        let ray = ls.shadow_ray(sp.origin)?;
        let local = sp.bsdf.to_local(ls.wi);
        let value = sp.bsdf.eval_local(local) * ls.radiance * (cos / ls.pdf);
        Some((ShadowProbe { ray, value }, ls, local, light))
    }

    /// [`Self::probe`] for a packet of shading points, bit for bit: the lights are chosen lane
    /// by lane, each chosen light samples its lanes at once ([`Light::sample_lanes`]), and the
    /// shadow segments, cosines and pdfs are computed over lanes, and f over lanes once per
    /// material ([`crate::bsdf::Bsdf::eval_lanes`]). Lanes without a point are left as they
    /// are.
    pub fn probe_packet(
        &self,
        packet: &ShadingPacket,
        u: &mut PacketDims,
        out: &mut [Option<LightProbe>; LANES],
    ) {
        for (lane, o) in out.iter_mut().enumerate() {
            if packet.mask >> lane & 1 != 0 {
                *o = None;
            }
        }
        self.probe_packet_each(packet, u, |lane, probe| out[lane] = Some(probe));
    }

    /// [`Self::probe_packet`], handing each lane's probe to `emit` (lane, probe) instead of
    /// storing it: a caller that keeps only the shadow probe lets the rest go unbuilt.
    #[inline(always)]
    pub fn probe_packet_each(
        &self,
        packet: &ShadingPacket,
        u: &mut PacketDims,
        mut emit: impl FnMut(usize, LightProbe),
    ) {
        let (mut ls, mut light) = (LaneSamples::default(), [usize::MAX; LANES]);
        let mut records = [[0.0; LANES]; LANE_RECORD];
        let r = self.shadow_rays(packet, u, &mut ls, &mut records, &mut light);
        shadow_values(
            self.isa,
            packet,
            &r,
            &ls,
            r.valid & packet.mask,
            |lane, local, value| {
                let mut sample = ls
                    .get(lane)
                    .expect("a valid shadow lane has a light sample");
                sample.pdf = r.pdf[lane];
                let ray = Ray::new(packet.geo.origin.get(lane), r.dir.get(lane), r.tmax[lane]);
                emit(
                    lane,
                    (ShadowProbe { ray, value }, sample, local, light[lane]),
                );
            },
        );
    }

    /// [`Self::probe_packet`]'s shadow probes written into `out`'s shadow rows (the rays as
    /// the kernel computed them, no lane moved on its own), each value times its
    /// [`LightWeight`] (1 for plain light sampling, the MIS weight for MIS: `value · w`, as the
    /// scalar path's `value *= w`). Diffuse lanes (a material of one built-in Lambert lobe)
    /// evaluate f = kd/π, the value and the weight over lanes, with the scalar operations in
    /// their order ([`DiffuseValues`]); the others evaluate f and the BSDF pdf the weight
    /// reads over lanes once per material, and weigh lane by lane.
    #[inline(always)]
    pub fn probe_packet_rows<W: LightWeight>(
        &self,
        packet: &ShadingPacket,
        u: &mut PacketDims,
        out: &mut ProbePacket,
        weight: &W,
    ) {
        let mut light = [usize::MAX; LANES];
        let (ls, records) = (&mut out.light_samples, &mut out.light_records);
        let r = self.shadow_rays(packet, u, ls, records, &mut light);
        let ls = &out.light_samples;
        let valid = r.valid & packet.mask;
        let (o, origin) = (&mut out.shadow, &packet.geo.origin);
        (o.ox, o.oy, o.oz) = (origin.x, origin.y, origin.z);
        (o.dx, o.dy, o.dz) = (r.dir.x, r.dir.y, r.dir.z);
        o.tmax = r.tmax;
        out.shadow_mask = valid;
        let (mut diffuse, mut delta) = (0u32, 0u32);
        let mut kd = Soa3::default();
        // Whether a light is a delta light, asked once per run of lanes holding it.
        let mut last: Option<(usize, bool)> = None;
        let mut rest = valid;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let Some(k) = packet.bsdf[lane].and_then(|b| b.diffuse()) else {
                continue;
            };
            diffuse |= 1 << lane;
            kd.set(lane, k);
            if !W::READS_DELTA {
                continue;
            }
            let is_delta = match last {
                Some((i, d)) if i == light[lane] => d,
                _ => {
                    let d = self.lights.get(light[lane]).is_delta();
                    last = Some((light[lane], d));
                    d
                }
            };
            delta |= (is_delta as u32) << lane;
        }
        // The other materials' BSDF pdfs, which MIS weighs against, over lanes per material.
        let others = valid & !diffuse;
        let mut p_bsdf = [0.0f32; LANES];
        if let Some(sampling) = weight.sampling() {
            packet.each_material(others, |bsdf, lanes| {
                let wo = &packet.geo.wo_local;
                bsdf.pdf_lanes(self.isa, wo, &r.local, sampling, lanes, &mut p_bsdf);
            });
        }
        shadow_values(self.isa, packet, &r, ls, others, |lane, _, value| {
            let w = weight.lane(r.pdf[lane], p_bsdf[lane], light[lane]);
            out.shadow_value.set(lane, value * w);
        });
        if diffuse != 0 {
            simd::run(
                self.isa,
                DiffuseValues {
                    r: &r,
                    radiance: &ls.radiance,
                    kd: &kd,
                    mask: diffuse,
                    delta,
                    weight,
                    out: &mut out.shadow_value,
                },
            );
        }
    }

    /// The shadow rays of a packet's light samples: the lights chosen lane by lane, each
    /// chosen light sampling its lanes at once, then the segments, cosines and pdfs over lanes.
    #[inline(always)]
    fn shadow_rays(
        &self,
        packet: &ShadingPacket,
        u: &mut PacketDims,
        ls: &mut LaneSamples,
        records: &mut LaneRecords,
        light: &mut [usize; LANES],
    ) -> ShadowRays {
        let [u_select, u0, u1, u2] = u.take::<4>();
        // `ls` may hold an earlier packet's samples (scratch): no lane is valid until a light
        // samples it.
        (ls.valid, ls.distant) = (0, 0);
        // The points and their sample numbers, as rows (no lane is moved on its own).
        let q = LaneQuery {
            p: &packet.p,
            n: &packet.geo.n,
            u: [u0, u1, u2],
        };
        let mut x = ShadowLanes {
            pmf: [0.0; WIDTH],
            geo: &packet.geo,
        };
        let chosen;
        let constant = self.selector.constant();
        // One dynamic call per packet, not per lane, where the choice cannot vary (one light).
        if let Some((i, pmf)) = constant {
            chosen = packet.mask;
            *light = [i; LANES];
            x.pmf = [pmf; WIDTH];
        } else {
            let mut numbers = [0.0f64; LANES];
            selection_numbers(self.isa, u_select, u2, &mut numbers);
            chosen = self
                .selector
                .sample_lanes(&q, &numbers, packet.mask, light, &mut x.pmf);
        }
        // Lights with a kernel over lanes of different lights (mesh triangles, spheres, quads)
        // hand over their records; each such kernel samples all its lanes at once. One light
        // for every lane samples them itself below ([`Light::sample_lanes`], its parameters
        // constants).
        let by_records = if constant.is_some() { 0 } else { chosen };
        let k = self.kernel_lanes(light, by_records);
        let with_kernel = k.mask;
        if with_kernel != 0 {
            gather_records(self.isa, &k.rows, records);
        }
        for_each_kernel(&k.kernels, with_kernel, |kernel, mask| {
            (kernel.sample)(self.isa, records, &q, mask, &self.methods, ls)
        });
        // Each other chosen light samples its lanes at once.
        let mut rest = chosen & !with_kernel;
        while rest != 0 {
            let i = light[rest.trailing_zeros() as usize];
            // One light for every lane holds them all (no lane-by-lane comparison).
            let mask = if constant.is_some() {
                chosen
            } else {
                lanes_holding(light, i) & chosen
            };
            rest &= !mask;
            self.lights
                .get(i)
                .sample_lanes(self.isa, &q, mask, &self.methods, ls);
        }
        struct Kernel<'a>(&'a LaneQuery<'a>, &'a LaneSamples, &'a ShadowLanes<'a>);
        impl simd::Kernel for Kernel<'_> {
            type Out = ShadowRays;
            #[inline(always)]
            fn run<L: Lanes>(self) -> ShadowRays {
                shadow_lanes::<L::V>(self.0, self.1, self.2)
            }
        }
        simd::run(self.isa, Kernel(&q, ls, &x))
    }

    /// The pdf with which [`Self::probe`] samples the direction to point `q` of part `local`
    /// of light `light` (selection included).
    pub fn pdf(&self, sp: &ShadingPoint, light: usize, q: Vec3, local: u32) -> f32 {
        self.lights.pdf(
            self.selector,
            &sp.light_ctx(),
            light,
            LightHit::Surface { q, local },
            &self.methods,
        )
    }

    /// [`Self::pdf`] of the lanes of `active`, lane i's point `at.q[i]` on light `light[i]`
    /// (0 in other lanes), bit for bit: lanes whose lights answer a kernel over records (an
    /// emissive mesh's triangles, each lane its own) through it, all at once; each other
    /// light over the lanes that hit it; then each lane's selection pmf, in the scalar order
    /// (pmf · pdf).
    pub fn pdf_packet(&self, light: &[u32; LANES], at: &SurfaceLanes, active: u32) -> [f32; LANES] {
        let mut pdf = [0.0f32; LANES];
        let mut with_kernel = 0;
        // Where every lane hit one light, it takes them all itself, its parameters constants
        // (no records to gather).
        let first = active.trailing_zeros() as usize;
        if active != 0 && lanes_holding(light, light[first]) & active != active {
            let k = self.kernel_lanes(&light.map(|i| i as usize), active);
            if k.mask.count_ones() >= MIN_PDF_KERNEL_LANES {
                with_kernel = k.mask;
                let mut records = [[0.0; WIDTH]; LANE_RECORD];
                gather_records(self.isa, &k.rows, &mut records);
                for_each_kernel(&k.kernels, k.mask, |kernel, mask| {
                    (kernel.pdf)(self.isa, &records, at, mask, &self.methods, &mut pdf)
                });
            }
        }
        self.lights.pdf_lanes_by_light(
            self.isa,
            light,
            at,
            active & !with_kernel,
            &self.methods,
            &mut pdf,
        );
        for (lane, o) in pdf.iter_mut().enumerate() {
            if active >> lane & 1 != 0 {
                *o *= self.selector.pmf(&at.from.ctx(lane), light[lane] as usize);
            }
        }
        pdf
    }

    /// The lanes of `lanes` whose lights answer a kernel over records ([`Light::lane_record`]),
    /// with each such lane's kernel and record (other lanes get the zero record, which no
    /// kernel reads: each runs only its own lanes).
    #[inline(always)]
    fn kernel_lanes(&self, light: &[usize; LANES], lanes: u32) -> KernelLanes<'_> {
        let mut k = KernelLanes {
            mask: 0,
            kernels: [None; LANES],
            // The caller's rows (a heap record was a malloc and a free per packet: 2.4 % of a
            // mesh_light `light` pass).
            rows: [&LaneRecord::ZERO; LANES],
        };
        let mut rest = lanes;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            if let Some(kernel) = self.kernels[light[lane]] {
                k.rows[lane] = &self.records[light[lane]];
                k.kernels[lane] = Some(kernel);
                k.mask |= 1 << lane;
            }
        }
        k
    }

    /// The pdf with which [`Self::probe`] samples direction `wi` towards the environment.
    pub fn env_pdf(&self, sp: &ShadingPoint, wi: Vec3) -> f32 {
        self.lights
            .env_pdf(self.selector, &sp.light_ctx(), wi, &self.methods)
    }

    /// [`Self::env_pdf`] of the directions `dirs` from the points of lanes `mask` (0 in the
    /// others): the environment's pdf over lanes, each lane's selection pmf after it, in the
    /// scalar order (pmf · pdf).
    pub fn env_pdf_packet(&self, packet: &ShadingPacket, dirs: &Soa3, mask: u32) -> [f32; LANES] {
        let mut out = [0.0f32; LANES];
        let (Some(i), Some(env)) = (self.lights.environment_index(), self.lights.environment())
        else {
            return out;
        };
        let pdf = env
            .map(self.methods.env.repr)
            .pdf_lanes(self.isa, dirs, mask);
        for (lane, o) in out.iter_mut().enumerate() {
            if (mask & packet.mask) >> lane & 1 != 0 {
                *o = self.selector.pmf(&packet.light_ctx(lane), i) * pdf[lane];
            }
        }
        out
    }
}

/// What [`BoundLights::kernel_lanes`] finds: the lanes whose lights have a kernel over records
/// (`mask`), each one's kernel, and each one's record (to gather).
struct KernelLanes<'a> {
    mask: u32,
    kernels: [Option<&'static LaneKernel>; LANES],
    rows: [&'a LaneRecord; LANES],
}

/// `f(kernel, lanes)` once per kernel among `kernels`' lanes `with_kernel`, with the lanes
/// that answer it (kernels are told apart by address, [`LaneKernel::is`]).
#[inline(always)]
fn for_each_kernel(
    kernels: &[Option<&'static LaneKernel>; LANES],
    with_kernel: u32,
    mut f: impl FnMut(&'static LaneKernel, u32),
) {
    let mut rest = with_kernel;
    while rest != 0 {
        let k = kernels[rest.trailing_zeros() as usize].expect("a lane with a kernel");
        let mut mask = 0;
        for (lane, other) in kernels.iter().enumerate() {
            if other.is_some_and(|o| o.is(k)) {
                mask |= 1 << lane;
            }
        }
        rest &= !mask;
        f(k, mask);
    }
}

/// A strategy's name with its light selector appended when it is not the default one:
/// `light@bvh`, `mis-power@uniform`.
pub fn with_selector(base: String, selector: &'static SelectorType) -> String {
    if selector == default_selector() {
        base
    } else {
        format!("{base}@{}", selector.name)
    }
}

/// Why a strategy with a non-default selector adds nothing on this scene, if it does not.
pub fn selector_applies(scene: &SceneView, selector: &'static SelectorType) -> Result<(), String> {
    if selector != default_selector() && scene.lights.len() < 2 {
        return Err(format!(
            "identical to the `{}` selector: the scene has one light",
            default_selector().name
        ));
    }
    Ok(())
}

impl Strategy for LightSampling {
    fn name(&self) -> String {
        let base = match (self.env, self.method) {
            (Some(e), _) => format!("env-{}", env_method_name(e)),
            (None, Some(o)) => format!("light-{}", o.name()),
            (None, None) => "light".into(),
        };
        with_selector(base, self.selector)
    }

    fn describe(&self) -> String {
        match (self.env, self.method) {
            (Some(_), _) => "as `light`, but the environment looked up and sampled in this representation by this sampler (cdf: marginal/conditional, hier: hierarchical warping)".into(),
            (None, Some(o)) => format!("as `light`, but {}", o.describe()),
            (None, None) if self.selector != default_selector() => format!(
                "as `light`, but the light chosen by the `{}` selector: {}",
                self.selector.name, self.selector.describe
            ),
            (None, None) => "power-proportional light choice; quad/mesh: uniform area, sphere: uniform cone, point/spot/directional: exact".into(),
        }
    }

    fn integrand(&self) -> Integrand {
        self.env
            .map_or(Integrand::DIRECT, |e| Integrand::Direct(e.repr))
    }

    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        let bound = BoundLights::bind(&scene, self.selector, self.methods())?;
        selector_applies(&scene, self.selector)?;
        if let Some(o) = self.method {
            if !scene.lights.has(o.shape()) {
                return Err(format!("no {} light", o.shape().name()));
            }
            if o.apply(bound.methods) != bound.methods {
                return Err(format!(
                    "a {} light cannot be sampled this way (spherical-rectangle sampling needs a rectangle)",
                    o.shape().name()
                ));
            }
        }
        match self.env {
            Some(_) if scene.lights.environment().is_none() => {
                return Err("the scene has no environment".into());
            }
            None if self.method.is_none()
                && scene.lights.len() == 1
                && scene.lights.has(LightShape::Environment) =>
            {
                return Err(
                    "identical to `env-latlong-cdf`: the environment is the only light".into(),
                );
            }
            _ => {}
        }
        Ok(Box::new(LightEstimator(bound)))
    }
}

struct LightEstimator<'s>(BoundLights<'s>);

impl Estimator for LightEstimator<'_> {
    fn layout(&self) -> Layout {
        Layout::of(&LIGHT_DIMS)
    }

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        match self.0.probe(sp, u) {
            Some((p, ..)) => Probes::shadow(p),
            None => Probes::default(),
        }
    }

    fn sample_packet(&self, packet: &ShadingPacket, u: &mut PacketDims, out: &mut ProbePacket) {
        self.0.probe_packet_rows(packet, u, out, &Unweighted);
    }
}
