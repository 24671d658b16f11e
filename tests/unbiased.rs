//! Unbiasedness of every estimator against closed forms. Each check is a two-sided z-test of
//! the sample mean with the standard error computed from the estimator's own sample variance,
//! at significance ALPHA; each also asserts that the test is sharp enough to see a 3 % bias.
//! Every check runs with every sample generator: the independent one as described, the
//! others (stratified, Sobol, Z-Sobol) over independently randomized replicates
//! (`PointCase::check_with`), whose spread is the honest standard error of correlated samples.

use dibench::bsdf::Bsdf;
use dibench::closed_form::{PointCase, point_irradiance, polygon_irradiance, sphere_irradiance};
use dibench::prepare::PreparedScene;
use dibench::sampling::GENERATORS;
use dibench::scene::Scene;
use dibench::stats::z_critical;
use dibench::strategy::estimate::estimate_at;
use dibench::strategy::{Integrand, ShadingPoint, Strategy, applicable, applies, by_name};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

/// False-alarm rate of one check. The seeds are fixed, so a pass is reproducible; ALPHA bounds
/// the chance that a correct estimator would have failed with a fresh seed.
const ALPHA: f64 = 1e-4;
const SAMPLES: u64 = 2_000_000;
/// Samples of each non-independent generator's check: 32 replicates of 8,192.
const QMC_SAMPLES: u64 = 32 * 8192;
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
/// Every direct-illumination strategy that applies to the scene, checked against the closed form.
fn check_all(scene: &PreparedScene, p: DVec3, n: DVec3, irradiance_per_unit_l: f64, seed: u64) {
    let (run, _) = applicable(scene);
    let direct: Vec<_> = run
        .into_iter()
        .filter(|s| s.integrand() == Integrand::DIRECT)
        .collect();
    assert!(direct.len() >= 2, "expected several strategies to compare");
    for (k, s) in direct.iter().enumerate() {
        check(
            scene,
            s.as_ref(),
            p,
            n,
            irradiance_per_unit_l,
            seed + 100 * k as u64,
        );
    }
}

fn check(
    scene: &PreparedScene,
    s: &dyn Strategy,
    p: DVec3,
    n: DVec3,
    irradiance_per_unit_l: f64,
    seed: u64,
) {
    let expected: [f64; 3] =
        std::array::from_fn(|c| ALBEDO[c] as f64 / PI * irradiance_per_unit_l * RADIANCE[c] as f64);
    let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
    check_mean(
        scene,
        s,
        ShadingPoint::new(p.as_vec3(), n.as_vec3(), -n.as_vec3(), &bsdf),
        expected,
        seed,
    );
}

/// z-test of a strategy's mean radiance at `sp` against `expected`, per channel.
fn check_mean(
    scene: &PreparedScene,
    s: &dyn Strategy,
    sp: ShadingPoint,
    expected: [f64; 3],
    seed: u64,
) {
    let case = PointCase {
        scene,
        point: sp,
        expected,
    };
    if let Err(e) = case.check(s, SAMPLES, seed, ALPHA, DETECTABLE_BIAS) {
        panic!("{e}");
    }
    // The same closed form with every other generator: REPLICATES independently randomized
    // replicates of QMC_SAMPLES / REPLICATES samples, t-tested across replicates.
    for g in GENERATORS.iter().filter(|g| !g.independent_samples()) {
        if let Err(e) = case.check_with(*g, s, QMC_SAMPLES, seed, ALPHA, DETECTABLE_BIAS) {
            panic!("{e}");
        }
    }
}

/// A 0.5 × 0.6 rectangle light of radiance [`RADIANCE`] facing down, 2 above the point.
fn rectangle() -> String {
    format!(
        "[[quad]]\ncorner = [-1.0, 2.0, -0.5]\nedge_u = [0.5, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.6]\nmaterial = \"m\"\nemission = {}\n",
        rgb(RADIANCE)
    )
}

/// The irradiance per unit radiance at the origin (normal +y) from [`rectangle`].
fn rectangle_irradiance() -> f64 {
    polygon_irradiance(
        DVec3::ZERO,
        DVec3::Y,
        &[
            DVec3::new(-1.0, 2.0, -0.5),
            DVec3::new(-1.0, 2.0, 0.1),
            DVec3::new(-0.5, 2.0, 0.1),
            DVec3::new(-0.5, 2.0, -0.5),
        ],
        1.0,
    )
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
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 11);
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
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 21);
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
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 31);
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
        let white = Bsdf::lambertian(Vec3::ONE);
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &white);
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
    check_all(&scene, p, DVec3::Y, e, 41);
}

/// Several lights of different kinds: power-proportional selection must weight each by its pmf.
#[test]
fn mixed_lights_sum() {
    let body = format!(
        "[[sphere]]\ncenter = [0.8, 1.5, 0.0]\nradius = 0.3\nmaterial = \"m\"\nemission = {l}\n{}",
        rectangle(),
        l = rgb(RADIANCE)
    );
    let scene = prepare(&body, &[]);
    let e = sphere_irradiance(DVec3::ZERO, DVec3::Y, DVec3::new(0.8, 1.5, 0.0), 0.3, 1.0)
        + rectangle_irradiance();
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 51);
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
        applies(by_name("cosine").unwrap().as_ref(), &scene).is_err(),
        "cosine sampling cannot see a point light"
    );
    let s = by_name("light").unwrap();
    let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &bsdf);
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

/// A rotated rectangle (orthogonal edges), so spherical-rectangle sampling applies.
#[test]
fn rectangle_light_solid_angle_sampling() {
    let corner = DVec3::new(-0.4, 1.3, -0.1);
    let (eu, ev) = (DVec3::new(0.6, -0.2, 0.3), DVec3::new(-0.1, 0.0, 0.2));
    let ev = ev - eu * (ev.dot(eu) / eu.length_squared()); // orthogonalise
    let (eu, ev) = if eu.cross(ev).y < 0.0 {
        (eu, ev)
    } else {
        (ev, eu)
    };
    let f = |v: DVec3| format!("[{}, {}, {}]", v.x, v.y, v.z);
    let scene = prepare(
        &format!(
            "[[quad]]\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"m\"\nemission = {}\n",
            f(corner),
            f(eu),
            f(ev),
            rgb(RADIANCE)
        ),
        &[],
    );
    assert!(applies(by_name("light-quad-sa").unwrap().as_ref(), &scene).is_ok());
    let e = polygon_irradiance(
        DVec3::ZERO,
        DVec3::Y,
        &[corner, corner + eu, corner + eu + ev, corner + ev],
        1.0,
    );
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 61);
}

/// Inside an emitting sphere E = πL at any point and orientation: every sphere method's
/// inside branch, and directions hitting the inner face.
#[test]
fn inside_an_emitting_sphere() {
    let scene = prepare(
        &format!(
            "[[sphere]]\ncenter = [0.1, 0.2, -0.1]\nradius = 2.0\nmaterial = \"m\"\nemission = {}\n",
            rgb(RADIANCE)
        ),
        &[],
    );
    let n = DVec3::new(0.3, 0.8, -0.5).normalize();
    check_all(&scene, DVec3::new(0.5, -0.4, 0.9), n, PI, 71);
}

/// Ambient occlusion under a spherical occluder fully above the horizon: AO = 1 - sin²σ cos β.
#[test]
fn ambient_occlusion_under_a_sphere() {
    let scene = prepare(
        "[ambient_occlusion]\ndistance = 1000.0\n[[sphere]]\ncenter = [0.5, 1.5, 0.2]\nradius = 0.7\nmaterial = \"m\"\n[[point_light]]\nposition = [0.0, 5.0, 0.0]\npower = [1.0, 1.0, 1.0]\n",
        &[],
    );
    let c = DVec3::new(0.5, 1.5, 0.2);
    let ao = 1.0 - sphere_irradiance(DVec3::ZERO, DVec3::Y, c, 0.7, 1.0) / PI;
    for (k, name) in ["ao-uniform", "ao-cosine"].iter().enumerate() {
        let s = by_name(name).unwrap();
        let white = Bsdf::lambertian(Vec3::ONE);
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &white);
        check_mean(&scene, s.as_ref(), sp, [ao; 3], 81 + k as u64);
    }
}

/// A point light beside an emitting rectangle, so MIS applies: the BSDF half cannot reach the
/// point light, so its light samples must weigh 1, and every strategy must find both lights'
/// sum (the point light's intensity is 0.4·L per channel, so one irradiance per unit L holds).
#[test]
fn point_light_beside_an_area_light_sums() {
    let k = 0.4;
    let power = RADIANCE.map(|l| (4.0 * PI * k) as f32 * l);
    let body = format!(
        "[[point_light]]\nposition = [0.3, 1.7, -0.4]\npower = {}\n{}",
        rgb(power),
        rectangle()
    );
    let scene = prepare(&body, &[]);
    let e = point_irradiance(DVec3::ZERO, DVec3::Y, DVec3::new(0.3, 1.7, -0.4), k)
        + rectangle_irradiance();
    assert!(
        applies(by_name("mis-power").unwrap().as_ref(), &scene).is_ok(),
        "MIS applies beside an emitting surface"
    );
    check_all(&scene, DVec3::ZERO, DVec3::Y, e, 61);
}

/// Spot and directional lights are deterministic estimates: exact to f32 precision.
#[test]
fn spot_and_directional_lights_are_exact() {
    let body = "[[spot_light]]\nposition = [0.2, 2.0, 0.1]\ndirection = [0.0, -1.0, 0.2]\ncone_angle_deg = 30.0\nfalloff_start_deg = 5.0\nintensity = [4.0, 4.0, 4.0]\n\
                [[directional_light]]\ndirection = [0.3, -1.0, 0.1]\nirradiance = [2.0, 1.0, 0.5]\n";
    let scene = prepare(body, &[]);
    let s = by_name("light").unwrap();
    let white = Bsdf::lambertian(Vec3::ONE);
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &white);
    // Each sample picks one of the two lights; the mean of many is their sum, but every
    // individual value is one light's exact contribution / pmf: check the mean to the pmf mix.
    let stats = estimate_at(&scene, s.as_ref(), &sp, 200_000, 9);
    let spot_dir = DVec3::new(0.0, -1.0, 0.2).normalize();
    let to_p = (DVec3::ZERO - DVec3::new(0.2, 2.0, 0.1)).normalize();
    let cos_t = to_p.dot(spot_dir);
    let (ce, cs) = (30f64.to_radians().cos(), 5f64.to_radians().cos());
    let falloff = if cos_t >= cs {
        1.0
    } else if cos_t <= ce {
        0.0
    } else {
        let t = (cos_t - ce) / (cs - ce);
        t * t * (3.0 - 2.0 * t)
    };
    let e_spot = point_irradiance(DVec3::ZERO, DVec3::Y, DVec3::new(0.2, 2.0, 0.1), 4.0) * falloff;
    assert!(
        falloff > 0.0 && falloff < 1.0,
        "the test point should sit in the falloff band"
    );
    let d = DVec3::new(0.3, -1.0, 0.1).normalize();
    let irr = [2.0, 1.0, 0.5];
    let z_crit = z_critical(ALPHA);
    for c in 0..3 {
        let expected = (e_spot + irr[c] * (-d).dot(DVec3::Y)) / PI;
        let z = stats[c].z_score(expected);
        assert!(
            z.abs() < z_crit,
            "channel {c}: {} vs {expected} (z = {z})",
            stats[c].mean
        );
    }
}

/// The linear-in-angle spot (Mitsuba 3's convention), registered as a light type in one file:
/// exact to f32 precision at a point in its falloff band, with the closed form
/// E = I₀ (θe − θ)/(θe − θs) cos θp / d² computed here in f64. Its `power` form of the
/// intensity is checked too: Φ = I₀ · Φ/I₀ for the same light given by power.
#[test]
fn linear_spot_light_is_exact() {
    let (pos, axis) = (
        DVec3::new(0.2, 2.0, 0.1),
        DVec3::new(0.0, -1.0, 0.2).normalize(),
    );
    let to_p = (DVec3::ZERO - pos).normalize();
    let theta = to_p.cross(axis).length().atan2(to_p.dot(axis));
    let (te, ts) = (30f64.to_radians(), 5f64.to_radians());
    let falloff = (te - theta) / (te - ts);
    assert!(
        falloff > 0.0 && falloff < 1.0,
        "the test point should sit in the falloff band"
    );
    // Φ/I₀ = 2π [(1 − cos θs) + ((θe − θs) cos θs + sin θs − sin θe)/(θe − θs)].
    let solid =
        2.0 * PI * ((1.0 - ts.cos()) + ((te - ts) * ts.cos() + ts.sin() - te.sin()) / (te - ts));
    let white = Bsdf::lambertian(Vec3::ONE);
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &white);
    let s = by_name("light").unwrap();
    for emit in [
        "intensity = [4.0, 4.0, 4.0]".to_string(),
        format!("power = {}", rgb([(4.0 * solid) as f32; 3])),
    ] {
        let scene = prepare(
            &format!(
                "[[linear_spot_light]]\nposition = [0.2, 2.0, 0.1]\ndirection = [0.0, -1.0, 0.2]\n\
                 cone_angle_deg = 30.0\nfalloff_start_deg = 5.0\n{emit}\n"
            ),
            &[],
        );
        let stats = estimate_at(&scene, s.as_ref(), &sp, 64, 9);
        let expected = point_irradiance(DVec3::ZERO, DVec3::Y, pos, 4.0) * falloff / PI;
        for st in &stats {
            assert!(
                (st.mean - expected).abs() <= 1e-5 * expected,
                "{emit}: {} vs {expected}",
                st.mean
            );
        }
    }
}

/// Glossy and blended materials have no simple closed form under an area light, but every
/// unbiased strategy must agree: a two-sample z-test of each against MIS (power heuristic).
#[test]
fn glossy_strategies_agree() {
    for (spec, exponent) in [
        ([0.0, 0.0, 0.0], 0.0),
        ([0.5, 0.5, 0.5], 20.0),
        ([0.9, 0.9, 0.9], 200.0),
    ] {
        let scene = prepare(
            &format!(
                "[[sphere]]\ncenter = [0.6, 1.2, -0.3]\nradius = 0.3\nmaterial = \"m\"\nemission = {l}\n\
                 [[quad]]\ncorner = [-0.9, 1.5, -0.4]\nedge_u = [0.5, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.5]\nmaterial = \"m\"\nemission = {l}\n",
                l = rgb(RADIANCE)
            ),
            &[],
        );
        let kd = Vec3::splat(0.9) - Vec3::from(spec);
        let bsdf = Bsdf::blend(kd, Vec3::from(spec), exponent);
        // Viewed so that the mirror direction points between the two lights.
        let view = Vec3::new(0.2, -1.0, 0.35).normalize();
        let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, view, &bsdf);
        let reference = estimate_at(
            &scene,
            by_name("mis-power").unwrap().as_ref(),
            &sp,
            SAMPLES,
            91,
        );
        let z_crit = z_critical(ALPHA);
        let (run, _) = applicable(&scene);
        for (k, s) in run
            .iter()
            .filter(|s| s.integrand() == Integrand::DIRECT && s.name() != "mis-power")
            .enumerate()
        {
            let st = estimate_at(&scene, s.as_ref(), &sp, SAMPLES, 92 + k as u64);
            let z = (st[0].mean - reference[0].mean)
                / (st[0].std_error().powi(2) + reference[0].std_error().powi(2)).sqrt();
            assert!(
                z.abs() < z_crit,
                "ks {spec:?} n {exponent}: {} = {:.5e} vs mis-power {:.5e} (z = {z:.2})",
                s.name(),
                st[0].mean,
                reference[0].mean
            );
        }
    }
}
