//! Emissive triangle meshes, one light per triangle, emitting on front faces (counter-clockwise
//! winding). The selector picks the triangle, so a light BVH can weigh every triangle by its
//! own distance, orientation and radiance (Conty Estevez & Kulla 2018 build their tree over
//! triangles for the same reason). Under power selection a mesh of one radiance is sampled
//! exactly as when it was one light choosing triangle i with probability A_i/A: the power
//! pmf of triangle i is P_mesh/P·A_i/A, the product the former sampler had.
//! Area sampling: a uniform point, pdf_A = 1/A_i, converted to solid angle by d²/|cos θ_l|.
//! Solid-angle sampling: uniform on the spherical triangle (Arvo 1995), pdf 1/Ω_i.

use super::bounds::{Bounds, LightBounds};
use super::{
    LANE_RECORD, LaneKernel, LaneQuery, LaneRecords, LaneSamples, Light, LightCtx, LightHit,
    LightMethods, LightSample, LightShape, MeshMethod, direction_to, record_rows,
};
use crate::geometry::triangle::Triangle;
use crate::math::gamma;
use crate::math::luminance;
use crate::sampling::spherical::{MIN_SOLID_ANGLE, SphericalTriangle, triangle_solid_angle};
use crate::sampling::warp::{sample_uniform_triangle, uniform_triangle};
use crate::simd::{self, Isa, Lanes, Soa3, V3, Vector, WIDTH};
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub struct TriangleLight {
    pub triangle: Triangle,
    /// Unit normal of the emitting (front) face.
    pub normal: Vec3,
    pub area: f32,
    pub radiance: Vec3,
}

impl TriangleLight {
    /// None for a triangle without area (collinear or repeated vertices): it cannot emit.
    pub fn new(triangle: Triangle, radiance: Vec3) -> Option<Self> {
        let c = triangle.cross();
        let area = 0.5 * c.length();
        let normal = c.normalize_or_zero();
        (area > 0.0 && normal != Vec3::ZERO).then_some(TriangleLight {
            triangle,
            normal,
            area,
            radiance,
        })
    }

    /// A uniform point on the triangle. None when p sees its back or lies in its plane.
    pub fn sample_area(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        let (q, q_error) = self.triangle.point_uniform(u);
        let (wi, d2) = direction_to(p, q)?;
        let cos_l = -self.normal.dot(wi);
        if cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point: q,
            normal: self.normal,
            point_error: q_error,
            radiance: self.radiance,
            pdf: d2 / (self.area * cos_l),
            distant: false,
        })
    }

    /// Solid-angle pdf of [`Self::sample_area`] for the direction reaching light point q.
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

    /// The triangle as a spherical triangle seen from p, when it is large enough for f64
    /// solid-angle sampling.
    fn spherical_triangle(&self, p: Vec3) -> Option<SphericalTriangle> {
        let t = &self.triangle;
        let (a, b, c) = (
            (t.v0 - p).as_dvec3().normalize(),
            (t.v1 - p).as_dvec3().normalize(),
            (t.v2 - p).as_dvec3().normalize(),
        );
        if triangle_solid_angle(a, b, c) < MIN_SOLID_ANGLE {
            return None;
        }
        SphericalTriangle::new(a, b, c)
    }

    fn faces(&self, p: Vec3) -> bool {
        (p - self.triangle.v0).dot(self.normal) > 0.0
    }

    /// Uniform in the triangle's solid angle (Arvo 1995): pdf 1/Ω. Triangles too small in
    /// solid angle are sampled by area instead; the pdf follows suit.
    pub fn sample_solid_angle(&self, p: Vec3, u: [f32; 2]) -> Option<LightSample> {
        if !self.faces(p) {
            return None;
        }
        let Some(st) = self.spherical_triangle(p) else {
            return self.sample_area(p, u);
        };
        let w = st.sample([u[0] as f64, u[1] as f64]);
        // Where the direction meets the triangle's plane.
        let n = self.normal.as_dvec3();
        let cos = w.dot(n);
        if cos >= 0.0 {
            return None; // grazing the plane: measure zero for a front-facing triangle
        }
        let dist = (self.triangle.v0 - p).as_dvec3().dot(n) / cos;
        let point = p + (w * dist).as_vec3();
        Some(LightSample {
            wi: w.as_vec3(),
            point,
            normal: self.normal,
            point_error: gamma(3) * (p.abs() + (w * dist).as_vec3().abs()),
            radiance: self.radiance,
            pdf: (1.0 / st.area()) as f32,
            distant: false,
        })
    }

    pub fn pdf_solid_angle(&self, p: Vec3, q: Vec3) -> f32 {
        if !self.faces(p) {
            return 0.0;
        }
        match self.spherical_triangle(p) {
            Some(st) => (1.0 / st.area()) as f32,
            None => self.pdf_area(p, q),
        }
    }
}

impl Triangle {
    /// A uniform point and its error bound.
    pub fn point_uniform(&self, u: [f32; 2]) -> (Vec3, Vec3) {
        let (b1, b2) = sample_uniform_triangle(u);
        (self.point(b1, b2), self.point_error(b1, b2))
    }
}

/// Area sampling of mesh triangles with each lane's own triangle (its record: v0, v1, v2, the
/// normal, the area, the radiance), over lanes.
static AREA_LANES: LaneKernel = LaneKernel {
    name: "mesh triangles by area",
    sample: sample_area_lanes,
};

fn sample_area_lanes(
    isa: Isa,
    records: &LaneRecords,
    q: &LaneQuery,
    active: u32,
    _m: &LightMethods,
    out: &mut LaneSamples,
) {
    struct Kernel<'a>(&'a LaneRecords, &'a LaneQuery, u32, &'a mut LaneSamples);
    impl simd::Kernel for Kernel<'_> {
        type Out = ();
        #[inline(always)]
        fn run<L: Lanes>(self) {
            area_lanes::<L::V>(self.0, self.1, self.2, self.3)
        }
    }
    simd::run(isa, Kernel(records, q, active, out))
}

/// [`TriangleLight::sample_area`] for each lane's triangle, bit for bit.
#[inline(always)]
fn area_lanes<V: Vector<WIDTH>>(r: &LaneRecords, q: &LaneQuery, a: u32, out: &mut LaneSamples) {
    let v3 = |k: usize| record_rows::<V>(r, k);
    let (b1, b2) = uniform_triangle(V::load(&q.u[0]), V::load(&q.u[1]));
    let (point, error) = Triangle::point_lanes([v3(0), v3(3), v3(6)], b1, b2);
    let normal = v3(9);
    // direction_to
    let d = point - V3::load(&q.p);
    let d2 = d.dot(d);
    let wi = d / d2.sqrt();
    let cos_l = normal.dot(wi).neg();
    let zero = V::splat(0.0);
    let valid = a & zero.lt(d2) & !cos_l.le(zero);
    let pdf = d2.div(V::load(&r[12]).mul(cos_l));
    let keep = |new: V3<V>, old: &mut Soa3| V3::select(a, new, V3::load(old)).store(old);
    keep(wi, &mut out.wi);
    keep(point, &mut out.point);
    keep(normal, &mut out.normal);
    keep(error, &mut out.point_error);
    keep(v3(13), &mut out.radiance);
    V::select(a, pdf, V::load(&out.pdf)).store(&mut out.pdf);
    out.valid = (out.valid & !a) | valid;
    out.distant &= !a;
}

impl Light for TriangleLight {
    /// Area sampling through its kernel over records, this triangle's record in every lane.
    fn sample_lanes(
        &self,
        isa: Isa,
        q: &LaneQuery,
        active: u32,
        m: &LightMethods,
        out: &mut LaneSamples,
    ) {
        match self.lane_record(m) {
            Some((k, r)) => (k.sample)(isa, &r.map(|v| [v; WIDTH]), q, active, m, out),
            None => super::sample_lane_by_lane(self, q, active, m, out),
        }
    }

    fn lane_record(&self, m: &LightMethods) -> Option<(&'static LaneKernel, [f32; LANE_RECORD])> {
        if m.mesh != MeshMethod::Area {
            return None;
        }
        let t = &self.triangle;
        let mut r = [0.0; LANE_RECORD];
        for (k, v) in [t.v0, t.v1, t.v2, self.normal].iter().enumerate() {
            r[3 * k..3 * k + 3].copy_from_slice(&v.to_array());
        }
        r[12] = self.area;
        r[13..16].copy_from_slice(&self.radiance.to_array());
        Some((&AREA_LANES, r))
    }

    fn shape(&self) -> LightShape {
        LightShape::Mesh
    }

    fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * luminance(self.radiance)
    }

    fn bounds(&self) -> Bounds {
        let t = &self.triangle;
        Bounds::Local(LightBounds::flat(
            &[t.v0, t.v1, t.v2],
            self.normal,
            luminance(self.radiance),
            self.area,
        ))
    }

    fn sample(&self, ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        let u = [u[0], u[1]];
        match m.mesh {
            MeshMethod::Area => self.sample_area(ctx.p, u),
            MeshMethod::SolidAngle => self.sample_solid_angle(ctx.p, u),
        }
    }

    fn pdf(&self, ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        let LightHit::Surface { q, .. } = at else {
            return 0.0;
        };
        match m.mesh {
            MeshMethod::Area => self.pdf_area(ctx.p, q),
            MeshMethod::SolidAngle => self.pdf_solid_angle(ctx.p, q),
        }
    }

    /// One-sided: front faces (counter-clockwise winding).
    fn emitted(&self, n: Vec3, w: Vec3, _local: u32) -> Vec3 {
        if n.dot(w) > 0.0 {
            self.radiance
        } else {
            Vec3::ZERO
        }
    }
}

/// χ² cases: four coplanar triangles of unequal area facing down onto the origin from
/// `height`, one triangle picked by the power selector (∝ area here), then sampled by each
/// method: the whole distribution a mesh light's sample has.
pub fn chi2_cases() -> Vec<crate::chi2::WarpEntry> {
    MeshMethod::ALL
        .into_iter()
        .map(|method| {
            let name = match method {
                MeshMethod::Area => "mesh-area",
                MeshMethod::SolidAngle => "mesh-solid-angle",
            };
            crate::chi2::WarpEntry::new(
                name,
                match method {
                    MeshMethod::Area => "mesh light, triangle by power then uniform by area",
                    MeshMethod::SolidAngle => {
                        "mesh light, triangle by power then spherical triangle (Arvo 1995)"
                    }
                },
                &[("height", 1.2)],
                &[&[], &[("height", 0.3)], &[("height", 20.0)]],
                move |p| chi2_case(p, name, method),
            )
        })
        .collect()
}

/// Triangles behind the power selector as one light, for the χ² adapter: u[2] selects.
#[derive(Debug)]
struct PowerSelected {
    triangles: Vec<TriangleLight>,
    table: crate::sampling::discrete::AliasTable,
}

impl Light for PowerSelected {
    fn shape(&self) -> LightShape {
        LightShape::Mesh
    }

    fn power(&self) -> f32 {
        self.triangles.iter().map(|t| t.power()).sum()
    }

    fn bounds(&self) -> Bounds {
        let mut sum = super::bounds::BoundsSum::default();
        for t in &self.triangles {
            if let Bounds::Local(b) = t.bounds() {
                sum.add(&b);
            }
        }
        Bounds::Local(sum.bounds())
    }

    fn sample(&self, ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        let i = self.table.sample(u[2] as f64);
        let mut s = self.triangles[i].sample(ctx, u, m)?;
        s.pdf *= self.table.pmf(i);
        Some(s)
    }

    fn pdf(&self, ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        let LightHit::Surface { local, .. } = at else {
            return 0.0;
        };
        let i = local as usize;
        self.table.pmf(i) * self.triangles[i].pdf(ctx, at, m)
    }
}

fn chi2_case(
    p: &crate::chi2::Params,
    name: &str,
    method: MeshMethod,
) -> Result<crate::chi2::WarpCase, String> {
    use crate::chi2::{cap_around, first_hit, label, light_case, param};
    let h = param(p, "height");
    if h <= 0.0 {
        return Err("height must be positive".into());
    }
    let v = [
        Vec3::new(-0.6, -0.5, h),
        Vec3::new(0.7, -0.4, h),
        Vec3::new(0.5, 0.6, h),
        Vec3::new(-0.4, 0.5, h),
        Vec3::new(0.0, 0.9, h),
        Vec3::new(-0.1, -0.9, h),
    ];
    let faces = [[0usize, 2, 1], [0, 3, 2], [3, 4, 2], [0, 1, 5]];
    let tris: Vec<Triangle> = faces
        .iter()
        .map(|f| Triangle::new(v[f[0]], v[f[1]], v[f[2]]))
        .collect();
    debug_assert!(tris.iter().all(|t| t.cross().z < 0.0));
    let triangles: Vec<TriangleLight> = tris
        .iter()
        .map(|&t| TriangleLight::new(t, Vec3::ONE).ok_or("degenerate triangle"))
        .collect::<Result<_, _>>()?;
    let powers: Vec<f32> = triangles.iter().map(|t| t.power()).collect();
    let table = crate::sampling::discrete::AliasTable::new(&powers).ok_or("no power")?;
    let chart = cap_around(Vec3::new(0.0, 0.0, h), &v);
    let methods = LightMethods {
        mesh: method,
        ..LightMethods::BASIC
    };
    Ok(light_case(
        label(name, p),
        PowerSelected { triangles, table },
        methods,
        move |w| first_hit(&tris, w),
        chart,
    ))
}
