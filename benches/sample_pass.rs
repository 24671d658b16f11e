//! Cost of sample passes (one sample per pixel over the whole image) per strategy per scene:
//! the t_sample in Veach's efficiency 1/(σ²·t_sample). Each iteration renders a group of
//! 16 passes, as `compare` renders them (`Renderer::add_passes`); the throughput is samples.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::{MAX_GROUP, Renderer};
use dibench::scene::Scene;
use dibench::strategy::applicable;
use dibench::tracer::backends;
use std::time::Duration;

fn sample_pass(c: &mut Criterion) {
    for name in Scene::builtin_names() {
        // The packet backend, as `compare` uses by default, so the cost per pass matches.
        let scene = PreparedScene::with_tracer(
            Scene::load(&Scene::resolve(&name).unwrap()).unwrap(),
            |g| backends::build("packet", g).expect("the packet backend always builds"),
        );
        let (strategies, _) = applicable(&scene);
        let mut group = c.benchmark_group(format!("sample_pass/{name}"));
        group
            .sample_size(10)
            .warm_up_time(Duration::from_millis(300))
            .measurement_time(Duration::from_secs(2))
            .throughput(Throughput::Elements(
                scene.scene.width as u64 * scene.scene.height as u64 * MAX_GROUP,
            ));
        for s in &strategies {
            let mut renderer = Renderer::new(&scene, s.as_ref(), 1).unwrap();
            let mut film = Film::new(scene.scene.width, scene.scene.height);
            group.bench_function(s.name(), |b| {
                b.iter(|| renderer.add_passes(&mut film, MAX_GROUP))
            });
        }
        group.finish();
    }
}

criterion_group!(benches, sample_pass);
criterion_main!(benches);
