//! The public extension API, exercised as a researcher would: the one-sample MIS strategy of
//! `examples/custom_strategy.rs`, defined outside the crate, is unbiased against closed forms
//! (a sphere light, a quad light with a glossy receiver, an environment) and runs in `compare`
//! beside the built-in strategies through the library, landing in results.csv.

#[path = "../examples/custom_strategy.rs"]
#[allow(dead_code)] // its main() is the example's
mod custom_strategy;

use custom_strategy::OneSampleMis;
use dibench::bsdf::Bsdf;
use dibench::closed_form::{PointCase, polygon_irradiance, sphere_irradiance};
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::strategy::{ShadingPoint, applies};
use glam::{DVec3, Vec3};
use std::f64::consts::PI;

const HEADER: &str = "[camera]\neye = [0.0, 5.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
    [image]\nwidth = 8\nheight = 8\n[[material]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n";
const ALBEDO: [f32; 3] = [0.8, 0.5, 0.3];
const L: [f64; 3] = [3.0, 2.0, 1.0];

fn prepare(body: &str) -> PreparedScene {
    let dir = tempfile::tempdir().unwrap();
    PreparedScene::new(
        Scene::parse(&format!("{HEADER}{body}"), &dir.path().join("t.toml")).unwrap(),
    )
}

fn check(scene: &PreparedScene, irradiance_per_unit_l: f64, seed: u64) {
    let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
    let case = PointCase {
        scene,
        point: ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &bsdf),
        expected: std::array::from_fn(|c| ALBEDO[c] as f64 / PI * irradiance_per_unit_l * L[c]),
    };
    if let Err(e) = case.check(&OneSampleMis, 1_000_000, seed, 1e-4, 0.03) {
        panic!("{e}");
    }
}

#[test]
fn one_sample_mis_is_unbiased() {
    let sphere = prepare(&format!(
        "[[sphere]]\ncenter = [0.4, 2.0, -0.3]\nradius = 0.6\nmaterial = \"m\"\nemission = {L:?}\n"
    ));
    check(
        &sphere,
        sphere_irradiance(DVec3::ZERO, DVec3::Y, DVec3::new(0.4, 2.0, -0.3), 0.6, 1.0),
        1,
    );
    let (c, eu, ev) = (
        DVec3::new(-0.5, 1.0, -0.4),
        DVec3::new(1.2, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 0.9),
    );
    let quad = prepare(&format!(
        "[[quad]]\ncorner = [-0.5, 1.0, -0.4]\nedge_u = [1.2, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.9]\nmaterial = \"m\"\nemission = {L:?}\n"
    ));
    // edge_u × edge_v = −y: the quad emits down onto the point.
    check(
        &quad,
        polygon_irradiance(
            DVec3::ZERO,
            DVec3::Y,
            &[c, c + eu, c + eu + ev, c + ev],
            1.0,
        ),
        2,
    );
    let env = prepare(&format!("[environment]\nconstant = {L:?}\n"));
    check(&env, PI, 3);
    // It refuses what it cannot estimate: a point light (the BSDF half never reaches it).
    let point = prepare("[[point_light]]\nposition = [0.0, 2.0, 0.0]\npower = [1.0, 1.0, 1.0]\n");
    assert!(applies(&OneSampleMis, &point).is_err());
}

#[test]
fn compare_runs_a_strategy_defined_outside_the_crate() {
    use clap::Parser;
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("tiny.toml");
    std::fs::write(
        &scene,
        format!("{HEADER}[[quad]]\ncorner = [-0.5, 1.0, -0.4]\nedge_u = [1.2, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.9]\nmaterial = \"m\"\nemission = {L:?}\n[[quad]]\ncorner = [-5.0, 0.0, 5.0]\nedge_u = [10.0, 0.0, 0.0]\nedge_v = [0.0, 0.0, -10.0]\nmaterial = \"m\"\n"),
    )
    .unwrap();
    let out = dir.path().join("out");
    let args = [
        "dibench",
        "compare",
        scene.to_str().unwrap(),
        "--time",
        "0.05",
        "--reference-spp",
        "16",
        "--strategies",
        "light,one-sample-mis",
        "--out",
        out.to_str().unwrap(),
    ];
    let mut strategies = dibench::strategy::registry();
    strategies.push(Box::new(OneSampleMis));
    dibench::cli::run_with(dibench::cli::Cli::parse_from(args), strategies).unwrap();
    let run = std::fs::read_dir(out.join("tiny"))
        .unwrap()
        .flatten()
        .find(|e| e.path().join("results.csv").exists())
        .unwrap();
    let csv = std::fs::read_to_string(run.path().join("results.csv")).unwrap();
    assert!(csv.lines().any(|l| l.contains(",one-sample-mis,")), "{csv}");
    assert!(csv.lines().any(|l| l.contains(",light,")), "{csv}");
    // A name clash with a built-in strategy is refused: names key results and streams.
    let mut clash = dibench::strategy::registry();
    clash.push(dibench::strategy::by_name("light").unwrap());
    assert!(dibench::cli::run_with(dibench::cli::Cli::parse_from(args), clash).is_err());
}
