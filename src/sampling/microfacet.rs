//! The GGX (Trowbridge–Reitz) microfacet distribution in the local shading frame (z = normal,
//! x and y the anisotropy axes) and four samplers of its reflection lobe, each beside its pdf
//! and its inverse (as the warps in `warp.rs`): all normals by D(h)·cos θh (Walter et al.
//! 2007), visible normals (Heitz 2018), visible normals by spherical caps (Dupuy & Benyoub
//! 2023) and bounded visible normals (Eto & Tokuyoshi 2023). Each pdf is the solid-angle
//! density of the reflected direction over the whole sphere: a sampler may return a direction
//! below the surface, where the BSDF is zero, and its pdf still counts it.
//!
//! Formulations keep grazing angles and α = 1e-4 finite: Λ, G1 and G2 are written with the
//! stretched length t(ω) = |(αx ωx, αy ωy, ωz)| so that nothing divides by cos θ (Heitz 2014,
//! "Understanding the masking-shadowing function", eqs. 72 and 99 rearranged).

use crate::sampling::warp::cos_sin_turns;
use crate::simd::{V3, Vector, WIDTH};
use glam::Vec3;
use std::f32::consts::PI;

/// Which GGX sampler a lobe draws its directions with: a part of a BSDF-sampling strategy.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
pub enum MicrofacetSampler {
    /// Half vectors with density D(h)·cos θh (Walter et al. 2007, eqs. 35–36).
    Ndf,
    /// Visible normals D_wo(h) = G1(wo)·max(0, wo·h)·D(h)/cos θo (Heitz 2018).
    #[default]
    Vndf,
    /// The same density, drawn by sampling a spherical cap (Dupuy & Benyoub 2023).
    VndfCap,
    /// Visible normals restricted to a smaller cap that drops only half vectors reflecting
    /// below the surface (Eto & Tokuyoshi 2023).
    VndfBounded,
}

impl MicrofacetSampler {
    pub const ALL: [MicrofacetSampler; 4] = [
        MicrofacetSampler::Ndf,
        MicrofacetSampler::Vndf,
        MicrofacetSampler::VndfCap,
        MicrofacetSampler::VndfBounded,
    ];

    /// The name part of a strategy using this sampler.
    pub fn name(self) -> &'static str {
        match self {
            MicrofacetSampler::Ndf => "ggx-ndf",
            MicrofacetSampler::Vndf => "ggx-vndf",
            MicrofacetSampler::VndfCap => "ggx-vndf-cap",
            MicrofacetSampler::VndfBounded => "ggx-vndf-bounded",
        }
    }

    pub fn describe(self) -> &'static str {
        match self {
            MicrofacetSampler::Ndf => "GGX half vectors by D·cos θh (Walter et al. 2007)",
            MicrofacetSampler::Vndf => "GGX visible normals (Heitz 2018)",
            MicrofacetSampler::VndfCap => {
                "GGX visible normals by spherical caps (Dupuy & Benyoub 2023)"
            }
            MicrofacetSampler::VndfBounded => "GGX bounded visible normals (Eto & Tokuyoshi 2023)",
        }
    }

    /// A reflected direction for view `wo` (wo.z > 0); it may lie below the surface.
    pub fn sample(self, g: &Ggx, wo: Vec3, u: [f32; 2]) -> Vec3 {
        to_vec3(self.sample_v(g, of_vec3(wo), u[0], u[1]))
    }

    /// The half vector [`Self::sample`] reflects about (h.z ≥ 0).
    pub fn sample_half_vector(self, g: &Ggx, wo: Vec3, u: [f32; 2]) -> Vec3 {
        to_vec3(self.sample_half_vector_v(g, of_vec3(wo), u[0], u[1]))
    }

    /// [`Self::sample`] written once over lanes: the scalar sampler is this with `f32` as one
    /// lane, so directions drawn over lanes are the scalar ones bit for bit on every ISA.
    #[inline(always)]
    pub fn sample_v<V: Vector<N>, const N: usize>(self, g: &Ggx, wo: V3<V>, u0: V, u1: V) -> V3<V> {
        reflect_v(wo, self.sample_half_vector_v(g, wo, u0, u1))
    }

    /// [`Self::sample_half_vector`] over lanes (one lane: `f32`).
    #[inline(always)]
    pub fn sample_half_vector_v<V: Vector<N>, const N: usize>(
        self,
        g: &Ggx,
        wo: V3<V>,
        u0: V,
        u1: V,
    ) -> V3<V> {
        match self {
            MicrofacetSampler::Ndf => ndf_half(g, u0, u1),
            MicrofacetSampler::Vndf => vndf_half(g, wo, u0, u1),
            MicrofacetSampler::VndfCap => {
                let v = normalize_v(g.stretch_v(wo));
                cap_half(g, v, v.z, u0, u1)
            }
            MicrofacetSampler::VndfBounded => {
                let v = normalize_v(g.stretch_v(wo));
                cap_half(g, v, g.bounded_k_v(wo).mul(v.z), u0, u1)
            }
        }
    }

    /// Solid-angle density of [`Self::sample`] at `wi`: [`Self::pdf_half`] at the half vector
    /// of (wo, wi) taken on the upper side (h and −h reflect wo to the same wi).
    pub fn pdf(self, g: &Ggx, wo: Vec3, wi: Vec3) -> f32 {
        match half_vector(wo, wi) {
            Some(h) => self.pdf_half(g, wo, if h.z < 0.0 { -h } else { h }),
            None => 0.0,
        }
    }

    /// The density of [`Self::sample`] at the reflection of wo about the unit half vector `h`
    /// (h.z ≥ 0, either sign of wo·h). In f32, the half vector recovered from a reflected
    /// direction near the horizon loses the digits that a 1e-3 lobe lives in; this form lets
    /// a test evaluate the density at the exact half vector it sampled.
    pub fn pdf_half(self, g: &Ggx, wo: Vec3, h: Vec3) -> f32 {
        match self {
            MicrofacetSampler::Ndf => ggx_ndf_pdf(g, wo, h),
            MicrofacetSampler::Vndf | MicrofacetSampler::VndfCap => ggx_vndf_pdf(g, wo, h),
            MicrofacetSampler::VndfBounded => ggx_vndf_bounded_pdf(g, wo, h),
        }
    }

    /// The u that [`Self::sample`] maps to the half vector `h` (h.z > 0, and wo·h > 0 for the
    /// visible-normal samplers).
    pub fn invert(self, g: &Ggx, wo: Vec3, h: Vec3) -> [f32; 2] {
        match self {
            MicrofacetSampler::Ndf => invert_ggx_ndf(g, h),
            MicrofacetSampler::Vndf => invert_ggx_vndf(g, wo, h),
            MicrofacetSampler::VndfCap => invert_cap(g, wo, h, g.stretch(wo).normalize().z),
            MicrofacetSampler::VndfBounded => invert_cap(g, wo, h, g.bounded_cap_floor(wo)),
        }
    }
}

/// The anisotropic GGX distribution with roughness αx along x and αy along y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ggx {
    pub ax: f32,
    pub ay: f32,
}

impl Ggx {
    /// D(h) = 1 / (π αx αy (hx²/αx² + hy²/αy² + hz²)²) for unit h, zero below the surface.
    /// For α ≤ 1 the bracket is ≥ 1, so D ≤ 1/(π αx αy): no overflow at α = 1e-4.
    pub fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let (x, y) = (h.x / self.ax, h.y / self.ay);
        let s = x * x + y * y + h.z * h.z;
        1.0 / (PI * self.ax * self.ay * s * s)
    }

    /// (αx ωx, αy ωy, ωz), unnormalised: a direction in the α = 1 configuration.
    pub fn stretch(&self, w: Vec3) -> Vec3 {
        Vec3::new(self.ax * w.x, self.ay * w.y, w.z)
    }

    /// [`Self::stretch`] over lanes.
    #[inline(always)]
    fn stretch_v<V: Vector<N>, const N: usize>(&self, w: V3<V>) -> V3<V> {
        V3 {
            x: V::splat(self.ax).mul(w.x),
            y: V::splat(self.ay).mul(w.y),
            z: w.z,
        }
    }

    /// t(ω) = |(αx ωx, αy ωy, ωz)|, so that Λ(ω) = (t − |ωz|)/(2|ωz|).
    pub fn stretched_len(&self, w: Vec3) -> f32 {
        self.stretch(w).length()
    }

    /// Smith masking G1(ω) = 1/(1 + Λ(ω)) = 2|ωz|/(|ωz| + t(ω)): 0 at the horizon, no division
    /// by cos θ.
    pub fn g1(&self, w: Vec3) -> f32 {
        let z = w.z.abs();
        2.0 * z / (z + self.stretched_len(w))
    }

    /// Height-correlated masking-shadowing G2 = 1/(1 + Λ(wo) + Λ(wi)) = 2 zo zi/(zo ti + zi to).
    pub fn g2(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        2.0 * zo * zi / (zo * self.stretched_len(wi) + zi * self.stretched_len(wo))
    }

    /// D(h)·G2/(4 cos θo cos θi) = D(h)/(2 (zo ti + zi to)): the BRDF without Fresnel, finite
    /// at grazing angles (the cosines cancel against G2's numerator).
    pub fn d_g2_over_cosines(&self, wo: Vec3, wi: Vec3, h: Vec3) -> f32 {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        let denom = zo * self.stretched_len(wi) + zi * self.stretched_len(wo);
        0.5 * self.d(h) / denom
    }

    /// [`Self::d`] over lanes, the same operations in the same order (the constant
    /// π·αx·αy rounded as the scalar product's first two steps round it).
    #[inline(always)]
    pub fn d_lanes<V: Vector<WIDTH>>(&self, h: V3<V>) -> V {
        let zero = V::splat(0.0);
        let (x, y) = (h.x.div(V::splat(self.ax)), h.y.div(V::splat(self.ay)));
        let s = x.mul(x).add(y.mul(y)).add(h.z.mul(h.z));
        let d = V::splat(1.0).div(V::splat(PI * self.ax * self.ay).mul(s).mul(s));
        h.z.le_select(zero, zero, d)
    }

    /// [`Self::stretched_len`] over lanes.
    #[inline(always)]
    pub fn stretched_len_lanes<V: Vector<WIDTH>>(&self, w: V3<V>) -> V {
        let s = V3 {
            x: V::splat(self.ax).mul(w.x),
            y: V::splat(self.ay).mul(w.y),
            z: w.z,
        };
        s.dot(s).sqrt()
    }

    /// [`Self::d_g2_over_cosines`] over lanes.
    #[inline(always)]
    pub fn d_g2_over_cosines_lanes<V: Vector<WIDTH>>(&self, wo: V3<V>, wi: V3<V>, h: V3<V>) -> V {
        let (zo, zi) = (wo.z.abs(), wi.z.abs());
        let denom = zo
            .mul(self.stretched_len_lanes(wi))
            .add(zi.mul(self.stretched_len_lanes(wo)));
        V::splat(0.5).mul(self.d_lanes(h)).div(denom)
    }

    /// The floor −b of the sampled cap's z in the stretched frame: b = k·ŵo.z with Eto &
    /// Tokuyoshi's k (2023, eqs. 5–6), a = min(αx, αy, 1), s = 1 + |wo.xy|. k = 1 is the full
    /// visible-normal cap of Dupuy & Benyoub.
    pub fn bounded_cap_floor(&self, wo: Vec3) -> f32 {
        self.bounded_k(wo) * self.stretch(wo).normalize().z
    }

    /// Eto & Tokuyoshi's k = (1 − a²) s² / (s² + a² wo.z²) for wo.z > 0.
    pub fn bounded_k(&self, wo: Vec3) -> f32 {
        self.bounded_k_v(of_vec3(wo))
    }

    /// The lanes whose half vector `h` comes from a point below the cap z ≥ −k·ŵo.z (in the
    /// band the bounded sampler drops), over lanes (one lane: `f32`): [`cap_point`]'s z
    /// against the floor.
    #[inline(always)]
    pub(crate) fn below_cap_v<V: Vector<N>, const N: usize>(
        &self,
        wo: V3<V>,
        h: V3<V>,
        k: V,
    ) -> u32 {
        let v = normalize_v(self.stretch_v(wo));
        cap_point_v(self, v, h).z.lt(k.neg().mul(v.z))
    }

    /// [`Self::bounded_k`] over lanes (one lane: `f32`).
    #[inline(always)]
    pub(crate) fn bounded_k_v<V: Vector<N>, const N: usize>(&self, wo: V3<V>) -> V {
        let a = self.ax.min(self.ay).min(1.0);
        let a2 = V::splat(a * a);
        let one = V::splat(1.0);
        let s = one.add(wo.x.mul(wo.x).add(wo.y.mul(wo.y)).sqrt());
        let s2 = s.mul(s);
        one.sub(a2).mul(s2).div(s2.add(a2.mul(wo.z).mul(wo.z)))
    }
}

/// Mirror of `wo` about the unit normal `h`.
pub fn reflect(wo: Vec3, h: Vec3) -> Vec3 {
    2.0 * wo.dot(h) * h - wo
}

/// [`reflect`] over lanes (one lane: `f32`), glam's operations in glam's order.
#[inline(always)]
fn reflect_v<V: Vector<N>, const N: usize>(wo: V3<V>, h: V3<V>) -> V3<V> {
    let k = V::splat(2.0).mul(dot_v(wo, h));
    V3 {
        x: k.mul(h.x).sub(wo.x),
        y: k.mul(h.y).sub(wo.y),
        z: k.mul(h.z).sub(wo.z),
    }
}

// Three-vectors over lanes of any width (one lane: `f32`), with glam's `Vec3` operations in
// glam's order: what the samplers above are written on, once for the scalar path and the lanes.

#[inline(always)]
fn of_vec3(v: Vec3) -> V3<f32> {
    V3 {
        x: v.x,
        y: v.y,
        z: v.z,
    }
}

#[inline(always)]
fn to_vec3(v: V3<f32>) -> Vec3 {
    Vec3::new(v.x, v.y, v.z)
}

#[inline(always)]
fn dot_v<V: Vector<N>, const N: usize>(a: V3<V>, b: V3<V>) -> V {
    a.x.mul(b.x).add(a.y.mul(b.y)).add(a.z.mul(b.z))
}

#[inline(always)]
fn scale_v<V: Vector<N>, const N: usize>(a: V3<V>, k: V) -> V3<V> {
    V3 {
        x: a.x.mul(k),
        y: a.y.mul(k),
        z: a.z.mul(k),
    }
}

#[inline(always)]
fn add_v<V: Vector<N>, const N: usize>(a: V3<V>, b: V3<V>) -> V3<V> {
    V3 {
        x: a.x.add(b.x),
        y: a.y.add(b.y),
        z: a.z.add(b.z),
    }
}

/// glam's `normalize`: times 1/|a|.
#[inline(always)]
fn normalize_v<V: Vector<N>, const N: usize>(a: V3<V>) -> V3<V> {
    scale_v(a, V::splat(1.0).div(dot_v(a, a).sqrt()))
}

/// The half vector of a reflection pair, None when wi = −wo (no half vector).
pub fn half_vector(wo: Vec3, wi: Vec3) -> Option<Vec3> {
    let h = wo + wi;
    let len2 = h.length_squared();
    (len2 > 0.0).then(|| h / len2.sqrt())
}

/// Half vector with density D(h)·h.z: the slope (αx r cos φ, αy r sin φ) with r² = u/(1−u)
/// has GGX's slope distribution, whose half vector is (−slope, 1) normalised (Walter et al.
/// 2007; Heitz 2014, §5.3); the sign of the slope is immaterial by symmetry.
pub fn sample_ggx_ndf(g: &Ggx, u: [f32; 2]) -> Vec3 {
    to_vec3(ndf_half(g, u[0], u[1]))
}

/// [`sample_ggx_ndf`] over lanes (one lane: `f32`); φ = 2π·u1 by [`cos_sin_turns`].
#[inline(always)]
fn ndf_half<V: Vector<N>, const N: usize>(g: &Ggx, u0: V, u1: V) -> V3<V> {
    let r = u0.div(V::splat(1.0).sub(u0)).sqrt();
    let (c, s) = cos_sin_turns(u1);
    normalize_v(V3 {
        x: V::splat(g.ax).mul(r).mul(c),
        y: V::splat(g.ay).mul(r).mul(s),
        z: V::splat(1.0),
    })
}

/// Inverse of [`sample_ggx_ndf`] for h.z > 0.
pub fn invert_ggx_ndf(g: &Ggx, h: Vec3) -> [f32; 2] {
    let (x, y) = (h.x / (g.ax * h.z), h.y / (g.ay * h.z));
    let r2 = x * x + y * y;
    [r2 / (1.0 + r2), wrap_phi(y.atan2(x))]
}

/// Density of the reflected direction under NDF sampling, at its half vector h (h.z ≥ 0):
/// D(h) h.z / (4 |wo·h|), the reflection Jacobian 4|wo·h| (Walter et al. 2007, eq. 14).
pub fn ggx_ndf_pdf(g: &Ggx, wo: Vec3, h: Vec3) -> f32 {
    let c = wo.dot(h).abs();
    if c == 0.0 {
        return 0.0;
    }
    g.d(h) * h.z / (4.0 * c)
}

/// Visible normal by Heitz 2018 ("Sampling the GGX distribution of visible normals", JCGT 7(4),
/// listing 1): stretch wo to the α = 1 configuration, sample the projected hemisphere as a disk
/// whose far half is squeezed by (1 + cos θ)/2, lift, and unstretch.
pub fn sample_ggx_vndf(g: &Ggx, wo: Vec3, u: [f32; 2]) -> Vec3 {
    to_vec3(vndf_half(g, of_vec3(wo), u[0], u[1]))
}

/// [`sample_ggx_vndf`] over lanes (one lane: `f32`); φ = 2π·u1 by [`cos_sin_turns`].
#[inline(always)]
fn vndf_half<V: Vector<N>, const N: usize>(g: &Ggx, wo: V3<V>, u0: V, u1: V) -> V3<V> {
    let (zero, one) = (V::splat(0.0), V::splat(1.0));
    let v = normalize_v(g.stretch_v(wo));
    let (t1, t2) = heitz_basis_v(v);
    let r = u0.sqrt();
    let (c, s) = cos_sin_turns(u1);
    let p1 = r.mul(c);
    let p2 = r.mul(s);
    let h = V::splat(0.5).mul(one.add(v.z));
    let p2 = one
        .sub(h)
        .mul(one.sub(p1.mul(p1)).max(zero).sqrt())
        .add(h.mul(p2));
    let lift = one.sub(p1.mul(p1)).sub(p2.mul(p2)).max(zero).sqrt();
    let n = add_v(add_v(scale_v(t1, p1), scale_v(t2, p2)), scale_v(v, lift));
    unstretch_normal_v(
        g,
        V3 {
            x: n.x,
            y: n.y,
            z: n.z.max(zero),
        },
    )
}

/// Heitz's orthonormal basis (T1, T2) orthogonal to the stretched view `v`.
fn heitz_basis(v: Vec3) -> (Vec3, Vec3) {
    let (t1, t2) = heitz_basis_v(of_vec3(v));
    (to_vec3(t1), to_vec3(t2))
}

/// [`heitz_basis`] over lanes: T1 = (−v.y, v.x, 0)/|v.xy|, +x where v is the normal.
#[inline(always)]
fn heitz_basis_v<V: Vector<N>, const N: usize>(v: V3<V>) -> (V3<V>, V3<V>) {
    let zero = V::splat(0.0);
    let len2 = v.x.mul(v.x).add(v.y.mul(v.y));
    let tilted = zero.lt(len2);
    let len = V::select(tilted, len2, V::splat(1.0)).sqrt();
    let t1 = V3 {
        x: V::select(tilted, v.y.neg().div(len), V::splat(1.0)),
        y: V::select(tilted, v.x.div(len), zero),
        z: zero,
    };
    // glam's cross, component by component.
    let t2 = V3 {
        x: v.y.mul(t1.z).sub(t1.y.mul(v.z)),
        y: v.z.mul(t1.x).sub(t1.z.mul(v.x)),
        z: v.x.mul(t1.y).sub(t1.x.mul(v.y)),
    };
    (t1, t2)
}

/// A normal of the α = 1 configuration back in the α configuration: normalize(αx n.x, αy n.y,
/// n.z). A zero vector (a measure-zero draw exactly on the rim) becomes −z, which reflects wo
/// below the surface where every pdf here is zero.
#[cfg(test)]
fn unstretch_normal(g: &Ggx, n: Vec3) -> Vec3 {
    to_vec3(unstretch_normal_v(g, of_vec3(n)))
}

/// [`unstretch_normal`] over lanes (one lane: `f32`).
#[inline(always)]
fn unstretch_normal_v<V: Vector<N>, const N: usize>(g: &Ggx, n: V3<V>) -> V3<V> {
    // glam's try_normalize: 1/|m| finite and positive, else the fallback.
    let m = g.stretch_v(n);
    let rcp = V::splat(1.0).div(dot_v(m, m).sqrt());
    let ok = rcp.lt(V::splat(f32::INFINITY)) & V::splat(0.0).lt(rcp);
    let zero = V::splat(0.0);
    V3 {
        x: V::select(ok, m.x.mul(rcp), zero),
        y: V::select(ok, m.y.mul(rcp), zero),
        z: V::select(ok, m.z.mul(rcp), V::splat(-1.0)),
    }
}

/// The α = 1 configuration of a half vector: normalize(hx/αx, hy/αy, hz).
fn stretched_normal(g: &Ggx, h: Vec3) -> Vec3 {
    to_vec3(stretched_normal_v(g, of_vec3(h)))
}

/// [`stretched_normal`] over lanes (one lane: `f32`).
#[inline(always)]
fn stretched_normal_v<V: Vector<N>, const N: usize>(g: &Ggx, h: V3<V>) -> V3<V> {
    normalize_v(V3 {
        x: h.x.div(V::splat(g.ax)),
        y: h.y.div(V::splat(g.ay)),
        z: h.z,
    })
}

/// Inverse of [`sample_ggx_vndf`] for h.z > 0 and wo·h > 0.
pub fn invert_ggx_vndf(g: &Ggx, wo: Vec3, h: Vec3) -> [f32; 2] {
    let v = g.stretch(wo).normalize();
    let (t1, t2) = heitz_basis(v);
    let n = stretched_normal(g, h);
    let p1 = n.dot(t1);
    let s = 0.5 * (1.0 + v.z);
    let p2 = (n.dot(t2) - (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt()) / s;
    [p1 * p1 + p2 * p2, wrap_phi(p2.atan2(p1))]
}

/// The visible-normal density of the reflected direction at its half vector h,
/// D_wo(h)/(4 wo·h) = G1(wo) D(h)/(4 zo) = D(h)/(2 (zo + to)) for wo·h > 0 (the cosine cancels;
/// Heitz 2018, eq. 17 with the reflection Jacobian).
pub fn ggx_vndf_pdf(g: &Ggx, wo: Vec3, h: Vec3) -> f32 {
    ggx_cap_pdf(g, wo, h, 1.0)
}

/// Visible normal by Dupuy & Benyoub 2023 ("Sampling Visible GGX Normals with Spherical Caps",
/// HPG): in the α = 1 configuration the visible normals of ŵo are ŵo + c with c uniform on the
/// cap z ≥ −ŵo.z of the unit sphere; unstretch.
pub fn sample_ggx_vndf_cap(g: &Ggx, wo: Vec3, u: [f32; 2]) -> Vec3 {
    MicrofacetSampler::VndfCap.sample_half_vector(g, wo, u)
}

/// Bounded visible normal by Eto & Tokuyoshi 2023 ("Bounded VNDF Sampling for Smith–GGX
/// Reflections", SIGGRAPH Asia TC): the cap of [`sample_ggx_vndf_cap`] cut at z ≥ −k·ŵo.z,
/// where the dropped band holds only half vectors that reflect wo below the surface.
pub fn sample_ggx_vndf_bounded(g: &Ggx, wo: Vec3, u: [f32; 2]) -> Vec3 {
    MicrofacetSampler::VndfBounded.sample_half_vector(g, wo, u)
}

/// ŵo + c with c uniform on the spherical cap z ≥ −b, unstretched, over lanes (one lane:
/// `f32`); φ = 2π·u0 by [`cos_sin_turns`]. With 1 − z = u1·(1 + b), sin²θ = (1 − z)(1 + z)
/// has no cancellation near the pole.
#[inline(always)]
fn cap_half<V: Vector<N>, const N: usize>(g: &Ggx, v: V3<V>, b: V, u0: V, u1: V) -> V3<V> {
    let one = V::splat(1.0);
    let (c, s) = cos_sin_turns(u0);
    let one_minus_z = u1.mul(one.add(b));
    let z = one.sub(one_minus_z);
    let sin = one_minus_z
        .mul(V::splat(2.0).sub(one_minus_z))
        .max(V::splat(0.0))
        .sqrt();
    let point = V3 {
        x: sin.mul(c),
        y: sin.mul(s),
        z,
    };
    unstretch_normal_v(g, add_v(point, v))
}

/// The cap point a half vector comes from: c = reflect(ŵo, ĥ) in the α = 1 configuration
/// (|λĥ − ŵo| = 1 gives λ = 2 ĥ·ŵo).
fn cap_point(g: &Ggx, v: Vec3, h: Vec3) -> Vec3 {
    to_vec3(cap_point_v(g, of_vec3(v), of_vec3(h)))
}

/// [`cap_point`] over lanes (one lane: `f32`): the reflection of ŵo about ĥ.
#[inline(always)]
fn cap_point_v<V: Vector<N>, const N: usize>(g: &Ggx, v: V3<V>, h: V3<V>) -> V3<V> {
    reflect_v(v, stretched_normal_v(g, h))
}

/// Inverse of the cap samplers for the cap z ≥ −b.
fn invert_cap(g: &Ggx, wo: Vec3, h: Vec3, b: f32) -> [f32; 2] {
    let v = g.stretch(wo).normalize();
    let c = cap_point(g, v, h);
    [wrap_phi(c.y.atan2(c.x)), (1.0 - c.z) / (1.0 + b)]
}

/// Density of the bounded sampler at the half vector h: D(h)/(2 (k zo + to)) where h's cap point lies
/// in the kept cap, zero in the dropped band (Eto & Tokuyoshi 2023, eq. 8 with the reflection
/// Jacobian; the band test is what keeps the density exact for directions below the surface).
pub fn ggx_vndf_bounded_pdf(g: &Ggx, wo: Vec3, h: Vec3) -> f32 {
    ggx_cap_pdf(g, wo, h, g.bounded_k(wo))
}

/// The cap samplers' density for the cap z ≥ −k·ŵo.z (k = 1: every visible normal), at the
/// half vector h; zero for normals wo cannot see.
fn ggx_cap_pdf(g: &Ggx, wo: Vec3, h: Vec3, k: f32) -> f32 {
    if wo.z <= 0.0 || h.z <= 0.0 || wo.dot(h) <= 0.0 {
        return 0.0;
    }
    if k < 1.0 && g.below_cap_v(of_vec3(wo), of_vec3(h), k) != 0 {
        return 0.0;
    }
    0.5 * g.d(h) / (k * wo.z + g.stretched_len(wo))
}

fn wrap_phi(phi: f32) -> f32 {
    let t = phi / (2.0 * PI);
    if t < 0.0 {
        t + 1.0
    } else {
        t.min(super::stream::ONE_MINUS_EPSILON)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    fn views() -> impl Iterator<Item = Vec3> {
        [0.0f32, 60.0, 89.0].into_iter().map(|t| {
            let (t, p) = (t.to_radians(), 0.5f32);
            Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos())
        })
    }

    fn dists() -> impl Iterator<Item = Ggx> {
        [0.05f32, 0.3, 1.0].into_iter().flat_map(|a| {
            [1.0f32, 10.0]
                .into_iter()
                .map(move |r| Ggx { ax: a, ay: a / r })
        })
    }

    /// Solid angle of the spherical triangle (a, b, c) (Van Oosterom & Strackee 1983).
    fn triangle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
        let num = a.dot(b.cross(c)).abs();
        let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
        2.0 * num.atan2(den)
    }

    /// Solid angle covered by the image of the u-square of side `d` centred on `u`.
    fn image_area(map: &dyn Fn([f32; 2]) -> Vec3, u: [f32; 2], d: f32) -> f64 {
        let w = |du: f32, dv: f32| map([u[0] + du, u[1] + dv]).as_dvec3().normalize();
        let (a, b, c, e) = (
            w(-d / 2.0, -d / 2.0),
            w(d / 2.0, -d / 2.0),
            w(d / 2.0, d / 2.0),
            w(-d / 2.0, d / 2.0),
        );
        triangle(a, b, c) + triangle(a, c, e)
    }

    /// Largest |area/(du² · (1/pdf)) − 1| over an interior grid of u, and how many points were
    /// checked: the pdf is the density of the map itself, pointwise (samples below the surface
    /// included). Squares across which the pdf varies by more than 5 % (near wo·h = 0, where
    /// the reflection Jacobian diverges) are too coarse for a finite difference and skipped,
    /// and so are points within 0.05 of −wo, where f32 cannot resolve that Jacobian (those
    /// directions lie below the surface).
    fn worst_jacobian_error(
        wo: Vec3,
        sample: &dyn Fn([f32; 2]) -> Vec3,
        pdf: &dyn Fn(Vec3) -> f32,
    ) -> (f64, usize) {
        let mut worst = 0.0f64;
        let mut checked = 0;
        for i in 1..10 {
            for j in 0..10 {
                let u = [i as f32 / 10.0, (j as f32 + 0.5) / 10.0];
                if (sample(u) + wo).length() < 0.05 {
                    continue;
                }
                let p = pdf(sample(u)) as f64;
                // A square whose image is ~5e-4 rad across: large against f32's 6e-8 direction
                // grid, small against the lobe.
                let d = (5e-4 * p.sqrt()).clamp(1e-4, 0.02) as f32;
                let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(a, b)| pdf(sample([u[0] + a * d / 2.0, u[1] + b * d / 2.0])) as f64);
                if corners.iter().any(|c| (c / p - 1.0).abs() > 5e-2) {
                    continue;
                }
                checked += 1;
                let area = image_area(sample, u, d);
                worst = worst.max((area * p / (d as f64 * d as f64) - 1.0).abs());
            }
        }
        (worst, checked)
    }

    /// Sample/pdf consistency of every sampler: its pdf is the Jacobian density of its map, and
    /// a visible-normal pdf without G1 fails the same check (the negative control).
    #[test]
    fn every_pdf_is_its_samplers_jacobian() {
        for g in dists() {
            for wo in views() {
                for s in MicrofacetSampler::ALL {
                    let (e, n) =
                        worst_jacobian_error(wo, &|u| s.sample(&g, wo, u), &|wi| s.pdf(&g, wo, wi));
                    assert!(e < 1e-2, "{s:?} {g:?} wo {wo}: Jacobian off by {e:.3e}");
                    // NDF sampling seen at 89° is dominated by the 1/|wo·h| reflection Jacobian
                    // (wo·h ~ 0.02): few squares are smooth there; the χ² suite covers it.
                    let exempt = s == MicrofacetSampler::Ndf && wo.z < 0.1;
                    assert!(
                        n >= 30 || exempt,
                        "{s:?} {g:?} wo {wo}: only {n} of 90 points smooth"
                    );
                }
                if wo.z < 0.9 && g.ax >= 0.3 {
                    let no_g1 = |wi: Vec3| {
                        let h = half_vector(wo, wi).unwrap();
                        g.d(h) / (4.0 * wo.z)
                    };
                    let (e, _) = worst_jacobian_error(
                        wo,
                        &|u| MicrofacetSampler::Vndf.sample(&g, wo, u),
                        &no_g1,
                    );
                    assert!(e > 3e-2, "{g:?} wo {wo}: a pdf without G1 passed ({e:.3e})");
                }
            }
        }
    }

    /// Each sampler's inverse maps its samples back to their u.
    #[test]
    fn inverses_round_trip() {
        for g in dists().chain([Ggx { ax: 1e-3, ay: 1e-4 }]) {
            for wo in views() {
                for s in MicrofacetSampler::ALL {
                    for i in 1..10 {
                        for j in 1..10 {
                            let u = [i as f32 / 10.0, j as f32 / 10.0];
                            let back = s.invert(&g, wo, s.sample_half_vector(&g, wo, u));
                            let du = (back[0] - u[0]).abs();
                            let dv = (back[1] - u[1]).abs().min(1.0 - (back[1] - u[1]).abs());
                            assert!(
                                du < 2e-3 && dv < 2e-3,
                                "{s:?} {g:?} wo {wo}: {u:?} -> {back:?}"
                            );
                        }
                    }
                }
            }
        }
    }

    /// The band the bounded sampler drops, z ∈ [−ŵo.z, −k ŵo.z), holds only half vectors that
    /// reflect wo below the surface; with k 10 % smaller the band reaches valid reflections,
    /// which the same check sees (the negative control).
    #[test]
    fn bounded_cap_drops_only_reflections_below_the_surface() {
        let highest_in_band = |g: &Ggx, wo: Vec3, k: f32| {
            let v = g.stretch(wo).normalize();
            let mut best = f32::NEG_INFINITY;
            for i in 0..=200 {
                let z = -v.z + (v.z - k * v.z) * i as f32 / 200.0;
                let sin = (1.0 - z * z).max(0.0).sqrt();
                for j in 0..256 {
                    let phi = 2.0 * PI * j as f32 / 256.0;
                    let c = Vec3::new(sin * phi.cos(), sin * phi.sin(), z);
                    let h = unstretch_normal(g, c + v);
                    if z < -k * v.z {
                        best = best.max(reflect(wo, h).z);
                    }
                }
            }
            best
        };
        let mut control_caught = 0;
        for a in [0.05f32, 0.3, 0.7] {
            for r in [1.0f32, 10.0] {
                let g = Ggx { ax: a, ay: a / r };
                for t in [30.0f32, 60.0, 80.0, 89.0] {
                    let (t, p) = (t.to_radians(), 0.5f32);
                    let wo = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                    let k = g.bounded_k(wo);
                    let top = highest_in_band(&g, wo, k);
                    assert!(
                        top <= 1e-5,
                        "{g:?} θo {t}: dropped band reflects to z = {top}"
                    );
                    if highest_in_band(&g, wo, 0.9 * k) > 1e-3 {
                        control_caught += 1;
                    }
                }
            }
        }
        assert!(
            control_caught >= 12,
            "a too-large band went unnoticed ({control_caught}/24)"
        );
    }

    /// α = 1e-4 and 1, views from 0° to exactly 90°, u at the corners of the unit square: every
    /// sample is a unit vector and every pdf finite and non-negative.
    #[test]
    fn extremes_stay_finite() {
        let one = super::super::stream::ONE_MINUS_EPSILON;
        for g in [
            Ggx { ax: 1e-4, ay: 1e-4 },
            Ggx { ax: 1e-3, ay: 1e-4 },
            Ggx { ax: 1.0, ay: 1.0 },
            Ggx { ax: 1.0, ay: 0.1 },
        ] {
            for t in [0.0f32, 45.0, 89.0, 89.99, 90.0] {
                let t = t.to_radians();
                let wo = Vec3::new(t.sin(), 0.0, t.cos().max(0.0));
                for s in MicrofacetSampler::ALL {
                    for u in [[0.0, 0.0], [one, one], [0.0, one], [one, 0.0], [0.5, 0.5]] {
                        let wi = s.sample(&g, wo, u);
                        assert!(
                            wi.is_finite() && (wi.length() - 1.0).abs() < 1e-3,
                            "{s:?} {g:?} θ {t}: {u:?} -> {wi}"
                        );
                        let p = s.pdf(&g, wo, wi);
                        assert!(p.is_finite() && p >= 0.0, "{s:?} {g:?}: pdf {p}");
                    }
                }
                let h = Vec3::new(0.3, 0.1, 0.9).normalize();
                assert!(g.d_g2_over_cosines(wo, reflect(wo, h), h).is_finite());
                assert!(g.g1(wo).is_finite() && g.g2(wo, Vec3::Z).is_finite());
            }
        }
    }

    /// Smith's Λ matches D: ∫ D(h) max(0, ω·h) dωh = cos θ / G1(ω) (the projected-area
    /// identity, Heitz 2014 eq. 8), by quadrature; and ∫ D cos θh = 1. A G1 built for
    /// another α fails the same identity.
    #[test]
    fn masking_matches_the_distribution() {
        use crate::bsdf::quadrature::integrate_2d;
        let mut controls = 0;
        for g in dists().chain([Ggx { ax: 1e-2, ay: 1e-3 }]) {
            let (ax, ay) = (g.ax as f64, g.ay as f64);
            for w in views().chain([Vec3::new(0.6, 0.0, 0.8)]) {
                let wd = w.as_dvec3();
                let q = integrate_2d(
                    &mut |phi: f64, t: f64| {
                        let (st, ct) = t.sin_cos();
                        let m = DVec3::new(ax * st * phi.cos(), ay * st * phi.sin(), ct);
                        let len = m.length();
                        let h = m / len;
                        let jac = ax * ay * st / (len * len * len);
                        let d = g.d(h.as_vec3()) as f64;
                        DVec3::new(d * h.z * jac, d * wd.dot(h).max(0.0) * jac, 0.0)
                    },
                    (0.0, 2.0 * std::f64::consts::PI),
                    (0.0, std::f64::consts::FRAC_PI_2),
                    1e-7,
                );
                assert!(
                    (q.value.x - 1.0).abs() < 2e-5,
                    "{g:?}: ∫ D cos = {}",
                    q.value.x
                );
                let projected = wd.z / g.g1(w) as f64;
                assert!(
                    (q.value.y / projected - 1.0).abs() < 2e-5,
                    "{g:?} {w}: {} vs {projected}",
                    q.value.y
                );
                // Where a G1 for 1.2α differs from the right one by 10× the tolerance, the
                // identity must reject it.
                let wrong = Ggx {
                    ax: g.ax * 1.2,
                    ay: g.ay * 1.2,
                };
                if (wrong.g1(w) / g.g1(w) - 1.0).abs() > 2e-4 {
                    let off = wd.z / wrong.g1(w) as f64;
                    assert!(
                        (q.value.y / off - 1.0).abs() > 2e-5,
                        "{g:?}: G1 of 1.2α passed"
                    );
                    controls += 1;
                }
            }
        }
        assert!(
            controls >= 10,
            "the wrong G1 was tried only {controls} times"
        );
    }
}
