//! A cheap, deterministic mutation fuzzer for the scene parser (no nightly toolchain needed for
//! cargo-fuzz): thousands of byte- and token-level mutations of real scene files must each give
//! a scene or an error naming the file, never a panic; a scene that parses must prepare and
//! render one finite pass.

use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::strategy::by_name;
use std::panic::{AssertUnwindSafe, catch_unwind};

const TOKENS: &[&str] = &[
    "nan",
    "inf",
    "-inf",
    "-1.0",
    "0",
    "0.0",
    "1e40",
    "-1e-45",
    "1e-30",
    "[",
    "]",
    "\"",
    "=",
    "\n",
    "[[quad]]\n",
    "[[sphere]]\n",
    "[image]\n",
    "radius = 0.0\n",
    "emission = [1e38, 1e38, 1e38]\n",
    "exponent = 1e30\n",
    "width = 4294967295\n",
    "material = \"\"\n",
    "#",
    ",",
    "{}",
    "true",
];

/// SplitMix64: a fixed, dependency-free stream of mutation choices.
struct Mix(u64);
impl Mix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

fn mutate(text: &str, rng: &mut Mix) -> String {
    let mut b = text.as_bytes().to_vec();
    for _ in 0..1 + rng.below(3) {
        let at = rng.below(b.len() + 1);
        match rng.below(4) {
            0 if !b.is_empty() => {
                let end = (at + 1 + rng.below(8)).min(b.len());
                b.drain(at.min(end)..end);
            }
            1 => {
                let t = TOKENS[rng.below(TOKENS.len())].as_bytes();
                b.splice(at..at, t.iter().copied());
            }
            2 if at < b.len() => b[at] = b" 0123456789.-+e[]=\"nai\n"[rng.below(23)],
            _ => {
                // Replace a number-looking run with a token.
                let t = TOKENS[rng.below(12)].as_bytes();
                let end = (at + rng.below(6)).min(b.len());
                b.splice(at..end, t.iter().copied());
            }
        }
    }
    String::from_utf8_lossy(&b).into_owned()
}

#[test]
fn mutated_scenes_parse_or_fail_cleanly() {
    let scenes = [
        "cornell",
        "sphere_light",
        "spot_directional",
        "glossy",
        "mesh_light",
    ];
    let mut rng = Mix(7);
    let (mut ok, mut err) = (0, 0);
    for name in scenes {
        let src =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("scenes/{name}.toml"));
        let text = std::fs::read_to_string(&src).unwrap();
        for k in 0..2000 {
            let mutant = mutate(&text, &mut rng);
            // Named as if beside the original (never written), so its mesh paths resolve.
            let path = src.with_file_name(format!("{name}_{k}.toml"));
            let outcome = catch_unwind(AssertUnwindSafe(|| match Scene::parse(&mutant, &path) {
                Ok(mut scene) => {
                    // Keep the image small: a mutant may legitimately ask for a huge one.
                    scene.width = scene.width.min(8);
                    scene.height = scene.height.min(8);
                    let prepared = PreparedScene::new(scene);
                    let s = by_name("light").unwrap();
                    if dibench::strategy::applies(s.as_ref(), &prepared).is_ok() {
                        let mut film = Film::new(prepared.scene.width, prepared.scene.height);
                        Renderer::new(&prepared, s.as_ref(), 1)
                            .unwrap()
                            .add_pass(&mut film);
                        let img = film.mean();
                        assert!(
                            img.pixels.iter().flatten().all(|c| c.is_finite()),
                            "non-finite pixel from an accepted scene:\n{mutant}"
                        );
                    }
                    true
                }
                Err(e) => {
                    let msg = e.to_string();
                    assert!(
                        msg.contains(&format!("{name}_{k}.toml")),
                        "error without the file name: {msg}"
                    );
                    false
                }
            }));
            match outcome {
                Ok(true) => ok += 1,
                Ok(false) => err += 1,
                Err(_) => panic!("the parser or renderer panicked on:\n{mutant}"),
            }
        }
    }
    // The mutator must exercise both paths, or the test proves nothing.
    assert!(ok > 100 && err > 100, "{ok} accepted, {err} rejected");
}
