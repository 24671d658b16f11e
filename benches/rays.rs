//! Ray throughput per ray class on the same fixed ray sets as `dibench rays` (smaller image):
//! the packet backend at each available ISA (16-ray packets with the hybrid switch), its
//! single-ray wide-BVH kernel alone (`packet-1ray`: every ray on its own, 8 children or 8
//! triangles per vector step), the obvhs baseline, and Embree's 1-ray and 16-wide kernels
//! with `--features embree`. On `bunny`, and on `dragon` when scripts/fetch-dragon.sh has
//! fetched it (skipped with a message otherwise).
//!
//! `cargo bench --bench rays -- --profile-time 10 'rays/bunny/primary/packet-avx512'` runs one
//! kernel alone for a profiler.
//!
//! `DIBENCH_HYBRID_SWEEP=1 cargo bench --bench rays` first times the packet backend at the best
//! ISA with several hybrid switches (node lanes, leaf lanes), interleaved round by round (the
//! `dibench rays` protocol), and prints Mrays/s per class with the measured lane occupancy:
//! how `HYBRID_LANES`/`LEAF_LANES` were chosen. `DIBENCH_SWEEP_SIZE=N` sets its image size
//! (N×N rays per class; 256 by default). `DIBENCH_BUILD_SWEEP=1` does the same for
//! build parameters (obvhs preset × SAH block cost), with build times and tree shapes.
//! `DIBENCH_FRUSTUM_SWEEP=1` times camera rays (the `primary` class) at 128² and 512² on bunny,
//! the dragon and cornell with several interval-only switches (`FRUSTUM_CHILDREN`): how it was
//! chosen.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dibench::harness::rays::{Packing, Subject, generate, measure, subjects};
use dibench::prepare::PreparedScene;
use dibench::scene::Scene;
use dibench::simd::Isa;
use dibench::tracer::packet::PacketTracer;
use std::time::Duration;

fn scene(name: &str) -> Option<PreparedScene> {
    match Scene::resolve(name).and_then(|p| Scene::load(&p)) {
        Ok(s) => Some(PreparedScene::new(s)),
        Err(e) => {
            eprintln!("rays bench: skipping `{name}` ({e}); run scripts/fetch-{name}.sh");
            None
        }
    }
}

/// The hybrid sweep's image size: `DIBENCH_SWEEP_SIZE`, else 256.
fn sweep_size() -> u32 {
    match std::env::var("DIBENCH_SWEEP_SIZE") {
        Ok(v) => v
            .parse()
            .ok()
            .filter(|&n| (4..=4096).contains(&n))
            .unwrap_or_else(|| panic!("DIBENCH_SWEEP_SIZE={v}: give a size from 4 to 4096")),
        Err(_) => 256,
    }
}

/// The hybrid-switch sweep (see the module docs).
fn hybrid_sweep() {
    let variants = [(0, 0), (4, 2), (6, 3), (8, 3), (8, 4), (10, 4), (17, 17)];
    let isa = Isa::available()[0];
    let size = sweep_size();
    for name in ["bunny", "dragon"] {
        let Some(scene) = scene(name) else { continue };
        let sets = generate(&scene, size, 1);
        // One tree for every variant (see frustum_sweep).
        let tr = PacketTracer::build(scene.world.geometry.clone(), isa).unwrap();
        let subjects: Vec<Subject> = variants
            .iter()
            .map(|&(n, l)| Subject::Packet(tr.clone().with_hybrid(n, l)))
            .collect();
        let rows = measure(name, &sets, &subjects, 9, 1, Packing::Tile);
        println!(
            "hybrid sweep, {name}, {}, {}²: Mrays/s (lane occupancy) per (node, leaf) switch",
            isa.name(),
            size
        );
        for set in &sets {
            let line: Vec<String> = rows
                .iter()
                .filter(|r| r.ray_class == set.class)
                .zip(&variants)
                .map(|(r, (n, l))| {
                    format!(
                        "{n}/{l}: {:.2} ({:.2})",
                        r.mrays_per_s,
                        r.active_lane_fraction.unwrap_or(0.0)
                    )
                })
                .collect();
            println!("  {:<15} {}", set.class, line.join("  "));
        }
    }
}

/// The interval-only switch sweep for camera packets (see the module docs).
fn frustum_sweep() {
    let variants = [None, Some(0), Some(2), Some(8)];
    let isa = Isa::available()[0];
    for name in ["bunny", "dragon", "cornell"] {
        let Some(scene) = scene(name) else { continue };
        for size in [128, 512] {
            let sets: Vec<_> = generate(&scene, size, 1)
                .into_iter()
                .filter(|s| s.class == "primary")
                .collect();
            // One tree for every variant: separate copies of the dragon's would evict each
            // other from the caches between rounds, and the order would decide.
            let tr = PacketTracer::build(scene.world.geometry.clone(), isa).unwrap();
            let subjects: Vec<Subject> = variants
                .iter()
                .map(|&k| Subject::Packet(tr.clone().with_frustum_children(k)))
                .collect();
            let rows = measure(name, &sets, &subjects, 9, 1, Packing::Tile);
            let line: Vec<String> = rows
                .iter()
                .zip(&variants)
                .map(|(r, k)| {
                    format!(
                        "{}: {:.2}",
                        k.map_or("per-lane".into(), |k| k.to_string()),
                        r.mrays_per_s
                    )
                })
                .collect();
            println!(
                "frustum sweep, {name} {size}x{size}, {}: primary Mrays/s per interval-only switch  {}",
                isa.name(),
                line.join("  ")
            );
        }
    }
}

/// The build-parameter sweep (see the module docs).
fn build_sweep() {
    use dibench::tracer::packet::BuildParams;
    use obvhs::BvhBuildParams as P;
    let presets = [
        ("fast", P::fast_build()),
        ("medium", P::medium_build()),
        // Medium with reinsertion over every node: today's default.
        ("default", BuildParams::default().preset),
        ("very_slow", P::very_slow_build()),
    ];
    let isa = Isa::available()[0];
    for name in ["bunny", "dragon"] {
        let Some(scene) = scene(name) else { continue };
        let sets = generate(&scene, 256, 1);
        let mut labels = vec![];
        let mut subjects = vec![];
        for (pname, preset) in presets {
            for block_cost in [1.0, 1.5, 2.5] {
                let p = BuildParams {
                    preset: P {
                        max_prims_per_leaf: 1,
                        ..preset
                    },
                    block_cost,
                    ..BuildParams::default()
                };
                let tr = PacketTracer::build_with(scene.world.geometry.clone(), isa, &p).unwrap();
                println!(
                    "{name} {pname} block_cost {block_cost}: {}",
                    tr.wide().describe()
                );
                labels.push(format!("{pname}/{block_cost}"));
                subjects.push(Subject::Packet(tr));
            }
        }
        let rows = measure(name, &sets, &subjects, 7, 1, Packing::Tile);
        println!(
            "build sweep, {name}, {}: Mrays/s per (preset/block cost)",
            isa.name()
        );
        for set in &sets {
            let line: Vec<String> = rows
                .iter()
                .filter(|r| r.ray_class == set.class)
                .zip(&labels)
                .map(|(r, l)| format!("{l}: {:.2}", r.mrays_per_s))
                .collect();
            println!("  {:<15} {}", set.class, line.join("  "));
        }
    }
}

fn rays(c: &mut Criterion) {
    if std::env::var_os("DIBENCH_HYBRID_SWEEP").is_some() {
        hybrid_sweep();
    }
    if std::env::var_os("DIBENCH_BUILD_SWEEP").is_some() {
        build_sweep();
    }
    if std::env::var_os("DIBENCH_FRUSTUM_SWEEP").is_some() {
        frustum_sweep();
    }
    for name in ["bunny", "dragon"] {
        let Some(scene) = scene(name) else { continue };
        let sets = generate(&scene, 128, 1);
        // Every compiled-in backend: `cargo bench --features embree` puts Embree (1-ray and
        // 16-wide) beside the packet core.
        let backends: Vec<String> = dibench::tracer::backends::AVAILABLE
            .iter()
            .map(|b| b.to_string())
            .collect();
        let mut subjects = subjects(&scene, &backends, &Isa::available()).unwrap();
        for isa in Isa::available() {
            subjects.push(Subject::Single(
                PacketTracer::build(scene.world.geometry.clone(), isa).unwrap(),
            ));
        }
        for set in &sets {
            let mut group = c.benchmark_group(format!("rays/{name}/{}", set.class));
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
}

criterion_group!(benches, rays);
criterion_main!(benches);
