//! Strategies that sample a direction and find the emitter it reaches: uniform hemisphere
//! (pdf 1/2π), cosine hemisphere (pdf cos θ/π) and BSDF sampling (the material's lobe
//! mixture, by the strategy's [`BsdfSampling`] part: lobe selection and GGX sampler).
//! Estimator f·Le·cos θ / pdf. None of them can reach a delta light.

use super::{
    EmissionProbe, Estimator, ProbePacket, Probes, ShadingLanes, ShadingPacket, ShadingPoint,
    Strategy,
};
use crate::bsdf::lambert::diffuse_lanes;
use crate::bsdf::{
    BsdfSampling, CosineLanes, CosineQuery, FrameRows, directions_to_world, sample_cosine_lanes,
};
use crate::geometry::Ray;
use crate::prepare::SceneView;
use crate::sampling::warp::{
    UNIFORM_HEMISPHERE_PDF, cosine_hemisphere_pdf, sample_cosine_hemisphere,
    sample_uniform_hemisphere,
};
use crate::sampling::{Dimension, Dims, Layout, PacketDims};
use crate::simd::{self, Isa, Lanes, Soa3, V3, Vector, WIDTH};

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DirectionKind {
    UniformHemisphere,
    CosineHemisphere,
    Bsdf,
}

impl DirectionKind {
    pub const ALL: [DirectionKind; 3] = [
        DirectionKind::UniformHemisphere,
        DirectionKind::CosineHemisphere,
        DirectionKind::Bsdf,
    ];
}

/// The BSDF-sampling part of a layout: the direction in the lobe, then the lobe.
pub const BSDF_DIMS: [Dimension; 2] = [
    Dimension::pair("bsdf direction"),
    Dimension::one("bsdf lobe"),
];

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct DirectionSampling {
    pub kind: DirectionKind,
    /// How `bsdf` picks a lobe and samples a microfacet lobe (unused by the hemisphere
    /// samplers, which keep the default).
    pub sampling: BsdfSampling,
}

impl DirectionSampling {
    pub fn new(kind: DirectionKind) -> Self {
        DirectionSampling {
            kind,
            sampling: BsdfSampling::default(),
        }
    }

    /// BSDF sampling with `sampling`: `bsdf` + its name suffix (`bsdf-ggx-ndf`, ...).
    pub fn bsdf(sampling: BsdfSampling) -> Self {
        DirectionSampling {
            kind: DirectionKind::Bsdf,
            sampling,
        }
    }
}

/// Why no direction-sampling strategy applies, if none does.
pub fn direction_sampling_applies(scene: &SceneView) -> Result<(), String> {
    if scene.lights.has_delta() {
        return Err(
            "the scene has a point, spot or directional light, which no sampled direction can hit"
                .into(),
        );
    }
    if !scene.has_emitting_surface() && scene.lights.environment().is_none() {
        return Err("the scene has no emitting surface and no environment".into());
    }
    Ok(())
}

impl Strategy for DirectionSampling {
    fn name(&self) -> String {
        match self.kind {
            DirectionKind::UniformHemisphere => "uniform".into(),
            DirectionKind::CosineHemisphere => "cosine".into(),
            DirectionKind::Bsdf => format!("bsdf{}", self.sampling.name_suffix()),
        }
    }

    fn describe(&self) -> String {
        match self.kind {
            DirectionKind::UniformHemisphere => {
                "uniform hemisphere directions, emission of the first hit"
            }
            DirectionKind::CosineHemisphere => {
                "cosine-weighted hemisphere directions, emission of the first hit"
            }
            DirectionKind::Bsdf => {
                return format!(
                    "BSDF-sampled directions ({}), emission of the first hit",
                    self.sampling.describe()
                );
            }
        }
        .into()
    }

    fn bind<'s>(&self, scene: SceneView<'s>) -> Result<Box<dyn Estimator + 's>, String> {
        direction_sampling_applies(&scene)?;
        if self.kind == DirectionKind::Bsdf
            && scene.world.materials.iter().all(|b| b.is_cosine_sampled())
        {
            return Err("identical to `cosine`: every material is Lambertian".into());
        }
        if let Some(why) = self.sampling.same_as_default(&scene.world.materials) {
            return Err(format!("identical to `bsdf`: {why}"));
        }
        Ok(Box::new(DirectionEstimator {
            strategy: *self,
            isa: Isa::detect().unwrap_or(Isa::Portable),
        }))
    }
}

struct DirectionEstimator {
    strategy: DirectionSampling,
    isa: Isa,
}

impl Estimator for DirectionEstimator {
    fn layout(&self) -> Layout {
        match self.strategy.kind {
            DirectionKind::Bsdf => Layout::of(&BSDF_DIMS),
            _ => Layout::of(&[Dimension::pair("direction")]),
        }
    }

    fn sample(&self, sp: &ShadingPoint, u: &mut Dims) -> Probes {
        let (wi, pdf) = match self.strategy.kind {
            DirectionKind::UniformHemisphere => (
                sp.bsdf
                    .frame
                    .to_world(sample_uniform_hemisphere(u.get_2d())),
                UNIFORM_HEMISPHERE_PDF,
            ),
            DirectionKind::CosineHemisphere => {
                let local = sample_cosine_hemisphere(u.get_2d());
                (
                    sp.bsdf.frame.to_world(local),
                    cosine_hemisphere_pdf(local.z),
                )
            }
            DirectionKind::Bsdf => {
                let s = sp.bsdf.sample(u.get_3d(), self.strategy.sampling);
                return emission_probe_with(sp, s.wi, s.f, s.pdf);
            }
        };
        emission_probe(sp, wi, pdf)
    }

    /// [`Self::sample`] for a packet, bit for bit: cosine-hemisphere directions (every lane of
    /// `cosine`, the lanes of cosine-sampled materials for `bsdf`) are drawn and taken to world
    /// space over lanes; f, the pdf and the rest lane by lane.
    fn sample_packet(&self, packet: &ShadingPacket, u: &mut PacketDims, out: &mut ProbePacket) {
        match self.strategy.kind {
            DirectionKind::UniformHemisphere => {
                for (lane, sp) in packet.points() {
                    out.set(lane, self.sample(&sp, &mut u.lane(lane)));
                }
                u.skip(2);
            }
            DirectionKind::CosineHemisphere => {
                let [u0, u1] = u.take::<2>();
                if packet.mask == 0 {
                    return;
                }
                let q = cosine_query(packet, [u0, u1]);
                let r = sample_cosine_lanes(self.isa, &q);
                for (lane, sp) in packet.points() {
                    let (wi, pdf) = (r.wi.get(lane), cosine_hemisphere_pdf(r.z[lane]));
                    if sp.n.dot(wi) > 0.0 && pdf > 0.0 {
                        let f = sp.bsdf.eval_local(r.local.get(lane));
                        out.set(lane, emission_probe_with(&sp, wi, f, pdf));
                    }
                }
            }
            DirectionKind::Bsdf => {
                bsdf_emission_packet(self.isa, packet, u, self.strategy.sampling, out)
            }
        }
    }
}

/// What [`sample_cosine_lanes`] needs for the points of `packet`, with sample numbers `u`:
/// the frames' rows as they are.
#[inline(always)]
fn cosine_query(packet: &ShadingPacket, u: [&[f32; WIDTH]; 2]) -> CosineQuery {
    CosineQuery {
        s: packet.geo.s,
        t: packet.geo.t,
        n: packet.geo.n,
        u: [*u[0], *u[1]],
    }
}

/// The emission probe of `sp.bsdf.sample(u.get_3d(), sampling)` for each lane of a packet,
/// bit for bit, written into `out` (the probes of [`emission_probe_with`]): lanes whose
/// material is cosine-sampled draw their directions over lanes ([`sample_cosine_lanes`]: the
/// lobe drawn by u[2] does not change the direction), the others over lanes once per material
/// (`Bsdf::sample_local_lanes`). Diffuse lanes
/// (a material of one built-in Lambert lobe) finish over lanes too, f = kd/π and pdf = cos/π
/// with the scalar path's operations ([`DiffuseProbes`]); the others evaluate f and the
/// mixture pdf over lanes, once per material ([`probe_lanes`]).
#[inline(always)]
pub fn bsdf_emission_packet(
    isa: Isa,
    packet: &ShadingPacket,
    u: &mut PacketDims,
    sampling: BsdfSampling,
    out: &mut ProbePacket,
) {
    let [u0, u1, u2] = u.take::<3>();
    let (mut cosine, mut diffuse, mut other) = (0u32, 0u32, 0u32);
    let mut kd = Soa3::default();
    let mut rest = packet.mask;
    while rest != 0 {
        let lane = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        let Some(bsdf) = packet.bsdf[lane] else {
            continue;
        };
        if let Some(k) = bsdf.diffuse() {
            diffuse |= 1 << lane;
            kd.set(lane, k);
        } else if bsdf.is_cosine_sampled() {
            cosine |= 1 << lane;
        } else {
            other |= 1 << lane;
        }
    }
    if other != 0 {
        // The other lanes' directions over lanes, once per material, then f and the pdf.
        let geo = &packet.geo;
        let (mut sampled, mut wi, mut local) = (Soa3::default(), Soa3::default(), Soa3::default());
        packet.each_material(other, |bsdf, lanes| {
            let u = [u0, u1, u2];
            bsdf.sample_local_lanes(isa, &geo.wo_local, u, sampling, lanes, &mut sampled);
        });
        let frames = FrameRows {
            s: &geo.s,
            t: &geo.t,
            n: &geo.n,
        };
        directions_to_world(isa, frames, &sampled, other, (&mut wi, &mut local));
        probe_lanes(isa, packet, other, (&wi, &local), sampling, out);
    }
    if cosine | diffuse == 0 {
        return;
    }
    let r = sample_cosine_lanes(isa, &cosine_query(packet, [u0, u1]));
    probe_lanes(isa, packet, cosine, (&r.wi, &r.local), sampling, out);
    if diffuse != 0 {
        simd::run(
            isa,
            DiffuseProbes {
                r: &r,
                kd: &kd,
                geo: &packet.geo,
                mask: diffuse,
                out,
            },
        );
    }
}

/// The emission probes of the lanes of `mask` from their sampled directions (`wi` in the
/// world, `local` in the shading frame, as `LocalBsdf::sample` rounds them): f and the
/// mixture pdf over lanes once per material, then the probes over lanes ([`EmissionProbes`]).
#[inline(always)]
fn probe_lanes(
    isa: Isa,
    packet: &ShadingPacket,
    mask: u32,
    (wi, local): (&Soa3, &Soa3),
    sampling: BsdfSampling,
    out: &mut ProbePacket,
) {
    if mask == 0 {
        return;
    }
    let (mut f, mut pdf) = (Soa3::default(), [0.0f32; WIDTH]);
    let wo = &packet.geo.wo_local;
    packet.each_material(mask, |bsdf, lanes| {
        bsdf.eval_lanes(isa, wo, local, lanes, &mut f);
        bsdf.pdf_lanes(isa, wo, local, sampling, lanes, &mut pdf);
    });
    simd::run(
        isa,
        EmissionProbes {
            wi,
            f: &f,
            pdf: &pdf,
            geo: &packet.geo,
            mask: mask & packet.mask,
            out,
        },
    );
}

/// The emission probes of the lanes of `mask` for directions `wi` with f and pdf known, over
/// lanes ([`store_emission_probes`]).
struct EmissionProbes<'a> {
    wi: &'a Soa3,
    f: &'a Soa3,
    pdf: &'a [f32; WIDTH],
    geo: &'a ShadingLanes,
    mask: u32,
    out: &'a mut ProbePacket,
}

impl simd::Kernel for EmissionProbes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (wi, f, pdf) = (V3::load(self.wi), V3::load(self.f), L::V::load(self.pdf));
        store_emission_probes(self.geo, self.mask, wi, f, pdf, self.out);
    }
}

/// The emission probes of diffuse lanes `mask` over lanes: f and the pdf by
/// [`diffuse_lanes`], then [`store_emission_probes`].
struct DiffuseProbes<'a> {
    r: &'a CosineLanes,
    kd: &'a Soa3,
    geo: &'a ShadingLanes,
    mask: u32,
    out: &'a mut ProbePacket,
}

impl simd::Kernel for DiffuseProbes<'_> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let (wi, local) = (
            V3::<L::V>::load(&self.r.wi),
            V3::<L::V>::load(&self.r.local),
        );
        let (f, pdf) = diffuse_lanes(V3::load(self.kd), local.z);
        store_emission_probes(self.geo, self.mask, wi, f, pdf, self.out);
    }
}

/// [`emission_probe_from`] for the lanes of `mask`, each scalar operation in its order (no
/// probe where n·wi ≤ 0 or pdf ≤ 0, else the ray from the point's origin along wi with weight
/// f·(n·wi/pdf)), so every lane is its scalar probe bit for bit; other lanes kept.
#[inline(always)]
fn store_emission_probes<V: Vector<WIDTH>>(
    geo: &ShadingLanes,
    mask: u32,
    wi: V3<V>,
    f: V3<V>,
    pdf: V,
    out: &mut ProbePacket,
) {
    let zero = V::splat(0.0);
    let cos = V3::<V>::load(&geo.n).dot(wi);
    let ok = mask & !cos.le(zero) & !pdf.le(zero);
    let weight = f.scale(cos.div(pdf));
    let e = &mut out.emission;
    let origin = V3::<V>::load(&geo.origin);
    let rows: [(&mut [f32; WIDTH], V); 7] = [
        (&mut e.ox, origin.x),
        (&mut e.oy, origin.y),
        (&mut e.oz, origin.z),
        (&mut e.dx, wi.x),
        (&mut e.dy, wi.y),
        (&mut e.dz, wi.z),
        (&mut e.tmax, V::splat(f32::INFINITY)),
    ];
    for (row, v) in rows {
        V::select(ok, v, V::load(row)).store(row);
    }
    V3::select(ok, weight, V3::load(&out.emission_weight)).store(&mut out.emission_weight);
    V::select(ok, pdf, V::load(&out.emission_pdf)).store(&mut out.emission_pdf);
    out.emission_mask = (out.emission_mask & !mask) | ok;
}

/// The emission probe for a direction sampled with solid-angle pdf `pdf`; nothing for
/// directions below the surface or of zero pdf (measure-zero or outside the support: no
/// contribution, and no division by zero).
pub fn emission_probe(sp: &ShadingPoint, wi: glam::Vec3, pdf: f32) -> Probes {
    let cos = sp.n.dot(wi);
    if cos <= 0.0 || pdf <= 0.0 {
        return Probes::default();
    }
    emission_probe_with(sp, wi, sp.bsdf.eval(wi), pdf)
}

/// As [`emission_probe`] with f(wi) already known (a BSDF sample carries it).
pub fn emission_probe_with(sp: &ShadingPoint, wi: glam::Vec3, f: glam::Vec3, pdf: f32) -> Probes {
    emission_probe_from(sp.origin, sp.n, wi, f, pdf)
}

/// [`emission_probe_with`] for the point whose rays leave from `origin`, normal `n`.
#[inline(always)]
fn emission_probe_from(
    origin: glam::Vec3,
    n: glam::Vec3,
    wi: glam::Vec3,
    f: glam::Vec3,
    pdf: f32,
) -> Probes {
    let cos = n.dot(wi);
    if cos <= 0.0 || pdf <= 0.0 {
        return Probes::default();
    }
    let weight = f * (cos / pdf);
    Probes {
        shadow: None,
        emission: Some(EmissionProbe {
            ray: Ray::new(origin, wi, f32::INFINITY),
            weight,
            pdf,
        }),
    }
}
