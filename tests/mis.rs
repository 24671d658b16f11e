//! MIS weights as the estimators apply them, for samples whose pdfs are known: one light
//! sample and one BSDF sample at a Lambertian point under one rectangular light, with fixed
//! sample dimensions. The light sample's weight must be the heuristic's w(p_light, p_bsdf),
//! the BSDF sample's w(p_bsdf, p_light), and for one direction the two weights sum to one.

use dibench::bsdf::Bsdf;
use dibench::prepare::PreparedScene;
use dibench::sampling::Dims;
use dibench::scene::Scene;
use dibench::strategy::{ShadingPoint, by_name};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// A 1 × 0.6 rectangle light 1 above the origin, off-centre, emitting downwards.
const SCENE: &str = r#"
[camera]
eye = [0.0, 5.0, 5.0]
look_at = [0.0, 0.0, 0.0]
fov_y_deg = 40.0
[image]
width = 4
height = 4
[[material]]
name = "m"
albedo = [0.5, 0.5, 0.5]
[[quad]]
corner = [-0.2, 1.0, -0.3]
edge_u = [1.0, 0.0, 0.0]
edge_v = [0.0, 0.0, 0.6]
material = "m"
emission = [1.0, 1.0, 1.0]
"#;

/// Solid angle of a planar polygon seen from the origin (sum of Van Oosterom–Strackee triangle
/// angles over a fan).
fn solid_angle(v: &[DVec3]) -> f64 {
    (1..v.len() - 1)
        .map(|i| {
            let (a, b, c) = (v[0], v[i], v[i + 1]);
            let num = a.dot(b.cross(c)).abs();
            let (la, lb, lc) = (a.length(), b.length(), c.length());
            let den = la * lb * lc + a.dot(b) * lc + a.dot(c) * lb + b.dot(c) * la;
            2.0 * num.atan2(den)
        })
        .sum()
}

fn weights(h: &str) -> (f64, f64) {
    let dir = tempfile::tempdir().unwrap();
    let scene = PreparedScene::new(Scene::parse(SCENE, &dir.path().join("mis.toml")).unwrap());
    let white = Bsdf::lambertian(Vec3::ONE);
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &white);
    let omega = solid_angle(&[
        DVec3::new(-0.2, 1.0, -0.3),
        DVec3::new(-0.2, 1.0, 0.3),
        DVec3::new(0.8, 1.0, 0.3),
        DVec3::new(0.8, 1.0, -0.3),
    ]);
    let p_light = 1.0 / omega; // one light: selection pmf 1; spherical rectangle: uniform
    let mis = by_name(h).unwrap();
    let est = mis.bind(scene.view(mis.integrand())).unwrap();
    let reference = by_name("light-quad-sa").unwrap();
    let plain = reference.bind(scene.view(reference.integrand())).unwrap();
    // Light: selection, point (0.3, 0.6), part; BSDF: direction (0.45, 0.5) (cosine lobe near
    // the normal, which hits the light), lobe.
    let u = [0.5, 0.3, 0.6, 0.5, 0.45, 0.5, 0.5];
    let probes = est.sample(&sp, &mut Dims::new(&u));
    let unweighted = plain.sample(&sp, &mut Dims::new(&u[..4]));
    let (shadow, base) = (probes.shadow.unwrap(), unweighted.shadow.unwrap());
    let wi = shadow.ray.dir.as_dvec3();
    let p_bsdf = wi.y / PI;
    let w_light = shadow.value.x as f64 / base.value.x as f64;
    // The BSDF sample: its direction hits the light; its weight is the estimator's.
    let e = probes.emission.unwrap();
    let hit = scene
        .tracer
        .intersect(&e.ray)
        .expect("the BSDF direction hits the light");
    let surf = scene.surface(&e.ray, &hit);
    let w_bsdf = est.emission_weight(&sp, &e, &surf) as f64;
    let p_light_at_bsdf_dir = p_light;
    let r_light = p_bsdf / p_light;
    let r_bsdf = p_light_at_bsdf_dir / (e.ray.dir.y as f64 / PI);
    let expect = |r: f64| match h {
        "mis-power" => 1.0 / (1.0 + r * r),
        _ => 1.0 / (1.0 + r),
    };
    assert!(
        (w_light - expect(r_light)).abs() < 1e-4,
        "{h}: light weight {w_light} vs {}",
        expect(r_light)
    );
    assert!(
        (w_bsdf - expect(r_bsdf)).abs() < 1e-4,
        "{h}: BSDF weight {w_bsdf} vs {}",
        expect(r_bsdf)
    );
    (w_light, expect(1.0 / r_light))
}

#[test]
fn mis_weights_are_the_heuristics_and_sum_to_one() {
    for h in ["mis-power", "mis-balance"] {
        let (w_light, w_bsdf_same_dir) = weights(h);
        assert!((w_light + w_bsdf_same_dir - 1.0).abs() < 1e-6, "{h}");
        // Away from p_light = p_bsdf, where both heuristics give ½, so the test tells them apart.
        assert!(
            (w_light - 0.5).abs() > 0.1,
            "{h}: weight {w_light} does not separate the heuristics"
        );
    }
}

/// `mis-power-area` applies where some light's area and solid-angle samplers differ (a quad,
/// a mesh light) and is refused as `mis-power` itself elsewhere (a sphere: the cone both ways).
#[test]
fn area_mis_applies_only_where_it_differs() {
    use dibench::strategy::applies;
    let load =
        |name: &str| PreparedScene::new(Scene::load(&Scene::resolve(name).unwrap()).unwrap());
    let area = by_name("mis-power-area").unwrap();
    for name in ["cornell", "mesh_light"] {
        assert_eq!(applies(area.as_ref(), &load(name)), Ok(()), "{name}");
    }
    let why = applies(area.as_ref(), &load("sphere_light")).unwrap_err();
    assert!(why.contains("identical to `mis-power`"), "{why}");
}
