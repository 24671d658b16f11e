//! Same scene, seed and thread count give the same image, bit for bit. The random streams are
//! keyed by (seed, strategy, pixel, pass), so the thread count does not matter either.

use dibench::film::{Film, Image};
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::registry;

fn render(scene: &PreparedScene, strategy: &str, seed: u64, threads: usize) -> Image {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let strategy = registry()
        .into_iter()
        .find(|s| s.name() == strategy)
        .unwrap();
    pool.install(|| {
        let mut r = Renderer::new(scene, strategy.as_ref(), seed).unwrap();
        let mut film = Film::new(scene.scene.width, scene.scene.height);
        for _ in 0..3 {
            r.add_pass(&mut film);
        }
        film.mean()
    })
}

#[test]
fn same_seed_same_image_any_thread_count() {
    let scene = PreparedScene::new(Scene::load(&Scene::resolve("cornell").unwrap()).unwrap());
    for strategy in ["light", "cosine"] {
        let a = render(&scene, strategy, 7, 2);
        let b = render(&scene, strategy, 7, 2);
        assert!(
            a == b,
            "{strategy}: two runs with the same seed and threads differ"
        );
        let c = render(&scene, strategy, 7, 1);
        assert!(a == c, "{strategy}: 1 and 2 threads differ");
        let d = render(&scene, strategy, 8, 2);
        assert!(
            a != d,
            "{strategy}: a different seed gave the same image (seed unused?)"
        );
    }
}
