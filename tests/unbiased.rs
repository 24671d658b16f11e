//! Unbiasedness of every estimator against closed forms. Each check is a two-sided z-test of
//! the sample mean with the standard error computed from the estimator's own sample variance,
//! at significance ALPHA; each also asserts that the test is sharp enough to see a 3 % bias.

use dibench::closed_form::{point_irradiance, polygon_irradiance, sphere_irradiance};
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::stats::z_critical;
use dibench::strategy::estimate::estimate_at;
use dibench::strategy::{ShadingPoint, by_name};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// False-alarm rate of one check. The seeds are fixed, so a pass is reproducible; ALPHA bounds
/// the chance that a correct estimator would have failed with a fresh seed.
const ALPHA: f64 = 1e-4;
const SAMPLES: u64 = 2_000_000;
/// The smallest relative bias each check must be able to detect.
const DETECTABLE_BIAS: f64 = 0.03;
const ALBEDO: [f32; 3] = [0.8, 0.5, 0.3];
const RADIANCE: [f32; 3] = [3.0, 2.0, 1.0];

const HEADER: &str = r#"
[camera]
eye = [0.0, 5.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[image]
width = 8
height = 8
[[material]]
name = "m"
albedo = [0.5, 0.5, 0.5]
"#;

fn prepare(body: &str, files: &[(&str, &str)]) -> PreparedScene {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = dir.path().join("test.toml");
    PreparedScene::new(Scene::parse(&format!("{HEADER}{body}"), &path).unwrap())
}

/// Reflected radiance ρE/π at p (normal n) must match the strategy's mean, channel by channel.
fn check(
    scene: &PreparedScene,
    strategy: &str,
    p: DVec3,
    n: DVec3,
    irradiance_per_unit_l: f64,
    seed: u64,
) {
    let s = by_name(strategy).unwrap();
    s.applies(scene).unwrap();
    let sp = ShadingPoint::new(p.as_vec3(), n.as_vec3(), -n.as_vec3(), Vec3::from(ALBEDO));
    let stats = estimate_at(scene, s.as_ref(), &sp, SAMPLES, seed);
    let z_crit = z_critical(ALPHA);
    for c in 0..3 {
        let expected = ALBEDO[c] as f64 / PI * irradiance_per_unit_l * RADIANCE[c] as f64;
        let st = &stats[c];
        let z = st.z_score(expected);
        assert!(
            z.abs() < z_crit,
            "{strategy}, channel {c}: mean {:.6e} vs closed form {expected:.6e} (se {:.2e}, z = {z:.2}, critical {z_crit:.2})",
            st.mean,
            st.std_error()
        );
        assert!(
            st.std_error() * z_crit < DETECTABLE_BIAS * expected,
            "{strategy}: standard error {:.2e} too large to detect a {}% bias of {expected:.3e}",
            st.std_error(),
            DETECTABLE_BIAS * 100.0
        );
    }
}

fn rgb(c: [f32; 3]) -> String {
    format!("[{}, {}, {}]", c[0], c[1], c[2])
}

#[test]
fn sphere_light_fully_above_the_horizon() {
    let (c, r) = (DVec3::new(0.4, 2.0, -0.3), 0.6);
    let scene = prepare(
        &format!(
            "[[sphere]]\ncenter = [0.4, 2.0, -0.3]\nradius = 0.6\nmaterial = \"m\"\nemission = {}\n",
            rgb(RADIANCE)
        ),
        &[],
    );
    let e = sphere_irradiance(DVec3::ZERO, DVec3::Y, c, r, 1.0);
    // The textbook form, to tie the general formula to E = πL sin²θmax cos θ.
    let d = c.length();
    assert!((e - PI * (r / d).powi(2) * c.y / d).abs() < 1e-12);
    for (k, s) in ["light", "cosine"].iter().enumerate() {
        check(&scene, s, DVec3::ZERO, DVec3::Y, e, 11 + k as u64);
    }
}

#[test]
fn sphere_light_partly_below_the_horizon() {
    let (c, r) = (DVec3::new(2.0, 0.3, 0.0), 0.6);
    let scene = prepare(
        &format!(
            "[[sphere]]\ncenter = [2.0, 0.3, 0.0]\nradius = 0.6\nmaterial = \"m\"\nemission = {}\n",
            rgb(RADIANCE)
        ),
        &[],
    );
    let e = sphere_irradiance(DVec3::ZERO, DVec3::Y, c, r, 1.0);
    for (k, s) in ["light", "cosine"].iter().enumerate() {
        check(&scene, s, DVec3::ZERO, DVec3::Y, e, 21 + k as u64);
    }
}

#[test]
fn quad_light_lamberts_formula() {
    let (corner, eu, ev) = (
        DVec3::new(-0.3, 1.5, -0.2),
        DVec3::new(0.9, 0.0, 0.2),
        DVec3::new(0.1, 0.3, 0.7),
    );
    assert!(
        eu.cross(ev).y < 0.0,
        "the emitting side (edge_u × edge_v) must face the receiver below"
    );
    let body = format!(
        "[[quad]]\ncorner = [{}, {}, {}]\nedge_u = [{}, {}, {}]\nedge_v = [{}, {}, {}]\nmaterial = \"m\"\nemission = {}\n",
        corner.x,
        corner.y,
        corner.z,
        eu.x,
        eu.y,
        eu.z,
        ev.x,
        ev.y,
        ev.z,
        rgb(RADIANCE)
    );
    let scene = prepare(&body, &[]);
    let e = polygon_irradiance(
        DVec3::ZERO,
        DVec3::Y,
        &[corner, corner + eu, corner + eu + ev, corner + ev],
        1.0,
    );
    for (k, s) in ["light", "cosine"].iter().enumerate() {
        check(&scene, s, DVec3::ZERO, DVec3::Y, e, 31 + k as u64);
    }
}

#[test]
fn back_of_a_quad_light_is_dark() {
    // Emitting side up (edge_u × edge_v = +y): the receiver below sees only its back.
    let scene = prepare(
        &format!(
            "[[quad]]\ncorner = [-0.5, 1.0, -0.5]\nedge_u = [0.0, 0.0, 1.0]\nedge_v = [1.0, 0.0, 0.0]\nmaterial = \"m\"\nemission = {}\n",
            rgb(RADIANCE)
        ),
        &[],
    );
    for s in ["light", "cosine"] {
        let st = by_name(s).unwrap();
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, Vec3::ONE);
        let stats = estimate_at(&scene, st.as_ref(), &sp, 10_000, 5);
        assert_eq!(
            stats[0].mean, 0.0,
            "{s} sees light from the back of a one-sided emitter"
        );
    }
}

/// A mesh light of four coplanar, non-overlapping triangles of unequal areas: area-proportional
/// triangle choice must still be unbiased. The closed form sums Lambert's formula per triangle.
#[test]
fn mesh_light_sum_of_triangles() {
    let v = [
        DVec3::new(-0.6, 1.2, -0.5),
        DVec3::new(0.7, 1.2, -0.4),
        DVec3::new(0.5, 1.2, 0.6),
        DVec3::new(-0.4, 1.2, 0.5),
        DVec3::new(0.0, 1.2, 0.9),
        DVec3::new(-0.1, 1.2, -0.9),
    ];
    // Faces wound so their normals point down (-y), the receiver's side.
    let faces = [[0usize, 1, 2], [0, 2, 3], [3, 2, 4], [0, 5, 1]];
    let mut obj = String::new();
    for p in &v {
        obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
    }
    for f in &faces {
        let (a, b, c) = (v[f[0]], v[f[1]], v[f[2]]);
        let down = (b - a).cross(c - a).y < 0.0;
        let f = if down { *f } else { [f[0], f[2], f[1]] };
        obj += &format!("f {} {} {}\n", f[0] + 1, f[1] + 1, f[2] + 1);
    }
    let scene = prepare(
        &format!(
            "[[mesh]]\nfile = \"light.obj\"\nmaterial = \"m\"\nemission = {}\n",
            rgb(RADIANCE)
        ),
        &[("light.obj", &obj)],
    );
    let p = DVec3::new(0.1, 0.0, 0.05);
    let e: f64 = faces
        .iter()
        .map(|f| polygon_irradiance(p, DVec3::Y, &[v[f[0]], v[f[1]], v[f[2]]], 1.0))
        .sum();
    for (k, s) in ["light", "cosine"].iter().enumerate() {
        check(&scene, s, p, DVec3::Y, e, 41 + k as u64);
    }
}

/// Several lights of different kinds: power-proportional selection must weight each by its pmf.
#[test]
fn mixed_lights_sum() {
    let body = format!(
        "[[sphere]]\ncenter = [0.8, 1.5, 0.0]\nradius = 0.3\nmaterial = \"m\"\nemission = {l}\n\
         [[quad]]\ncorner = [-1.0, 2.0, -0.5]\nedge_u = [0.5, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.6]\nmaterial = \"m\"\nemission = {l}\n",
        l = rgb(RADIANCE)
    );
    let scene = prepare(&body, &[]);
    let e = sphere_irradiance(DVec3::ZERO, DVec3::Y, DVec3::new(0.8, 1.5, 0.0), 0.3, 1.0)
        + polygon_irradiance(
            DVec3::ZERO,
            DVec3::Y,
            &[
                DVec3::new(-1.0, 2.0, -0.5),
                DVec3::new(-1.0, 2.0, 0.1),
                DVec3::new(-0.5, 2.0, 0.1),
                DVec3::new(-0.5, 2.0, -0.5),
            ],
            1.0,
        );
    for (k, s) in ["light", "cosine"].iter().enumerate() {
        check(&scene, s, DVec3::ZERO, DVec3::Y, e, 51 + k as u64);
    }
}

/// A point light's estimate is deterministic (one direction, no variance): it must equal
/// ρ/π · I cos θ / d² to f32 precision.
#[test]
fn point_light_is_exact() {
    let power = [12.0f32, 8.0, 4.0];
    let scene = prepare(
        &format!(
            "[[point_light]]\nposition = [0.3, 1.7, -0.4]\npower = {}\n",
            rgb(power)
        ),
        &[],
    );
    assert!(
        by_name("cosine").unwrap().applies(&scene).is_err(),
        "cosine sampling cannot see a point light"
    );
    let s = by_name("light").unwrap();
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, Vec3::from(ALBEDO));
    let stats = estimate_at(&scene, s.as_ref(), &sp, 16, 3);
    for c in 0..3 {
        let e = point_irradiance(
            DVec3::ZERO,
            DVec3::Y,
            DVec3::new(0.3, 1.7, -0.4),
            power[c] as f64 / (4.0 * PI),
        );
        let expected = ALBEDO[c] as f64 / PI * e;
        assert_eq!(stats[c].variance(), 0.0);
        assert!(
            ((stats[c].mean - expected) / expected).abs() < 1e-6,
            "channel {c}: {} vs {expected}",
            stats[c].mean
        );
    }
}
