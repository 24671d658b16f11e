//! Cost of one light selection (`LightSelector::sample`) per selector on the many-light
//! scenes, at 1,024 fixed shading points on the floor (y = 0, normal +y) with fixed random
//! numbers; criterion's throughput is selections per second. docs/many-lights.md quotes it.
//! Also the build time of each selector over the scene's lights, printed once.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dibench::lights::LightCtx;
use dibench::lights::selector::SELECTORS;
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use glam::Vec3;
use std::hint::black_box;
use std::time::{Duration, Instant};

const POINTS: usize = 1024;

/// A small deterministic generator (splitmix64), so the points do not depend on a crate.
struct Mix(u64);

impl Mix {
    fn f(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn selection(c: &mut Criterion) {
    for name in ["many_city", "many_far_and_near", "many_mesh"] {
        let scene = PreparedScene::new(Scene::load(&Scene::resolve(name).unwrap()).unwrap());
        let (lo, hi) = scene
            .lights
            .lights()
            .iter()
            .filter_map(|l| match l.bounds() {
                dibench::lights::bounds::Bounds::Local(b) => Some((b.lo, b.hi)),
                _ => None,
            })
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), (lo, hi)| {
                (a.min(lo), b.max(hi))
            });
        let mut r = Mix(17);
        let queries: Vec<(LightCtx, f64)> = (0..POINTS)
            .map(|_| {
                let x = lo.x + (hi.x - lo.x) * r.f() as f32;
                let z = lo.z + (hi.z - lo.z) * r.f() as f32;
                let ctx = LightCtx {
                    p: Vec3::new(x, 0.0, z),
                    n: Vec3::Y,
                };
                (ctx, r.f())
            })
            .collect();
        let mut group = c.benchmark_group(format!("selection/{name}"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(200))
            .measurement_time(Duration::from_millis(800))
            .throughput(Throughput::Elements(POINTS as u64));
        for &kind in SELECTORS.iter() {
            let t0 = Instant::now();
            let Ok(sel) = scene.lights.selector(kind) else {
                eprintln!("{name}/{}: does not apply", kind.name);
                continue;
            };
            eprintln!(
                "{name}: {} lights, {} built in {:.3} s",
                scene.lights.len(),
                kind.name,
                t0.elapsed().as_secs_f64()
            );
            group.bench_function(kind.name, |b| {
                b.iter(|| {
                    for (ctx, u) in &queries {
                        black_box(sel.sample(black_box(ctx), *u));
                    }
                })
            });
            // The same queries with new numbers every iteration, as a render draws them: the
            // 1,024 fixed numbers above repeat, so a branch predictor learns choices a render
            // cannot (the alias table's keep-or-alias step). For the point-free selectors,
            // where that step is most of the cost.
            if matches!(kind.name, "power" | "uniform") {
                group.bench_function(format!("{}-fresh", kind.name), |b| {
                    // Shifted by the golden ratio's fraction each iteration (a Weyl sequence):
                    // uniform, never repeating.
                    let mut shift = 0.0f64;
                    b.iter(|| {
                        shift = (shift + 0.618_033_988_749_894_9).fract();
                        for (ctx, u) in &queries {
                            black_box(sel.sample(black_box(ctx), (*u + shift).fract()));
                        }
                    })
                });
            }
        }
        group.finish();
    }
}

criterion_group!(benches, selection);
criterion_main!(benches);
