//! The sample generators as the strategies use them: the (0,2)-net property of every layout
//! pair of every built-in strategy (Sobol, Owen-scrambled Sobol, Z-Sobol per pixel), one point
//! per stratum (stratified), unbiasedness over randomizations, determinism, independence
//! across seeds and across the groups of one sample, and each strategy's layout against what
//! it reads. Every check has a negative control: a deliberately broken variant it must reject.

use dibench::prepare::PreparedScene;
use dibench::sampling::qmc::{is_02_net, owen, sobol_0, sobol_1};
use dibench::sampling::sobol::{fill_groups, group_seed, sequence_seed};
use dibench::sampling::stratified::grid;
use dibench::sampling::{
    Dims, GENERATORS, Layout, SampleGenerator, SampleKey, Setup, generator, stream::name_id,
};
use dibench::scene::Scene;
use dibench::stats::correlation;
use dibench::strategy::{ShadingPoint, registry};
use glam::Vec3;
use std::path::Path;

fn scene(name: &str) -> PreparedScene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(format!("{name}.toml"));
    PreparedScene::new(Scene::load(&path).unwrap())
}

/// Every distinct layout (camera's pair first) of the built-in strategies that apply to the
/// measured scenes, with a strategy that has it.
fn layouts() -> Vec<(String, Layout)> {
    let mut out: Vec<(String, Layout)> = Vec::new();
    for sc in ["cornell", "mesh_light", "env_sky_glossy"] {
        let sc = scene(sc);
        for s in registry() {
            if let Ok(e) = s.bind(sc.view(s.integrand())) {
                let l = Layout::camera().then(e.layout());
                if !out.iter().any(|(_, k)| *k == l) {
                    out.push((s.name(), l));
                }
            }
        }
    }
    assert!(out.len() >= 3, "{out:?}");
    out
}

fn key(seed: u64, pixel: u64, index: u64) -> SampleKey {
    SampleKey {
        seed,
        strategy: name_id("light"),
        pixel,
        index,
    }
}

/// The first `n` samples of a pixel, each dimension as a 32-bit fraction (f32 → u32: exact,
/// the values are multiples of 2^-24).
fn samples(g: &dyn SampleGenerator, setup: &Setup, seed: u64, pixel: u64, n: u64) -> Vec<Vec<u32>> {
    let d = setup.layout.len();
    (0..n)
        .map(|i| {
            let mut v = vec![0.0f32; d];
            g.fill(setup, key(seed, pixel, i), &mut v);
            v.iter()
                .map(|&x| {
                    assert!((0.0..1.0).contains(&x), "{} gave {x}", g.name());
                    (x as f64 * 4_294_967_296.0) as u32
                })
                .collect()
        })
        .collect()
}

/// Every pair of the layout, as (start, purpose).
fn pairs(l: &Layout) -> Vec<(usize, &'static str)> {
    l.offsets()
        .filter(|(_, d)| d.width == 2)
        .map(|(s, d)| (s, d.purpose))
        .collect()
}

/// The first 2^m samples of a pixel (m = 1..8) form a (0,m,2)-net in every pair of every
/// built-in layout, and 2^m points in each single dimension one per interval of 2^-m; for
/// Sobol, Z-Sobol with the spp known and under a time budget, in several pixels and seeds.
#[test]
fn qmc_pairs_are_02_nets_for_every_strategy_layout() {
    for (strategy, layout) in layouts() {
        for name in ["sobol", "zsobol"] {
            let g = generator(name).unwrap();
            for spp in [None, Some(256)] {
                let setup = Setup {
                    layout: layout.clone(),
                    spp,
                    width: 128,
                    height: 96,
                };
                for (seed, pixel) in [(1u64, 0u64), (2, 77), (3, 128 * 95 + 127)] {
                    let all = samples(g, &setup, seed, pixel, 256);
                    for m in 1..=8u32 {
                        let n = 1usize << m;
                        for (start, purpose) in pairs(&layout) {
                            let pts: Vec<[u32; 2]> =
                                all[..n].iter().map(|s| [s[start], s[start + 1]]).collect();
                            assert!(
                                is_02_net(&pts),
                                "{name} (spp {spp:?}), {strategy}: pair {start} ({purpose}) of \
                                 pixel {pixel}, first {n} samples, is not a (0,{m},2)-net"
                            );
                        }
                        for (start, d) in layout.offsets().filter(|(_, d)| d.width == 1) {
                            let mut cells: Vec<u32> =
                                all[..n].iter().map(|s| s[start] >> (32 - m)).collect();
                            cells.sort_unstable();
                            cells.dedup();
                            assert_eq!(cells.len(), n, "{name}, {strategy}: {}", d.purpose);
                        }
                    }
                }
            }
        }
    }
}

/// Unscrambled Sobol (0, 1) is a net in every aligned block; the negative controls: a pair
/// built from one dimension twice, and a pair whose two coordinates shuffle the index with
/// different seeds (the bug of scrambling a pair's dimensions independently), are not.
#[test]
fn net_test_sees_broken_pairs() {
    for m in 1..=8u32 {
        let n = 1u32 << m;
        let pts: Vec<[u32; 2]> = (0..n).map(|i| [sobol_0(i), sobol_1(i)]).collect();
        assert!(is_02_net(&pts));
        let twice: Vec<[u32; 2]> = (0..n).map(|i| [sobol_0(i), sobol_0(i)]).collect();
        // (Two points on the diagonal are still a (0,1,2)-net.)
        assert!(
            m == 1 || !is_02_net(&twice),
            "m {m}: a reused dimension passes"
        );
    }
    // Shuffling the two coordinates' indices separately breaks the pairing for most seeds.
    let broken = (0..20u64)
        .filter(|&s| {
            let pts: Vec<[u32; 2]> = (0..64u32)
                .map(|i| [sobol_0(owen(i, s)), sobol_1(owen(i, s ^ 99))])
                .collect();
            !is_02_net(&pts)
        })
        .count();
    assert!(
        broken >= 15,
        "only {broken} of 20 separately shuffled pairs are caught"
    );
}

/// Z-Sobol's Morton part: the 4 pixels of an aligned 2×2 quad, with spp = 2^L known, together
/// hold an aligned block of 4·2^L sequence points, so their union is a (0,L+2,2)-net in every
/// pair — the cross-pixel structure that spreads the error as blue noise.
#[test]
fn zsobol_quads_share_one_net() {
    let g = generator("zsobol").unwrap();
    let setup = Setup {
        layout: Layout::camera().then(Layout::of(&dibench::strategy::light_sampling::LIGHT_DIMS)),
        spp: Some(16),
        width: 64,
        height: 64,
    };
    for (x0, y0) in [(0u64, 0u64), (10, 20), (62, 30)] {
        let mut union = Vec::new();
        for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
            union.extend(samples(g, &setup, 5, (y0 + dy) * 64 + x0 + dx, 16));
        }
        for (start, _) in pairs(&setup.layout) {
            let pts: Vec<[u32; 2]> = union.iter().map(|s| [s[start], s[start + 1]]).collect();
            assert!(is_02_net(&pts), "quad at ({x0}, {y0}), pair {start}");
        }
    }
    // The control: the same four pixels with Sobol (independent per pixel) are not one net.
    let sobol = generator("sobol").unwrap();
    let mut union = Vec::new();
    for p in [0u64, 1, 64, 65] {
        union.extend(samples(sobol, &setup, 5, p, 16));
    }
    let pts: Vec<[u32; 2]> = union.iter().map(|s| [s[2 + 1], s[2 + 2]]).collect();
    assert!(!is_02_net(&pts), "independent pixels passed as one net");
}

/// Stratified with N known puts, in every pair, one point in each cell of its nx × ny grid,
/// and in each single dimension one point per interval of 1/N, for N prime, square and not.
#[test]
fn stratified_puts_one_point_per_stratum() {
    let g = generator("stratified").unwrap();
    for (strategy, layout) in layouts() {
        for n in [7u64, 16, 24] {
            let setup = Setup {
                layout: layout.clone(),
                spp: Some(n),
                width: 128,
                height: 96,
            };
            let all = samples(g, &setup, 4, 300, n);
            let cell = |x: u32, k: u64| ((x as f64 / 4_294_967_296.0) * k as f64) as u64;
            for (start, d) in layout.offsets() {
                let mut cells: Vec<u64> = if d.width == 2 {
                    let (nx, ny) = grid(n);
                    all.iter()
                        .map(|s| cell(s[start], nx) + nx * cell(s[start + 1], ny))
                        .collect()
                } else {
                    all.iter().map(|s| cell(s[start], n)).collect()
                };
                cells.sort_unstable();
                cells.dedup();
                assert_eq!(cells.len() as u64, n, "{strategy}, N {n}: {}", d.purpose);
            }
        }
        // Without a sample count it refuses, saying why.
        let none = Setup {
            layout,
            spp: None,
            width: 1,
            height: 1,
        };
        assert!(g.check(&none).unwrap_err().contains("--spp"));
    }
    // The control: independent samples do not stratify (16 points in 16 cells collide).
    let setup = Setup::point(
        Layout::of(&[dibench::sampling::Dimension::one("x")]),
        Some(16),
    );
    let ind = generator("independent").unwrap();
    let mut cells: Vec<u32> = samples(ind, &setup, 4, 0, 16)
        .iter()
        .map(|s| s[0] >> 28)
        .collect();
    cells.sort_unstable();
    cells.dedup();
    assert!(cells.len() < 16);
}

/// Per-scramble estimates of a known 2-D integral with `n` points, over 1,000 seeds.
fn scramble_estimates(
    n: u64,
    f: &dyn Fn(f64, f64) -> f64,
    points: &dyn Fn(u64, u64) -> Vec<[f64; 2]>,
) -> (f64, f64) {
    let est: Vec<f64> = (0..1000u64)
        .map(|seed| {
            let p = points(seed, n);
            p.iter().map(|q| f(q[0], q[1])).sum::<f64>() / n as f64
        })
        .collect();
    let mean = est.iter().sum::<f64>() / est.len() as f64;
    let var = est.iter().map(|e| (e - mean).powi(2)).sum::<f64>() / (est.len() - 1) as f64;
    (mean, (var / est.len() as f64).sqrt())
}

fn generator_points(name: &str, start: usize) -> impl Fn(u64, u64) -> Vec<[f64; 2]> {
    let g = generator(name).unwrap();
    let layout = Layout::camera().then(Layout::of(&dibench::strategy::light_sampling::LIGHT_DIMS));
    move |seed, n| {
        let setup = Setup {
            layout: layout.clone(),
            spp: Some(n),
            width: 16,
            height: 16,
        };
        (0..n)
            .map(|i| {
                let mut v = [0.0f32; 6];
                g.fill(&setup, key(seed, 33, i), &mut v);
                [v[start] as f64, v[start + 1] as f64]
            })
            .collect()
    }
}

/// The mean over 1,000 randomizations of the estimate of ∫∫ f is within 4 standard errors
/// (from the estimates' own spread) of the truth, for a smooth f and a discontinuous one, for
/// every generator, on the camera pair and the light-point pair, with 2^4 and 3 (a prefix
/// that is not a power of two) points. Controls: a generator that ignores its seed (no
/// randomization) and one whose scramble leaves the top digit alone are caught.
#[test]
fn unbiased_over_randomizations() {
    let smooth = |x: f64, y: f64| x * y * y; // ∫∫ = 1/6
    let step = |x: f64, y: f64| if x + y < 0.8 { 1.0 } else { 0.0 }; // ∫∫ = 0.32
    let within = |(mean, se): (f64, f64), truth: f64| (mean - truth).abs() <= 4.0 * se + 1e-7;
    for g in GENERATORS {
        for start in [0usize, 3] {
            for n in [16u64, 3] {
                let pts = generator_points(g.name(), start);
                let s = scramble_estimates(n, &smooth, &pts);
                assert!(
                    within(s, 1.0 / 6.0),
                    "{} smooth n {n} pair {start}: {s:?}",
                    g.name()
                );
                let s = scramble_estimates(n, &step, &pts);
                assert!(
                    within(s, 0.32),
                    "{} step n {n} pair {start}: {s:?}",
                    g.name()
                );
            }
        }
    }
    // Control 1: no randomization (every seed the same scramble).
    let fixed = |_seed: u64, n: u64| -> Vec<[f64; 2]> {
        (0..n as u32)
            .map(|i| {
                let j = owen(i, 7);
                [unit(owen(sobol_0(j), 8)), unit(owen(sobol_1(j), 9))]
            })
            .collect()
    };
    assert!(!within(scramble_estimates(3, &step, &fixed), 0.32));
    // Control 2: the top digit left unscrambled (the first point always in [0, ½)²).
    let top_fixed = |seed: u64, n: u64| -> Vec<[f64; 2]> {
        (0..n as u32)
            .map(|i| {
                let keep = |x: u32, s: u64| (owen(x, s) & !(1 << 31)) | (x & (1 << 31));
                [
                    unit(keep(sobol_0(i), seed)),
                    unit(keep(sobol_1(i), seed ^ 5)),
                ]
            })
            .collect()
    };
    assert!(!within(scramble_estimates(3, &step, &top_fixed), 0.32));
}

fn unit(x: u32) -> f64 {
    x as f64 / 4_294_967_296.0
}

/// No dimension is used twice within a sample: across 4,096 samples (64 pixels × 64 passes)
/// every two dimensions of the MIS layout (camera pair, light 1+2+1, bsdf 2+1) are
/// uncorrelated, |r| < 5/√n, for every generator; the control is a Sobol that seeds every
/// group alike — each group then repeats the first one — and is caught.
#[test]
fn no_dimension_is_reused_within_a_sample() {
    let mis = dibench::strategy::by_name("mis-power").unwrap();
    let sc = scene("cornell");
    let layout = Layout::camera().then(mis.bind(sc.view(mis.integrand())).unwrap().layout());
    let d = layout.len();
    let setup = Setup {
        layout: layout.clone(),
        spp: Some(64),
        width: 8,
        height: 8,
    };
    let collect = |fill: &dyn Fn(SampleKey, &mut [f32])| -> Vec<Vec<f64>> {
        let mut cols = vec![Vec::new(); d];
        for pixel in 0..64u64 {
            for i in 0..64u64 {
                let mut v = vec![0.0f32; d];
                fill(key(11, pixel, i), &mut v);
                for (c, x) in cols.iter_mut().zip(&v) {
                    c.push(*x as f64);
                }
            }
        }
        cols
    };
    let worst = |cols: &[Vec<f64>]| -> f64 {
        let mut w = 0.0f64;
        for a in 0..d {
            for b in a + 1..d {
                w = w.max(correlation(&cols[a], &cols[b]).abs());
            }
        }
        w
    };
    let bound = 5.0 / (4096f64).sqrt();
    for g in GENERATORS {
        let cols = collect(&|k, v| g.fill(&setup, k, v));
        let w = worst(&cols);
        assert!(
            w < bound,
            "{}: dimensions correlated, |r| = {w:.3}",
            g.name()
        );
    }
    let broken = collect(&|k, v| {
        let seq = sequence_seed(&k, 0);
        fill_groups(&setup, k.index as u32, |_| group_seed(seq, 0), v)
    });
    assert!(worst(&broken) > 0.9, "a reused dimension is not seen");
}

/// The same key gives the same values (twice, and from other threads); different seeds give
/// uncorrelated images: per-pixel values of seed s and s + 1 correlate at |r| < 5/√n, for
/// every generator. Control: a "seed" that is ignored gives r = 1.
#[test]
fn deterministic_and_independent_across_seeds() {
    let layout = Layout::camera().then(Layout::of(&dibench::strategy::light_sampling::LIGHT_DIMS));
    for g in GENERATORS {
        let setup = Setup {
            layout: layout.clone(),
            spp: Some(4),
            width: 64,
            height: 64,
        };
        let image = |seed: u64| -> Vec<f64> {
            (0..4096u64)
                .flat_map(|p| {
                    let mut v = [0.0f32; 6];
                    g.fill(&setup, key(seed, p, 2), &mut v);
                    v.map(|x| x as f64)
                })
                .collect()
        };
        let a = image(21);
        assert_eq!(a, image(21), "{}: not deterministic", g.name());
        let other = std::thread::scope(|s| s.spawn(|| image(21)).join().unwrap());
        assert_eq!(a, other, "{}", g.name());
        let r = correlation(&a, &image(22));
        assert!(
            r.abs() < 5.0 / (a.len() as f64).sqrt(),
            "{}: seeds correlate, r = {r}",
            g.name()
        );
        assert!((correlation(&a, &a) - 1.0).abs() < 1e-12);
    }
}

/// Every built-in strategy reads exactly the dimensions its layout declares: over many samples
/// at points where every part of it succeeds, the most it reads is the layout's length (more
/// would panic in `Dims`; fewer is a layout that over-declares or a part that re-reads a copy).
/// The control: a layout padded by one dimension is caught.
#[test]
fn every_strategy_reads_its_whole_layout() {
    let mut checked = 0;
    for sc in ["cornell", "mesh_light", "sphere_light", "env_sky_glossy"] {
        let sc = scene(sc);
        let bsdf = dibench::bsdf::Bsdf::lambertian(Vec3::splat(0.5));
        for s in registry() {
            let Ok(e) = s.bind(sc.view(s.integrand())) else {
                continue;
            };
            let n = e.layout().len();
            let g = generator("independent").unwrap();
            let setup = Setup::point(e.layout(), None);
            let max_used = |pad: usize| -> usize {
                let mut most = 0;
                // Points on the scene's floor-ish, facing up and facing around.
                for i in 0..2000u64 {
                    let mut v = vec![0.0f32; n + pad];
                    g.fill(&setup, key(i, 0, i), &mut v[..n]);
                    let t = i as f32 * 0.618;
                    let normal = Vec3::new(t.sin() * 0.3, 1.0, t.cos() * 0.3).normalize();
                    let sp = ShadingPoint::new(Vec3::new(0.1, 0.01, 0.1), normal, -normal, &bsdf);
                    let mut u = Dims::new(&v);
                    let _ = e.sample(&sp, &mut u);
                    most = most.max(u.used());
                }
                most
            };
            assert_eq!(
                max_used(0),
                n,
                "{}: layout {}",
                s.name(),
                e.layout().describe()
            );
            assert!(max_used(1) < n + 1, "control: {}", s.name());
            checked += 1;
        }
    }
    assert!(checked >= 10, "{checked}");
}

/// A generator that squashes every dimension toward 0 (a biased point set) and claims
/// nothing about independence: the replicate check of `PointCase::check_with` must reject it,
/// while Sobol passes the same case — the negative control of the closed-form checks under QMC.
struct Squashed;

impl SampleGenerator for Squashed {
    fn name(&self) -> &'static str {
        "squashed"
    }
    fn describe(&self) -> &'static str {
        "biased on purpose"
    }
    fn fill(&self, setup: &Setup, key: SampleKey, out: &mut [f32]) {
        generator("sobol").unwrap().fill(setup, key, out);
        for x in out {
            *x *= 0.9;
        }
    }
}

#[test]
fn closed_form_check_with_replicates_rejects_a_biased_generator() {
    use dibench::closed_form::{PointCase, polygon_irradiance};
    use glam::DVec3;
    let text = "[camera]\neye = [0.0, 5.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n\
        [image]\nwidth = 8\nheight = 8\n[[material]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n\
        [[quad]]\ncorner = [-0.5, 1.0, -0.4]\nedge_u = [1.2, 0.0, 0.0]\nedge_v = [0.0, 0.0, 0.9]\n\
        material = \"m\"\nemission = [1.0, 1.0, 1.0]\n";
    let dir = tempfile::tempdir().unwrap();
    let sc = PreparedScene::new(Scene::parse(text, &dir.path().join("t.toml")).unwrap());
    let c = DVec3::new(-0.5, 1.0, -0.4);
    let (eu, ev) = (DVec3::new(1.2, 0.0, 0.0), DVec3::new(0.0, 0.0, 0.9));
    let e = polygon_irradiance(
        DVec3::ZERO,
        DVec3::Y,
        &[c, c + eu, c + eu + ev, c + ev],
        1.0,
    );
    let bsdf = dibench::bsdf::Bsdf::lambertian(Vec3::ONE);
    let case = PointCase {
        scene: &sc,
        point: ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &bsdf),
        expected: [e / std::f64::consts::PI; 3],
    };
    let light = dibench::strategy::by_name("light").unwrap();
    for g in GENERATORS {
        case.check_with(*g, light.as_ref(), 32 * 4096, 3, 1e-4, 0.03)
            .unwrap_or_else(|e| panic!("{e}"));
    }
    let err = case
        .check_with(&Squashed, light.as_ref(), 32 * 4096, 3, 1e-4, 0.03)
        .unwrap_err();
    assert!(err.contains("closed form"), "{err}");
}

/// The cost of one `fill` of the MIS layout per generator (ns), printed; not a check (run with
/// `--ignored --nocapture`): what a sample generator adds to every sample at equal time.
#[test]
#[ignore]
fn fill_cost() {
    let mis = dibench::strategy::by_name("mis-power").unwrap();
    let sc = scene("cornell");
    let layout = Layout::camera().then(mis.bind(sc.view(mis.integrand())).unwrap().layout());
    let setup = Setup::image(Layout::of(&layout.0[1..]), None, 128, 128);
    for g in GENERATORS.iter().filter(|g| g.name() != "stratified") {
        let mut v = vec![0.0f32; setup.layout.len()];
        let mut acc = 0.0f32;
        let t = std::time::Instant::now();
        let n = 2_000_000u64;
        for k in 0..n {
            g.fill(&setup, key(1, k % 16384, k / 16384), &mut v);
            acc += v[3];
        }
        let ns = t.elapsed().as_nanos() as f64 / n as f64;
        println!("{:<12} {ns:6.1} ns per fill ({acc})", g.name());
    }
}
