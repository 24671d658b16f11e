//! The Embree backend against obvhs: randomized closest-hit and occlusion queries (single rays
//! and 16-packets with partial masks) on the built-in scenes, the crosscheck on every scene in
//! scenes/, and a render on each backend.
#![cfg(feature = "embree")]

use dibench::geometry::{Hit, Ray};
use dibench::harness::crosscheck::{self, Mode, Traced, exact_t};
use dibench::harness::raysets::{Query, RaySet};
use dibench::prepare::PreparedScene;
use dibench::sampling::stream::SampleStream;
use dibench::sampling::warp::sample_uniform_sphere;
use dibench::scene::Scene;
use dibench::tracer::embree::{Coherence, EmbreeTracer};
use dibench::tracer::{HitPacket, LANES, RayPacket, Tracer};
use glam::Vec3;

const SCENES: [&str; 4] = ["cornell", "sphere_light", "mesh_light", "bunny"];

fn load(name: &str) -> PreparedScene {
    PreparedScene::new(Scene::load(&Scene::resolve(name).unwrap()).unwrap())
}

/// Rays from random points in (a box slightly larger than) the scene's bounds in uniformly
/// random directions; every third one gets a finite tmax.
fn random_rays(scene: &PreparedScene, n: usize, seed: u64) -> Vec<Ray> {
    let g = &scene.world.geometry;
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for t in &g.triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    for s in &g.spheres {
        lo = lo.min(s.center - s.radius);
        hi = hi.max(s.center + s.radius);
    }
    let pad = (hi - lo) * 0.1;
    let (lo, hi) = (lo - pad, hi + pad);
    let mut rng = SampleStream::new(seed, 99, 0, 0);
    (0..n)
        .map(|i| {
            let u = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d());
            let o = lo + (hi - lo) * u;
            let d = sample_uniform_sphere(rng.next_2d());
            let tmax = if i % 3 == 0 {
                (hi - lo).length() * rng.next_1d()
            } else {
                f32::INFINITY
            };
            Ray::new(o, d, tmax)
        })
        .collect()
}

fn same(scene: &PreparedScene, ray: &Ray, a: Option<Hit>, b: Option<Hit>) -> bool {
    match (a, b) {
        (None, None) => true,
        (Some(a), Some(b)) if a.prim == b.prim => {
            crosscheck::t_rel_diff(ray, a.t, b.t) <= 1e-3
                && (a.u - b.u).abs() < 1e-3
                && (a.v - b.v).abs() < 1e-3
        }
        // A tie on a shared edge: our exact tests hit both at the same t.
        (Some(a), Some(b)) => matches!(
            (exact_t(scene, ray, a.prim), exact_t(scene, ray, b.prim)),
            (Some(x), Some(y)) if (x - y).abs() <= 1e-4 * x.max(y)
        ),
        _ => false,
    }
}

#[test]
fn embree_matches_obvhs_on_random_rays_single_and_partial_packets() {
    for name in SCENES {
        let scene = load(name);
        let embree = EmbreeTracer::build(scene.world.geometry.clone()).unwrap();
        let rays = random_rays(&scene, 4096, 5);
        let mut bad = 0;
        let mut hits_seen = 0;
        let mut rng = SampleStream::new(3, 4, 5, 6);
        for chunk in rays.chunks(LANES) {
            let mut packet = RayPacket::default();
            for (l, r) in chunk.iter().enumerate() {
                packet.set(l, r);
            }
            // A random partial mask (never all lanes of a chunk on, on purpose, half the time).
            let mut active = (rng.next_1d() * 65536.0) as u16;
            if chunk.len() < LANES {
                active &= (1 << chunk.len()) - 1;
            }
            let mut hp = HitPacket::default();
            embree.intersect16(&packet, active, &mut hp, Coherence::Incoherent);
            let mut hc = HitPacket::default();
            embree.intersect16(&packet, active, &mut hc, Coherence::Coherent);
            let occ = embree.occluded_packet(&packet, active);
            for (l, ray) in chunk.iter().enumerate() {
                let want = scene.tracer.intersect(ray);
                let want_occ = scene.tracer.occluded(ray);
                hits_seen += want.is_some() as usize;
                let on = active & (1 << l) != 0;
                let mut agree = same(&scene, ray, want, embree.intersect(ray))
                    && embree.occluded(ray) == want_occ;
                if on {
                    agree &= same(&scene, ray, want, hp.get(l))
                        && same(&scene, ray, want, hc.get(l))
                        && (occ & (1 << l) != 0) == want_occ;
                } else {
                    assert!(
                        hp.get(l).is_none() && hc.get(l).is_none(),
                        "{name}: inactive lane hit"
                    );
                    assert!(occ & (1 << l) == 0, "{name}: inactive lane occluded");
                }
                bad += !agree as usize;
            }
        }
        assert!(
            hits_seen > 500,
            "{name}: only {hits_seen} hits; the test is too weak"
        );
        // Allow a ray or two of 4096 (each compared five ways): an edge-on triangle, or an
        // origin within our conservative t bound of a large triangle (a point 2e-5 above a
        // 40-unit floor), where our test drops a hit that Embree keeps.
        assert!(bad <= 2, "{name}: {bad} disagreements");
    }
}

#[test]
fn primitive_ids_barycentrics_and_spheres_map_back() {
    // sphere_light has both triangles and spheres; hit points must agree through (u, v).
    let scene = load("sphere_light");
    assert!(!scene.world.geometry.spheres.is_empty());
    let embree = EmbreeTracer::build(scene.world.geometry.clone()).unwrap();
    let (mut tri, mut sph) = (0, 0);
    for ray in random_rays(&scene, 4096, 11) {
        if let Some(h) = embree.intersect(&ray) {
            let s = scene.surface(&ray, &h);
            assert!((s.p - ray.at(h.t)).length() < 1e-3 * h.t.max(1.0), "{h:?}");
            match scene.world.geometry.sphere_index(h.prim) {
                Some(_) => sph += 1,
                None => tri += 1,
            }
        }
    }
    assert!(tri > 100 && sph > 10, "triangles {tri}, spheres {sph}");
}

#[test]
fn empty_packet_and_tracer_name() {
    let scene = load("cornell");
    let embree = EmbreeTracer::build(scene.world.geometry.clone()).unwrap();
    assert_eq!(embree.name(), "embree");
    let mut h = HitPacket::default();
    embree.intersect_packet(&RayPacket::default(), 0, &mut h);
    assert!((0..LANES).all(|l| h.get(l).is_none()));
    assert_eq!(embree.occluded_packet(&RayPacket::default(), 0), 0);
}

#[test]
fn crosscheck_passes_on_every_scene() {
    let out = tempfile::tempdir().unwrap();
    let mut names: Vec<_> = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes"))
        .unwrap()
        .flatten()
        .filter_map(|e| {
            let p = e.path();
            (p.extension()? == "toml").then_some(p)
        })
        .collect();
    names.sort();
    assert!(names.len() >= 4);
    for path in names {
        let mut scene = PreparedScene::new(Scene::load(&path).unwrap());
        let report = crosscheck::run(&mut scene, out.path(), 1).unwrap();
        assert!(
            report.failures.is_empty(),
            "{}: {:?}",
            path.display(),
            report.failures
        );
        assert!(
            report
                .rows
                .iter()
                .any(|r| r.backend == "embree" && r.set == "render")
        );
        assert!(report.csv.exists());
    }
}

#[test]
fn crosscheck_detects_a_wrong_backend() {
    // The comparison must be able to fail: shifting every t by 1 % is caught.
    let scene = load("cornell");
    let rays = random_rays(&scene, 512, 2);
    let set = RaySet::from_rays("primary", Query::Closest, false, &rays);
    let reference = Traced {
        hits: crosscheck::trace_closest(scene.tracer.as_ref(), &set, Mode::Single),
        occluded: crosscheck::trace_occluded(scene.tracer.as_ref(), &set, Mode::Single),
    };
    let mut shifted = Traced {
        hits: reference.hits.clone(),
        occluded: reference.occluded.clone(),
    };
    for h in shifted.hits.iter_mut().flatten() {
        h.t *= 1.01;
    }
    shifted.occluded[0] = !shifted.occluded[0];
    let a = crosscheck::agreement(&scene, &rays, &reference, &shifted);
    assert!(!a.failures(rays.len()).is_empty());
    assert_eq!(a.occlusion_mismatch, 1);
}

#[test]
fn render_with_embree_equals_obvhs() {
    for name in ["cornell", "sphere_light"] {
        let obvhs = load(name);
        let embree = PreparedScene::with_tracer(obvhs.scene.clone(), |g| {
            Box::new(EmbreeTracer::build(g).unwrap())
        });
        let strategy = dibench::strategy::by_name("light").unwrap();
        let a = crosscheck::render(&obvhs, strategy.as_ref(), 3, 2).unwrap();
        let b = crosscheck::render(&embree, strategy.as_ref(), 3, 2).unwrap();
        let d = crosscheck::image_rel_rmse(&a, &b);
        assert!(d < 1e-4, "{name}: relative RMSE {d}");
    }
}
