//! Cost of a packet's sample numbers: `SampleGenerator::fill_lanes` of 16 lanes at the
//! dimensions `mis-power` reads (2 camera + 1 selection + 3 light + 3 BSDF = 9), per generator,
//! for packets of one pass over 16 pixels (`GENERATOR`) and of one pixel's 16 passes
//! (`GENERATOR/one-pixel`: what passes rendered in groups hand it). The random streams are part
//! of every sample's cost (#19 item 8).

use criterion::{Criterion, black_box, criterion_group, criterion_main};
use dibench::sampling::GENERATORS;
use dibench::sampling::generator::MAX_DIMENSIONS;
use dibench::sampling::{Layout, SampleKeys, Setup};
use dibench::simd::WIDTH;
use dibench::strategy::{direction::BSDF_DIMS, light_sampling::LIGHT_DIMS};

fn fill_lanes(c: &mut Criterion) {
    let layout = Layout::of(&LIGHT_DIMS).then(Layout::of(&BSDF_DIMS));
    let (w, h) = (256u32, 256u32);
    let setup = Setup::image(layout, Some(1024), w, h);
    let dims = setup.layout.len();
    let mut group = c.benchmark_group("fill_lanes");
    for g in GENERATORS.iter() {
        let mut out = [[0.0f32; WIDTH]; MAX_DIMENSIONS];
        // 64 packets per iteration: 1,024 samples. Lane i of a packet at `round`: its pixel and
        // its pass.
        type Keys = fn(u64, u64, u64) -> (u64, u64);
        let shapes: [(String, Keys); 2] = [
            (g.name().to_string(), |round, packet, i| {
                (packet * WIDTH as u64 + i, round % 1024)
            }),
            (format!("{}/one-pixel", g.name()), |round, packet, i| {
                ((round * 64 + packet) % (256 * 256), i)
            }),
        ];
        for (name, keys) in shapes {
            let mut round = 0u64;
            group.bench_function(name, |b| {
                b.iter(|| {
                    round += 1;
                    for packet in 0..64u64 {
                        let lane = |i: usize| keys(round, packet, i as u64);
                        let keys = SampleKeys::of_render(
                            1,
                            0x5eed,
                            std::array::from_fn(|i| lane(i).0),
                            std::array::from_fn(|i| lane(i).1),
                        );
                        g.fill_lanes(&setup, &keys, 0xffff, dims, &mut out);
                        black_box(&out);
                    }
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, fill_lanes);
criterion_main!(benches);
