//! Renders groups of 16 passes of one strategy on one scene, as `compare` renders them once a
//! pass has been timed (`Renderer::add_passes`: each packet one pixel's 16 samples), and
//! nothing else: a fixed workload for `scripts/instructions.sh`, which counts the
//! instructions of `Renderer::add_passes_with_streams` under callgrind. (`compare` under valgrind would time its
//! passes at valgrind's pace and render them one at a time, packed as 4×4 pixel tiles,
//! which its timed runs do for the first pass only.)
//!
//! ```text
//! passes SCENE STRATEGY GROUPS   → renders GROUPS × 16 passes with the packet backend, seed 1
//! ```
//!
//! cargo build --release --example passes

use dibench::film::Film;
use dibench::prepare::PreparedScene;
use dibench::render::{MAX_GROUP, Renderer};
use dibench::scene::Scene;
use dibench::strategy::by_name;
use dibench::tracer::backends;

fn main() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, strategy, groups] = args.as_slice() else {
        return Err("usage: passes SCENE STRATEGY GROUPS".into());
    };
    let groups: u64 = groups
        .parse()
        .ok()
        .filter(|&g| g > 0)
        .ok_or_else(|| format!("GROUPS: `{groups}` is not a whole number above 0"))?;
    let path = Scene::resolve(scene).map_err(|e| e.to_string())?;
    let loaded = Scene::load(&path).map_err(|e| e.to_string())?;
    let prepared = PreparedScene::with_tracer(loaded, |g| {
        backends::build("packet", g).expect("the packet backend always builds")
    });
    let s = by_name(strategy).ok_or_else(|| format!("STRATEGY: unknown strategy `{strategy}`"))?;
    // Says which scene the strategy does not apply to, and why.
    let mut renderer = Renderer::new(&prepared, s.as_ref(), 1).map_err(|e| e.to_string())?;
    let mut film = Film::new(prepared.scene.width, prepared.scene.height);
    // One thread, this one: callgrind switches its collection on per thread, on entering the
    // function it is given, so the tiles' work must run on the thread that enters it.
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build()
        .map_err(|e| e.to_string())?;
    pool.install(|| {
        for _ in 0..groups {
            renderer.add_passes(&mut film, MAX_GROUP);
        }
    });
    // The film's mean, so the work cannot be optimised away and two builds can be compared.
    let sum: f64 = film.sum.iter().flatten().sum();
    let mean = sum / (3 * film.sum.len()) as f64 / film.spp as f64;
    let samples = film.spp * film.sum.len() as u64;
    println!("{samples} samples ({} passes), mean {mean:.9}", film.spp);
    Ok(())
}
