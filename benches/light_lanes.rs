//! Cost of sampling a light for 16 shading points: one call over lanes (`Light::sample_lanes`,
//! on each ISA) against 16 scalar calls (`Light::sample`), for the samplers that run over lanes
//! in f64 (the spherical rectangle and triangle, the sphere's cone) and the lat/long
//! environment's two samplers. docs/tracer.md quotes the result.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dibench::env::{EnvMethod, EnvSampler, Environment, Repr, synthetic_environment};
use dibench::geometry::triangle::Triangle;
use dibench::lights::environment::EnvironmentLight;
use dibench::lights::mesh::TriangleLight;
use dibench::lights::quad::QuadLight;
use dibench::lights::sphere::SphereLight;
use dibench::lights::{LaneQueryRows, LaneSamples, Light, LightMethods, MeshMethod, QuadMethod};
use dibench::sampling::stream::SampleStream;
use dibench::simd::{Isa, WIDTH};
use glam::Vec3;
use std::hint::black_box;
use std::sync::Arc;
use std::time::Duration;

/// 64 packets of points on a floor 1.5 below the light, facing up, with random sample numbers.
fn packets() -> Vec<LaneQueryRows> {
    let mut rng = SampleStream::new(1, 2, 3, 4);
    (0..64)
        .map(|_| {
            let mut q = LaneQueryRows::default();
            for lane in 0..WIDTH {
                let [a, b] = rng.next_2d();
                q.p.set(lane, Vec3::new(4.0 * a - 2.0, 0.0, 4.0 * b - 2.0));
                q.n.set(lane, Vec3::Y);
                let [u0, u1] = rng.next_2d();
                q.u[0][lane] = u0;
                q.u[1][lane] = u1;
                q.u[2][lane] = rng.next_1d();
            }
            q
        })
        .collect()
}

fn bench_light(c: &mut Criterion, name: &str, light: &dyn Light, m: &LightMethods) {
    let qs = packets();
    let mut group = c.benchmark_group(format!("light_lanes/{name}"));
    group
        .sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements((qs.len() * WIDTH) as u64));
    group.bench_function("scalar", |b| {
        b.iter(|| {
            let mut acc = 0.0f32;
            for q in &qs {
                for lane in 0..WIDTH {
                    let u = [q.u[0][lane], q.u[1][lane], q.u[2][lane]];
                    if let Some(s) = light.sample(&q.ctx(lane), u, m) {
                        acc += s.pdf;
                    }
                }
            }
            black_box(acc)
        })
    });
    for isa in Isa::available() {
        group.bench_with_input(BenchmarkId::new("lanes", isa.name()), &isa, |b, &isa| {
            b.iter(|| {
                let mut acc = 0.0f32;
                for q in &qs {
                    let mut out = LaneSamples::default();
                    light.sample_lanes(isa, &q.query(), u32::MAX >> (32 - WIDTH), m, &mut out);
                    acc += out.pdf.iter().sum::<f32>();
                }
                black_box(acc)
            })
        });
    }
    group.finish();
}

fn light_lanes(c: &mut Criterion) {
    let quad = QuadLight::new(
        Vec3::new(-0.5, 1.5, -0.5),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::ONE,
    );
    let solid_angle = LightMethods {
        quad: QuadMethod::SolidAngle,
        ..LightMethods::BASIC
    };
    bench_light(c, "quad-solid-angle", &quad, &solid_angle);
    let sphere = SphereLight {
        center: Vec3::new(0.0, 1.5, 0.0),
        radius: 0.3,
        radiance: Vec3::ONE,
    };
    bench_light(c, "sphere-cone", &sphere, &LightMethods::BASIC);
    // Facing down: (v1 − v0) × (v2 − v0) is −Y.
    let triangle = TriangleLight::new(
        Triangle::new(
            Vec3::new(-0.5, 1.5, -0.5),
            Vec3::new(0.5, 1.5, -0.5),
            Vec3::new(0.0, 1.5, 0.5),
        ),
        Vec3::ONE,
    )
    .unwrap();
    let solid_angle = LightMethods {
        mesh: MeshMethod::SolidAngle,
        ..LightMethods::BASIC
    };
    bench_light(c, "triangle-solid-angle", &triangle, &solid_angle);
    let env = EnvironmentLight {
        env: Arc::new(Environment::build(&synthetic_environment(50.0))),
        scene_radius: 1.0,
    };
    for sampler in EnvSampler::ALL {
        let m = LightMethods {
            env: EnvMethod {
                repr: Repr::LatLong,
                sampler,
            },
            ..LightMethods::BASIC
        };
        bench_light(c, &format!("env-latlong-{}", sampler.name()), &env, &m);
    }
}

criterion_group!(benches, light_lanes);
criterion_main!(benches);
