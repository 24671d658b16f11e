//! Ray throughput per ray class: the packet backend at each available ISA against the obvhs
//! single-ray baseline, on the same fixed ray sets as `dibench rays` (smaller image).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dibench::harness::rays::{generate, subjects};
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::simd::Isa;
use std::time::Duration;

fn rays(c: &mut Criterion) {
    let scene = PreparedScene::new(Scene::load(&Scene::resolve("bunny").unwrap()).unwrap());
    let sets = generate(&scene, 128, 1);
    // Every compiled-in backend: `cargo bench --features embree` puts Embree (1-ray and 16-wide)
    // beside the packet core.
    let backends: Vec<String> = dibench::harness::rays::BACKENDS
        .iter()
        .map(|b| b.to_string())
        .collect();
    let subjects = subjects(&scene, &backends, &Isa::available()).unwrap();
    for set in &sets {
        let mut group = c.benchmark_group(format!("rays/bunny/{}", set.class));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2))
            .throughput(Throughput::Elements(set.rays()));
        for s in &subjects {
            let (backend, isa) = s.label();
            group.bench_function(format!("{backend}-{isa}"), |b| b.iter(|| s.trace(set, 1)));
        }
        group.finish();
    }
}

criterion_group!(benches, rays);
criterion_main!(benches);
