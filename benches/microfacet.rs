//! Cost per sample of each GGX sampler: draw a reflected direction and evaluate its pdf (what a
//! BSDF-sampling strategy pays per sample, the BRDF itself excluded), over 4,096 fixed u and
//! three configurations (docs/microfacet.md quotes the result).

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dibench::bsdf::MicrofacetSampler;
use dibench::bsdf::ggx::{Ggx, chi2_view};
use dibench::sampling::stream::SampleStream;
use std::hint::black_box;
use std::time::Duration;

const N: usize = 4096;

fn samplers(c: &mut Criterion) {
    let mut rng = SampleStream::new(1, 2, 3, 4);
    let us: Vec<[f32; 2]> = (0..N).map(|_| [rng.next_1d(), rng.next_1d()]).collect();
    let configs = [
        ("a0.3-theta60", Ggx { ax: 0.3, ay: 0.3 }, 60.0),
        (
            "a0.05x0.005-theta89",
            Ggx {
                ax: 0.05,
                ay: 0.005,
            },
            89.0,
        ),
        ("a1-theta0", Ggx { ax: 1.0, ay: 1.0 }, 0.0),
    ];
    let mut group = c.benchmark_group("ggx_sample_pdf");
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(N as u64));
    for (label, g, theta) in configs {
        let wo = chi2_view(theta);
        for s in MicrofacetSampler::ALL {
            group.bench_with_input(BenchmarkId::new(s.name(), label), &g, |b, g| {
                b.iter(|| {
                    let mut acc = 0.0f32;
                    for &u in &us {
                        let wi = s.sample(g, wo, u);
                        acc += s.pdf(g, wo, wi) + wi.z;
                    }
                    black_box(acc)
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, samplers);
criterion_main!(benches);
