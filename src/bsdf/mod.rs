//! Surface reflectance as a set of lobes, each evaluated and sampled in the local shading
//! frame (z = shading normal, on the viewer's side), one file per lobe (after tray_rust's
//! `bxdf/`). A BSDF samples by first choosing a lobe — the [`LobeSelection`] policy, a part of
//! the strategy — then a direction from that lobe, by the lobe's own sampler (the
//! [`MicrofacetSampler`] part, for lobes that have several); its pdf is the mixture of every
//! lobe's pdf (the lecture's multi-lobe recipe), so any lobe's direction is weighted correctly.
//!
//! Material types (`type` in a scene's `[[material]]`) are registered in [`MATERIALS`], each
//! beside the lobe it builds on; `material` parses and validates their fields.
//!
//! Reflection only: every lobe is zero for directions below the surface (wi.z ≤ 0).

pub mod fresnel;
pub mod material;
pub mod quadrature;

crate::plugin::registry! {
    /// Every material type, in listing order.
    pub static MATERIALS: material::MaterialType = [
        lambert::DIFFUSE,
        phong::PHONG,
        ggx::GGX,
        principled::PRINCIPLED,
    ];
}

pub use crate::sampling::microfacet::MicrofacetSampler;

use crate::math::{Frame, luminance};
use crate::simd::{self, Isa, Lanes, Soa3, V3, Vector, WIDTH};
use glam::Vec3;
use std::sync::Arc;

/// One reflectance lobe in the local shading frame (wo.z > 0 for a point seen from outside;
/// wo.z ≤ 0 only for a point seen exactly edge-on, where a lobe may reflect nothing).
pub trait Lobe: Send + Sync + std::fmt::Debug {
    /// f(wo, wi); zero for wi.z ≤ 0.
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3;

    /// f(wo, wi) when the half vector h = normalize(wo + wi) is known exactly (a quadrature over
    /// half vectors): a lobe that depends on h uses it instead of recovering it from wi, which
    /// near the horizon loses the digits a narrow lobe lives in. Default: [`Self::eval`].
    fn eval_with_half_vector(&self, wo: Vec3, wi: Vec3, _h: Vec3) -> Vec3 {
        self.eval(wo, wi)
    }

    /// [`Self::eval`] of the lanes of `mask` (row `lane` of `wo` and `wi`) added to their rows
    /// of `acc`, bit for bit `acc + eval` per lane; other lanes of `acc` are kept. The default
    /// goes lane by lane; a built-in lobe overrides it with one pass over lanes on `isa`.
    fn add_eval_lanes(&self, isa: Isa, wo: &Soa3, wi: &Soa3, mask: u32, acc: &mut Soa3) {
        let _ = isa;
        let mut rest = mask;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            acc.set(lane, acc.get(lane) + self.eval(wo.get(lane), wi.get(lane)));
        }
    }

    /// `p` times [`Self::pdf`] of the lanes of `mask` added to their entries of `acc`, bit for
    /// bit `acc + p·pdf` per lane; other lanes kept. The default goes lane by lane; a built-in
    /// lobe overrides it with one pass over lanes on `isa`.
    fn add_pdf_lanes(&self, isa: Isa, q: &PdfQuery, p: f32, acc: &mut [f32; WIDTH]) {
        let _ = isa;
        add_pdf_lane_by_lane(self, q, p, acc);
    }

    /// A direction drawn from this lobe's own density [`Self::pdf`] (by `sampler` if the lobe
    /// is a microfacet lobe; other lobes ignore it); it may lie below the surface (f = 0 there),
    /// so the pdf stays a density over the whole sphere.
    fn sample(&self, wo: Vec3, u: [f32; 2], sampler: MicrofacetSampler) -> Vec3;

    /// [`Self::sample`] of the lanes of `q.mask` into their rows of `out`, bit for bit; other
    /// rows kept. The default goes lane by lane; a built-in lobe overrides it with one pass
    /// over lanes on `isa`.
    fn sample_lanes(&self, isa: Isa, q: &SampleQuery, out: &mut Soa3) {
        let _ = isa;
        let mut rest = q.mask;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let u = [q.u[0][lane], q.u[1][lane]];
            out.set(lane, self.sample(q.wo.get(lane), u, q.sampler));
        }
    }

    /// Solid-angle density of [`Self::sample`].
    fn pdf(&self, wo: Vec3, wi: Vec3, sampler: MicrofacetSampler) -> f32;

    /// The lobe's reflectance coefficient: the weight the by-coefficient policy gives it.
    fn coefficient(&self) -> Vec3;

    /// An estimate of the lobe's directional albedo ∫ f cos dωi at `wo`, for the by-albedo
    /// policy: the coefficient unless the lobe knows better (Fresnel at the view angle).
    fn albedo_estimate(&self, _wo: Vec3) -> Vec3 {
        self.coefficient()
    }

    /// [`Self::albedo_estimate`] can differ from the coefficient.
    fn estimates_albedo(&self) -> bool {
        false
    }

    /// Sampling this lobe is cosine-weighted hemisphere sampling (so a strategy can tell when
    /// BSDF sampling would only repeat `cosine`).
    fn is_cosine_sampled(&self) -> bool {
        false
    }

    /// The lobe is sampled by the [`MicrofacetSampler`] it is given.
    fn is_microfacet(&self) -> bool {
        false
    }

    /// The spread (αx, αy) of the lobe's half vectors about the normal, as a GGX roughness: the
    /// scale a quadrature over half vectors must resolve ([1, 1] for a smooth lobe).
    fn half_vector_spread(&self) -> [f32; 2] {
        [1.0, 1.0]
    }
}

/// A built-in lobe's f over lanes: [`Lobe::eval`]'s operations in its order, per lane, so
/// every lane is the scalar value bit for bit. Lanes below the surface compute with finite
/// stand-ins and return 0, as the scalar test does.
pub(crate) trait EvalLanes: Sync {
    fn eval_v<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>) -> V3<V>;
    /// [`Lobe::pdf`] over lanes.
    fn pdf_v<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>, sampler: MicrofacetSampler) -> V;
    /// [`Lobe::sample`] over lanes, written on the scalar sampler's own lane code.
    fn sample_v<V: Vector<WIDTH>>(&self, wo: V3<V>, u: [V; 2], sampler: MicrofacetSampler)
    -> V3<V>;
}

/// Lanes a lobe draws directions for: the views in the shading frame, two sample numbers per
/// lane, the sampler a microfacet lobe draws with, and the lanes.
pub struct SampleQuery<'a> {
    pub wo: &'a Soa3,
    pub u: [&'a [f32; WIDTH]; 2],
    pub sampler: MicrofacetSampler,
    pub mask: u32,
}

/// Lanes whose pdf a lobe is asked for: the directions in the shading frame, the sampler a
/// microfacet lobe draws with, and the lanes.
pub struct PdfQuery<'a> {
    pub wo: &'a Soa3,
    pub wi: &'a Soa3,
    pub sampler: MicrofacetSampler,
    pub mask: u32,
}

/// `acc + p·pdf` lane by lane: [`Lobe::add_pdf_lanes`]' default.
fn add_pdf_lane_by_lane<L: Lobe + ?Sized>(lobe: &L, q: &PdfQuery, p: f32, acc: &mut [f32; WIDTH]) {
    let mut rest = q.mask;
    while rest != 0 {
        let lane = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        acc[lane] += p * lobe.pdf(q.wo.get(lane), q.wi.get(lane), q.sampler);
    }
}

/// [`Lobe::add_pdf_lanes`] of a lobe with [`EvalLanes`]: one pass over lanes on `isa`.
pub(crate) fn add_pdf_lanes<E: EvalLanes>(
    lobe: &E,
    isa: Isa,
    q: &PdfQuery,
    p: f32,
    acc: &mut [f32; WIDTH],
) {
    struct Kernel<'a, E> {
        lobe: &'a E,
        q: &'a PdfQuery<'a>,
        p: f32,
        acc: &'a mut [f32; WIDTH],
    }
    impl<E: EvalLanes> simd::Kernel for Kernel<'_, E> {
        type Out = ();
        #[inline(always)]
        fn run<L: Lanes>(self) {
            let q = self.q;
            let pdf = self
                .lobe
                .pdf_v(V3::<L::V>::load(q.wo), V3::load(q.wi), q.sampler);
            let acc = L::V::load(self.acc);
            L::V::select(q.mask, acc.add(L::V::splat(self.p).mul(pdf)), acc).store(self.acc);
        }
    }
    simd::run(isa, Kernel { lobe, q, p, acc });
}

/// [`Lobe::sample_lanes`] of a lobe with [`EvalLanes`]: one pass over lanes on `isa`.
pub(crate) fn sample_lanes<E: EvalLanes>(lobe: &E, isa: Isa, q: &SampleQuery, out: &mut Soa3) {
    struct Kernel<'a, E> {
        lobe: &'a E,
        q: &'a SampleQuery<'a>,
        out: &'a mut Soa3,
    }
    impl<E: EvalLanes> simd::Kernel for Kernel<'_, E> {
        type Out = ();
        #[inline(always)]
        fn run<L: Lanes>(self) {
            let q = self.q;
            let u = [L::V::load(q.u[0]), L::V::load(q.u[1])];
            let w = self.lobe.sample_v(V3::<L::V>::load(q.wo), u, q.sampler);
            V3::select(q.mask, w, V3::load(self.out)).store(self.out);
        }
    }
    simd::run(isa, Kernel { lobe, q, out });
}

/// [`Lobe::add_eval_lanes`] of a lobe with [`EvalLanes`]: one pass over lanes on `isa`.
pub(crate) fn add_eval_lanes<E: EvalLanes>(
    lobe: &E,
    isa: Isa,
    wo: &Soa3,
    wi: &Soa3,
    mask: u32,
    acc: &mut Soa3,
) {
    struct Kernel<'a, E> {
        lobe: &'a E,
        wo: &'a Soa3,
        wi: &'a Soa3,
        mask: u32,
        acc: &'a mut Soa3,
    }
    impl<E: EvalLanes> simd::Kernel for Kernel<'_, E> {
        type Out = ();
        #[inline(always)]
        fn run<L: Lanes>(self) {
            let f = self
                .lobe
                .eval_v(V3::<L::V>::load(self.wo), V3::load(self.wi));
            let acc = V3::load(self.acc);
            V3::select(self.mask, acc + f, acc).store(self.acc);
        }
    }
    simd::run(
        isa,
        Kernel {
            lobe,
            wo,
            wi,
            mask,
            acc,
        },
    );
}

/// How a BSDF chooses the lobe it samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum LobeSelection {
    /// In proportion to each lobe's coefficient luminance (the lecture's recipe).
    #[default]
    Coefficient,
    /// In proportion to the luminance of each lobe's directional-albedo estimate at the view
    /// direction (Fresnel-weighted; Mitsuba 3's `principled` picks lobes this way).
    Albedo,
}

impl LobeSelection {
    pub const ALL: [LobeSelection; 2] = [LobeSelection::Coefficient, LobeSelection::Albedo];

    pub fn name(self) -> &'static str {
        match self {
            LobeSelection::Coefficient => "select-coefficient",
            LobeSelection::Albedo => "select-albedo",
        }
    }
}

/// The BSDF-sampling part of a strategy: how a lobe is chosen, and which sampler a microfacet
/// lobe draws with. The defaults are dibench's original BSDF sampling (and their names add
/// nothing to a strategy's name).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub struct BsdfSampling {
    pub lobes: LobeSelection,
    pub microfacet: MicrofacetSampler,
}

impl BsdfSampling {
    /// The variants beside the default that the strategy registry lists: each GGX sampler
    /// other than the default, and selection by albedo estimate.
    pub fn variants() -> Vec<BsdfSampling> {
        let mut v: Vec<BsdfSampling> = MicrofacetSampler::ALL
            .into_iter()
            .filter(|&m| m != MicrofacetSampler::default())
            .map(|microfacet| BsdfSampling {
                microfacet,
                ..Default::default()
            })
            .collect();
        v.push(BsdfSampling {
            lobes: LobeSelection::Albedo,
            ..Default::default()
        });
        v
    }

    /// What this part adds to a strategy's name: `-ggx-ndf`, `-select-albedo`, nothing for
    /// the defaults.
    pub fn name_suffix(&self) -> String {
        let mut s = String::new();
        if self.microfacet != MicrofacetSampler::default() {
            s += "-";
            s += self.microfacet.name();
        }
        if self.lobes != LobeSelection::default() {
            s += "-";
            s += self.lobes.name();
        }
        s
    }

    pub fn describe(&self) -> String {
        let lobes = match self.lobes {
            LobeSelection::Coefficient => "lobe chosen by coefficient",
            LobeSelection::Albedo => "lobe chosen by albedo estimate",
        };
        format!("{lobes}, {}", self.microfacet.describe())
    }

    /// Why sampling `materials` this way would repeat the default sampling exactly, if it
    /// would: no lobe uses the microfacet sampler, or no lobe estimates its albedo.
    pub fn same_as_default(&self, materials: &[Bsdf]) -> Option<String> {
        if self.microfacet != MicrofacetSampler::default()
            && !materials.iter().any(Bsdf::has_microfacet)
        {
            return Some("no material has a microfacet (GGX) lobe".into());
        }
        if self.lobes != LobeSelection::default() && !materials.iter().any(Bsdf::estimates_albedo) {
            return Some(
                "no material has several lobes with an albedo estimate apart from its coefficient"
                    .into(),
            );
        }
        None
    }
}

/// A BSDF sample: the world direction with f and the mixture pdf for it.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub wi: Vec3,
    pub f: Vec3,
    pub pdf: f32,
}

/// The most lobes a material may have (selection probabilities live on the stack).
pub const MAX_LOBES: usize = 4;

/// Lobe selection probabilities, in lobe order (zero beyond the lobe count).
type Selection = [f32; MAX_LOBES];

/// A material's lobes. Cheap to clone (the lobes are shared).
#[derive(Clone, Debug)]
pub struct Bsdf {
    lobes: Vec<Arc<dyn Lobe>>,
    /// Selection probabilities by coefficient, in lobe order; the last is 1 − Σ of the others
    /// so that they sum to one exactly.
    by_coefficient: Selection,
    /// Every lobe is cosine-sampled ([`Lobe::is_cosine_sampled`]), so the sampled direction
    /// does not depend on the lobe chosen.
    cosine_sampled: bool,
    /// Some(kd) where the only lobe is the built-in [`lambert::Lambert`] of kd: `eval` and
    /// `pdf` then skip the dynamic call per lobe (it was 2.6 % of a cornell `light` profile,
    /// per lane: docs/tracer.md, stop 36), with the same values.
    diffuse: Option<Vec3>,
}

/// Probabilities proportional to `weights` (non-negative), the last one 1 − Σ of the others;
/// None when they are all zero.
fn normalised(weights: &[f32]) -> Option<Selection> {
    let total: f32 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut p = [0.0; MAX_LOBES];
    let mut acc = 0.0;
    for (i, w) in weights.iter().enumerate() {
        p[i] = if i + 1 == weights.len() {
            1.0 - acc
        } else {
            w / total
        };
        acc += p[i];
    }
    Some(p)
}

impl Bsdf {
    /// A material of 1 to [`MAX_LOBES`] lobes.
    pub fn new(lobes: Vec<Arc<dyn Lobe>>) -> Self {
        assert!(
            !lobes.is_empty() && lobes.len() <= MAX_LOBES,
            "a material has 1 to {MAX_LOBES} lobes, got {}",
            lobes.len()
        );
        let weights: Vec<f32> = lobes.iter().map(|l| luminance(l.coefficient())).collect();
        // No reflectance at all: sample the first lobe (every f is zero anyway).
        let by_coefficient = normalised(&weights).unwrap_or_else(|| {
            let mut p = [0.0; MAX_LOBES];
            p[0] = 1.0;
            p
        });
        Bsdf {
            cosine_sampled: lobes.iter().all(|l| l.is_cosine_sampled()),
            lobes,
            by_coefficient,
            diffuse: None,
        }
    }

    /// Diffuse kd plus normalized-Phong ks with exponent n: the lecture's blend (either part
    /// left out when its coefficient is zero; a black material keeps a black Lambert lobe).
    pub fn blend(kd: Vec3, ks: Vec3, exponent: f32) -> Self {
        Self::blend_with(kd, ks, |ks| Arc::new(phong::Phong { ks, exponent }))
    }

    /// Diffuse kd plus a GGX lobe of coefficient ks: the lecture's "blend microfacet model".
    pub fn blend_ggx(kd: Vec3, ks: Vec3, dist: ggx::Ggx, fresnel: fresnel::Fresnel) -> Self {
        Self::blend_with(kd, ks, |ks| Arc::new(ggx::GgxLobe { ks, dist, fresnel }))
    }

    fn blend_with(kd: Vec3, ks: Vec3, glossy: impl FnOnce(Vec3) -> Arc<dyn Lobe>) -> Self {
        let mut lobes: Vec<Arc<dyn Lobe>> = Vec::new();
        if kd != Vec3::ZERO || ks == Vec3::ZERO {
            lobes.push(Arc::new(lambert::Lambert { kd }));
        }
        if ks != Vec3::ZERO {
            lobes.push(glossy(ks));
        }
        let diffuse = (ks == Vec3::ZERO).then_some(kd);
        Bsdf {
            diffuse,
            ..Self::new(lobes)
        }
    }

    pub fn lambertian(albedo: Vec3) -> Self {
        Self::blend(albedo, Vec3::ZERO, 0.0)
    }

    pub fn lobes(&self) -> &[Arc<dyn Lobe>] {
        &self.lobes
    }

    /// kd when the material is one built-in Lambert lobe of kd (f = kd/π, sampled by cosine):
    /// what callers that evaluate it over lanes need.
    pub fn diffuse(&self) -> Option<Vec3> {
        self.diffuse
    }

    /// BSDF sampling is cosine sampling for this material.
    pub fn is_cosine_sampled(&self) -> bool {
        self.cosine_sampled
    }

    /// Some lobe is sampled by the strategy's [`MicrofacetSampler`].
    pub fn has_microfacet(&self) -> bool {
        self.lobes.iter().any(|l| l.is_microfacet())
    }

    /// Selection by albedo estimate can differ from selection by coefficient.
    pub fn estimates_albedo(&self) -> bool {
        self.lobes.len() > 1 && self.lobes.iter().any(|l| l.estimates_albedo())
    }

    /// The lobe probabilities under `policy` for view `wo`. By albedo they fall back to the
    /// coefficients when every estimate is zero.
    fn selection(&self, policy: LobeSelection, wo: Vec3) -> Selection {
        match policy {
            LobeSelection::Coefficient => self.by_coefficient,
            LobeSelection::Albedo => {
                let mut w = [0.0f32; MAX_LOBES];
                for (w, l) in w.iter_mut().zip(&self.lobes) {
                    *w = luminance(l.albedo_estimate(wo)).max(0.0);
                }
                normalised(&w[..self.lobes.len()]).unwrap_or(self.by_coefficient)
            }
        }
    }

    /// Σ f over the lobes, in the local frame.
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if let Some(kd) = self.diffuse {
            // The sum below over the one lobe, inlined: the same bits.
            return Vec3::ZERO + lambert::Lambert { kd }.eval(wo, wi);
        }
        let mut f = Vec3::ZERO;
        for l in &self.lobes {
            f += l.eval(wo, wi);
        }
        f
    }

    /// [`Self::eval`] of the lanes of `mask` into their rows of `out` (other rows kept), bit
    /// for bit: each lobe's [`Lobe::add_eval_lanes`] in lobe order, from zero, as the scalar
    /// sum (the diffuse shortcut is that sum of its one lobe).
    pub fn eval_lanes(&self, isa: Isa, wo: &Soa3, wi: &Soa3, mask: u32, out: &mut Soa3) {
        for lane in 0..WIDTH {
            if mask >> lane & 1 != 0 {
                out.set(lane, Vec3::ZERO);
            }
        }
        for l in &self.lobes {
            l.add_eval_lanes(isa, wo, wi, mask, out);
        }
    }

    /// [`Self::pdf`] of the lanes of `mask` into their entries of `out` (others kept), bit for
    /// bit: the mixture's terms in lobe order, from zero, each lobe's
    /// [`Lobe::add_pdf_lanes`] with its selection probability (one lobe: probability 1,
    /// `0 + 1·p` being the scalar `0 + p`). Selection by albedo estimate, which depends on
    /// each lane's view, goes lane by lane.
    pub fn pdf_lanes(
        &self,
        isa: Isa,
        wo: &Soa3,
        wi: &Soa3,
        sampling: BsdfSampling,
        mask: u32,
        out: &mut [f32; WIDTH],
    ) {
        if self.lobes.len() > 1 && sampling.lobes == LobeSelection::Albedo {
            let mut rest = mask;
            while rest != 0 {
                let lane = rest.trailing_zeros() as usize;
                rest &= rest - 1;
                out[lane] = self.pdf(wo.get(lane), wi.get(lane), sampling);
            }
            return;
        }
        for (lane, o) in out.iter_mut().enumerate() {
            if mask >> lane & 1 != 0 {
                *o = 0.0;
            }
        }
        let q = PdfQuery {
            wo,
            wi,
            sampler: sampling.microfacet,
            mask,
        };
        if let [l] = &self.lobes[..] {
            l.add_pdf_lanes(isa, &q, 1.0, out);
            return;
        }
        for (l, &p) in self.lobes.iter().zip(&self.by_coefficient) {
            if p > 0.0 {
                l.add_pdf_lanes(isa, &q, p, out);
            }
        }
    }

    /// Mixture pdf of [`Self::sample_local`] under `sampling`, in the local frame.
    pub fn pdf(&self, wo: Vec3, wi: Vec3, sampling: BsdfSampling) -> f32 {
        // One lobe has probability 1 under either policy: the sum below, without the
        // selection (the same bits: 0 + 1·p).
        if let Some(kd) = self.diffuse {
            return 0.0 + lambert::Lambert { kd }.pdf(wo, wi, sampling.microfacet);
        }
        if let [l] = &self.lobes[..] {
            return 0.0 + l.pdf(wo, wi, sampling.microfacet);
        }
        let mut pdf = 0.0;
        for (l, &p) in self.lobes.iter().zip(&self.selection(sampling.lobes, wo)) {
            if p > 0.0 {
                pdf += p * l.pdf(wo, wi, sampling.microfacet);
            }
        }
        pdf
    }

    /// u[2] chooses the lobe, u[0..2] the direction within it; local frame.
    pub fn sample_local(&self, wo: Vec3, u: [f32; 3], sampling: BsdfSampling) -> Vec3 {
        if let [l] = &self.lobes[..] {
            return l.sample(wo, [u[0], u[1]], sampling.microfacet);
        }
        let chosen = self.choose(&self.selection(sampling.lobes, wo), u[2]);
        self.lobes[chosen].sample(wo, [u[0], u[1]], sampling.microfacet)
    }

    /// The lobe that `u` picks from the probabilities `probs` (the last one if rounding leaves
    /// the running sum below u).
    fn choose(&self, probs: &Selection, u: f32) -> usize {
        let mut cdf = 0.0;
        for (i, &p) in probs[..self.lobes.len()].iter().enumerate() {
            cdf += p;
            if u < cdf {
                return i;
            }
        }
        self.lobes.len() - 1
    }

    /// [`Self::sample_local`] of the lanes of `mask` (views `wo`, numbers `u`) into their rows
    /// of `out`, bit for bit; other rows kept. Each lane picks its lobe as the scalar path does;
    /// then each lobe draws its lanes with [`Lobe::sample_lanes`].
    pub fn sample_local_lanes(
        &self,
        isa: Isa,
        wo: &Soa3,
        u: [&[f32; WIDTH]; 3],
        sampling: BsdfSampling,
        mask: u32,
        out: &mut Soa3,
    ) {
        let query = |mask| SampleQuery {
            wo,
            u: [u[0], u[1]],
            sampler: sampling.microfacet,
            mask,
        };
        if let [l] = &self.lobes[..] {
            l.sample_lanes(isa, &query(mask), out);
            return;
        }
        let fixed = (sampling.lobes == LobeSelection::Coefficient).then_some(self.by_coefficient);
        let mut chosen = [0u32; MAX_LOBES];
        let mut rest = mask;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let probs = fixed.unwrap_or_else(|| self.selection(sampling.lobes, wo.get(lane)));
            chosen[self.choose(&probs, u[2][lane])] |= 1 << lane;
        }
        for (l, &lanes) in self.lobes.iter().zip(&chosen) {
            if lanes != 0 {
                l.sample_lanes(isa, &query(lanes), out);
            }
        }
    }
}

/// A BSDF at a surface point: the shading frame, the viewer's direction in it and the material.
/// World-space entry points, so strategies need not transform.
#[derive(Clone, Copy, Debug)]
pub struct LocalBsdf<'a> {
    pub frame: Frame,
    pub wo: Vec3,
    pub bsdf: &'a Bsdf,
}

impl LocalBsdf<'_> {
    /// World direction `wi` in the shading frame.
    pub fn to_local(&self, wi: Vec3) -> Vec3 {
        self.frame.to_local(wi)
    }

    /// f for world direction `wi`.
    pub fn eval(&self, wi: Vec3) -> Vec3 {
        self.bsdf.eval(self.wo, self.frame.to_local(wi))
    }

    /// f for a direction already in the shading frame.
    pub fn eval_local(&self, wi: Vec3) -> Vec3 {
        self.bsdf.eval(self.wo, wi)
    }

    pub fn pdf(&self, wi: Vec3, sampling: BsdfSampling) -> f32 {
        self.bsdf.pdf(self.wo, self.frame.to_local(wi), sampling)
    }

    /// The pdf of a direction already in the shading frame.
    pub fn pdf_local(&self, wi: Vec3, sampling: BsdfSampling) -> f32 {
        self.bsdf.pdf(self.wo, wi, sampling)
    }

    /// A world direction with f and pdf evaluated for the direction as rounded to world space,
    /// so value and density describe the same direction.
    pub fn sample(&self, u: [f32; 3], sampling: BsdfSampling) -> BsdfSample {
        let (wi, local) = self.sample_direction(u, sampling);
        BsdfSample {
            wi,
            f: self.bsdf.eval(self.wo, local),
            pdf: self.bsdf.pdf(self.wo, local, sampling),
        }
    }

    /// [`Self::sample`]'s direction: the world direction and that direction as rounded to
    /// world space, back in the shading frame (where f and the pdf are evaluated).
    pub fn sample_direction(&self, u: [f32; 3], sampling: BsdfSampling) -> (Vec3, Vec3) {
        let wi = self
            .frame
            .to_world(self.bsdf.sample_local(self.wo, u, sampling));
        (wi, self.frame.to_local(wi))
    }
}

/// Cosine-weighted directions for 16 shading frames at once: what [`sample_cosine_lanes`]
/// loads (lanes outside the caller's mask hold anything finite).
#[derive(Clone, Copy, Default)]
pub struct CosineQuery {
    /// The frames' axes.
    pub s: Soa3,
    pub t: Soa3,
    pub n: Soa3,
    /// The two sample numbers of each lane.
    pub u: [[f32; WIDTH]; 2],
}

impl CosineQuery {
    /// Lane `lane` samples in `frame` with numbers `u`.
    #[inline(always)]
    pub fn set(&mut self, lane: usize, frame: &Frame, u: [f32; 2]) {
        self.s.set(lane, frame.s);
        self.t.set(lane, frame.t);
        self.n.set(lane, frame.n);
        self.u[0][lane] = u[0];
        self.u[1][lane] = u[1];
    }
}

/// What [`sample_cosine_lanes`] computes for each lane.
#[derive(Clone, Copy, Default)]
pub struct CosineLanes {
    /// The world direction, `frame.to_world(sample_cosine_hemisphere(u))`.
    pub wi: Soa3,
    /// `frame.to_local(wi)`: the direction as rounded to world space, back in the frame (f and
    /// pdf are evaluated for it, as [`LocalBsdf::sample`] does).
    pub local: Soa3,
    /// z of the sample before the round trip (cos θ of the warp: `cosine`'s pdf).
    pub z: [f32; WIDTH],
}

/// Cosine-weighted hemisphere samples in 16 frames over lanes, bit for bit as the scalar
/// `frame.to_world(sample_cosine_hemisphere(u))` and `frame.to_local` of it: BSDF sampling of
/// every material whose lobes are all cosine-sampled (the direction does not depend on the
/// lobe), and the `cosine` strategy for any material.
pub fn sample_cosine_lanes(isa: Isa, q: &CosineQuery) -> CosineLanes {
    struct Kernel<'a>(&'a CosineQuery);
    impl simd::Kernel for Kernel<'_> {
        type Out = CosineLanes;
        #[inline(always)]
        fn run<L: Lanes>(self) -> CosineLanes {
            let q = self.0;
            let (s, t, n) = (V3::<L::V>::load(&q.s), V3::load(&q.t), V3::load(&q.n));
            let (x, y, z) =
                crate::sampling::warp::cosine_hemisphere(L::V::load(&q.u[0]), L::V::load(&q.u[1]));
            let (wi, local) = to_world_and_back([s, t, n], V3 { x, y, z });
            let mut out = CosineLanes::default();
            wi.store(&mut out.wi);
            local.store(&mut out.local);
            z.store(&mut out.z);
            out
        }
    }
    simd::run(isa, Kernel(q))
}

/// `frame.to_world(v)` and `frame.to_local` of that, over lanes with glam's operations in
/// glam's order (frames as their axes [s, t, n]): a sampled direction as rounded to world
/// space, and that direction back in the frame, where f and the pdf are evaluated (as
/// [`LocalBsdf::sample_direction`] does).
#[inline(always)]
pub fn to_world_and_back<V: Vector<WIDTH>>([s, t, n]: [V3<V>; 3], v: V3<V>) -> (V3<V>, V3<V>) {
    let wi = s.scale(v.x) + t.scale(v.y) + n.scale(v.z);
    let local = V3 {
        x: wi.dot(s),
        y: wi.dot(t),
        z: wi.dot(n),
    };
    (wi, local)
}

/// Frames over lanes: the axes of each lane's shading frame, the rows [`to_world_and_back`]
/// loads.
#[derive(Clone, Copy)]
pub struct FrameRows<'a> {
    pub s: &'a Soa3,
    pub t: &'a Soa3,
    pub n: &'a Soa3,
}

/// [`LocalBsdf::sample_direction`] of the lanes of `mask` whose directions in the frame
/// ([`Bsdf::sample_local_lanes`]) are `local`: their world directions into `wi`, and those
/// back in the frame into `back`, bit for bit; other rows kept.
pub fn directions_to_world(
    isa: Isa,
    frames: FrameRows,
    local: &Soa3,
    mask: u32,
    (wi, back): (&mut Soa3, &mut Soa3),
) {
    struct Kernel<'a> {
        frames: FrameRows<'a>,
        local: &'a Soa3,
        mask: u32,
        wi: &'a mut Soa3,
        back: &'a mut Soa3,
    }
    impl simd::Kernel for Kernel<'_> {
        type Out = ();
        #[inline(always)]
        fn run<L: Lanes>(self) {
            let f = self.frames;
            let axes = [V3::<L::V>::load(f.s), V3::load(f.t), V3::load(f.n)];
            let (w, b) = to_world_and_back(axes, V3::load(self.local));
            V3::select(self.mask, w, V3::load(self.wi)).store(self.wi);
            V3::select(self.mask, b, V3::load(self.back)).store(self.back);
        }
    }
    simd::run(
        isa,
        Kernel {
            frames,
            local,
            mask,
            wi,
            back,
        },
    );
}

/// The χ² cases of BSDF sampling: each material type's, in [`MATERIALS`] order (from the
/// file beside its lobe).
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    MATERIALS.iter().flat_map(|t| (t.chi2_cases)()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where `eval_lanes` on `isa` leaves `eval` for some lane of `mask` (to the bit), or
    /// changes a lane outside it; None when every lane agrees. `perturb` alters the lanes'
    /// result before the comparison (the negative control).
    fn lanes_mismatch(
        bsdf: &Bsdf,
        isa: Isa,
        wo: &Soa3,
        wi: &Soa3,
        mask: u32,
        perturb: impl Fn(&mut Soa3),
    ) -> Option<String> {
        let before = Soa3::splat(Vec3::new(-7.0, 0.5, 3.0));
        let mut out = before;
        bsdf.eval_lanes(isa, wo, wi, mask, &mut out);
        perturb(&mut out);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for lane in 0..WIDTH {
            let want = if mask >> lane & 1 != 0 {
                bsdf.eval(wo.get(lane), wi.get(lane))
            } else {
                before.get(lane)
            };
            if bits(out.get(lane)) != bits(want) {
                return Some(format!(
                    "{}: lane {lane} (wo {}, wi {}): {} against {want}",
                    isa.name(),
                    wo.get(lane),
                    wi.get(lane),
                    out.get(lane)
                ));
            }
        }
        None
    }

    /// Where `pdf_lanes` on `isa` leaves `pdf` for some lane of `mask` (to the bit), or
    /// changes a lane outside it; `perturb` alters the lanes' result first (negative control).
    fn pdf_mismatch(
        bsdf: &Bsdf,
        isa: Isa,
        (wo, wi): (&Soa3, &Soa3),
        sampling: BsdfSampling,
        mask: u32,
        perturb: impl Fn(&mut [f32; WIDTH]),
    ) -> Option<String> {
        let mut out = [-7.5f32; WIDTH];
        bsdf.pdf_lanes(isa, wo, wi, sampling, mask, &mut out);
        perturb(&mut out);
        for (lane, &got) in out.iter().enumerate() {
            let want = if mask >> lane & 1 != 0 {
                bsdf.pdf(wo.get(lane), wi.get(lane), sampling)
            } else {
                -7.5
            };
            if got.to_bits() != want.to_bits() {
                return Some(format!(
                    "{} {:?}: lane {lane} (wo {}, wi {}): {got} against {want}",
                    isa.name(),
                    sampling,
                    wo.get(lane),
                    wi.get(lane)
                ));
            }
        }
        None
    }

    /// Every built-in material kind the lane tests cover: diffuse, Phong blends (lane by lane,
    /// the trait's defaults), GGX blends with each Fresnel (one, Schlick, conductors),
    /// isotropic and anisotropic, α from 1e-4 to 1, and principled materials.
    fn lane_test_materials() -> Vec<Bsdf> {
        let kd = Vec3::new(0.7, 0.4, 0.1);
        let ks = Vec3::new(0.3, 0.5, 0.2);
        let mut materials = vec![
            Bsdf::lambertian(kd),
            Bsdf::blend(kd, ks, 20.0),
            Bsdf::blend(Vec3::ZERO, ks, 300.0),
        ];
        let fresnels = [
            fresnel::Fresnel::One,
            fresnel::Fresnel::Schlick {
                f0: Vec3::new(0.04, 0.5, 0.9),
            },
            fresnel::conductor_preset("gold").unwrap(),
            fresnel::conductor_preset("aluminium").unwrap(),
            fresnel::Fresnel::Conductor {
                eta: Vec3::new(1.0, 1.5, 1.0),
                k: Vec3::new(0.0, 0.0, 2.0),
            },
        ];
        for (i, f) in fresnels.into_iter().enumerate() {
            for (ax, ay) in [(1e-4, 1e-4), (0.0225, 0.0225), (0.25, 0.05), (1.0, 1.0)] {
                let dist = ggx::Ggx { ax, ay };
                let kd = if i % 2 == 0 { Vec3::ZERO } else { kd };
                materials.push(Bsdf::blend_ggx(kd, ks, dist, f));
            }
        }
        for (metallic, specular) in [(0.0, 0.5), (1.0, 0.5), (0.3, 1.0)] {
            materials.push(
                principled::Principled {
                    base: Vec3::new(0.9, 0.6, 0.2),
                    metallic,
                    specular,
                    dist: ggx::Ggx { ax: 0.15, ay: 0.09 },
                }
                .bsdf(),
            );
        }
        materials
    }

    /// Every built-in material's f and mixture pdf over lanes are its scalar ones, bit for
    /// bit, on every ISA, the pdf under every BSDF sampling (each GGX sampler, selection by
    /// coefficient and by albedo estimate):
    /// diffuse, Phong blends (lane by lane, the trait's default), GGX blends with each Fresnel
    /// (one, Schlick, conductors), isotropic and anisotropic, α from 1e-4 to 1, and
    /// principled materials; directions above, below and on the horizon, grazing, mirrored
    /// (wo + wi = 0, no half vector); lanes outside the mask keep what they held. Negative
    /// control: one lane's f or pdf off by an ulp is caught.
    #[test]
    fn eval_and_pdf_lanes_are_the_scalar_ones_on_every_isa() {
        use crate::sampling::stream::SampleStream;
        use crate::sampling::warp::sample_uniform_sphere;
        let materials = lane_test_materials();
        let mut rng = SampleStream::new(11, 2, 4, 1);
        let up = |v: Vec3| Vec3::new(v.x, v.y, v.z.abs());
        let mut checked = 0;
        for round in 0..200 {
            let (mut wo, mut wi) = (Soa3::default(), Soa3::default());
            for lane in 0..WIDTH {
                let a = sample_uniform_sphere(rng.next_2d());
                let b = sample_uniform_sphere(rng.next_2d());
                let (o, i) = match (lane + round) % 8 {
                    0 => (up(a), -up(a)),                                // mirrored: no half vector
                    1 => (up(a), Vec3::new(b.x, b.y, 0.0).normalize()),  // on the horizon
                    2 => (up(a), Vec3::new(b.x, b.y, 1e-4).normalize()), // grazing
                    3 => (Vec3::new(a.x, a.y, 1e-6).normalize(), up(b)),
                    4 => (up(a), up(a)), // the normal's neighbour
                    5 => (a, b),         // either side
                    _ => (up(a), up(b)),
                };
                wo.set(lane, o);
                wi.set(lane, i);
            }
            let mask = match round % 4 {
                0 => u32::from(u16::MAX),
                1 => 0x5a5a,
                2 => 1 << (round % 16),
                _ => (rng.next_2d()[0] * 65536.0) as u32,
            };
            let samplings: Vec<BsdfSampling> = [BsdfSampling::default()]
                .into_iter()
                .chain(BsdfSampling::variants())
                .collect();
            for bsdf in &materials {
                for isa in Isa::available() {
                    let miss = lanes_mismatch(bsdf, isa, &wo, &wi, mask, |_| {});
                    assert!(miss.is_none(), "{}", miss.unwrap());
                    for &sampling in &samplings {
                        let miss = pdf_mismatch(bsdf, isa, (&wo, &wi), sampling, mask, |_| {});
                        assert!(miss.is_none(), "{}", miss.unwrap());
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 1000, "{checked}");
        // Negative control: the comparison resolves one ulp in one lane.
        let (mut wo, mut wi) = (Soa3::default(), Soa3::default());
        for lane in 0..WIDTH {
            wo.set(lane, Vec3::new(0.1, 0.2, 0.97).normalize());
            wi.set(lane, Vec3::new(-0.3, 0.1, 0.9).normalize());
        }
        let ggx = &materials[5];
        assert!(ggx.eval(wo.get(3), wi.get(3)).x > 0.0);
        assert!(ggx.pdf(wo.get(3), wi.get(3), BsdfSampling::default()) > 0.0);
        for isa in Isa::available() {
            let off = |o: &mut Soa3| o.x[3] = f32::from_bits(o.x[3].to_bits() + 1);
            assert!(lanes_mismatch(ggx, isa, &wo, &wi, u32::from(u16::MAX), off).is_some());
            let off = |o: &mut [f32; WIDTH]| o[3] = f32::from_bits(o[3].to_bits() + 1);
            let all = u32::from(u16::MAX);
            let sampling = BsdfSampling::default();
            assert!(pdf_mismatch(ggx, isa, (&wo, &wi), sampling, all, off).is_some());
        }
    }

    /// A diffuse material's shortcut past the dynamic lobe call gives the bits of the lobe
    /// sum it replaces (a material built from the same Lambert lobe through `Bsdf::new`, which
    /// takes no shortcut), above and below the surface; a blend takes no shortcut.
    #[test]
    fn the_diffuse_shortcut_is_the_lobe_sum() {
        let kd = Vec3::new(0.73, 0.05, 0.0);
        let fast = Bsdf::lambertian(kd);
        let slow = Bsdf::new(vec![Arc::new(lambert::Lambert { kd })]);
        assert_eq!(fast.diffuse, Some(kd));
        assert_eq!(slow.diffuse, None);
        assert_eq!(Bsdf::blend(kd, Vec3::splat(0.2), 20.0).diffuse, None);
        let sampling = BsdfSampling::default();
        let wo = Vec3::new(0.3, -0.2, 0.933).normalize();
        let mut checked = 0;
        for i in 0..64 {
            let a = i as f32 * 0.7;
            let wi = Vec3::new(a.cos() * 0.6, a.sin() * 0.6, (i as f32 / 32.0) - 1.0).normalize();
            let bits = |v: Vec3| v.to_array().map(f32::to_bits);
            assert_eq!(bits(fast.eval(wo, wi)), bits(slow.eval(wo, wi)), "{wi}");
            assert_eq!(
                fast.pdf(wo, wi, sampling).to_bits(),
                slow.pdf(wo, wi, sampling).to_bits(),
                "{wi}"
            );
            checked += (wi.z > 0.0) as u32;
        }
        assert!(checked > 10 && checked < 60, "{checked}");
    }

    /// Directional albedo ∫ f cos dω ≤ kd + ks, with equality for the Phong lobe at normal
    /// incidence (the normalization); by Riemann sum over a fine (φ, cos θ) grid.
    #[test]
    fn energy_conservation_and_normalization() {
        let albedo = |b: &Bsdf, wo: Vec3| {
            let (nt, np) = (4000, 64);
            let mut s = 0.0f64;
            for i in 0..nt {
                let c = (i as f64 + 0.5) / nt as f64;
                for j in 0..np {
                    let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                    let st = (1.0 - c * c).sqrt();
                    let wi = Vec3::new((st * phi.cos()) as f32, (st * phi.sin()) as f32, c as f32);
                    s += b.eval(wo, wi).x as f64 * c;
                }
            }
            s * 2.0 * std::f64::consts::PI / (nt * np) as f64
        };
        let phong = Bsdf::blend(Vec3::ZERO, Vec3::ONE, 20.0);
        assert!((albedo(&phong, Vec3::Z) - 1.0).abs() < 2e-3);
        let grazing = Vec3::new(0.8, 0.0, 0.6);
        assert!(albedo(&phong, grazing) < 1.0);
        let blend = Bsdf::blend(Vec3::splat(0.5), Vec3::splat(0.5), 5.0);
        assert!((albedo(&blend, Vec3::Z) - 1.0).abs() < 2e-3);
    }

    /// Cosine samples over lanes are the scalar warp and frame round trip bit for bit, on every
    /// ISA, for frames about normals of every octant.
    #[test]
    fn cosine_lanes_are_the_scalar_samples_on_every_isa() {
        use crate::sampling::warp::sample_cosine_hemisphere;
        let mut checked = 0;
        for k in 0..64u64 {
            let r = |i: u64| (crate::math::mix64(k * 64 + i) >> 40) as f32 / (1u64 << 24) as f32;
            let mut q = CosineQuery::default();
            let mut frames = Vec::new();
            for lane in 0..WIDTH {
                let i = lane as u64 * 4;
                let n = Vec3::new(2.0 * r(i) - 1.0, 2.0 * r(i + 1) - 1.0, 2.0 * r(i + 2) - 1.0)
                    .normalize();
                let frame = Frame::from_normal(n);
                let u = if k == 0 {
                    [lane as f32 / 15.0, 0.5]
                } else {
                    [r(i + 3), r(i + 200)]
                };
                q.set(lane, &frame, u);
                frames.push((frame, u));
            }
            for isa in Isa::available() {
                let got = sample_cosine_lanes(isa, &q);
                for (lane, (frame, u)) in frames.iter().enumerate() {
                    let local = sample_cosine_hemisphere(*u);
                    let wi = frame.to_world(local);
                    assert_eq!(
                        got.wi.get(lane).to_array().map(f32::to_bits),
                        wi.to_array().map(f32::to_bits),
                        "{isa:?}"
                    );
                    assert_eq!(
                        got.local.get(lane).to_array().map(f32::to_bits),
                        frame.to_local(wi).to_array().map(f32::to_bits),
                        "{isa:?}"
                    );
                    assert_eq!(got.z[lane].to_bits(), local.z.to_bits(), "{isa:?}");
                    checked += 1;
                }
            }
        }
        assert!(checked >= 64 * WIDTH);
    }

    /// Where `sample_local_lanes` on `isa` leaves `sample_local` for some lane of `mask` (to
    /// the bit), or changes a lane outside it; `perturb` alters the lanes' result first
    /// (negative control).
    fn sample_mismatch(
        bsdf: &Bsdf,
        isa: Isa,
        (wo, u): (&Soa3, [&[f32; WIDTH]; 3]),
        sampling: BsdfSampling,
        mask: u32,
        perturb: impl Fn(&mut Soa3),
    ) -> Option<String> {
        let before = Soa3::splat(Vec3::new(-7.0, 0.5, 3.0));
        let mut out = before;
        bsdf.sample_local_lanes(isa, wo, u, sampling, mask, &mut out);
        perturb(&mut out);
        let bits = |v: Vec3| v.to_array().map(f32::to_bits);
        for lane in 0..WIDTH {
            let ul = u.map(|row| row[lane]);
            let want = if mask >> lane & 1 != 0 {
                bsdf.sample_local(wo.get(lane), ul, sampling)
            } else {
                before.get(lane)
            };
            if bits(out.get(lane)) != bits(want) {
                return Some(format!(
                    "{} {sampling:?}: lane {lane} (wo {}, u {ul:?}): {} against {want}",
                    isa.name(),
                    wo.get(lane),
                    out.get(lane)
                ));
            }
        }
        None
    }

    /// Every built-in material's BSDF samples over lanes are its scalar samples, bit for bit,
    /// on every ISA, under every BSDF sampling (each GGX sampler; lobes chosen by coefficient
    /// and by albedo estimate): views from the normal to edge-on and below (a GGX lobe returns
    /// −z there), numbers at 0, the quarter turns and 1 − ε as well as random ones; lanes
    /// outside the mask keep what they held. Then the frame round trip over lanes is the
    /// scalar `to_world` and `to_local`. Negative control: one lane off by an ulp is caught.
    #[test]
    fn sample_lanes_are_the_scalar_samples_on_every_isa() {
        use crate::sampling::stream::{ONE_MINUS_EPSILON, SampleStream};
        use crate::sampling::warp::sample_uniform_sphere;
        let materials = lane_test_materials();
        let samplings: Vec<BsdfSampling> = [BsdfSampling::default()]
            .into_iter()
            .chain(BsdfSampling::variants())
            .collect();
        let mut rng = SampleStream::new(12, 3, 5, 2);
        let special = [0.0, 0.25, 0.5, 0.75, ONE_MINUS_EPSILON, 0.125, 1e-7];
        let mut checked = 0;
        for round in 0..120 {
            let mut wo = Soa3::default();
            let mut u = [[0.0f32; WIDTH]; 3];
            for lane in 0..WIDTH {
                let a = sample_uniform_sphere(rng.next_2d());
                let o = match (lane + round) % 6 {
                    0 => Vec3::Z,
                    1 => Vec3::new(a.x, a.y, 0.0).normalize(), // edge-on
                    2 => Vec3::new(a.x, a.y, 1e-6).normalize(), // grazing
                    3 => a,                                    // either side
                    _ => Vec3::new(a.x, a.y, a.z.abs()),
                };
                wo.set(lane, o);
                let r = rng.next_2d();
                let v = rng.next_2d();
                u[0][lane] = if round % 3 == 0 {
                    special[(lane + round) % 7]
                } else {
                    r[0]
                };
                u[1][lane] = if round % 5 == 1 {
                    special[lane % 7]
                } else {
                    r[1]
                };
                u[2][lane] = v[0];
            }
            let mask = match round % 4 {
                0 => u32::from(u16::MAX),
                1 => 0xa5a5,
                2 => 1 << (round % 16),
                _ => (rng.next_2d()[0] * 65536.0) as u32,
            };
            let u = [&u[0], &u[1], &u[2]];
            for bsdf in &materials {
                for isa in Isa::available() {
                    for &sampling in &samplings {
                        let miss = sample_mismatch(bsdf, isa, (&wo, u), sampling, mask, |_| {});
                        assert!(miss.is_none(), "{}", miss.unwrap());
                        checked += 1;
                    }
                }
            }
            // The frame round trip of those directions, in frames about random normals.
            let (mut s, mut t, mut n) = (Soa3::default(), Soa3::default(), Soa3::default());
            let mut local = Soa3::default();
            materials[7].sample_local_lanes(
                Isa::available()[0],
                &wo,
                u,
                BsdfSampling::default(),
                u32::from(u16::MAX),
                &mut local,
            );
            for lane in 0..WIDTH {
                let f = Frame::from_normal(sample_uniform_sphere(rng.next_2d()));
                s.set(lane, f.s);
                t.set(lane, f.t);
                n.set(lane, f.n);
            }
            for isa in Isa::available() {
                let before = Soa3::splat(Vec3::new(2.0, -1.0, 0.5));
                let (mut wi, mut back) = (before, before);
                let frames = FrameRows {
                    s: &s,
                    t: &t,
                    n: &n,
                };
                directions_to_world(isa, frames, &local, mask, (&mut wi, &mut back));
                for lane in 0..WIDTH {
                    let f = Frame {
                        s: s.get(lane),
                        t: t.get(lane),
                        n: n.get(lane),
                    };
                    let w = f.to_world(local.get(lane));
                    let (want_wi, want_back) = if mask >> lane & 1 != 0 {
                        (w, f.to_local(w))
                    } else {
                        (before.get(lane), before.get(lane))
                    };
                    let bits = |v: Vec3| v.to_array().map(f32::to_bits);
                    assert_eq!(bits(wi.get(lane)), bits(want_wi), "{isa:?} lane {lane}");
                    assert_eq!(bits(back.get(lane)), bits(want_back), "{isa:?} lane {lane}");
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
        // Negative control: the comparison resolves one ulp in one lane.
        let wo = Soa3::splat(Vec3::new(0.1, 0.2, 0.97).normalize());
        let uu = [[0.3f32; WIDTH], [0.6f32; WIDTH], [0.9f32; WIDTH]];
        let u = [&uu[0], &uu[1], &uu[2]];
        let ggx = &materials[5];
        for isa in Isa::available() {
            let off = |o: &mut Soa3| o.y[3] = f32::from_bits(o.y[3].to_bits() + 1);
            let all = u32::from(u16::MAX);
            let sampling = BsdfSampling::default();
            assert!(sample_mismatch(ggx, isa, (&wo, u), sampling, all, |_| {}).is_none());
            assert!(sample_mismatch(ggx, isa, (&wo, u), sampling, all, off).is_some());
        }
    }

    /// Selection by coefficient luminance: probabilities sum to one and follow the weights.
    #[test]
    fn selection_by_coefficient() {
        let b = Bsdf::blend(Vec3::splat(0.3), Vec3::splat(0.6), 10.0);
        let p = b.selection(LobeSelection::Coefficient, Vec3::Z);
        assert_eq!(p[2..], [0.0, 0.0]);
        assert!((p[0] - 1.0 / 3.0).abs() < 1e-6 && (p[0] + p[1] - 1.0).abs() < 1e-7);
        assert_eq!(
            Bsdf::lambertian(Vec3::ONE).selection(LobeSelection::Coefficient, Vec3::Z),
            [1.0, 0.0, 0.0, 0.0]
        );
        assert_eq!(Bsdf::lambertian(Vec3::ZERO).lobes().len(), 1);
    }
}
