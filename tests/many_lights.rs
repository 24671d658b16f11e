//! Many lights: the light BVH over a million lights builds in seconds; degenerate and skewed
//! distributions (all lights at one point, on a line, at geometrically growing distances with
//! depth > 64) build without overflow or endless loops and keep pmf and sample in agreement,
//! where a 32-bit path trail (pbrt-v4) would not; every strategy with every selector is
//! unbiased against the sum of closed forms over many quads and spheres; a mesh is one light
//! per triangle and its power-selected pdf is the former one-light-per-mesh pdf.

mod selectors_common;

use dibench::bsdf::Bsdf;
use dibench::closed_form::{PointCase, polygon_irradiance, sphere_irradiance};
use dibench::geometry::triangle::Triangle;
use dibench::lights::bounds::ImportanceModel;
use dibench::lights::mesh::TriangleLight;
use dibench::lights::point::PointLight;
use dibench::lights::selector::LightSelector;
use dibench::lights::selector::bvh::LightBvh;
use dibench::lights::selector::bvh_split::SPLIT;
use dibench::lights::{Light, LightCtx, LightHit, LightMethods};
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::stats::{Welford, z_critical};
use dibench::strategy::{Integrand, ShadingPoint, applicable};
use glam::{DVec3, Vec3};
use selectors_common::{Rng, contexts};
use std::f64::consts::PI;
use std::time::Instant;

fn points(n: usize, at: impl Fn(usize) -> Vec3) -> Vec<Box<dyn Light>> {
    (0..n)
        .map(|k| {
            Box::new(PointLight {
                position: at(k),
                intensity: Vec3::splat(1.0 + (k % 7) as f32),
            }) as Box<dyn Light>
        })
        .collect()
}

/// Σ pmf over all lights at `ctx` (1, or 0 where nothing can be selected), and `samples`
/// draws whose reported p equals pmf.
fn check_tree(sel: &dyn LightSelector, n: usize, ctx: &LightCtx, samples: usize, seed: u64) {
    let sum: f64 = (0..n).map(|i| sel.pmf(ctx, i) as f64).sum();
    let mut r = Rng::new(seed);
    let mut any = false;
    for _ in 0..samples {
        if let Some((i, p)) = sel.sample(ctx, r.u64()) {
            any = true;
            assert_eq!(p, sel.pmf(ctx, i), "light {i}");
        }
    }
    let want = if any { 1.0 } else { 0.0 };
    assert!((sum - want).abs() < 1e-4, "Σ pmf = {sum}, sampled: {any}");
}

/// 10^6 small triangles of random orientation in a 100 m cube: build time and memory are
/// printed (docs/many-lights.md quotes them), the pmf still sums to 1 and matches `sample`.
#[test]
fn a_million_lights_build_in_seconds() {
    let mut r = Rng::new(1);
    let lights: Vec<Box<dyn Light>> = (0..1_000_000)
        .filter_map(|_| {
            let c = r.point(50.0);
            let s = r.log(0.01, 0.1);
            let t = Triangle::new(c + r.dir() * s, c + r.dir() * s, c + r.dir() * s);
            let l = TriangleLight::new(t, Vec3::splat(r.log(0.1, 10.0)))?;
            Some(Box::new(l) as Box<dyn Light>)
        })
        .collect();
    assert!(lights.len() > 999_000);
    for split in [None, Some(SPLIT)] {
        let t0 = Instant::now();
        let bvh = LightBvh::build(&lights, ImportanceModel::STANDARD, split).unwrap();
        let secs = t0.elapsed().as_secs_f64();
        let st = bvh.stats();
        eprintln!(
            "{} lights (split {split:?}): built in {secs:.2} s, {} nodes, depth {}, tree {:.1} MB, lights {:.1} MB",
            lights.len(),
            st.nodes,
            st.depth,
            st.bytes as f64 / 1e6,
            (lights.len() * (std::mem::size_of::<TriangleLight>() + 16)) as f64 / 1e6
        );
        assert_eq!(st.nodes, 2 * lights.len() - 1);
        assert!(secs < 60.0, "build took {secs} s");
        for ctx in contexts(2, 2) {
            check_tree(&bvh, lights.len(), &ctx, 2000, 3);
        }
    }
}

#[test]
fn lights_all_at_one_point() {
    let at = Vec3::new(1.0, 2.0, 3.0);
    let lights = points(10_000, |_| at);
    let bvh = LightBvh::build(&lights, ImportanceModel::STANDARD, None).unwrap();
    // Nothing to split on: halves by index, a balanced tree.
    assert_eq!(bvh.stats().depth, 14);
    for ctx in contexts(4, 20) {
        check_tree(&bvh, lights.len(), &ctx, 200, 5);
    }
    // From the point itself no light has a direction: nothing is selected.
    let here = LightCtx { p: at, n: Vec3::Y };
    assert!(bvh.sample(&here, 0.3).is_none());
    check_tree(&bvh, lights.len(), &here, 10, 6);
}

#[test]
fn lights_on_a_line() {
    let lights = points(10_000, |k| Vec3::new(0.0, 0.01 * k as f32, 0.0));
    for split in [None, Some(SPLIT)] {
        let bvh = LightBvh::build(&lights, ImportanceModel::STANDARD, split).unwrap();
        assert!(bvh.stats().depth <= 30, "depth {}", bvh.stats().depth);
        for ctx in contexts(7, 20) {
            check_tree(&bvh, lights.len(), &ctx, 200, 8);
        }
    }
}

/// Point lights on the three axes at distances 1.1^k: each split peels off the farthest
/// few, and the tree gets 105 levels deep (pbrt-v4 aborts at 64).
fn skewed() -> Vec<Box<dyn Light>> {
    points(2700, |k| {
        let mut v = Vec3::ZERO;
        v[k % 3] = 1.1f32.powi((k / 3) as i32);
        v
    })
}

#[test]
fn skewed_lights_make_a_deep_tree_that_still_agrees() {
    let lights = skewed();
    let bvh = LightBvh::build(&lights, ImportanceModel::STANDARD, None).unwrap();
    let depth = bvh.stats().depth;
    assert!(depth > 64, "depth {depth}");
    let ctxs = [
        LightCtx {
            p: Vec3::new(0.5, 0.4, 0.3),
            n: Vec3::ZERO,
        },
        LightCtx {
            p: Vec3::new(1e3, 2e3, -5e2),
            n: Vec3::new(-1.0, 0.0, 0.0),
        },
    ];
    for ctx in &ctxs {
        check_tree(&bvh, lights.len(), ctx, 5000, 9);
        // Walking a light's own path gives its pmf, for every light.
        for i in 0..lights.len() {
            let (leaf, p) = bvh.path_pmf(ctx, bvh.path(i).unwrap());
            assert_eq!((leaf, p), (i, bvh.pmf(ctx, i)));
        }
    }
}

/// pbrt-v4 records a light's path as a 32-bit trail, bit d set for "right" at depth d; in C++
/// `1u << d` past 31 is undefined and x86 wraps it to `1u << (d mod 32)`. Walking such trails
/// sends some deep lights to another leaf, so their pmf would be another light's.
#[test]
fn a_32_bit_path_trail_loses_deep_lights() {
    let lights = skewed();
    let bvh = LightBvh::build(&lights, ImportanceModel::STANDARD, None).unwrap();
    let ctx = LightCtx {
        p: Vec3::new(0.5, 0.4, 0.3),
        n: Vec3::ZERO,
    };
    let mut wrong = 0;
    for i in 0..lights.len() {
        let path = bvh.path(i).unwrap();
        let trail = path.iter().enumerate().fold(0u32, |t, (d, &right)| {
            t | ((right as u32).wrapping_shl(d as u32))
        });
        let walk = (0..).map(|d: u32| trail.wrapping_shr(d) & 1 == 1);
        let (leaf, p) = bvh.path_pmf(&ctx, walk);
        if leaf != i || p != bvh.pmf(&ctx, i) {
            wrong += 1;
            assert!(
                path.len() > 32,
                "a shallow light went astray: {i} depth {} leaf {leaf} p {p} vs {}",
                path.len(),
                bvh.pmf(&ctx, i)
            );
        }
    }
    eprintln!("{wrong} of {} lights lost by a 32-bit trail", lights.len());
    assert!(wrong > 0);
}

// ---- Unbiasedness over many quads and spheres -------------------------------------------

const RADIANCE: [f32; 3] = [3.0, 2.0, 1.0];
const ALBEDO: [f32; 3] = [0.8, 0.5, 0.3];

/// 20 quads and 20 spheres around a receiver at the origin (normal +y), each in its own
/// direction so none hides another, quads wholly above the horizon, three spheres straddling
/// it; radiances over a decade. Returns the scene text and the irradiance per unit radiance.
fn many_quads_and_spheres() -> (String, f64) {
    let mut r = Rng::new(21);
    let mut placed: Vec<(DVec3, f64)> = Vec::new(); // direction, angular radius
    let mut body = String::new();
    let mut e = 0.0;
    let f = |v: DVec3| format!("[{}, {}, {}]", v.x as f32, v.y as f32, v.z as f32);
    let mut k = 0;
    while k < 40 {
        let sphere = k % 2 == 1;
        let low = sphere && k < 6;
        let el: f64 = if low {
            r.range(-0.05, 0.1) as f64
        } else {
            r.range(0.35, 1.4) as f64
        };
        let az = r.range(0.0, 2.0 * std::f32::consts::PI) as f64;
        let dir = DVec3::new(el.cos() * az.cos(), el.sin(), el.cos() * az.sin());
        let dist = r.range(1.5, 4.0) as f64;
        let size = r.range(0.15, 0.4) as f64;
        let ang = (size * if sphere { 1.0 } else { 0.75 } / dist).asin() * 1.05;
        if placed.iter().any(|&(d, a)| d.angle_between(dir) < a + ang)
            || (!sphere && el - ang < 0.02)
        {
            continue;
        }
        placed.push((dir, ang));
        let scale = r.log(0.3, 3.0) as f64;
        let l = RADIANCE.map(|c| c * scale as f32);
        let c = dir * dist;
        if sphere {
            let (c, rad) = (c.as_vec3().as_dvec3(), size as f32 as f64);
            body += &format!(
                "[[sphere]]\ncenter = {}\nradius = {}\nmaterial = \"m\"\nemission = [{}, {}, {}]\n",
                f(c),
                rad as f32,
                l[0],
                l[1],
                l[2]
            );
            e += scale * sphere_irradiance(DVec3::ZERO, DVec3::Y, c, rad, 1.0);
        } else {
            // A rectangle facing the receiver, tilted by up to 35°, its edges rounded to f32
            // first so the closed form sees the quad that is rendered.
            let tilt = dibench::math::Frame::from_normal(r.dir())
                .to_world(Vec3::Z)
                .as_dvec3();
            let normal = (-dir + tilt * 0.6).normalize();
            let a = normal.cross(DVec3::Y).normalize();
            let b = normal.cross(a);
            let (eu, ev) = (a * size, b * size * 0.7);
            let (eu, ev) = if eu.cross(ev).dot(normal) > 0.0 {
                (eu, ev)
            } else {
                (ev, eu)
            };
            let corner = c - 0.5 * (eu + ev);
            let [corner, eu, ev] = [corner, eu, ev].map(|v| v.as_vec3().as_dvec3());
            body += &format!(
                "[[quad]]\ncorner = {}\nedge_u = {}\nedge_v = {}\nmaterial = \"m\"\nemission = [{}, {}, {}]\n",
                f(corner),
                f(eu),
                f(ev),
                l[0],
                l[1],
                l[2]
            );
            let v = [corner, corner + eu, corner + eu + ev, corner + ev];
            e += scale * polygon_irradiance(DVec3::ZERO, DVec3::Y, &v, 1.0);
        }
        k += 1;
    }
    (body, e)
}

fn prepare(body: &str) -> PreparedScene {
    let text = format!(
        "[camera]\neye = [0.0, 5.0, 5.0]\nlook_at = [0.0, 0.0, 0.0]\nfov_y_deg = 40.0\n[image]\nwidth = 8\nheight = 8\n[[material]]\nname = \"m\"\nalbedo = [0.5, 0.5, 0.5]\n{body}"
    );
    PreparedScene::new(Scene::parse(&text, std::path::Path::new("many.toml")).unwrap())
}

fn expected(e: f64) -> [f64; 3] {
    std::array::from_fn(|c| ALBEDO[c] as f64 / PI * e * RADIANCE[c] as f64)
}

#[test]
fn every_strategy_with_every_selector_is_unbiased_over_many_lights() {
    let (body, e) = many_quads_and_spheres();
    let scene = prepare(&body);
    assert_eq!(scene.lights.len(), 40);
    let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
    let case = PointCase {
        scene: &scene,
        point: ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &bsdf),
        expected: expected(e),
    };
    let (run, _) = applicable(&scene);
    let names: Vec<String> = run
        .iter()
        .filter(|s| s.integrand() == Integrand::DIRECT)
        .map(|s| s.name())
        .collect();
    for sel in ["uniform", "bvh", "bvh-split", "exhaustive"] {
        for base in ["light", "mis-power"] {
            let n = format!("{base}@{sel}");
            assert!(names.contains(&n), "{n} missing from {names:?}");
        }
    }
    for (k, s) in run
        .iter()
        .filter(|s| s.integrand() == Integrand::DIRECT)
        .enumerate()
    {
        if let Err(msg) = case.check(s.as_ref(), 2_000_000, 300 + k as u64, 1e-4, 0.03) {
            panic!("{msg}");
        }
    }
}

/// Light sampling with any selector, written out: f·L·cos/(pmf·pdf) when the shadow ray is
/// clear; mean and standard error of the first channel over `n` samples.
fn light_estimate(
    scene: &PreparedScene,
    sel: &dyn LightSelector,
    sp: &ShadingPoint,
    n: usize,
) -> Welford {
    let mut r = Rng::new(77);
    let mut w = Welford::default();
    let m = LightMethods::SOLID_ANGLE;
    for _ in 0..n {
        let (u_sel, ul) = (r.f(), [r.f(), r.f(), r.f()]);
        let mut v = 0.0;
        if let Some((_, ls)) = scene.lights.sample(sel, &sp.light_ctx(), u_sel, ul, &m) {
            let cos = sp.n.dot(ls.wi);
            if cos > 0.0
                && let Some(ray) = ls.shadow_ray(sp.origin)
                && !scene.tracer.occluded(&ray)
            {
                let f = sp.bsdf.eval_local(sp.bsdf.to_local(ls.wi));
                v = (f * ls.radiance * (cos / ls.pdf)).x as f64;
            }
        }
        w.add(v);
    }
    w
}

/// A selector that samples by the tree but reports the exhaustive selector's pmf: biased, and
/// the same z-test that passes the real tree rejects it.
struct Misreported<'a> {
    sample: &'a dyn LightSelector,
    pmf: &'a dyn LightSelector,
}

impl LightSelector for Misreported<'_> {
    fn sample(&self, ctx: &LightCtx, u: f64) -> Option<(usize, f32)> {
        let (i, _) = self.sample.sample(ctx, u)?;
        Some((i, self.pmf.pmf(ctx, i)))
    }
    fn pmf(&self, ctx: &LightCtx, light: usize) -> f32 {
        self.pmf.pmf(ctx, light)
    }
}

#[test]
fn the_unbiasedness_test_rejects_a_misreported_pmf() {
    let (body, e) = many_quads_and_spheres();
    let scene = prepare(&body);
    let bsdf = Bsdf::lambertian(Vec3::from(ALBEDO));
    let sp = ShadingPoint::new(Vec3::ZERO, Vec3::Y, -Vec3::Y, &bsdf);
    let by = |n: &str| {
        scene
            .lights
            .selector(dibench::lights::selector::by_name(n).unwrap())
            .unwrap()
    };
    let want = expected(e)[0];
    let z = |w: &Welford| (w.mean - want) / w.std_error();
    let good = light_estimate(&scene, by("bvh"), &sp, 400_000);
    let bad = light_estimate(
        &scene,
        &Misreported {
            sample: by("bvh"),
            pmf: by("exhaustive"),
        },
        &sp,
        400_000,
    );
    eprintln!("z: bvh {:.2}, misreported {:.2}", z(&good), z(&bad));
    assert!(z(&good).abs() < z_critical(1e-4));
    assert!(z(&bad).abs() > z_critical(1e-4));
}

// ---- Per-triangle lights ----------------------------------------------------------------

/// A mesh is one light per triangle; under power selection the full pdf of a point on
/// triangle i is pmf_i · d²/(A_i cos) = d²/(A cos), the former one-light-per-mesh area pdf.
/// Uniform selection gives another pdf (the check can fail).
#[test]
fn power_selected_triangles_keep_the_mesh_area_pdf() {
    let path = Scene::resolve("mesh_light").unwrap();
    let scene = PreparedScene::new(Scene::load(&path).unwrap());
    let n = scene.lights.len();
    assert_eq!(n, 96, "one light per triangle of the ring");
    let tris: Vec<TriangleLight> = scene
        .world
        .geometry
        .triangles
        .iter()
        .zip(&scene.world.prim_emitter)
        .filter(|(_, e)| e.is_some())
        .map(|(t, _)| TriangleLight::new(*t, Vec3::ONE).unwrap())
        .collect();
    let area: f64 = tris.iter().map(|t| t.area as f64).sum();
    let ctx = LightCtx {
        p: Vec3::new(0.2, 0.0, -0.3),
        n: Vec3::Y,
    };
    let m = LightMethods::BASIC;
    let mismatch = |sel: &dyn LightSelector| {
        let mut worst = 0.0f64;
        for (i, t) in tris.iter().enumerate() {
            let tr = &t.triangle;
            let q = (tr.v0 + tr.v1 + tr.v2) / 3.0;
            let d = (q - ctx.p).as_dvec3();
            let cos = -t.normal.as_dvec3().dot(d.normalize());
            let mesh_pdf = d.length_squared() / (area * cos);
            let pdf = scene
                .lights
                .pdf(sel, &ctx, i, LightHit::Surface { q, local: 0 }, &m)
                as f64;
            worst = worst.max((pdf / mesh_pdf - 1.0).abs());
        }
        worst
    };
    let sel = |n: &str| {
        scene
            .lights
            .selector(dibench::lights::selector::by_name(n).unwrap())
            .unwrap()
    };
    let power = mismatch(sel("power"));
    assert!(power < 1e-5, "power: {power:e}");
    assert!(mismatch(sel("uniform")) > 0.1);
}
