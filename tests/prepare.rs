//! Preparation builds only what a scene uses: one light per emitter the file declares (per
//! triangle for a mesh; no light structures otherwise), analytic spheres only for declared
//! spheres, environment structures only with `[environment]`, the AO integrand only with
//! `[ambient_occlusion]`, a light selection distribution only when there is a light; and every
//! strategy that does not apply is skipped with a reason. Checked on every built-in scene.

use dibench::lights::LightShape;
use dibench::lights::selector::default_selector;
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::strategy::{Integrand, applicable, integrands};

fn scenes() -> Vec<std::path::PathBuf> {
    let mut v: Vec<_> = std::fs::read_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes"))
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    v.sort();
    v
}

#[test]
fn prepare_builds_only_what_the_scene_declares() {
    let paths = scenes();
    assert!(paths.len() >= 10, "{paths:?}");
    let mut seen_env = (false, false);
    for path in paths {
        let scene = Scene::load(&path).unwrap();
        let name = scene.name.clone();
        let s = &scene;
        let emitting = |e: Option<glam::Vec3>| e.is_some_and(|e| e.max_element() > 0.0);
        let count = |shape: LightShape, p: &PreparedScene| {
            p.lights
                .lights()
                .iter()
                .filter(|l| l.shape() == shape)
                .count()
        };
        let quads = s.quads.iter().filter(|q| emitting(q.emission)).count();
        let spheres = s.spheres.iter().filter(|q| emitting(q.emission)).count();
        // One light per emitting triangle with area.
        let meshes: usize = s
            .meshes
            .iter()
            .filter(|m| emitting(m.emission))
            .map(|m| {
                let p = |i: u32| m.positions[i as usize];
                m.triangles
                    .iter()
                    .filter(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])) != glam::Vec3::ZERO)
                    .count()
            })
            .sum();
        // Every registered light type is point-shaped but the directional one.
        let dirs = s
            .lights
            .iter()
            .filter(|l| std::ptr::eq(l.kind, &dibench::lights::directional::DIRECTIONAL))
            .count();
        let points = s.lights.len() - dirs;
        let has_env = s.environment.is_some();
        let has_ao = s.ao_distance.is_some();
        let n_spheres = s.spheres.len();
        let p = PreparedScene::new(scene);

        for (shape, n) in [
            (LightShape::Quad, quads),
            (LightShape::Sphere, spheres),
            (LightShape::Mesh, meshes),
            (LightShape::Point, points),
            (LightShape::Direction, dirs),
            (LightShape::Environment, has_env as usize),
        ] {
            assert_eq!(count(shape, &p), n, "{name}: {} lights", shape.name());
        }
        assert_eq!(
            p.world.geometry.spheres.len(),
            n_spheres,
            "{name}: analytic spheres"
        );
        assert_eq!(
            p.lights.environment().is_some(),
            has_env,
            "{name}: environment structures"
        );
        assert_eq!(p.lights.environment_index().is_some(), has_env, "{name}");
        assert_eq!(
            p.lights.selector(default_selector()).is_ok(),
            !p.lights.is_empty(),
            "{name}"
        );
        if has_env {
            seen_env.0 = true;
        } else {
            seen_env.1 = true;
        }

        let ints = integrands(&p);
        assert!(ints.contains(&Integrand::DIRECT), "{name}");
        assert_eq!(
            ints.contains(&Integrand::AmbientOcclusion),
            has_ao,
            "{name}: AO"
        );
        assert_eq!(
            ints.len(),
            1 + has_ao as usize + 3 * has_env as usize,
            "{name}: {ints:?}"
        );

        let (run, skipped) = applicable(&p);
        assert!(!run.is_empty(), "{name}: nothing applies");
        for k in &skipped {
            assert!(
                !k.reason.trim().is_empty(),
                "{name}: {} skipped without a reason",
                k.name
            );
        }
        let skipped_env = skipped.iter().any(|k| k.name.starts_with("env-"));
        assert_eq!(
            skipped_env, !has_env,
            "{name}: env strategies skipped iff no environment"
        );
        let skipped_ao = skipped.iter().any(|k| k.name.starts_with("ao-"));
        assert_eq!(
            skipped_ao, !has_ao,
            "{name}: AO strategies skipped iff no AO section"
        );
    }
    assert!(
        seen_env.0 && seen_env.1,
        "the scenes must include both kinds"
    );
}
