//! Parallelogram area light, emitting on the side of edge_u × edge_v.
//! Area sampling: a uniform point q, pdf_A = 1/A, converted to solid angle at p by
//! pdf_ω = pdf_A · d² / |cos θ_l| (Veach 1997, eq. 8.10).

use super::bounds::{Bounds, LightBounds};
use super::{
    LANE_RECORD, LaneKernel, LaneQuery, LaneRecords, LaneSamples, Light, LightCtx, LightHit,
    LightMethods, LightSample, LightShape, QuadMethod, SurfaceLanes, d64, direction_to, f32s,
    flat_area_pdf_lanes, keep, record_rows, record_rows_d,
};
use crate::math::gamma;
use crate::math::luminance;
use crate::sampling::spherical::{MIN_SOLID_ANGLE, SphericalRectangle};
use crate::simd::{self, Isa, Kernel, Lanes, V3, Vector, Vector64, WIDTH, dot3};
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct QuadLight {
    pub corner: Vec3,
    pub edge_u: Vec3,
    pub edge_v: Vec3,
    /// Unit normal of the emitting side.
    pub normal: Vec3,
    pub area: f32,
    pub radiance: Vec3,
}

impl QuadLight {
    pub fn new(corner: Vec3, edge_u: Vec3, edge_v: Vec3, radiance: Vec3) -> Self {
        let c = edge_u.cross(edge_v);
        let area = c.length();
        QuadLight {
            corner,
            edge_u,
            edge_v,
            normal: c / area,
            area,
            radiance,
        }
    }

    /// Uniform area sampling. None when p sees the back (non-emitting) side, or lies in the
    /// light's plane: those directions carry no radiance, so no sample is the unbiased answer.
    pub fn sample_area(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let q = self.corner + self.edge_u * u[0] + self.edge_v * u[1];
        let (wi, d2) = direction_to(p, q)?;
        let cos_l = -self.normal.dot(wi);
        if cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point: q,
            normal: self.normal,
            // Two products and two sums (Higham's γ bound), plus the slack between the exact
            // parallelogram and the two f32 triangles it is traced as.
            point_error: gamma(6)
                * (self.corner.abs() + (self.edge_u * u[0]).abs() + (self.edge_v * u[1]).abs()),
            radiance: self.radiance,
            pdf: d2 / (self.area * cos_l),
            distant: false,
        })
    }

    /// Solid-angle pdf of [`Self::sample_area`] for the direction that reaches light point q.
    pub fn pdf_area(&self, p: Vec3, q: Vec3) -> f32 {
        let d = q - p;
        let d2 = d.length_squared();
        let cos_l = -self.normal.dot(d) / d2.sqrt();
        if cos_l > 0.0 {
            d2 / (self.area * cos_l)
        } else {
            0.0
        }
    }
}

impl QuadLight {
    /// The spherical rectangle seen from p, or None when p is behind the emitting side or in
    /// the plane (no radiance reaches p) or the solid angle is below
    /// [`MIN_SOLID_ANGLE`](crate::sampling::spherical::MIN_SOLID_ANGLE) (area sampling then).
    fn spherical_rect(&self, p: Vec3) -> Option<SphericalRectangle> {
        let corner = (self.corner - p).as_dvec3();
        if corner.dot(self.normal.as_dvec3()) >= 0.0 {
            return None;
        }
        SphericalRectangle::new(corner, self.edge_u.as_dvec3(), self.edge_v.as_dvec3())
            .filter(|r| r.area() >= MIN_SOLID_ANGLE)
    }

    /// p sees the emitting side.
    fn faces(&self, p: Vec3) -> bool {
        (p - self.corner).dot(self.normal) > 0.0
    }

    /// Uniform in the solid angle of the quad (Ureña, Fajardo, King 2013): pdf 1/Ω. Falls back
    /// to area sampling for tiny solid angles; [`Self::pdf_solid_angle`] makes the same choice.
    /// Needs orthogonal edges (checked when the scene is prepared).
    pub fn sample_solid_angle(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        if !self.faces(p) {
            return None;
        }
        let Some(rect) = self.spherical_rect(p) else {
            return self.sample_area(p, u);
        };
        let d = rect.sample([u[0] as f64, u[1] as f64]);
        let dist = d.length();
        let wi = (d / dist).as_vec3();
        let point = p + d.as_vec3();
        Some(LightSample {
            wi,
            point,
            normal: self.normal,
            // p + d rounded to f32; the f64 direction's own error is far below that.
            point_error: gamma(3) * (p.abs() + d.as_vec3().abs()),
            radiance: self.radiance,
            pdf: (1.0 / rect.area()) as f32,
            distant: false,
        })
    }

    pub fn pdf_solid_angle(&self, p: Vec3, q: Vec3) -> f32 {
        if !self.faces(p) {
            return 0.0;
        }
        match self.spherical_rect(p) {
            Some(rect) => (1.0 / rect.area()) as f32,
            None => self.pdf_area(p, q),
        }
    }

    /// Spherical-rectangle sampling assumes a rectangle, not a general parallelogram.
    pub fn is_rectangle(&self) -> bool {
        self.edge_u.dot(self.edge_v).abs() <= 1e-5 * self.edge_u.length() * self.edge_v.length()
    }
}

/// Where the lane kernels read their quads: one quad for every lane (constants), or each
/// lane's own (rows of a record: corner 0..3, edge_u 3..6, edge_v 6..9, normal 9..12, area 12,
/// radiance 13..16). Read where used, as f32 lanes or exactly as f64 lanes.
trait QuadLanes {
    fn corner<V: Vector<WIDTH>>(&self) -> V3<V>;
    fn edge_u<V: Vector<WIDTH>>(&self) -> V3<V>;
    fn edge_v<V: Vector<WIDTH>>(&self) -> V3<V>;
    fn normal<V: Vector<WIDTH>>(&self) -> V3<V>;
    fn area<V: Vector<WIDTH>>(&self) -> V;
    fn radiance<V: Vector<WIDTH>>(&self) -> V3<V>;
    fn edge_u_d<D: Vector64<WIDTH>>(&self) -> [D; 3];
    fn edge_v_d<D: Vector64<WIDTH>>(&self) -> [D; 3];
    fn normal_d<D: Vector64<WIDTH>>(&self) -> [D; 3];
}

impl QuadLanes for QuadLight {
    #[inline(always)]
    fn corner<V: Vector<WIDTH>>(&self) -> V3<V> {
        V3::splat(self.corner)
    }
    #[inline(always)]
    fn edge_u<V: Vector<WIDTH>>(&self) -> V3<V> {
        V3::splat(self.edge_u)
    }
    #[inline(always)]
    fn edge_v<V: Vector<WIDTH>>(&self) -> V3<V> {
        V3::splat(self.edge_v)
    }
    #[inline(always)]
    fn normal<V: Vector<WIDTH>>(&self) -> V3<V> {
        V3::splat(self.normal)
    }
    #[inline(always)]
    fn area<V: Vector<WIDTH>>(&self) -> V {
        V::splat(self.area)
    }
    #[inline(always)]
    fn radiance<V: Vector<WIDTH>>(&self) -> V3<V> {
        V3::splat(self.radiance)
    }
    #[inline(always)]
    fn edge_u_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        self.edge_u.as_dvec3().to_array().map(D::splat)
    }
    #[inline(always)]
    fn edge_v_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        self.edge_v.as_dvec3().to_array().map(D::splat)
    }
    #[inline(always)]
    fn normal_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        self.normal.as_dvec3().to_array().map(D::splat)
    }
}

impl QuadLanes for LaneRecords {
    #[inline(always)]
    fn corner<V: Vector<WIDTH>>(&self) -> V3<V> {
        record_rows(self, 0)
    }
    #[inline(always)]
    fn edge_u<V: Vector<WIDTH>>(&self) -> V3<V> {
        record_rows(self, 3)
    }
    #[inline(always)]
    fn edge_v<V: Vector<WIDTH>>(&self) -> V3<V> {
        record_rows(self, 6)
    }
    #[inline(always)]
    fn normal<V: Vector<WIDTH>>(&self) -> V3<V> {
        record_rows(self, 9)
    }
    #[inline(always)]
    fn area<V: Vector<WIDTH>>(&self) -> V {
        V::load(&self[12])
    }
    #[inline(always)]
    fn radiance<V: Vector<WIDTH>>(&self) -> V3<V> {
        record_rows(self, 13)
    }
    #[inline(always)]
    fn edge_u_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        record_rows_d(self, 3)
    }
    #[inline(always)]
    fn edge_v_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        record_rows_d(self, 6)
    }
    #[inline(always)]
    fn normal_d<D: Vector64<WIDTH>>(&self) -> [D; 3] {
        record_rows_d(self, 9)
    }
}

/// [`QuadLight::sample_area`] of each lane's quad for the lanes of `a` (u = `q.u[0..2]`), the
/// same operations in the same order over lanes; other lanes of `out` are kept.
#[inline(always)]
fn area_lanes<V: Vector<WIDTH>>(s: &impl QuadLanes, q: &LaneQuery, a: u32, out: &mut LaneSamples) {
    let zero = V::splat(0.0);
    let (u0, u1) = (V::load(q.u[0]), V::load(q.u[1]));
    let eu = s.edge_u::<V>().scale(u0);
    let ev = s.edge_v::<V>().scale(u1);
    let point = s.corner::<V>() + eu + ev;
    // direction_to
    let d = point - V3::load(q.p);
    let d2 = d.dot(d);
    let wi = d / d2.sqrt();
    let cos_l = s.normal::<V>().dot(wi).neg();
    let valid = a & zero.lt(d2) & !cos_l.le(zero);
    let error = (s.corner::<V>().abs() + eu.abs() + ev.abs()).scale(V::splat(gamma(6)));
    let pdf = d2.div(s.area::<V>().mul(cos_l));
    keep(a, wi, &mut out.wi);
    keep(a, point, &mut out.point);
    keep(a, s.normal::<V>(), &mut out.normal);
    keep(a, error, &mut out.point_error);
    keep(a, s.radiance::<V>(), &mut out.radiance);
    V::select(a, pdf, V::load(&out.pdf)).store(&mut out.pdf);
    out.valid = (out.valid & !a) | valid;
    out.distant &= !a;
}

/// [`QuadLight::sample_solid_angle`] of each lane's quad for the lanes of `a` (u =
/// `q.u[0..2]`), bit for bit: the same spherical rectangle over f64 lanes, area sampling
/// ([`area_lanes`]) for the lanes that fall back to it; other lanes of `out` are kept.
#[inline(always)]
fn solid_angle_lanes<V: Vector<WIDTH>, D: Vector64<WIDTH>>(
    s: &impl QuadLanes,
    q: &LaneQuery,
    a: u32,
    out: &mut LaneSamples,
) {
    let p = V3::<V>::load(q.p);
    let (rect, faces, solid) = rect_lanes::<V, D>(s, p, a);
    let d = rect.sample_lanes(D::from_f32(q.u[0]), D::from_f32(q.u[1]));
    let dist = dot3(d, d).sqrt();
    let wi = V3 {
        x: f32s::<V, D>(d[0].div(dist)),
        y: f32s::<V, D>(d[1].div(dist)),
        z: f32s::<V, D>(d[2].div(dist)),
    };
    let d32 = V3 {
        x: f32s::<V, D>(d[0]),
        y: f32s::<V, D>(d[1]),
        z: f32s::<V, D>(d[2]),
    };
    let point = p + d32;
    let error = (p.abs() + d32.abs()).scale(V::splat(gamma(3)));
    let pdf = f32s::<V, D>(D::splat(1.0).div(rect.area()));
    keep(solid, wi, &mut out.wi);
    keep(solid, point, &mut out.point);
    keep(solid, s.normal::<V>(), &mut out.normal);
    keep(solid, error, &mut out.point_error);
    keep(solid, s.radiance::<V>(), &mut out.radiance);
    V::select(solid, pdf, V::load(&out.pdf)).store(&mut out.pdf);
    // Lanes behind the light have no sample; tiny rectangles are sampled by area.
    out.valid = (out.valid & !(a & !faces)) | solid;
    out.distant &= !solid;
    area_lanes::<V>(s, q, faces & !solid, out);
}

/// [`QuadLight::faces`] and [`QuadLight::spherical_rect`] of each lane's quad for the lanes of
/// `a` seen from `p`: the rectangles, the lanes that face the emitting side, and those of them
/// whose rectangle is sampled (the others fall back to area sampling). Other lanes' rectangles
/// hold finite values that mean nothing.
#[inline(always)]
fn rect_lanes<V: Vector<WIDTH>, D: Vector64<WIDTH>>(
    s: &impl QuadLanes,
    p: V3<V>,
    a: u32,
) -> (SphericalRectangle<D>, u32, u32) {
    let corner32 = s.corner::<V>();
    let faces = a & V::splat(0.0).lt((p - corner32).dot(s.normal::<V>()));
    // The corner relative to p, rounded in f32 and then widened.
    let rel = corner32 - p;
    let corner = [d64::<V, D>(rel.x), d64::<V, D>(rel.y), d64::<V, D>(rel.z)];
    let n = s.normal_d::<D>();
    let front = dot3(corner, n).lt(D::splat(0.0));
    let (ex, ey) = (s.edge_u_d::<D>(), s.edge_v_d::<D>());
    let (rect, ok) = SphericalRectangle::<D>::lanes(corner, ex, ey);
    let solid = faces & front & ok & D::splat(MIN_SOLID_ANGLE).le(rect.area());
    (rect, faces, solid)
}

/// [`QuadLight::pdf_area`] of every lane of `at`.
#[inline(always)]
fn pdf_area_lanes<V: Vector<WIDTH>>(s: &impl QuadLanes, at: &SurfaceLanes) -> V {
    flat_area_pdf_lanes(s.normal::<V>(), s.area::<V>(), at)
}

/// [`QuadLight::pdf_solid_angle`] of the lanes of `a` (other lanes hold values that mean
/// nothing).
#[inline(always)]
fn pdf_solid_angle_lanes<V: Vector<WIDTH>, D: Vector64<WIDTH>>(
    s: &impl QuadLanes,
    at: &SurfaceLanes,
    a: u32,
) -> V {
    let zero = V::splat(0.0);
    let (rect, faces, solid) = rect_lanes::<V, D>(s, V3::load(&at.from.p), a);
    let pdf = V::select(solid, f32s::<V, D>(D::splat(1.0).div(rect.area())), zero);
    // Tiny rectangles were sampled by area (rare: only then is that pdf computed).
    let by_area = faces & !solid;
    if by_area == 0 {
        return pdf;
    }
    V::select(by_area, pdf_area_lanes::<V>(s, at), pdf)
}

/// Quads sampled over lanes of different quads (each lane's quad in a record), by the
/// method `m` picks: by area, or in the solid angle.
static QUAD_LANES: LaneKernel = LaneKernel {
    name: "quads",
    sample: sample_quad_records,
    pdf: pdf_quad_records,
};

fn pdf_quad_records(
    isa: Isa,
    records: &LaneRecords,
    at: &SurfaceLanes,
    active: u32,
    m: &LightMethods,
    out: &mut [f32; WIDTH],
) {
    simd::run(isa, QuadPdf(records, at, active, m.quad, out))
}

/// The pdfs of lanes `.2` of `.1` by method `.3` on quads `.0` (constants or records), into
/// `.4` (other lanes kept).
struct QuadPdf<'a, S>(
    &'a S,
    &'a SurfaceLanes,
    u32,
    QuadMethod,
    &'a mut [f32; WIDTH],
);

impl<S: QuadLanes> Kernel for QuadPdf<'_, S> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        let pdf = match self.3 {
            QuadMethod::Area => pdf_area_lanes::<L::V>(self.0, self.1),
            QuadMethod::SolidAngle => pdf_solid_angle_lanes::<L::V, L::D>(self.0, self.1, self.2),
        };
        L::V::select(self.2, pdf, L::V::load(self.4)).store(self.4)
    }
}

fn sample_quad_records(
    isa: Isa,
    records: &LaneRecords,
    q: &LaneQuery,
    active: u32,
    m: &LightMethods,
    out: &mut LaneSamples,
) {
    simd::run(isa, QuadKernel(records, q, active, m.quad, out))
}

/// Samples lanes `.2` of `.1` by method `.3` from quads `.0` (constants or records).
struct QuadKernel<'a, S>(
    &'a S,
    &'a LaneQuery<'a>,
    u32,
    QuadMethod,
    &'a mut LaneSamples,
);

impl<S: QuadLanes> Kernel for QuadKernel<'_, S> {
    type Out = ();
    #[inline(always)]
    fn run<L: Lanes>(self) {
        match self.3 {
            QuadMethod::Area => area_lanes::<L::V>(self.0, self.1, self.2, self.4),
            QuadMethod::SolidAngle => {
                solid_angle_lanes::<L::V, L::D>(self.0, self.1, self.2, self.4)
            }
        }
    }
}

impl Light for QuadLight {
    fn lane_record(&self, _m: &LightMethods) -> Option<(&'static LaneKernel, [f32; LANE_RECORD])> {
        let mut r = [0.0; LANE_RECORD];
        for (k, v) in [self.corner, self.edge_u, self.edge_v, self.normal]
            .iter()
            .enumerate()
        {
            r[3 * k..3 * k + 3].copy_from_slice(&v.to_array());
        }
        r[12] = self.area;
        r[13..16].copy_from_slice(&self.radiance.to_array());
        Some((&QUAD_LANES, r))
    }

    fn shape(&self) -> LightShape {
        LightShape::Quad
    }

    fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * luminance(self.radiance)
    }

    fn bounds(&self) -> Bounds {
        let (c, u, v) = (self.corner, self.edge_u, self.edge_v);
        Bounds::Local(LightBounds::flat(
            &[c, c + u, c + v, c + u + v],
            self.normal,
            luminance(self.radiance),
            self.area,
        ))
    }

    fn sample(&self, ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        match m.quad {
            QuadMethod::Area => self.sample_area(ctx.p, [u[0], u[1]]),
            QuadMethod::SolidAngle => self.sample_solid_angle(ctx.p, [u[0], u[1]]),
        }
    }

    fn sample_lanes(
        &self,
        isa: Isa,
        q: &LaneQuery,
        active: u32,
        m: &LightMethods,
        out: &mut LaneSamples,
    ) {
        simd::run(isa, QuadKernel(self, q, active, m.quad, out))
    }

    fn pdf(&self, ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        let LightHit::Surface { q, .. } = at else {
            return 0.0;
        };
        match m.quad {
            QuadMethod::Area => self.pdf_area(ctx.p, q),
            QuadMethod::SolidAngle => self.pdf_solid_angle(ctx.p, q),
        }
    }

    fn pdf_lanes(
        &self,
        isa: Isa,
        at: &SurfaceLanes,
        active: u32,
        m: &LightMethods,
        out: &mut [f32; WIDTH],
    ) {
        simd::run(isa, QuadPdf(self, at, active, m.quad, out))
    }

    fn usable_methods(&self, mut m: LightMethods) -> LightMethods {
        if !self.is_rectangle() {
            m.quad = QuadMethod::Area;
        }
        m
    }

    /// One-sided: the side of edge_u × edge_v.
    fn emitted(&self, n: Vec3, w: Vec3, _local: u32) -> Vec3 {
        if n.dot(w) > 0.0 {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }
}

/// χ² cases: a square of side `size` centred `dist` above the origin on +z, its emitting
/// normal tilted by `tilt` degrees away from facing the origin, sampled by each method.
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    QuadMethod::ALL
        .into_iter()
        .map(|method| {
            let name = match method {
                QuadMethod::Area => "quad-area",
                QuadMethod::SolidAngle => "quad-solid-angle",
            };
            crate::chi2::WarpEntry::new(
                name,
                match method {
                    QuadMethod::Area => "quad light, uniform by area, converted to solid angle",
                    QuadMethod::SolidAngle => "quad light, spherical rectangle (Ureña et al. 2013)",
                },
                &[("dist", 2.0), ("tilt", 30.0), ("size", 1.0)],
                &[
                    &[],
                    &[("tilt", 0.0), ("size", 4.0), ("dist", 1.0)],
                    &[("tilt", 85.0)],
                    &[("size", 0.01), ("dist", 5.0)],
                ],
                move |p| chi2_case(p, name, method),
            )
        })
        .collect()
}

fn chi2_case(
    p: &crate::chi2::Params,
    name: &str,
    method: QuadMethod,
) -> Result<crate::chi2::WarpCase, String> {
    use crate::chi2::{cap_around, first_hit, label, light_case, param};
    use crate::geometry::triangle::Triangle;
    let (dist, tilt, size) = (
        param(p, "dist"),
        param(p, "tilt").to_radians(),
        param(p, "size"),
    );
    if !(dist > 0.0 && size > 0.0 && (0.0..std::f32::consts::FRAC_PI_2).contains(&tilt)) {
        return Err("need dist > 0, size > 0 and tilt in [0, 90)".into());
    }
    let center = Vec3::new(0.0, 0.0, dist);
    let eu = Vec3::new(size, 0.0, 0.0);
    let ev = Vec3::new(0.0, -tilt.cos(), tilt.sin()) * size; // eu × ev faces -z tilted about x
    let corner = center - 0.5 * (eu + ev);
    let quad = QuadLight::new(corner, eu, ev, Vec3::ONE);
    let tris = [
        Triangle::new(corner, corner + eu, corner + eu + ev),
        Triangle::new(corner, corner + eu + ev, corner + ev),
    ];
    let chart = cap_around(
        center,
        &[corner, corner + eu, corner + ev, corner + eu + ev],
    );
    let methods = LightMethods {
        quad: method,
        ..LightMethods::BASIC
    };
    Ok(light_case(
        label(name, p),
        quad,
        methods,
        move |w| first_hit(&tris, w).map(|(q, _)| (q, 0)),
        chart,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::lane_tests;
    use crate::lights::{LaneQueryRows, LightMethods};
    use crate::sampling::stream::SampleStream;

    /// Spherical-rectangle samples of sixteen lanes at once are the scalar ones, bit for bit,
    /// on every ISA, for a rectangle with no axis-aligned edge: points in front of it near and
    /// far, 1e-5 off its plane, in its plane, behind it, and so far away that the solid angle
    /// falls below `MIN_SOLID_ANGLE` (area sampling, in the same kernel); u at 0 and just
    /// below 1 among the numbers; lanes outside the mask keep what they held.
    /// The tilted lamp of `tests/lanes.rs` (no edge has a zero component, so every lane
    /// operation's rounding shows).
    fn tilted() -> QuadLight {
        let (eu, ev) = (
            Vec3::new(0.4, 0.2, 0.4),
            Vec3::new(-0.333_333_3, 0.333_333_3, 0.166_666_67),
        );
        let light = QuadLight::new(Vec3::new(-0.3, 1.5, 0.1), eu, ev, Vec3::new(3.0, 2.0, 1.0));
        assert!(light.is_rectangle());
        light
    }

    /// A viewpoint of the kind `(lane + round) % 6`: far around the lamp, 1e-5 above its
    /// plane, in it, behind it, so far that its solid angle falls below `MIN_SOLID_ANGLE`, or
    /// just above it.
    fn viewpoint(light: &QuadLight, kind: usize, rng: &mut SampleStream) -> Vec3 {
        let (eu, ev, up) = (light.edge_u, light.edge_v, light.normal);
        let centre = light.corner + 0.5 * (eu + ev);
        let [a, b] = rng.next_2d();
        let [s, t] = rng.next_2d();
        let on_plane = light.corner + eu * (3.0 * s - 1.0) + ev * (3.0 * t - 1.0);
        match kind % 6 {
            0 => centre + crate::sampling::warp::sample_uniform_sphere([a, b]) * 3.0,
            1 => on_plane + up * 1e-5,
            2 => on_plane,
            3 => on_plane - up * (0.1 + a),
            4 => centre + up * 4e3 + eu * (a - 0.5) * 1e3,
            _ => on_plane + up * (0.01 + a),
        }
    }

    /// Lane `lane` of `at`: a [`viewpoint`] of kind `lane + round` and a point on `light`
    /// (its corner in every fourth lane, a point on its far edge in the next, else anywhere
    /// on it); returns the viewpoint's [`kind_of`].
    fn set_hit(
        at: &mut SurfaceLanes,
        lane: usize,
        round: usize,
        light: &QuadLight,
        rng: &mut SampleStream,
    ) -> usize {
        let p = viewpoint(light, lane + round, rng);
        let [s, t] = match lane % 4 {
            0 => [0.0, 0.0],
            1 => [1.0, rng.next_1d()],
            _ => rng.next_2d(),
        };
        let q = light.corner + light.edge_u * s + light.edge_v * t;
        let ctx = LightCtx {
            p,
            n: -light.normal,
        };
        at.set(lane, &ctx, q, 0);
        kind_of(light, p)
    }

    /// Which case of the scalar sampler `p` is: no sample, area, solid angle.
    fn kind_of(light: &QuadLight, p: Vec3) -> usize {
        match (light.faces(p), light.spherical_rect(p)) {
            (false, _) => 0,
            (true, None) => 1,
            (true, Some(_)) => 2,
        }
    }

    /// The solid-angle sampler over lanes is the scalar one bit for bit on every ISA, for
    /// points behind the light, in its plane, 1e-5 off it, far and near, and so far that it
    /// falls below `MIN_SOLID_ANGLE` (area sampling, in the same kernel); u at 0 and just
    /// below 1 among the numbers; lanes outside the mask keep what they held.
    #[test]
    fn solid_angle_lanes_are_the_scalar_samples_on_every_isa() {
        let light = tilted();
        let m = LightMethods {
            quad: QuadMethod::SolidAngle,
            ..LightMethods::BASIC
        };
        let mut rng = SampleStream::new(5, 2, 6, 1);
        let mut kinds = [0usize; 3];
        for round in 0..400 {
            let mut q = LaneQueryRows::default();
            for lane in 0..WIDTH {
                let p = viewpoint(&light, lane + round, &mut rng);
                q.p.set(lane, p);
                q.n.set(lane, -light.normal);
                lane_tests::set_numbers(&mut q, lane, round, &mut rng);
                kinds[kind_of(&light, p)] += 1;
            }
            let active = lane_tests::active_lanes(round, &mut rng);
            let label = format!("round {round}");
            lane_tests::assert_lanes_are_the_scalar_samples(&light, &q.query(), active, &m, &label);
        }
        assert!(kinds.iter().all(|&k| k > 400), "{kinds:?}");
    }

    /// Where the pdf kernel over records leaves [`QuadLight::pdf`] lane by lane on some ISA,
    /// for method `method`: sixteen quads per call ([`tilted`] moved and scaled lane by lane),
    /// seen from [`viewpoint`]s of every kind at points on each quad, corners and edges among
    /// them; the records changed by `alter`.
    fn pdf_records_mismatch(
        method: QuadMethod,
        alter: impl Fn(&mut LaneRecords),
    ) -> Option<String> {
        let m = LightMethods {
            quad: method,
            ..LightMethods::BASIC
        };
        let mut rng = SampleStream::new(8, 2, 6, 4);
        let mut kinds = [0usize; 3];
        for round in 0..300 {
            let mut at = SurfaceLanes::default();
            let mut lights = Vec::new();
            for lane in 0..WIDTH {
                let t = tilted();
                let [a, b] = rng.next_2d();
                let scale = 0.25 + 2.0 * a;
                let light = QuadLight::new(
                    t.corner + Vec3::new(b - 0.5, a, 0.5 * b),
                    t.edge_u * scale,
                    t.edge_v * scale,
                    t.radiance,
                );
                kinds[set_hit(&mut at, lane, round, &light, &mut rng)] += 1;
                lights.push(light);
            }
            let active = lane_tests::active_lanes(round, &mut rng);
            if let Some(e) = lane_tests::record_pdf_mismatch(&lights, &at, active, &m, &alter) {
                return Some(format!("{method:?} round {round}: {e}"));
            }
        }
        assert!(kinds.iter().all(|&k| k > 600), "{kinds:?}");
        None
    }

    /// Both methods' pdfs over records (lanes that hit different quads of a city's lamps and
    /// windows) are the scalar ones, bit for bit, on every ISA.
    #[test]
    fn pdfs_over_records_are_the_scalar_pdfs() {
        for method in QuadMethod::ALL {
            assert_eq!(pdf_records_mismatch(method, |_| ()), None);
        }
    }

    /// Controls: a record's area 1 % off is caught by area, its corner moved by 1 % of an
    /// edge in the solid angle.
    #[test]
    fn a_pdf_record_off_is_caught() {
        let area = pdf_records_mismatch(QuadMethod::Area, |r| r[12] = r[12].map(|a| a * 0.99));
        assert!(area.is_some());
        let moved = pdf_records_mismatch(QuadMethod::SolidAngle, |r| {
            for k in 0..3 {
                r[k] = std::array::from_fn(|lane| r[k][lane] + 0.01 * r[3 + k][lane]);
            }
        });
        assert!(moved.is_some());
    }

    /// Both methods' pdfs over lanes ([`Light::pdf_lanes`], the MIS weight of emission probes
    /// that hit the quad) are the scalar ones bit for bit on every ISA, from the viewpoints
    /// above, at points on the quad, its corners and edges among them; lanes outside the
    /// mask keep what they held.
    #[test]
    fn pdf_lanes_are_the_scalar_pdfs_on_every_isa() {
        let light = tilted();
        let mut rng = SampleStream::new(5, 3, 7, 2);
        let mut kinds = [0usize; 3];
        for method in QuadMethod::ALL {
            let m = LightMethods {
                quad: method,
                ..LightMethods::BASIC
            };
            for round in 0..400 {
                let mut at = SurfaceLanes::default();
                for lane in 0..WIDTH {
                    kinds[set_hit(&mut at, lane, round, &light, &mut rng)] += 1;
                }
                let active = lane_tests::active_lanes(round, &mut rng);
                let label = format!("{method:?} round {round}");
                lane_tests::assert_lane_pdfs_are_the_scalar_ones(&light, &at, active, &m, &label);
            }
        }
        assert!(kinds.iter().all(|&k| k > 800), "{kinds:?}");
    }
}
