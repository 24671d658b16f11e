//! Environment lighting against closed forms, for every strategy that applies (every
//! representation × sampler, alone and with MIS, and the direction-sampling baselines):
//! a constant environment (E = πL), a sky dome (upper hemisphere only: E = πL(1 + cos α)/2
//! for a normal tilted by α), and a linear environment L = a + b·y (E = πa + 2πb/3 for the
//! normal +Y). Each is a z-test with the standard error from the estimator's own variance,
//! plus a check that a 3 % bias would be detected. The maps go through the whole pipeline:
//! written as lat/long EXR, loaded from a scene file, resampled into every representation.

use dibench::bsdf::Bsdf;
use dibench::closed_form::PointCase;
use dibench::env::map::{LatLongImage, write_latlong};
use dibench::env::{Environment, Repr};
use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::{ShadingPoint, Strategy, applicable, applies, by_name};
use glam::Vec3;
use std::f64::consts::PI;

const ALPHA: f64 = 1e-4;
const SAMPLES: u64 = 200_000;
const DETECTABLE_BIAS: f64 = 0.03;
const ALBEDO: [f32; 3] = [0.8, 0.5, 0.3];

/// A scene with only an environment and a small sphere far below the shading point (so the
/// tracer has something, and a lower-hemisphere occluder that must not matter).
fn prepare(env: &str, image: Option<&LatLongImage>) -> (PreparedScene, tempfile::TempDir) {
    let dir = tempfile::tempdir().unwrap();
    if let Some(img) = image {
        write_latlong(&dir.path().join("env.exr"), img).unwrap();
    }
    let text = format!(
        "[camera]\neye = [0.0, 5.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
         [image]\nwidth = 8\nheight = 8\n[[material]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n\
         [[sphere]]\ncenter = [0.0, -3.0, 0.0]\nradius = 1.0\nmaterial = \"m\"\n{env}"
    );
    let path = dir.path().join("env.toml");
    (PreparedScene::new(Scene::parse(&text, &path).unwrap()), dir)
}

/// A lat/long image whose texels are the exact solid-angle means of L(cos θ) = f(y) over each
/// row band: for f linear in y the mean over a band is f at the band's mid y.
fn latlong_of_y(
    width: usize,
    height: usize,
    mean_over_band: impl Fn(f64, f64) -> [f64; 3],
) -> LatLongImage {
    let mut pixels = Vec::with_capacity(width * height);
    for row in 0..height {
        let y0 = (PI * row as f64 / height as f64).cos();
        let y1 = (PI * (row + 1) as f64 / height as f64).cos();
        let c = mean_over_band(y0, y1);
        let v = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
        pixels.extend(std::iter::repeat_n(v, width));
    }
    LatLongImage {
        width,
        height,
        pixels,
        clamped: 0,
    }
}

fn direct_strategies(scene: &PreparedScene) -> Vec<Box<dyn Strategy>> {
    applicable(scene)
        .0
        .into_iter()
        .filter(|s| s.integrand().is_direct())
        .collect()
}

/// Every applicable strategy's mean reflected radiance at the origin (normal n, Lambertian)
/// matches ρ/π · E per channel.
fn check_all(scene: &PreparedScene, n: Vec3, irradiance: [f64; 3], seed: u64) {
    let strategies = direct_strategies(scene);
    assert!(
        strategies.len() >= 19,
        "expected 16 environment strategies and the baselines, got {}",
        strategies.len()
    );
    for (k, s) in strategies.iter().enumerate() {
        let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
        let sp = ShadingPoint::new(Vec3::ZERO, n, -n, &bsdf);
        let case = PointCase {
            scene,
            point: sp,
            expected: std::array::from_fn(|c| ALBEDO[c] as f64 / PI * irradiance[c]),
        };
        if let Err(e) = case.check(s.as_ref(), SAMPLES, seed + k as u64, ALPHA, DETECTABLE_BIAS) {
            panic!("{e}");
        }
    }
}

#[test]
fn constant_environment_gives_pi_l() {
    let l = [1.5, 1.0, 0.25];
    let (scene, _dir) = prepare(
        &format!("[environment]\nconstant = [{}, {}, {}]\n", l[0], l[1], l[2]),
        None,
    );
    let n = Vec3::new(0.2, 1.0, -0.3).normalize();
    check_all(&scene, n, l.map(|c| PI * c), 100);
}

#[test]
fn sky_dome_up_and_tilted() {
    let l = [2.0, 1.0, 0.5];
    // Upper hemisphere only: with an even row count the horizon is a row boundary.
    let img = latlong_of_y(512, 256, |y0, y1| if y0 + y1 > 0.0 { l } else { [0.0; 3] });
    let (scene, _dir) = prepare("[environment]\nfile = \"env.exr\"\n", Some(&img));
    check_all(&scene, Vec3::Y, l.map(|c| PI * c), 200);
    let alpha = 60f64.to_radians();
    let n = Vec3::new(alpha.sin() as f32, alpha.cos() as f32, 0.0);
    check_all(
        &scene,
        n,
        l.map(|c| PI * c * (1.0 + alpha.cos()) / 2.0),
        300,
    );
}

#[test]
fn linear_environment() {
    let (a, b) = ([1.0, 0.8, 0.5], [0.9, -0.6, 0.4]);
    let img = latlong_of_y(512, 256, |y0, y1| {
        let y = 0.5 * (y0 + y1);
        std::array::from_fn(|c| a[c] + b[c] * y)
    });
    let (scene, _dir) = prepare(
        "[environment]\nfile = \"env.exr\"\nscale = 2.0\n",
        Some(&img),
    );
    let e: [f64; 3] = std::array::from_fn(|c| 2.0 * (PI * a[c] + 2.0 * PI / 3.0 * b[c]));
    check_all(&scene, Vec3::Y, e, 400);
}

/// A black map: no environment strategy applies (nothing to sample), the baselines render
/// black, and nothing is NaN or Inf.
#[test]
fn black_environment_is_finite_and_dark() {
    let (scene, _dir) = prepare("[environment]\nconstant = [0.0, 0.0, 0.0]\n", None);
    let (run, skipped) = applicable(&scene);
    assert!(skipped.iter().any(|s| s.name == "env-cube-hier"));
    assert!(run.iter().any(|s| s.name() == "cosine"));
    for s in &run {
        let mut r = Renderer::new(&scene, s.as_ref(), 1).unwrap();
        let mut film = Film::new(8, 8);
        r.add_pass(&mut film);
        assert!(
            film.mean().pixels.iter().flatten().all(|&c| c == 0.0),
            "{}: light from a black environment",
            s.name()
        );
    }
}

/// Each representation's integral ∫L dω (texels × their exact solid angles) matches the
/// source's; the resampling is a solid-angle-weighted 4×4 midpoint rule, so the only error is
/// quadrature over the sun's edge.
#[test]
fn representations_agree_on_the_integral() {
    let sun_dir = Vec3::new(0.5, 0.6, -0.4).normalize();
    let source = move |w: Vec3| {
        Vec3::splat(0.5 + 0.3 * w.y)
            + if w.dot(sun_dir) > 0.99 {
                Vec3::splat(200.0)
            } else {
                Vec3::ZERO
            }
    };
    // Closed form: ∫(0.5 + 0.3y) = 2π, sun cap 2π(1 - 0.99)·200.
    let exact = 2.0 * PI + 2.0 * PI * 0.01 * 200.0;
    let env = Environment::build(&source);
    for r in Repr::ALL {
        let map = &env.map(r).texels;
        let (w, h) = (map.width, map.height);
        let mut integral = 0.0f64;
        for (k, l) in map.texels.iter().enumerate() {
            // Texel solid angle by an 8×8 midpoint rule of the Jacobian.
            let mut omega = 0.0f64;
            for i in 0..8 {
                for j in 0..8 {
                    let uv = [
                        ((k % w) as f32 + (i as f32 + 0.5) / 8.0) / w as f32,
                        ((k / w) as f32 + (j as f32 + 0.5) / 8.0) / h as f32,
                    ];
                    omega += r.jacobian(uv) as f64 / (64.0 * (w * h) as f64);
                }
            }
            integral += l.x as f64 * omega;
        }
        let rel = (integral - exact) / exact;
        eprintln!("{r:?}: ∫L = {integral:.5}, closed form {exact:.5}, relative {rel:.2e}");
        assert!(rel.abs() < 5e-3, "{r:?}: ∫L = {integral} vs {exact}");
        // Lookups agree with the source away from the sun's edge.
        for w in [
            Vec3::Y,
            -Vec3::Y,
            Vec3::X,
            Vec3::new(0.3, -0.2, 0.9).normalize(),
        ] {
            let got = env.radiance(r, w).x;
            assert!((got - source(w).x).abs() < 0.02, "{r:?} at {w}: {got}");
        }
        assert!(env.radiance(r, sun_dir).x > 150.0, "{r:?}: no sun");
    }
}

/// Environment light sampling needs the scene to have an environment.
#[test]
fn environment_strategies_need_an_environment() {
    let (scene, _dir) = prepare(
        "[[point_light]]\nposition = [0.0, 2.0, 0.0]\npower = [1.0, 1.0, 1.0]\n",
        None,
    );
    assert!(
        scene.lights.environment().is_none(),
        "built an environment for a scene without one"
    );
    for name in ["env-latlong-cdf", "mis-env-octa-hier"] {
        assert!(applies(by_name(name).unwrap().as_ref(), &scene).is_err());
    }
}

/// Bad [environment] input: errors name the file and the field, no panic.
#[test]
fn bad_environment_input_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.toml");
    let header = "[camera]\neye = [0.0, 1.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
                  [image]\nwidth = 4\nheight = 4\n";
    let mut nan = latlong_of_y(8, 4, |_, _| [1.0; 3]);
    nan.pixels[5] = Vec3::new(1.0, f32::NAN, 0.0);
    write_latlong(&dir.path().join("nan.exr"), &nan).unwrap();
    // A truncated map: the first half of a valid EXR.
    let good = latlong_of_y(8, 4, |_, _| [1.0; 3]);
    write_latlong(&dir.path().join("good.exr"), &good).unwrap();
    let bytes = std::fs::read(dir.path().join("good.exr")).unwrap();
    std::fs::write(dir.path().join("truncated.exr"), &bytes[..bytes.len() / 2]).unwrap();
    std::fs::write(dir.path().join("garbage.exr"), b"not an EXR at all").unwrap();
    for (body, field, says) in [
        ("file = \"missing.exr\"", "environment.file", "cannot read"),
        ("file = \"nan.exr\"", "environment.file", "not finite"),
        (
            "file = \"truncated.exr\"",
            "environment.file",
            "truncated.exr",
        ),
        ("file = \"garbage.exr\"", "environment.file", "cannot read"),
        (
            "constant = [1.0, -1.0, 0.0]",
            "environment.constant",
            "non-negative",
        ),
        (
            "constant = [1.0, 1.0, 1.0]\nfile = \"nan.exr\"",
            "environment",
            "exactly one",
        ),
        (
            "constant = [1.0, 1.0, 1.0]\nscale = -2.0",
            "environment.scale",
            "non-negative",
        ),
        (
            "constant = [1.0, 1.0, 1.0]\nrotate = 3.0",
            "rotate",
            "unknown field",
        ),
    ] {
        let err = Scene::parse(&format!("{header}[environment]\n{body}\n"), &path)
            .err()
            .unwrap_or_else(|| panic!("accepted: {body}"))
            .to_string();
        assert!(
            err.contains("bad.toml") && err.contains(field) && err.contains(says),
            "{body}: {err}"
        );
    }
}

/// An environment mixed with a quad light, which hides the environment behind it:
/// E = πL_env + (L_quad − L_env)·E_quad/L, with E_quad/L Lambert's polygon formula. Exercises
/// light selection between the environment and an area light, and MIS across both.
#[test]
fn environment_with_a_quad_light() {
    use dibench::closed_form::polygon_irradiance;
    use glam::DVec3;
    let (le, lq) = ([0.5, 0.4, 0.2], [3.0, 2.0, 1.0]);
    let (corner, eu, ev) = (
        DVec3::new(-0.3, 1.5, -0.2),
        DVec3::new(0.9, 0.0, 0.2),
        DVec3::new(0.1, 0.3, 0.7),
    );
    assert!(eu.cross(ev).y < 0.0, "the emitting side must face down");
    let (scene, _dir) = prepare(
        &format!(
            "[environment]\nconstant = [{}, {}, {}]\n[[quad]]\ncorner = [-0.3, 1.5, -0.2]\n\
             edge_u = [0.9, 0.0, 0.2]\nedge_v = [0.1, 0.3, 0.7]\nmaterial = \"m\"\nemission = [{}, {}, {}]\n",
            le[0], le[1], le[2], lq[0], lq[1], lq[2]
        ),
        None,
    );
    let e_quad = polygon_irradiance(
        DVec3::ZERO,
        DVec3::Y,
        &[corner, corner + eu, corner + eu + ev, corner + ev],
        1.0,
    );
    let names: Vec<_> = direct_strategies(&scene).iter().map(|s| s.name()).collect();
    assert!(
        names.iter().any(|n| n == "light") && names.iter().any(|n| n == "mis-power"),
        "{names:?}"
    );
    check_all(
        &scene,
        Vec3::Y,
        std::array::from_fn(|c| PI * le[c] + (lq[c] - le[c]) * e_quad),
        500,
    );
}

/// Orientation: the map is read as documented (u = φ/2π with φ from +X towards +Z, v = θ/π
/// from +Y), checked with a map that is not symmetric in φ: radiance L in the upper quarter
/// wedge φ ∈ [0, π/2), θ < π/2, zero elsewhere. A horizontal normal n = (1, 0, 1)/√2 inside
/// the wedge receives E = L·∫∫ sin²θ (cos φ + sin φ)/√2 dθ dφ = L·π/(2√2); the same map
/// mirrored in φ would give it L·π(√2 − 1)/(4√2) (and every test map before this one was
/// symmetric in φ, so a mirrored reading went unseen).
#[test]
fn the_map_is_oriented_as_documented() {
    let (w, h) = (16, 8);
    let l = [2.0f32, 1.0, 0.5];
    let pixels = (0..w * h)
        .map(|k| {
            let (col, row) = (k % w, k / w);
            if col < w / 4 && row < h / 2 {
                Vec3::from(l)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let img = LatLongImage {
        width: w,
        height: h,
        pixels,
        clamped: 0,
    };
    let (scene, _dir) = prepare("[environment]\nfile = \"env.exr\"\n", Some(&img));
    let n = Vec3::new(1.0, 0.0, 1.0).normalize();
    let e = PI / (2.0 * 2f64.sqrt());
    let lat_long: Vec<_> = direct_strategies(&scene)
        .into_iter()
        .filter(|s| s.integrand() == dibench::strategy::Integrand::DIRECT)
        .collect();
    assert!(lat_long.len() >= 4, "{}", lat_long.len());
    for (k, s) in lat_long.iter().enumerate() {
        let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
        let case = PointCase {
            scene: &scene,
            point: ShadingPoint::new(Vec3::ZERO, n, -n, &bsdf),
            expected: std::array::from_fn(|c| ALBEDO[c] as f64 / PI * l[c] as f64 * e),
        };
        if let Err(err) = case.check(s.as_ref(), SAMPLES, 500 + k as u64, ALPHA, DETECTABLE_BIAS) {
            panic!("{err}");
        }
    }
}
