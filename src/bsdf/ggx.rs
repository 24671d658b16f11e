//! GGX microfacet reflection f = ks·F(wo·h)·D(h)·G2(wo, wi)/(4 cos θo cos θi) with Smith
//! height-correlated masking-shadowing (Walter et al. 2007; Heitz 2014), isotropic or
//! anisotropic, sampled by the strategy's [`MicrofacetSampler`] (distribution, samplers and
//! pdfs in `sampling::microfacet`); and the `ggx` material type: the lecture's "blend
//! microfacet model", a Lambert kd plus this lobe with coefficient ks.

use super::fresnel::{Fresnel, conductor_preset};
use super::material::{MaterialType, Params};
use super::{Bsdf, EvalLanes, Lobe, MicrofacetSampler, PdfQuery, SampleQuery};
use crate::error::Result;
pub use crate::sampling::microfacet::Ggx;
use crate::sampling::microfacet::half_vector;
use crate::simd::{Isa, Soa3, V3, Vector, WIDTH};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GgxLobe {
    /// Coefficient multiplying the lobe (1 for a pure conductor).
    pub ks: Vec3,
    pub dist: Ggx,
    pub fresnel: Fresnel,
}

impl Lobe for GgxLobe {
    fn eval(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        // Both directions above the surface: wo + wi ≠ 0.
        let Some(h) = half_vector(wo, wi) else {
            return Vec3::ZERO;
        };
        self.eval_with_half_vector(wo, wi, h)
    }

    fn eval_with_half_vector(&self, wo: Vec3, wi: Vec3, h: Vec3) -> Vec3 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.ks * self.fresnel.eval(wo.dot(h)) * self.dist.d_g2_over_cosines(wo, wi, h)
    }

    fn add_eval_lanes(&self, isa: Isa, wo: &Soa3, wi: &Soa3, mask: u32, acc: &mut Soa3) {
        super::add_eval_lanes(self, isa, wo, wi, mask, acc);
    }

    fn add_pdf_lanes(&self, isa: Isa, q: &PdfQuery, p: f32, acc: &mut [f32; WIDTH]) {
        super::add_pdf_lanes(self, isa, q, p, acc);
    }

    fn sample(&self, wo: Vec3, u: [f32; 2], sampler: MicrofacetSampler) -> Vec3 {
        if wo.z <= 0.0 {
            // Seen edge-on: the lobe reflects nothing and has zero pdf everywhere; a direction
            // below the surface contributes nothing.
            return Vec3::NEG_Z;
        }
        sampler.sample(&self.dist, wo, u)
    }

    fn sample_lanes(&self, isa: Isa, q: &SampleQuery, out: &mut Soa3) {
        super::sample_lanes(self, isa, q, out);
    }

    fn pdf(&self, wo: Vec3, wi: Vec3, sampler: MicrofacetSampler) -> f32 {
        if wo.z <= 0.0 {
            return 0.0;
        }
        sampler.pdf(&self.dist, wo, wi)
    }

    /// ks times the reflectance at normal incidence.
    fn coefficient(&self) -> Vec3 {
        self.ks * self.fresnel.eval(1.0)
    }

    /// ks·F(cos θo): Fresnel at the view angle, ignoring the masking losses.
    fn albedo_estimate(&self, wo: Vec3) -> Vec3 {
        self.ks * self.fresnel.eval(wo.z)
    }

    fn estimates_albedo(&self) -> bool {
        !self.fresnel.is_one()
    }

    fn is_microfacet(&self) -> bool {
        true
    }

    fn half_vector_spread(&self) -> [f32; 2] {
        [self.dist.ax, self.dist.ay]
    }
}

impl EvalLanes for GgxLobe {
    /// [`Lobe::eval`]: the half vector, then [`Lobe::eval_with_half_vector`].
    #[inline(always)]
    fn eval_v<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>) -> V3<V> {
        let zero = V::splat(0.0);
        let above = !wo.z.le(zero) & !wi.z.le(zero);
        let (ok, wo, wi, h) = half_vector_lanes(above, wo, wi);
        let f = (V3::splat(self.ks) * self.fresnel.eval_lanes(wo.dot(h)))
            .scale(self.dist.d_g2_over_cosines_lanes(wo, wi, h));
        V3::select(ok, f, V3::splat(Vec3::ZERO))
    }

    /// [`Lobe::pdf`]: [`MicrofacetSampler::pdf`] for wo.z > 0, the half vector taken on the
    /// upper side.
    #[inline(always)]
    fn pdf_v<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>, sampler: MicrofacetSampler) -> V {
        let zero = V::splat(0.0);
        let (ok, wo, _, h) = half_vector_lanes(!wo.z.le(zero), wo, wi);
        let h = V3::select(h.z.lt(zero), -h, h);
        let g = &self.dist;
        let (pdf, valid) = match sampler {
            MicrofacetSampler::Ndf => {
                // ggx_ndf_pdf: d(h)·h.z/(4 |wo·h|), 0 where wo·h = 0.
                let c = wo.dot(h).abs();
                let nonzero = !c.eq(zero);
                let c = V::select(nonzero, c, V::splat(1.0));
                (g.d_lanes(h).mul(h.z).div(V::splat(4.0).mul(c)), nonzero)
            }
            _ => {
                // ggx_cap_pdf: 0.5·d(h)/(k·wo.z + t(wo)), 0 unless wo.z, h.z and wo·h are all
                // positive; k = 1 but for the bounded sampler, whose k < 1 also zeroes the
                // half vectors whose cap point lies in the dropped band.
                let one = V::splat(1.0);
                let mut valid = !wo.z.le(zero) & !h.z.le(zero) & !wo.dot(h).le(zero);
                let k = if sampler == MicrofacetSampler::VndfBounded {
                    let k = g.bounded_k_v(wo);
                    valid &= !(k.lt(one) & g.below_cap_v(wo, h, k));
                    k
                } else {
                    one
                };
                let denom = k.mul(wo.z).add(g.stretched_len_lanes(wo));
                (V::splat(0.5).mul(g.d_lanes(h)).div(denom), valid)
            }
        };
        V::select(ok & valid, pdf, zero)
    }

    /// [`Lobe::sample`]: the sampler's own code over lanes; lanes seen edge-on (wo.z ≤ 0)
    /// draw with a stand-in view (+z) and return −z, as the scalar lobe does.
    #[inline(always)]
    fn sample_v<V: Vector<WIDTH>>(&self, wo: V3<V>, u: [V; 2], sampler: MicrofacetSampler) -> V3<V> {
        let above = !wo.z.le(V::splat(0.0));
        let wo = V3::select(above, wo, V3::splat(Vec3::Z));
        let w = sampler.sample_v(&self.dist, wo, u[0], u[1]);
        V3::select(above, w, V3::splat(Vec3::NEG_Z))
    }
}

/// `half_vector(wo, wi)` over lanes for the lanes of `take`: (the lanes of `take` that have
/// one, wo, wi, h), the lanes without one (|wo + wi|² = 0) or outside `take` going on with the
/// normal for both directions, so that every lane's arithmetic stays finite.
#[inline(always)]
fn half_vector_lanes<V: Vector<WIDTH>>(
    take: u32,
    wo: V3<V>,
    wi: V3<V>,
) -> (u32, V3<V>, V3<V>, V3<V>) {
    let s = wo + wi;
    let ok = take & V::splat(0.0).lt(s.dot(s));
    let up = V3::splat(Vec3::Z);
    let (wo, wi) = (V3::select(ok, wo, up), V3::select(ok, wi, up));
    let s = wo + wi;
    (ok, wo, wi, s / s.dot(s).sqrt())
}

/// The smallest α a scene may ask for: below it the lobe is narrower than the f32 direction
/// grid resolves near the mirror direction (tested down to here: χ², stress).
pub const MIN_ALPHA: f32 = 1e-4;

/// The distribution of a material: `roughness` r ∈ [0.01, 1] with α = r² and an optional
/// `anisotropy` a ∈ [0, 1] (αx = α, αy = α·(1 − 0.9a): 1:10 at a = 1), or `alpha` given
/// directly (one number, or [αx, αy]); every α in [1e-4, 1]. Without either, the roughness
/// `default` (None: `roughness` is required).
pub fn parse_distribution(p: &mut Params, default: Option<f32>) -> Result<Ggx> {
    let alpha = p.number_or_pair("alpha")?;
    let roughness = match p.number_in("roughness", 0.01, 1.0)? {
        None if alpha.is_none() => default,
        r => r,
    };
    let anisotropy = p.number_in("anisotropy", 0.0, 1.0)?;
    let [ax, ay] = match (alpha, roughness) {
        (Some(_), Some(_)) => {
            return Err(p.error("alpha", "give `alpha` or `roughness`, not both"));
        }
        (Some(_), None) if anisotropy.is_some() => {
            return Err(p.error("anisotropy", "applies to `roughness`; give [αx, αy] as `alpha`"));
        }
        (Some(a), None) => a,
        (None, Some(r)) => {
            let a = r * r;
            [a, a * (1.0 - 0.9 * anisotropy.unwrap_or(0.0))]
        }
        (None, None) => return Err(p.error("roughness", "required (or `alpha`)")),
    };
    for (axis, a) in [("x", ax), ("y", ay)] {
        if !(MIN_ALPHA..=1.0).contains(&a) {
            let key = if alpha.is_some() {
                "alpha"
            } else if axis == "y" && anisotropy.is_some() {
                "anisotropy"
            } else {
                "roughness"
            };
            return Err(p.error(
                key,
                format!("gives α{axis} = {a:e}, outside [{MIN_ALPHA:e}, 1]"),
            ));
        }
    }
    Ok(Ggx { ax, ay })
}

/// The Fresnel term of a `ggx` material: `f0` (Schlick), `conductor` (a named metal, see
/// `fresnel::CONDUCTORS`) or `eta` and `k` (a complex index per channel); none: F = 1.
fn parse_fresnel(p: &mut Params) -> Result<Fresnel> {
    let f0 = p.rgb_in("f0", 0.0, 1.0)?;
    let named = p.text("conductor")?;
    let eta = p.rgb("eta")?;
    let k = p.rgb("k")?;
    let given = [f0.is_some(), named.is_some(), eta.is_some() || k.is_some()];
    if given.iter().filter(|&&g| g).count() > 1 {
        return Err(p.error("", "give at most one of `f0`, `conductor`, `eta` + `k`"));
    }
    if let Some(f0) = f0 {
        return Ok(Fresnel::Schlick { f0 });
    }
    if let Some(name) = named {
        let known: Vec<_> = super::fresnel::CONDUCTORS.iter().map(|c| c.0).collect();
        return conductor_preset(&name).ok_or_else(|| {
            p.error(
                "conductor",
                format!("unknown conductor `{name}` (known: {})", known.join(", ")),
            )
        });
    }
    match (eta, k) {
        (Some(eta), Some(k)) => {
            // Real conductors have η, κ of order 0.01–20; the bounds keep |η + iκ|² and its
            // inverse finite in f32, so the Fresnel equations can never overflow.
            let ok = |v: glam::Vec3, lo: f32| v.min_element() >= lo && v.max_element() <= 1e3;
            if !ok(eta, 1e-3) || !ok(k, 0.0) {
                return Err(p.error(
                    "eta",
                    "need 1e-3 ≤ η ≤ 1e3 and 0 ≤ κ ≤ 1e3 per channel",
                ));
            }
            Ok(Fresnel::Conductor { eta, k })
        }
        (None, None) => Ok(Fresnel::One),
        (Some(_), None) => Err(p.error("k", "required with `eta`")),
        (None, Some(_)) => Err(p.error("eta", "required with `k`")),
    }
}

/// `type = "ggx"`: `albedo` kd (default 0) + `specular` ks (default 1) times a GGX lobe,
/// kd + ks ≤ 1 per channel; roughness as [`parse_distribution`], Fresnel as [`parse_fresnel`].
pub static GGX: MaterialType = MaterialType {
    name: "ggx",
    describe: "Lambert kd + GGX ks (the lecture's blend microfacet model), Fresnel 1, Schlick or conductor",
    fields: &[
        "albedo",
        "specular",
        "roughness",
        "anisotropy",
        "alpha",
        "f0",
        "conductor",
        "eta",
        "k",
    ],
    parse: parse_ggx,
    chi2_cases,
};

fn parse_ggx(p: &mut Params) -> Result<Bsdf> {
    let kd = p.rgb_in("albedo", 0.0, 1.0)?.unwrap_or(Vec3::ZERO);
    let ks = p.rgb_in("specular", 0.0, 1.0)?.unwrap_or(Vec3::ONE);
    if (kd + ks).max_element() > 1.0 {
        return Err(p.error(
            "",
            "albedo + specular must be ≤ 1 per channel (energy conservation)",
        ));
    }
    let dist = parse_distribution(p, None)?;
    let fresnel = parse_fresnel(p)?;
    Ok(Bsdf::blend_ggx(kd, ks, dist, fresnel))
}

/// The χ² chart of a GGX sampler: a sample is binned as its half vector in the α = 1
/// configuration, ĥ = normalize(hx/αx, hy/αy, hz) — the reflection wi ↦ h (h on the upper
/// side) and the stretch are bijections, and in ĥ even an α = 1e-3 lobe spreads over every
/// cell. The density carries both Jacobians: p(ĥ) = p(wi)·4|wo·h|·αx αy/|(αx ĥx, αy ĥy, ĥz)|³,
/// with p(wi) from the sampler's pdf at the half vector (`pdf_half`: a wi rounded to f32 near
/// the horizon no longer holds the half vector of a 1e-3 lobe, see `MicrofacetSampler::pdf`).
pub fn ggx_warp_case(
    label: String,
    g: Ggx,
    wo: Vec3,
    sample_half_vector: impl Fn([f32; 2]) -> Vec3 + 'static,
    pdf_half: impl Fn(Vec3) -> f32 + 'static,
) -> crate::chi2::WarpCase {
    use crate::chi2::{Chart, DEFAULT_SLACK, WarpCase};
    use std::rc::Rc;
    let density = Rc::new(move |n: Vec3| -> f64 {
        let m = g.stretch(n);
        let h = m.normalize();
        let jac = 4.0 * wo.dot(h).abs() as f64 * (g.ax as f64 * g.ay as f64)
            / (m.length() as f64).powi(3);
        pdf_half(h) as f64 * jac
    });
    let d2 = density.clone();
    WarpCase {
        label,
        sample: Box::new(move |u| {
            let h = sample_half_vector([u[0], u[1]]);
            let n = Vec3::new(h.x / g.ax, h.y / g.ay, h.z).try_normalize()?;
            Some((n, density(n) as f32))
        }),
        pdf: Box::new(move |n| if n.z < 0.0 { 0.0 } else { d2(n) }),
        mismatch_slack: DEFAULT_SLACK,
        chart: Chart::cap(Vec3::Z, 1.0 + 1e-6),
    }
}

/// The view direction of the χ² cases: θo off the normal at 30° azimuth (off both axes).
pub fn chi2_view(theta_o_deg: f32) -> Vec3 {
    let (t, p) = (theta_o_deg.to_radians(), 30f32.to_radians());
    Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
}

/// α ∈ {1e-3, 0.05, 0.3, 1} × αx:αy ∈ {1:1, 10:1} × θo ∈ {0°, 60°, 89°}.
const GGX_SUITE: &[&[(&str, f64)]] = &[
    &[("alpha", 1e-3), ("aspect", 1.0), ("theta_o", 0.0)],
    &[("alpha", 1e-3), ("aspect", 1.0), ("theta_o", 60.0)],
    &[("alpha", 1e-3), ("aspect", 1.0), ("theta_o", 89.0)],
    &[("alpha", 1e-3), ("aspect", 10.0), ("theta_o", 0.0)],
    &[("alpha", 1e-3), ("aspect", 10.0), ("theta_o", 60.0)],
    &[("alpha", 1e-3), ("aspect", 10.0), ("theta_o", 89.0)],
    &[("alpha", 0.05), ("aspect", 1.0), ("theta_o", 0.0)],
    &[("alpha", 0.05), ("aspect", 1.0), ("theta_o", 60.0)],
    &[("alpha", 0.05), ("aspect", 1.0), ("theta_o", 89.0)],
    &[("alpha", 0.05), ("aspect", 10.0), ("theta_o", 0.0)],
    &[("alpha", 0.05), ("aspect", 10.0), ("theta_o", 60.0)],
    &[("alpha", 0.05), ("aspect", 10.0), ("theta_o", 89.0)],
    &[("alpha", 0.3), ("aspect", 1.0), ("theta_o", 0.0)],
    &[("alpha", 0.3), ("aspect", 1.0), ("theta_o", 60.0)],
    &[("alpha", 0.3), ("aspect", 1.0), ("theta_o", 89.0)],
    &[("alpha", 0.3), ("aspect", 10.0), ("theta_o", 0.0)],
    &[("alpha", 0.3), ("aspect", 10.0), ("theta_o", 60.0)],
    &[("alpha", 0.3), ("aspect", 10.0), ("theta_o", 89.0)],
    &[("alpha", 1.0), ("aspect", 1.0), ("theta_o", 0.0)],
    &[("alpha", 1.0), ("aspect", 1.0), ("theta_o", 60.0)],
    &[("alpha", 1.0), ("aspect", 1.0), ("theta_o", 89.0)],
    &[("alpha", 1.0), ("aspect", 10.0), ("theta_o", 0.0)],
    &[("alpha", 1.0), ("aspect", 10.0), ("theta_o", 60.0)],
    &[("alpha", 1.0), ("aspect", 10.0), ("theta_o", 89.0)],
];

/// One χ² entry per GGX sampler, over [`GGX_SUITE`].
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    use crate::chi2::{WarpEntry, label, param};
    MicrofacetSampler::ALL
        .into_iter()
        .map(|sampler| {
            WarpEntry::new(
                sampler.name(),
                sampler.describe(),
                &[("alpha", 0.3), ("aspect", 1.0), ("theta_o", 60.0)],
                GGX_SUITE,
                move |p| {
                    let (alpha, aspect, theta) =
                        (param(p, "alpha"), param(p, "aspect"), param(p, "theta_o"));
                    let valid = (MIN_ALPHA..=1.0).contains(&alpha)
                        && aspect >= 1.0
                        && (0.0..90.0).contains(&theta);
                    if !valid {
                        return Err("need 1e-4 ≤ alpha ≤ 1, aspect ≥ 1, 0 ≤ theta_o < 90".into());
                    }
                    let g = Ggx {
                        ax: alpha,
                        ay: alpha / aspect,
                    };
                    let wo = chi2_view(theta);
                    Ok(ggx_warp_case(
                        label(sampler.name(), p),
                        g,
                        wo,
                        move |u| sampler.sample_half_vector(&g, wo, u),
                        move |h| sampler.pdf_half(&g, wo, h),
                    ))
                },
            )
        })
        .collect()
}
