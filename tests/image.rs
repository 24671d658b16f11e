//! Closed forms through the whole camera → tile → film path, where every other test checks
//! one shading point: an emitter filling the view renders exactly its radiance and its back
//! exactly zero; a sub-pixel emitter shows the pixel jitter covers the pixel in both axes;
//! a wide image maps pixels to the right directions (aspect and field of view); two strategies
//! that compute the same estimator never share random numbers; camera rays and BSDF samples
//! that escape see the environment.

use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::{Strategy, applicable, by_name};

const L: [f64; 3] = [3.0, 2.0, 0.5];

fn scene(camera: &str, image: (u32, u32), body: &str) -> PreparedScene {
    let text = format!(
        "{camera}\n[image]\nwidth = {}\nheight = {}\n[[material]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n{body}",
        image.0, image.1
    );
    let dir = tempfile::tempdir().unwrap();
    PreparedScene::new(Scene::parse(&text, &dir.path().join("image.toml")).unwrap())
}

fn quad(corner: [f32; 3], eu: [f32; 3], ev: [f32; 3]) -> String {
    format!(
        "[[quad]]\ncorner = {corner:?}\nedge_u = {eu:?}\nedge_v = {ev:?}\nmaterial = \"m\"\nemission = {L:?}\n"
    )
}

fn render(scene: &PreparedScene, s: &dyn Strategy, seed: u64, spp: u64) -> Film {
    let mut r = Renderer::new(scene, s, seed).unwrap();
    let mut film = Film::new(scene.scene.width, scene.scene.height);
    for _ in 0..spp {
        r.add_pass(&mut film);
    }
    film
}

const FACING: &str = "[camera]\neye = [0.0, 0.0, 1.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 60.0";

/// The camera sees the front of a one-sided emitter that fills the view: every pixel is L,
/// exactly, for every strategy (nothing else lights the emitter); seen from behind, exactly 0.
#[test]
fn an_emitter_filling_the_view_renders_exactly_its_radiance_front_and_zero_back() {
    let front = scene(
        FACING,
        (8, 6),
        &quad([-10.0, -10.0, 0.0], [20.0, 0.0, 0.0], [0.0, 20.0, 0.0]),
    );
    let back = scene(
        FACING,
        (8, 6),
        &quad([-10.0, -10.0, 0.0], [0.0, 20.0, 0.0], [20.0, 0.0, 0.0]),
    );
    for (sc, want) in [(&front, L), (&back, [0.0; 3])] {
        let (run, _) = applicable(sc);
        assert!(
            run.len() >= 4,
            "{:?}",
            run.iter().map(|s| s.name()).collect::<Vec<_>>()
        );
        for s in &run {
            let img = render(sc, s.as_ref(), 3, 2).mean();
            for (k, p) in img.pixels.iter().enumerate() {
                assert_eq!(*p, want, "{}: pixel {k}", s.name());
            }
        }
    }
}

/// 2×2 pixels, 90° field of view, looking down −z: pixel (0, 0) spans x ∈ [−1, 0), y ∈ (0, 1]
/// on the plane z = −1. An emitter on its upper-left quarter covers u ∈ [0, ½)² of the pixel's
/// jitter, so the pixel's mean is L/4 (binomial noise), and the other pixels see nothing.
/// Jitter drawn from one number for both axes would give L/2, no jitter 0 or L.
#[test]
fn the_pixel_jitter_covers_the_pixel_in_both_axes() {
    let camera = "[camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov_y_deg = 90.0";
    let sc = scene(
        camera,
        (2, 2),
        &quad([-1.0, 0.5, -1.0], [0.5, 0.0, 0.0], [0.0, 0.5, 0.0]),
    );
    let spp = 4096u64;
    let img = render(&sc, by_name("light").unwrap().as_ref(), 5, spp).mean();
    let fraction = img.pixels[0][0] / L[0];
    // Binomial standard deviation of the covered fraction: sqrt(p(1-p)/n) = 0.0068.
    let sigma = (0.25f64 * 0.75 / spp as f64).sqrt();
    assert!(
        (fraction - 0.25).abs() < 4.5 * sigma,
        "covered fraction {fraction} (expected 0.25 ± {sigma:.4})"
    );
    for k in 1..4 {
        assert_eq!(img.pixels[k], [0.0; 3], "pixel {k} sees the emitter");
    }
}

/// A 4×2 image at 90° vertical field of view spans x ∈ [−2, 2) on the plane z = −1: pixel
/// (0, 0) is x ∈ [−2, −1), y ∈ (0, 1], wholly on an emitter there, and pixel (1, 0) wholly off.
/// A camera that ignored the aspect ratio would put pixel (0, 0) at x ∈ [−1, −0.5).
#[test]
fn pixels_map_to_directions_by_aspect_and_field_of_view() {
    let camera = "[camera]\neye = [0.0, 0.0, 0.0]\nlook_at = [0.0, 0.0, -1.0]\nfov_y_deg = 90.0";
    let sc = scene(
        camera,
        (4, 2),
        &quad([-2.0, 0.0, -1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]),
    );
    let img = render(&sc, by_name("light").unwrap().as_ref(), 7, 64).mean();
    assert_eq!(img.pixels[0], L, "pixel (0, 0)");
    for k in 1..8 {
        assert_eq!(img.pixels[k], [0.0; 3], "pixel {k}");
    }
}

/// `light` and `env-latlong-cdf` compute the same estimator on a scene with an environment
/// and a quad light; their images must still differ (each strategy has its own random
/// numbers), while each is reproducible.
#[test]
fn strategies_never_share_random_numbers() {
    // A floor facing the camera, lit by a small quad above it (emitting downwards) and a
    // constant environment.
    let body = format!(
        "{}[[quad]]\ncorner = [-10.0, -10.0, 0.0]\nedge_u = [20.0, 0.0, 0.0]\nedge_v = [0.0, 20.0, 0.0]\nmaterial = \"m\"\n[environment]\nconstant = [0.2, 0.2, 0.2]\n",
        quad([-0.3, -0.3, 0.5], [0.0, 0.6, 0.0], [0.6, 0.0, 0.0])
    );
    let sc = scene(FACING, (8, 8), &body);
    let a = by_name("light").unwrap();
    let b = by_name("env-latlong-cdf").unwrap();
    let (ia, ib) = (
        render(&sc, a.as_ref(), 11, 1),
        render(&sc, b.as_ref(), 11, 1),
    );
    assert_ne!(ia.sum, ib.sum, "two strategies drew the same samples");
    assert_eq!(
        ia.sum,
        render(&sc, a.as_ref(), 11, 1).sum,
        "not reproducible"
    );
    assert_ne!(
        ia.sum,
        render(&sc, a.as_ref(), 12, 1).sum,
        "the seed is ignored"
    );
}

/// The environment through the whole path, camera escapes and BSDF samples that escape: a
/// camera at height 1 looks along the horizon over a floor (albedo ρ = ½) under a constant
/// environment L. The top four rows look up, so every strategy sees L there; the bottom three
/// rows see the floor, whose reflected radiance is ρ·L, and `cosine` estimates it with zero
/// variance (f·cos/pdf = ρ for every sample, each of which escapes to L). A lane whose escape
/// were dropped, doubled or given another lane's ray would move a pixel off by a whole term.
#[test]
fn the_environment_is_seen_by_camera_rays_and_escaping_samples() {
    let env = [0.6f32, 0.4, 0.2];
    let camera = "[camera]\neye = [0.0, 1.0, 0.0]\nlook_at = [0.0, 1.0, -1.0]\nfov_y_deg = 60.0";
    let body = format!(
        "[[quad]]\ncorner = [-20.0, 0.0, -40.0]\nedge_u = [0.0, 0.0, 40.0]\nedge_v = [40.0, 0.0, 0.0]\nmaterial = \"m\"\n[environment]\nconstant = {env:?}\n"
    );
    let (w, h) = (8usize, 8usize);
    let sc = scene(camera, (w as u32, h as u32), &body);
    let close =
        |got: [f64; 3], want: [f64; 3]| (0..3).all(|c| (got[c] - want[c]).abs() <= 1e-5 * want[c]);
    let sky = env.map(f64::from);
    let floor = sky.map(|c| 0.5 * c);
    let (run, _) = applicable(&sc);
    assert!(run.iter().any(|s| s.name() == "cosine"));
    for s in &run {
        let img = render(&sc, s.as_ref(), 9, 4).mean();
        for k in 0..4 * w {
            assert!(
                close(img.pixels[k], sky),
                "{}: sky pixel {k}: {:?}",
                s.name(),
                img.pixels[k]
            );
        }
        if s.name() == "cosine" {
            for k in 5 * w..h * w {
                assert!(
                    close(img.pixels[k], floor),
                    "cosine: floor pixel {k}: {:?}",
                    img.pixels[k]
                );
            }
        }
    }
}
