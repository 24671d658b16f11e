//! Emissive triangle mesh, emitting on front faces (counter-clockwise winding).
//! Area sampling: a triangle chosen with probability A_i/A, then a uniform point on it, so the
//! area pdf is 1/A over the whole mesh; converted to solid angle by d²/|cos θ_l|.

use super::{
    Light, LightCtx, LightHit, LightMethods, LightSample, LightShape, MeshMethod, direction_to,
};
use crate::geometry::triangle::Triangle;
use crate::math::gamma;
use crate::math::luminance;
use crate::sampling::discrete::DiscreteDistribution;
use crate::sampling::spherical::{MIN_SOLID_ANGLE, SphericalTriangle, triangle_solid_angle};
use crate::sampling::warp::sample_uniform_triangle;
use glam::Vec3;

#[derive(Clone, Debug)]
pub struct MeshLight {
    pub triangles: Vec<Triangle>,
    /// Unit normals; zero for degenerate triangles, which are never sampled (weight 0).
    pub normals: Vec<Vec3>,
    pub area: f32,
    pub by_area: DiscreteDistribution,
    pub radiance: Vec3,
}

impl MeshLight {
    /// None when the mesh has no area at all.
    pub fn new(triangles: Vec<Triangle>, radiance: Vec3) -> Option<Self> {
        let areas: Vec<f32> = triangles.iter().map(Triangle::area).collect();
        let by_area = DiscreteDistribution::new(&areas)?;
        let normals = triangles
            .iter()
            .map(|t| t.cross().normalize_or_zero())
            .collect();
        Some(MeshLight {
            area: by_area.total() as f32,
            triangles,
            normals,
            by_area,
            radiance,
        })
    }

    /// u[2] picks the triangle (a fresh dimension, not a rescaled one: with 1e8 area ratios a
    /// rescaled u would have no resolution left), u[0..2] the point on it.
    pub fn sample_area(&self, p: Vec3, u: [f32; 3]) -> Option<LightSample> {
        let i = self.by_area.sample(u[2]);
        let (q, q_error) = self.triangles[i].point_uniform([u[0], u[1]]);
        let n = self.normals[i];
        let (wi, d2) = direction_to(p, q)?;
        let cos_l = -n.dot(wi);
        if cos_l <= 0.0 {
            return None;
        }
        Some(LightSample {
            wi,
            point: q,
            normal: n,
            point_error: q_error,
            radiance: self.radiance,
            pdf: d2 / (self.area * cos_l),
            distant: false,
        })
    }

    /// Solid-angle pdf of [`Self::sample_area`] for the direction reaching point q on triangle i.
    pub fn pdf_area(&self, p: Vec3, q: Vec3, i: usize) -> f32 {
        let d = q - p;
        let d2 = d.length_squared();
        let cos_l = -self.normals[i].dot(d) / d2.sqrt();
        if cos_l > 0.0 {
            d2 / (self.area * cos_l)
        } else {
            0.0
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

impl MeshLight {
    /// Triangle i as a spherical triangle seen from p, when p sees its front and it is large
    /// enough for f64 solid-angle sampling.
    fn spherical_triangle(&self, p: Vec3, i: usize) -> Option<SphericalTriangle> {
        let t = &self.triangles[i];
        let (a, b, c) = (
            (t.v0 - p).as_dvec3(),
            (t.v1 - p).as_dvec3(),
            (t.v2 - p).as_dvec3(),
        );
        let (a, b, c) = (a.normalize(), b.normalize(), c.normalize());
        if triangle_solid_angle(a, b, c) < MIN_SOLID_ANGLE {
            return None;
        }
        SphericalTriangle::new(a, b, c)
    }

    fn faces(&self, p: Vec3, i: usize) -> bool {
        (p - self.triangles[i].v0).dot(self.normals[i]) > 0.0
    }

    /// Triangle by area (u[2]), then uniform in its solid angle (Arvo 1995): pdf pmf_i/Ω_i.
    /// Triangles too small in solid angle are sampled by area instead; the pdf follows suit.
    pub fn sample_solid_angle(&self, p: Vec3, u: [f32; 3]) -> Option<LightSample> {
        let i = self.by_area.sample(u[2]);
        if !self.faces(p, i) {
            return None;
        }
        let Some(st) = self.spherical_triangle(p, i) else {
            return self.sample_area(p, u);
        };
        let w = st.sample([u[0] as f64, u[1] as f64]);
        // Where the direction meets the triangle's plane.
        let t = &self.triangles[i];
        let n = self.normals[i].as_dvec3();
        let cos = w.dot(n);
        if cos >= 0.0 {
            return None; // grazing the plane: measure zero for a front-facing triangle
        }
        let dist = (t.v0 - p).as_dvec3().dot(n) / cos;
        let point = p + (w * dist).as_vec3();
        let pdf = (self.by_area.pmf(i) as f64 / st.area()) as f32;
        Some(LightSample {
            wi: w.as_vec3(),
            point,
            normal: self.normals[i],
            point_error: gamma(3) * (p.abs() + (w * dist).as_vec3().abs()),
            radiance: self.radiance,
            pdf,
            distant: false,
        })
    }

    pub fn pdf_solid_angle(&self, p: Vec3, q: Vec3, i: usize) -> f32 {
        if !self.faces(p, i) {
            return 0.0;
        }
        match self.spherical_triangle(p, i) {
            Some(st) => (self.by_area.pmf(i) as f64 / st.area()) as f32,
            None => self.pdf_area(p, q, i),
        }
    }
}

impl Light for MeshLight {
    fn shape(&self) -> LightShape {
        LightShape::Mesh
    }

    fn power(&self) -> f32 {
        std::f32::consts::PI * self.area * luminance(self.radiance)
    }

    fn sample(&self, ctx: &LightCtx, u: [f32; 3], m: &LightMethods) -> Option<LightSample> {
        match m.mesh {
            MeshMethod::Area => self.sample_area(ctx.p, u),
            MeshMethod::SolidAngle => self.sample_solid_angle(ctx.p, u),
        }
    }

    fn pdf(&self, ctx: &LightCtx, at: LightHit, m: &LightMethods) -> f32 {
        let LightHit::Surface { q, local } = at else {
            return 0.0;
        };
        match m.mesh {
            MeshMethod::Area => self.pdf_area(ctx.p, q, local as usize),
            MeshMethod::SolidAngle => self.pdf_solid_angle(ctx.p, q, local as usize),
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
/// `height`, sampled by each method.
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
                    MeshMethod::Area => "mesh light, triangle by area then uniform by area",
                    MeshMethod::SolidAngle => {
                        "mesh light, triangle by area then spherical triangle (Arvo 1995)"
                    }
                },
                &[("height", 1.2)],
                &[&[], &[("height", 0.3)], &[("height", 20.0)]],
                move |p| chi2_case(p, name, method),
            )
        })
        .collect()
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
    let light = MeshLight::new(tris.clone(), Vec3::ONE).ok_or("degenerate mesh")?;
    let chart = cap_around(Vec3::new(0.0, 0.0, h), &v);
    let methods = LightMethods {
        mesh: method,
        ..LightMethods::BASIC
    };
    Ok(light_case(
        label(name, p),
        light,
        methods,
        move |w| first_hit(&tris, w),
        chart,
    ))
}
