//! NaN and Inf must be impossible: every applicable strategy on every built-in scene renders a
//! few passes with only finite, non-negative pixels. (Shading points on emitters, which can
//! draw their own position as a light sample, are where this used to fail.)

use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::applicable;

#[test]
fn every_strategy_on_every_scene_is_finite() {
    for name in Scene::builtin_names() {
        let mut scene = Scene::load(&Scene::resolve(&name).unwrap()).unwrap();
        // Many-light scenes (`many_*`) at a sixteenth of their pixels: `@exhaustive` costs
        // O(lights) per sample (~0.1 ms on the city), and 4 passes of the full image would
        // add about a minute to the suite.
        if name.starts_with("many") {
            scene.width = scene.width.div_ceil(4);
            scene.height = scene.height.div_ceil(4);
        }
        let scene = PreparedScene::new(scene);
        let (strategies, _) = applicable(&scene);
        for s in &strategies {
            let mut r = Renderer::new(&scene, s.as_ref(), 5).unwrap();
            let mut film = Film::new(scene.scene.width, scene.scene.height);
            for _ in 0..4 {
                r.add_pass(&mut film);
            }
            let img = film.mean();
            let bad = img
                .pixels
                .iter()
                .filter(|p| p.iter().any(|c| !c.is_finite() || *c < 0.0))
                .count();
            assert_eq!(
                bad,
                0,
                "{name}/{}: {bad} non-finite or negative pixels",
                s.name()
            );
        }
    }
}
