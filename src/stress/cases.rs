//! The stiff cases, generated in code so each parameter sweep is one loop: tiny and near
//! lights, grazing and degenerate emitters, extreme Phong exponents, far-away geometry and
//! degenerate spot cones. Every case is a small scene (TOML text plus any OBJ files), one
//! shading point, and the closed-form reflected radiance there where one is known.

use super::{StressCase, ViewPoint};
use crate::closed_form::{point_irradiance, polygon_irradiance, sphere_irradiance};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// Grey everywhere: a sample is one number (the channel mean), checked against one closed form.
const ALBEDO: f64 = 0.8;

const HEADER: &str = "[camera]\neye = [0.0, 0.5, 6.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 50.0\n\
[image]\nwidth = 8\nheight = 8\n\
[[material]]\nname = \"grey\"\nalbedo = [0.8, 0.8, 0.8]\n";

fn v3(v: DVec3) -> String {
    format!("[{:e}, {:e}, {:e}]", v.x, v.y, v.z)
}

fn grey(l: f64) -> String {
    format!("[{l:e}, {l:e}, {l:e}]")
}

/// f32 coordinates as the scene will hold them, widened for the closed forms: the closed form
/// describes the geometry actually rendered, not the decimal the case was written with.
fn f32r(v: DVec3) -> DVec3 {
    v.as_vec3().as_dvec3()
}

/// A grey Lambertian point under lights whose irradiance at the shading point is `e(p)`.
/// Strategy sets that must resolve a case (see `StressCase::must_resolve`).
const MIS: [&str; 2] = ["mis-balance", "mis-power"];
const SPHERE_SAMPLERS: &[&str] = &[
    "light",
    "light-sphere-area",
    "light-sphere-cap",
    MIS[0],
    MIS[1],
];
const SPHERE_CONE: &[&str] = &["light", MIS[0], MIS[1]];
const QUAD_SAMPLERS: &[&str] = &["light", "light-quad-sa", MIS[0], MIS[1]];
const QUAD_SOLID_ANGLE: &[&str] = &["light-quad-sa", MIS[0], MIS[1]];
const MESH_SAMPLERS: &[&str] = &["light", "light-mesh-sa", MIS[0], MIS[1]];
const LIGHT_ONLY: &[&str] = &["light"];
const MIS_AND_LIGHT: &[&str] = &["light", MIS[0], MIS[1]];
const ALL: &[&str] = &[
    "uniform",
    "cosine",
    "bsdf",
    "light",
    "light-quad-sa",
    "light-sphere-area",
    "light-sphere-cap",
    "light-mesh-sa",
    MIS[0],
    MIS[1],
];

fn lambert_case(
    name: String,
    about: String,
    body: String,
    p: DVec3,
    n: DVec3,
    must_resolve: &'static [&'static str],
    e: impl Fn(DVec3) -> f64 + Send + Sync + 'static,
) -> StressCase {
    StressCase {
        name,
        about,
        scene: format!("{HEADER}{body}"),
        files: Vec::new(),
        point: ViewPoint::lambert(p, n, ALBEDO),
        expected: Some(Arc::new(move |p| ALBEDO / PI * e(p))),
        must_resolve,
        known_unresolvable: &[],
        why_unresolvable: "",
        every_env_representation: false,
    }
}

fn sphere_body(c: DVec3, r: f64, l: f64) -> String {
    format!(
        "[[sphere]]\ncenter = {}\nradius = {r:e}\nmaterial = \"grey\"\nemission = {}\n",
        v3(c),
        grey(l)
    )
}

fn quad_body(corner: DVec3, eu: DVec3, ev: DVec3, emission: Option<f64>) -> String {
    let mut s = format!(
        "[[quad]]\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"grey\"\n",
        v3(corner),
        v3(eu),
        v3(ev)
    );
    if let Some(l) = emission {
        s += &format!("emission = {}\n", grey(l));
    }
    s
}

fn quad_vertices(corner: DVec3, eu: DVec3, ev: DVec3) -> [DVec3; 4] {
    let (c, u, v) = (f32r(corner), f32r(eu), f32r(ev));
    [c, c + u, c + u + v, c + v]
}

/// Sphere lights seen under sinθmax = 1e-2 … 1e-6, both as a tiny sphere nearby and (at the
/// smallest size) as a unit sphere far away. Radiance 1/sin²θmax keeps the answer O(1).
fn tiny_spheres(out: &mut Vec<StressCase>) {
    let dir = DVec3::new(0.5, 1.0, 0.2).normalize();
    for k in 2..=6 {
        let s = 10f64.powi(-k);
        let (c, r) = (f32r(dir), s as f32 as f64);
        let l = 1.0 / (s * s);
        out.push(lambert_case(
            format!("sphere-sin-1e-{k}"),
            format!("sphere light of radius {s:e} at distance 1 (sinθmax = {s:e})"),
            sphere_body(c, r, l),
            DVec3::ZERO,
            DVec3::Y,
            SPHERE_SAMPLERS,
            move |p| sphere_irradiance(p, DVec3::Y, c, r, l),
        ));
    }
    let d = 1e6;
    let (c, r) = (f32r(dir * d), 1.0);
    let l = d * d;
    out.push(lambert_case(
        "sphere-far-1e6".into(),
        "unit sphere light 1e6 away (sinθmax = 1e-6, f32 spacing 0.06 at the light)".into(),
        sphere_body(c, r, l),
        DVec3::ZERO,
        DVec3::Y,
        SPHERE_SAMPLERS,
        move |p| sphere_irradiance(p, DVec3::Y, c, r, l),
    ));
}

/// Shading points 1e-6 from an emitter's surface, and inside a sphere light.
fn near_lights(out: &mut Vec<StressCase>) {
    // 1e-6 outside a unit sphere light, normal tilted 60° off the outward direction so the
    // sphere straddles the horizon (the partial-horizon closed form).
    let dir = DVec3::new(0.3, 1.0, -0.2).normalize();
    let p = f32r(dir * (1.0 + 1e-6));
    let side = dir.cross(DVec3::X).normalize();
    let n = (dir * 0.5 + side * (0.75f64).sqrt()).normalize();
    out.push(lambert_case(
        "sphere-near-1e-6".into(),
        "point 1e-6 outside a unit sphere light, sphere straddling its horizon".into(),
        sphere_body(DVec3::ZERO, 1.0, 1.0),
        p,
        n,
        SPHERE_CONE,
        move |p| sphere_irradiance(p, n, DVec3::ZERO, 1.0, 1.0),
    ));
    // 1e-6 below the centre of a unit quad light facing down (edge_u × edge_v = -y).
    let (corner, eu, ev) = (
        DVec3::new(-0.5, 1.0, -0.5),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 1.0),
    );
    let verts = quad_vertices(corner, eu, ev);
    let p = DVec3::new(0.0, f32r(DVec3::splat(1.0 - 1e-6)).y, 0.0);
    out.push(lambert_case(
        "quad-near-1e-6".into(),
        "point 1e-6 below the centre of a unit quad light".into(),
        quad_body(corner, eu, ev, Some(1.0)),
        p,
        DVec3::Y,
        QUAD_SOLID_ANGLE,
        move |p| polygon_irradiance(p, DVec3::Y, &verts, 1.0),
    ));
    // Inside a sphere light, deep and 1e-6 from its inner surface: E = πL whatever the normal.
    let n = DVec3::new(0.2, -0.9, 0.4).normalize();
    for (name, at) in [
        ("sphere-inside", 0.3),
        ("sphere-inside-near-1e-6", 1.0 - 1e-6),
    ] {
        let mut case = lambert_case(
            name.into(),
            format!("point at {at} of the radius inside a unit sphere light"),
            sphere_body(DVec3::ZERO, 1.0, 1.0),
            f32r(DVec3::new(0.0, at, 0.0)),
            n,
            ALL,
            |_| PI,
        );
        if at > 0.5 {
            // The surface 1e-6 above p fills the half-space above it; the receiver's hemisphere
            // takes (1 − 0.9)/2 = 5 % of its cosine-weighted directions from there, all from
            // surface points within ~1e-5 of p: a 3e-11 share of the sphere's area.
            case.known_unresolvable = &["light-sphere-area", "light-sphere-cap"];
            case.why_unresolvable =
                "area sampling from 1e-6 inside: 5% of E comes from 3e-11 of the area";
        }
        out.push(case);
    }
}

/// A unit quad light seen at 89.9°, 90° and 90.1° from its normal (in front, edge-on, behind),
/// then a huge (1e4) and a tiny (1e-4) one.
fn quads(out: &mut Vec<StressCase>) {
    // Light in the plane z = 0 facing +z, centred at (0, 2, 0); p sits 2 from the centre.
    let (corner, eu, ev) = (
        DVec3::new(-0.5, 1.5, 0.0),
        DVec3::new(1.0, 0.0, 0.0),
        DVec3::new(0.0, 1.0, 0.0),
    );
    let centre = DVec3::new(0.0, 2.0, 0.0);
    for (name, deg) in [
        ("quad-grazing-89.9", 89.9f64),
        ("quad-grazing-90", 90.0),
        ("quad-grazing-90.1", 90.1),
    ] {
        let t = deg.to_radians();
        let mut p = f32r(centre + 2.0 * DVec3::new(0.0, -t.sin(), t.cos()));
        if deg == 90.0 {
            p.z = 0.0; // exactly in the plane (cos 90° is 6e-17 in floating point)
        }
        let n = (f32r(centre) - p).normalize();
        let verts = quad_vertices(corner, eu, ev);
        let e = move |p: DVec3| {
            if p.z > 0.0 {
                polygon_irradiance(p, n, &verts, 1.0)
            } else {
                0.0 // edge-on or behind a one-sided emitter
            }
        };
        out.push(lambert_case(
            name.into(),
            format!("unit quad light seen {deg}° off its normal"),
            quad_body(corner, eu, ev, Some(1.0)),
            p,
            n,
            QUAD_SAMPLERS,
            e,
        ));
    }
    for (name, size, l) in [("quad-huge-1e4", 1e4, 1.0), ("quad-tiny-1e-4", 1e-4, 1e8)] {
        // edge_u × edge_v = -y: emitting down onto p.
        let (corner, eu, ev) = (
            DVec3::new(-0.3 * size, 1.0, -0.6 * size),
            DVec3::new(size, 0.0, 0.0),
            DVec3::new(0.0, 0.0, size),
        );
        let verts = quad_vertices(corner, eu, ev);
        out.push(lambert_case(
            name.into(),
            format!("square light of side {size:e} at height 1"),
            quad_body(corner, eu, ev, Some(l)),
            DVec3::ZERO,
            DVec3::Y,
            QUAD_SOLID_ANGLE,
            move |p| polygon_irradiance(p, DVec3::Y, &verts, l),
        ));
    }
}

/// Mesh lights with zero-area triangles, and with a 1e8 area ratio between two triangles.
fn meshes(out: &mut Vec<StressCase>) {
    let l = 1.0;
    let mesh = |verts: &[DVec3], faces: &[[usize; 3]]| {
        let mut obj = String::new();
        for v in verts {
            obj += &format!("v {:e} {:e} {:e}\n", v.x, v.y, v.z);
        }
        for f in faces {
            obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
        }
        obj
    };
    let body = format!(
        "[[mesh]]\nfile = \"light.obj\"\nmaterial = \"grey\"\nemission = {}\n",
        grey(l)
    );
    // Faces wound clockwise seen from above, so they emit downwards onto p at the origin.
    let irradiance = |verts: &[DVec3], faces: &[[usize; 3]]| {
        let tris: Vec<[DVec3; 3]> = faces
            .iter()
            .map(|f| [f32r(verts[f[0]]), f32r(verts[f[1]]), f32r(verts[f[2]])])
            .collect();
        move |p: DVec3| -> f64 {
            tris.iter()
                .map(|t| polygon_irradiance(p, DVec3::Y, t, l))
                .sum()
        }
    };
    let v = [
        DVec3::new(-0.5, 1.0, -0.5),
        DVec3::new(0.5, 1.0, -0.5),
        DVec3::new(0.5, 1.0, 0.5),
        DVec3::new(-0.5, 1.0, 0.5),
        DVec3::new(0.0, 1.0, 0.0), // on the diagonal 0–2: faces with it and 0, 2 are collinear
    ];
    let faces = [[0, 1, 2], [0, 2, 3], [0, 4, 2], [1, 1, 3]];
    let mut case = lambert_case(
        "mesh-degenerate".into(),
        "mesh light of two triangles plus a collinear and a repeated-vertex one (zero area)".into(),
        body.clone(),
        DVec3::ZERO,
        DVec3::Y,
        MESH_SAMPLERS,
        irradiance(&v, &faces[..2]),
    );
    case.files = vec![("light.obj".into(), mesh(&v, &faces).into_bytes())];
    out.push(case);

    let h = (2e-8f64).sqrt(); // legs of a right triangle of area 1e-8
    let v = [
        DVec3::new(-1.0, 1.0, -0.5),
        DVec3::new(0.0, 1.0, -0.5),
        DVec3::new(-1.0, 1.0, 1.5),
        DVec3::new(0.3, 1.0, 0.2),
        DVec3::new(0.3, 1.0, 0.2 + h),
        DVec3::new(0.3 + h, 1.0, 0.2),
    ];
    let faces = [[0, 1, 2], [3, 5, 4]];
    let mut case = lambert_case(
        "mesh-area-ratio-1e8".into(),
        "mesh light of two triangles with areas 1 and 1e-8".into(),
        body,
        DVec3::ZERO,
        DVec3::Y,
        MESH_SAMPLERS,
        irradiance(&v, &faces),
    );
    case.files = vec![("light.obj".into(), mesh(&v, &faces).into_bytes())];
    out.push(case);
}

/// Normalized Phong with n = 0, 1, 1e4, 1e6 inside a sphere light (L = 1 from every direction),
/// seen along the normal: the lobe sits wholly above the horizon and reflects exactly
/// kd + ks, since ∫ (n+2)/(2π) cos^(n+1)θ dω = 1.
fn phong(out: &mut Vec<StressCase>) {
    // Pure glossy at the high exponents, so that a sampler that never finds the lobe shows up
    // as unresolved (all-zero samples) rather than as a diffuse-only mean with a misleading
    // sample variance.
    for (name, exponent, kd, ks) in [
        ("phong-0", 0.0, 0.1, 0.8),
        ("phong-1", 1.0, 0.1, 0.8),
        ("phong-1e4", 1e4, 0.0, 0.9),
        ("phong-1e6", 1e6, 0.0, 0.9),
    ] {
        let body = format!(
            "[[material]]\nname = \"phong\"\nalbedo = [{kd}, {kd}, {kd}]\nspecular = [{ks}, {ks}, {ks}]\nexponent = {exponent:e}\n{}",
            sphere_body(DVec3::ZERO, 3.0, 1.0)
        );
        out.push(StressCase {
            name: name.into(),
            about: format!("kd {kd} + ks {ks} Phong, exponent {exponent:e}, inside a sphere light"),
            scene: format!("{HEADER}{body}"),
            files: Vec::new(),
            point: ViewPoint {
                p: DVec3::new(0.2, -0.3, 0.1),
                n: DVec3::Y,
                view_dir: -DVec3::Y,
                kd,
                ks,
                exponent,
                material: None,
                trace_from: None,
            },
            expected: Some(Arc::new(move |_| kd + ks)),
            // A lobe 1e-3 rad wide is found by BSDF sampling, not by sampling the sphere.
            must_resolve: if exponent > 1e3 {
                &["bsdf", MIS[0], MIS[1]]
            } else {
                ALL
            },
            // Measured: mis-balance lands 6e-6 (relative) below kd + ks at n = 1e6 with a
            // relative variance of 3e-8, i.e. an f32 precision floor of the lobe's pdf near
            // its peak (bsdf sampling cannot show it: its f/pdf cancels by construction).
            known_unresolvable: if exponent > 1e5 { &[MIS[0]] } else { &[] },
            why_unresolvable: "f32 precision floor of the n = 1e6 lobe pdf (~6e-6 relative)",
            every_env_representation: false,
        });
    }
}

/// GGX reflection (F = 1) with α = 1e-4 and α = 1, isotropic and 10:1 anisotropic, seen 89.9°
/// and 89.99° off the normal from inside a sphere light of L = 1: the reflected radiance is
/// the single-scattering white furnace E(wo), 1 − μ ln(1 + 1/μ) at α = 1 (exact) and the f64
/// reference quadrature otherwise. At α = 1e-4 the lobe is 2e-4 rad wide and, at 89.99°, the
/// mirror direction sits 1.7e-4 rad above the horizon.
fn microfacet(out: &mut Vec<StressCase>) {
    use crate::bsdf::quadrature::{ggx_white_furnace, ggx_white_furnace_alpha_one};
    const SAMPLED: &[&str] = &[
        "bsdf",
        "bsdf-ggx-vndf-cap",
        "bsdf-ggx-vndf-bounded",
        MIS[0],
        MIS[1],
        "mis-power-ggx-vndf-cap",
        "mis-power-ggx-vndf-bounded",
    ];
    for (name, ax, ay) in [
        ("ggx-1e-4", 1e-4f64, 1e-4f64),
        ("ggx-aniso-1e-3x1e-4", 1e-3, 1e-4),
        ("ggx-1", 1.0, 1.0),
        ("ggx-aniso-1x0.1", 1.0, 0.1),
    ] {
        for deg in [89.9f64, 89.99] {
            let t = deg.to_radians();
            // Seen along (sin θ, −cos θ, 0.3 sin θ)/|…|: off both anisotropy axes (local x is
            // world +X and local y world −Z for the normal +Y).
            let view_dir = DVec3::new(t.sin(), -t.cos(), 0.3 * t.sin()).normalize();
            let wo_world = -view_dir;
            let wo = DVec3::new(wo_world.x, -wo_world.z, wo_world.y);
            let e = if ax == 1.0 && ay == 1.0 {
                ggx_white_furnace_alpha_one(wo.z)
            } else {
                ggx_white_furnace(ax, ay, wo, 1e-7).value.x
            };
            let body = format!(
                "[[material]]\nname = \"ggx\"\ntype = \"ggx\"\nalpha = [{ax:e}, {ay:e}]\n{}",
                sphere_body(DVec3::ZERO, 3.0, 1.0)
            );
            // Measured: NDF sampling lands 1.7 % (z ≈ 6.6) above E at α = 1e-4 seen at
            // 89.99°. There a reflected direction, rounded to f32, keeps the tilt of its
            // half vector (~1e-4) to only ~100 %: the sum wo + wi that recovers h cancels to
            // ~3e-8, below wi's own 6e-8 spacing. NDF's f·cos/pdf = G2·|wo·h|/(cos θo cos θh)
            // takes |·| of that noise (convex: biased up); the visible-normal samplers'
            // G2/G1 does not depend on h, and stay within their standard errors.
            let ndf_floor = ax == 1e-4 && deg > 89.95;
            out.push(StressCase {
                name: format!("{name}-grazing-{deg}"),
                about: format!(
                    "GGX αx {ax:e}, αy {ay:e}, F = 1, seen {deg}° off the normal inside a sphere light (E = {e:.6})"
                ),
                scene: format!("{HEADER}{body}"),
                files: Vec::new(),
                point: ViewPoint {
                    p: DVec3::new(0.2, -0.3, 0.1),
                    n: DVec3::Y,
                    view_dir,
                    kd: 0.0,
                    ks: 0.0,
                    exponent: 0.0,
                    material: Some("ggx"),
                    trace_from: None,
                },
                expected: Some(Arc::new(move |_| e)),
                must_resolve: SAMPLED,
                known_unresolvable: if ndf_floor {
                    &["bsdf-ggx-ndf", "mis-power-ggx-ndf"]
                } else {
                    &[]
                },
                why_unresolvable: "f32 floor: wi near the horizon does not hold a 1e-4 lobe's half vector, and NDF's weight |wo·h|/cos θo amplifies it (+1.7 %)",
                every_env_representation: false,
            });
        }
    }
}

/// A floor and a quad light 1e5 units from the origin, the floor tilted so the shading point
/// (found by a traced ray, as in a render) is off the plane by f32 rounding: a shadow ray that
/// re-hits its own surface darkens the mean, and an offset that overshoots (a 256-ulp offset
/// is 2 units here) starts rays above the light.
fn far_geometry(out: &mut Vec<StressCase>) {
    let o = DVec3::splat(1e5);
    let (fu, fv) = (DVec3::new(4.0, 0.3, 0.0), DVec3::new(0.0, 0.7, -4.0));
    let floor_n = fu.cross(fv).normalize();
    let floor_corner = o - 0.5 * (fu + fv);
    let p = f32r(o + 0.37 * fu.normalize() - 0.21 * fv.normalize());
    // The light 1 above the floor's centre, facing down, axis-aligned with corners on the f32
    // grid (spacing 1/128 at 1e5): the traced triangles and the sampled parallelogram are then
    // the same set, and the closed form describes both. (With rounded corners the two differ
    // by up to half a grid step per vertex: ~1 % of this light's area.)
    // Eight units up: the floor point's error bound there is γ₇·1e5 ≈ 0.04, and rays for
    // emission probes start that far above p, seeing a light at distance 1 under a ~8 % larger
    // solid angle (measured); at distance 8 the effect is ~1 %, below this test's resolution.
    let (lu, lv) = (DVec3::new(6.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 6.0));
    let light_corner = o + DVec3::new(-3.0, 8.0, -3.0);
    let mut body = quad_body(floor_corner, fu, fv, None);
    body += &quad_body(light_corner, lu, lv, Some(1.0));
    let n = f32r(floor_n).normalize();
    let verts = quad_vertices(light_corner, lu, lv);
    let mut case = lambert_case(
        "far-geometry-1e5".into(),
        "point on a tilted floor 1e5 from the origin under a quad light, found by a traced ray (self-intersection)".into(),
        body,
        p,
        n,
        MIS_AND_LIGHT,
        move |p| polygon_irradiance(p, n, &verts, 1.0),
    );
    // Seen from 3 units away, past the light's edge, so the floor point is a real hit.
    case.point.trace_from = Some(p + 3.0 * (n + 0.9 * fu.normalize()).normalize());
    out.push(case);
}

/// A floor in the plane y = 0, the shading point found by a traced ray: the point's error
/// bound along the normal is exactly zero, so its rays start on the floor itself and only the
/// intersector's own conservative t bound (pbrt-v4 §6.8.7) keeps them from re-hitting it.
/// Without that bound every shadow ray was occluded at t ~ 1e-10 (found by the Embree
/// cross-check on the Cornell box, whose floor, back and left walls lie in such planes).
fn plane_through_origin(out: &mut Vec<StressCase>) {
    let (fu, fv) = (DVec3::new(0.0, 0.0, 4.0), DVec3::new(4.0, 0.0, 0.0));
    let floor_corner = DVec3::new(-2.0, 0.0, -2.0);
    let (lu, lv) = (DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 0.0, 1.0));
    // Off to the side: rays towards it are x-dominant, so the watertight test's shear mixes
    // the floor's coordinates and its t for the floor is rounding, not an exact 0.
    let light_corner = DVec3::new(1.8, 1.0, -0.5);
    let mut body = quad_body(floor_corner, fu, fv, None);
    body += &quad_body(light_corner, lu, lv, Some(1.0));
    let verts = quad_vertices(light_corner, lu, lv);
    let p = DVec3::new(0.3, 0.0, -0.2);
    let mut case = lambert_case(
        "plane-through-origin".into(),
        "point on a floor in the plane y = 0 (zero error along the normal), found by a traced ray"
            .into(),
        body,
        p,
        DVec3::Y,
        ALL,
        move |p| polygon_irradiance(p, DVec3::Y, &verts, 1.0),
    );
    // From beside the light, so the traced ray meets the floor first.
    case.point.trace_from = Some(p + DVec3::new(-2.0, 1.5, 0.0));
    out.push(case);
}

/// Spot lights with cones of 0° (lights only its axis: nothing reaches an off-axis point) and
/// 180° (all directions: a point light).
fn spots(out: &mut Vec<StressCase>) {
    let pos = DVec3::new(0.3, 2.0, -0.2);
    let i = 5.0;
    for (name, cone) in [("spot-cone-0", 0.0), ("spot-cone-180", 180.0)] {
        let at = f32r(pos);
        let e = move |p| {
            if cone > 0.0 {
                point_irradiance(p, DVec3::Y, at, i)
            } else {
                0.0
            }
        };
        let body = format!(
            "[[spot_light]]\nposition = {}\ndirection = [0.0, -1.0, 0.0]\ncone_angle_deg = {cone:?}\nintensity = {}\n",
            v3(pos),
            grey(i)
        );
        out.push(lambert_case(
            name.into(),
            format!("spot light with a {cone}° cone, point off its axis"),
            body,
            DVec3::ZERO,
            DVec3::Y,
            LIGHT_ONLY,
            e,
        ));
    }
}

/// A directional light's shadow ray runs along the light's direction, unbounded: an occluder
/// straight above p blocks it, one beside p (between p and the world origin) does not.
fn directional(out: &mut Vec<StressCase>) {
    let light =
        "[[directional_light]]\ndirection = [0.0, -1.0, 0.0]\nirradiance = [2.0, 2.0, 2.0]\n";
    let p = DVec3::new(5.0, 0.0, 5.0);
    for (name, occluder, e) in [
        (
            "directional-occluded",
            quad_body(
                DVec3::new(4.0, 3.0, 4.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(0.0, 0.0, 2.0),
                None,
            ),
            0.0,
        ),
        (
            "directional-open",
            "[[sphere]]\ncenter = [2.5, 0.0, 2.5]\nradius = 0.5\nmaterial = \"grey\"\n".to_string(),
            2.0,
        ),
    ] {
        out.push(lambert_case(
            name.into(),
            format!("directional light from straight above, {name}"),
            format!("{light}{occluder}"),
            p,
            DVec3::Y,
            LIGHT_ONLY,
            move |_| e,
        ));
    }
}

/// Every stiff case, in a stable order.
pub fn all() -> Vec<StressCase> {
    let mut out = Vec::new();
    tiny_spheres(&mut out);
    near_lights(&mut out);
    quads(&mut out);
    meshes(&mut out);
    phong(&mut out);
    microfacet(&mut out);
    far_geometry(&mut out);
    plane_through_origin(&mut out);
    spots(&mut out);
    directional(&mut out);
    environments(&mut out);
    out
}

/// A lat/long map as EXR bytes (written through the crate's own writer, then read back).
fn latlong_exr(width: usize, height: usize, texel: impl Fn(usize, usize) -> f32) -> Vec<u8> {
    use crate::env::map::{LatLongImage, write_latlong};
    let img = LatLongImage {
        width,
        height,
        pixels: (0..width * height)
            .map(|k| glam::Vec3::splat(texel(k % width, k / width)))
            .collect(),
        clamped: 0,
    };
    let dir = tempfile::tempdir().expect("a temporary directory");
    let path = dir.path().join("map.exr");
    write_latlong(&path, &img).expect("writing a temporary EXR");
    std::fs::read(&path).expect("reading back a temporary EXR")
}

/// Environment maps at the extremes, lighting a Lambertian point facing +Y (the lat/long pole),
/// with nothing else in the scene. The black and 1×1 maps are the same function in every
/// representation, so all 16 environment strategies run on them; for the sun map the suite
/// runs the `direct` integrand, i.e. the lat/long representation, which reproduces a 512×256
/// input texel for texel (nearest reconstruction, resampled at the same resolution), so the
/// closed form is an exact sum over texels:
/// ∫ over a texel of cos θ dω = Δφ (sin²θ₁ − sin²θ₀)/2 in the upper hemisphere.
fn environments(out: &mut Vec<StressCase>) {
    const ENV_ALL: &[&str] = &[
        "uniform",
        "cosine",
        "bsdf",
        MIS[0],
        "env-latlong-cdf",
        "env-latlong-hier",
        "mis-env-latlong-cdf",
        "mis-env-latlong-hier",
        "env-cube-cdf",
        "env-cube-hier",
        "env-octa-cdf",
        "env-octa-hier",
        "env-healpix-cdf",
        "env-healpix-hier",
        "mis-env-cube-cdf",
        "mis-env-cube-hier",
        "mis-env-octa-cdf",
        "mis-env-octa-hier",
        "mis-env-healpix-cdf",
        "mis-env-healpix-hier",
    ];
    const ENV_SAMPLERS: &[&str] = &[
        "env-latlong-cdf",
        "env-latlong-hier",
        "mis-env-latlong-cdf",
        "mis-env-latlong-hier",
    ];
    let body = "[environment]\nfile = \"env.exr\"\n".to_string();
    let with_map = |name: &str, about: String, exr: Vec<u8>, must, e: f64| {
        let mut case = lambert_case(
            name.into(),
            about,
            body.clone(),
            DVec3::ZERO,
            DVec3::Y,
            must,
            move |_| e,
        );
        case.files = vec![("env.exr".into(), exr)];
        case
    };
    // Sun: one texel 1e6 times the sky (max/median = 1e6), 30° from the zenith.
    let (w, h) = (512usize, 256usize);
    let (sky, sun) = (1e-3f64, 1e3f64);
    let (sx, sy) = (77usize, 42usize);
    let texel_cos = |y: usize| {
        let (t0, t1) = (PI * y as f64 / h as f64, PI * (y + 1) as f64 / h as f64);
        2.0 * PI / w as f64 * (t1.sin().powi(2) - t0.sin().powi(2)) / 2.0
    };
    let e_sun = PI * sky + (sun - sky) * texel_cos(sy);
    let mut sun_case = with_map(
        "env-sun-1e6",
        format!(
            "512×256 map: sky {sky:e}, one sun texel {sun:e} (max/median 1e6) 30° from the normal"
        ),
        latlong_exr(w, h, |x, y| {
            if (x, y) == (sx, sy) {
                sun as f32
            } else {
                sky as f32
            }
        }),
        ENV_SAMPLERS,
        e_sun,
    );
    // The sun texel is 2e-5 of the cosine-weighted hemisphere: direction samplers see it about
    // once per 50,000 samples, so their mean is the sky's alone (a rare-event miss the
    // effective sample size cannot flag, since the sky makes every sample non-zero).
    sun_case.known_unresolvable = &["uniform", "cosine", "bsdf"];
    sun_case.why_unresolvable = "direction sampling meets the 2e-5 sun about once per 5e4 samples";
    out.push(sun_case);
    // All black: no sampler is built, the baselines must return exactly 0.
    let mut black = with_map(
        "env-black",
        "64×32 map, every texel 0".into(),
        latlong_exr(64, 32, |_, _| 0.0),
        &[],
        0.0,
    );
    black.every_env_representation = true;
    out.push(black);
    // 1×1: a constant environment, E = πL, in every representation.
    let l = 0.7f64;
    let mut constant = with_map(
        "env-1x1",
        format!(
            "1×1 map of radiance {l} (a constant environment, E = πL, in every representation)"
        ),
        latlong_exr(1, 1, |_, _| l as f32),
        ENV_ALL,
        PI * l,
    );
    constant.every_env_representation = true;
    out.push(constant);
}
