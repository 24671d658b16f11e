//! The sample path over lanes (#19 part B) against the scalar path it replaces: for shading
//! points the camera sees in every built-in scene with lights of every shape, a packet's light
//! probes ([`BoundLights::probe_packet`], on every ISA) and an estimator's packet of probes
//! ([`Estimator::sample_packet`]) must equal the scalar ones lane by lane, bit for bit, and
//! consume the same sample dimensions.

use dibench::geometry::Ray;
use dibench::lights::selector::default_selector;
use dibench::lights::{LightMethods, MethodOverride};
use dibench::prepare::{PreparedScene, SurfaceHit};
use dibench::render::camera_ray;
use dibench::sampling::generator::MAX_DIMENSIONS;
use dibench::sampling::stream::SampleStream;
use dibench::sampling::{Dims, LaneValues, PacketDims};
use dibench::scene::Scene;
use dibench::simd::{Isa, Soa3};
use dibench::strategy::light_sampling::{BoundLights, LightProbe};
use dibench::strategy::{
    EmissionProbe, Estimator, ProbePacket, Probes, ShadingPacket, ShadingPoint, ShadowProbe,
    by_name,
};
use dibench::tracer::LANES;
use glam::Vec3;

/// Scenes with quad, sphere, mesh, point, spot, directional and environment lights, and with
/// Phong, GGX and principled materials beside Lambertian ones (packets of mixed materials).
const SCENES: [&str; 8] = [
    "cornell",
    "bunny",
    "sphere_light",
    "mesh_light",
    "spot_directional",
    "env_venice_bunny",
    "glossy",
    "ggx_gold_bunny",
];

/// [`FLOOR`] under a rectangle light whose edges have no zero component, so every lane
/// operation's rounding shows (the built-in quads are axis-aligned or tilted about one axis),
/// beside a point light, so that MIS meets delta lights and area lights in one packet.
const TILTED: &str = r#"
[[quad]]
corner = [-0.3, 1.5, 0.1]
edge_u = [0.4, 0.2, 0.4]
edge_v = [-0.3333333, 0.3333333, 0.16666667]
material = "lamp"
emission = [3.0, 2.0, 1.0]
[[point_light]]
position = [0.7, 1.1, 0.4]
power = [4.0, 4.0, 4.0]
"#;

/// A floor seen from above, and a black material for emitters: what [`TILTED`], [`SPHERES`]
/// and [`ONE_TRIANGLE`] light.
const FLOOR: &str = r#"
[camera]
eye = [0.2, 1.4, 3.5]
look_at = [0.0, 0.2, 0.0]
fov_y_deg = 55.0
[image]
width = 32
height = 32
[[material]]
name = "floor"
albedo = [0.6, 0.5, 0.4]
[[material]]
name = "lamp"
albedo = [0.0, 0.0, 0.0]
[[quad]]
corner = [-2.0, 0.0, -2.0]
edge_u = [0.0, 0.0, 4.0]
edge_v = [4.0, 0.0, 0.0]
material = "floor"
"#;

/// Sphere lights of different centres, radii and radiances over a floor, one of them
/// enclosing the whole scene, over [`FLOOR`]: packets whose lanes chose different spheres
/// (each lane's own sphere in the cone kernel's records), some lanes inside their sphere.
const SPHERES: &str = r#"
[[sphere]]
center = [-0.6, 0.9, 0.1]
radius = 0.13
material = "lamp"
emission = [9.0, 7.0, 5.0]
[[sphere]]
center = [0.5, 0.6, -0.3]
radius = 0.31
material = "lamp"
emission = [2.0, 3.0, 4.0]
[[sphere]]
center = [0.3, 0.05, 0.9]
radius = 0.45
material = "lamp"
emission = [0.5, 0.25, 0.125]
[[sphere]]
center = [0.0, 0.5, 0.0]
radius = 20.0
material = "lamp"
emission = [0.05, 0.05, 0.05]
"#;

/// One emitting triangle (facing down, tilted) over [`FLOOR`]: the only light, so every lane
/// holds it and it samples them itself.
const ONE_TRIANGLE: &str = r#"
[[mesh]]
file = "triangle.obj"
material = "lamp"
emission = [5.0, 4.0, 3.0]
"#;

fn scenes() -> Vec<(String, PreparedScene)> {
    let mut v: Vec<(String, PreparedScene)> = SCENES
        .iter()
        .map(|&name| {
            let path = Scene::resolve(name).unwrap();
            (
                name.to_string(),
                PreparedScene::new(Scene::load(&path).unwrap()),
            )
        })
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let scene = Scene::parse(&format!("{FLOOR}{TILTED}"), &dir.path().join("tilted.toml")).unwrap();
    v.push(("tilted".into(), PreparedScene::new(scene)));
    let scene = Scene::parse(
        &format!("{FLOOR}{SPHERES}"),
        &dir.path().join("spheres.toml"),
    )
    .unwrap();
    v.push(("spheres".into(), PreparedScene::new(scene)));
    std::fs::write(
        dir.path().join("triangle.obj"),
        "v -0.4 1.3 0.2\nv 0.5 1.1 -0.3\nv 0.1 1.5 0.6\nf 1 2 3\n",
    )
    .unwrap();
    let scene = Scene::parse(
        &format!("{FLOOR}{ONE_TRIANGLE}"),
        &dir.path().join("one_triangle.toml"),
    )
    .unwrap();
    v.push(("one_triangle".into(), PreparedScene::new(scene)));
    v
}

const DIMS: usize = 16;

/// Packets of shading points seen through random pixels, with lane 5 of every packet and
/// every lane whose camera ray misses left empty; and sample values for every lane. The lanes
/// without a point hold a made-up point, as a renderer's reused packet holds an earlier
/// tile's: nothing may read them.
fn packets(scene: &PreparedScene, count: usize) -> Vec<(ShadingPacket<'_>, LaneValues)> {
    let (w, h) = (scene.scene.width, scene.scene.height);
    let mut rng = SampleStream::new(7, 0x1a_4e5, 0, 0);
    let mut f = move || rng.next_1d();
    (0..count)
        .map(|_| {
            let points = std::array::from_fn(|lane| {
                if lane == 5 {
                    return None;
                }
                let (x, y) = ((f() * w as f32) as u32 % w, (f() * h as f32) as u32 % h);
                let ray = camera_ray(&scene.scene.camera, w, h, x, y, [f(), f()]);
                let hit = scene.tracer.intersect(&ray)?;
                let s = scene.world.surface(&ray, &hit);
                Some(ShadingPoint::with_error(
                    s.p,
                    s.p_error,
                    s.ng,
                    ray.dir,
                    &scene.world.materials[s.material as usize],
                ))
            });
            let mut packet = ShadingPacket::from_points(&points);
            for lane in (0..LANES).filter(|l| packet.mask >> l & 1 == 0) {
                packet.bsdf[lane] = Some(&scene.world.materials[0]);
                packet.pixel[lane] = 7;
                let g = &mut packet.geo;
                let p = Vec3::new(123.0, -45.0, 6.0);
                for (to, v) in [
                    (&mut packet.p, p),
                    (&mut g.n, Vec3::Z),
                    (&mut g.s, Vec3::X),
                    (&mut g.t, Vec3::Y),
                    (&mut g.wo, Vec3::new(0.6, 0.0, 0.8)),
                    (&mut g.wo_local, Vec3::new(0.6, 0.0, 0.8)),
                    (&mut g.origin, p),
                ] {
                    to.set(lane, v);
                }
            }
            let mut values: LaneValues = [[0.0; LANES]; MAX_DIMENSIONS];
            for lane in 0..LANES {
                for row in values.iter_mut().take(DIMS) {
                    row[lane] = f();
                }
            }
            (packet, values)
        })
        .collect()
}

fn dims(values: &LaneValues) -> [Dims<'_>; LANES] {
    std::array::from_fn(|lane| Dims::lane(values, lane, 0, DIMS))
}

/// The dimensions the lanes with a point read, one count per lane, beside the count the
/// packet read; every count must be the packet's.
fn dimensions_read(packet: &ShadingPacket, u: &[Dims; LANES], pu: &PacketDims) -> Vec<usize> {
    let mut v: Vec<usize> = (0..LANES)
        .filter(|l| packet.mask >> l & 1 != 0)
        .map(|l| u[l].used())
        .collect();
    v.push(DIMS - pu.remaining());
    v
}

/// The probes a renderer's reused packet holds before a tile: an earlier tile's rows, every
/// lane cleared. Nothing may read the rows of a lane that gets no probe.
fn stale_probes() -> ProbePacket {
    let mut p = ProbePacket::default();
    let ray = Ray::new(Vec3::new(9.0, -3.0, 2.0), Vec3::Y, 5.0);
    for lane in 0..LANES {
        p.set(
            lane,
            Probes {
                shadow: Some(ShadowProbe {
                    ray,
                    value: Vec3::splat(4.0),
                }),
                emission: Some(EmissionProbe {
                    ray,
                    weight: Vec3::splat(3.0),
                    pdf: 0.5,
                }),
            },
        );
    }
    p.clear();
    p
}

/// A packet's points one by one, and its probes as the estimator writes them (into a stale
/// probe packet) and lane by lane.
#[allow(clippy::type_complexity)]
fn sampled<'a>(
    est: &dyn Estimator,
    packet: &ShadingPacket<'a>,
    values: &LaneValues,
) -> (
    [Option<ShadingPoint<'a>>; LANES],
    ProbePacket,
    [Probes; LANES],
) {
    let points = std::array::from_fn(|l| packet.point(l));
    let mut packed = stale_probes();
    est.sample_packet(packet, &mut PacketDims::new(values, 0, DIMS), &mut packed);
    let probes = std::array::from_fn(|lane| packed.get(lane));
    (points, packed, probes)
}

/// Debug text prints every float by its shortest round trip, so equal text is equal bits.
fn same<T: std::fmt::Debug>(a: &T, b: &T) -> bool {
    format!("{a:?}") == format!("{b:?}")
}

#[test]
fn light_probes_over_lanes_are_the_scalar_ones() {
    let mut checked = 0;
    let mut with_probe = 0;
    for (name, scene) in scenes() {
        let view = scene.view(dibench::strategy::Integrand::DIRECT);
        let packets = packets(&scene, 48);
        let mut sets = vec![LightMethods::BASIC, LightMethods::SOLID_ANGLE];
        sets.extend(
            MethodOverride::all()
                .into_iter()
                .map(|o| o.apply(LightMethods::BASIC)),
        );
        if scene.scene.environment.is_some() {
            // Every representation and sampler (lat/long, by either sampler, has a kernel
            // over lanes).
            sets.extend(dibench::strategy::env_methods().map(|env| LightMethods {
                env,
                ..LightMethods::BASIC
            }));
        }
        for methods in sets {
            let strategy = format!("{methods:?}");
            let mut bound = BoundLights::bind(&view, default_selector(), methods).unwrap();
            for isa in Isa::available() {
                bound.isa = isa;
                for (packet, values) in &packets {
                    let points: &[Option<ShadingPoint>; LANES] =
                        &std::array::from_fn(|l| packet.point(l));
                    let mut want: [Option<LightProbe>; LANES] = [None; LANES];
                    let mut u = dims(values);
                    for lane in 0..LANES {
                        if let Some(sp) = &points[lane] {
                            want[lane] = bound.probe(sp, &mut u[lane]);
                        }
                    }
                    let mut got: [Option<LightProbe>; LANES] = [None; LANES];
                    let mut pu = PacketDims::new(values, 0, DIMS);
                    bound.probe_packet(packet, &mut pu, &mut got);
                    let read = dimensions_read(packet, &u, &pu);
                    assert!(
                        read.iter().all(|&n| n == read[0]),
                        "{name} {strategy} {isa:?}: dimensions read {read:?}"
                    );
                    for lane in 0..LANES {
                        assert!(
                            same(&got[lane], &want[lane]),
                            "{name} {strategy} {isa:?} lane {lane}:\n got {:?}\nwant {:?}",
                            got[lane],
                            want[lane]
                        );
                        checked += points[lane].is_some() as usize;
                        with_probe += want[lane].is_some() as usize;
                    }
                }
            }
        }
    }
    // The comparison is not vacuous: most points get a probe.
    assert!(
        checked > 4000 && with_probe > checked / 3,
        "{checked} {with_probe}"
    );
}

#[test]
fn estimators_packets_are_their_samples() {
    for (name, scene) in scenes() {
        let packets = packets(&scene, 24);
        for strategy in [
            "light",
            "uniform",
            "cosine",
            "bsdf",
            "mis-power",
            "mis-power-area",
            "mis-balance",
        ] {
            let s = by_name(strategy).unwrap();
            let Ok(est) = s.bind(scene.view(s.integrand())) else {
                continue;
            };
            for (packet, values) in &packets {
                let points: &[Option<ShadingPoint>; LANES] =
                    &std::array::from_fn(|l| packet.point(l));
                let mut want = [Probes::default(); LANES];
                let mut u = dims(values);
                for lane in 0..LANES {
                    if let Some(sp) = &points[lane] {
                        want[lane] = est.sample(sp, &mut u[lane]);
                    }
                }
                let mut got = stale_probes();
                let mut pu = PacketDims::new(values, 0, DIMS);
                est.sample_packet(packet, &mut pu, &mut got);
                let got: [Probes; LANES] = std::array::from_fn(|lane| got.get(lane));
                let read = dimensions_read(packet, &u, &pu);
                assert!(
                    read.iter().all(|&n| n == read[0]),
                    "{name} {strategy}: dimensions read {read:?}"
                );
                for lane in 0..LANES {
                    assert!(
                        same(&got[lane], &want[lane]),
                        "{name} {strategy} lane {lane}:\n got {:?}\nwant {:?}",
                        got[lane],
                        want[lane]
                    );
                }
            }
        }
    }
}

/// The MIS weights of emission probes that escape, over lanes
/// ([`Estimator::env_weight_packet`]), equal [`Estimator::env_weight`] lane by lane, bit for
/// bit, for every environment representation and sampler, on every scene with an environment.
#[test]
fn env_weights_over_lanes_are_the_scalar_ones() {
    let mut checked = 0;
    for (name, scene) in scenes() {
        if scene.lights.environment().is_none() {
            continue;
        }
        let packets = packets(&scene, 24);
        for strategy in [
            "mis-power",
            "mis-env-latlong-cdf",
            "mis-env-latlong-hier",
            "mis-env-cube-hier",
            "mis-env-octa-cdf",
            "mis-env-healpix-hier",
            "cosine",
        ] {
            let s = by_name(strategy).unwrap();
            // `mis-power` is the same as `mis-env-latlong-cdf` where the environment is the only
            // light, and is not bound there.
            let Ok(est) = s.bind(scene.view(s.integrand())) else {
                continue;
            };
            for (packet, values) in &packets {
                let (points, packed, probes) = sampled(est.as_ref(), packet, values);
                let points = &points;
                let mut dirs = Soa3::default();
                let mut mask = 0u32;
                for lane in 0..LANES {
                    if let (Some(_), Some(e)) = (&points[lane], &probes[lane].emission) {
                        dirs.set(lane, e.ray.dir);
                        mask |= 1 << lane;
                    }
                }
                let got = est.env_weight_packet(packet, &packed, &dirs, mask);
                for lane in 0..LANES {
                    if mask >> lane & 1 == 0 {
                        continue;
                    }
                    let (sp, e) = (points[lane].as_ref().unwrap(), &probes[lane].emission);
                    let want = est.env_weight(sp, e.as_ref().unwrap());
                    assert_eq!(
                        got[lane].to_bits(),
                        want.to_bits(),
                        "{name} {strategy} lane {lane}: {} against {want}",
                        got[lane]
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 1000, "{checked}");
}

/// The MIS weights of emission probes that hit an emitting surface, over lanes
/// ([`Estimator::emission_weight_packet`], each light's pdf over the lanes that hit it), equal
/// [`Estimator::emission_weight`] lane by lane, bit for bit, for both light-sampling methods
/// of MIS and for an estimator that keeps the default (`cosine`), on every scene with an
/// emitting surface.
#[test]
fn emission_weights_over_lanes_are_the_scalar_ones() {
    let mut checked = 0;
    for (name, scene) in scenes() {
        if !scene.world.prim_emitter.iter().any(Option::is_some) {
            continue;
        }
        // Enough packets that cornell's small lamp is hit by a few hundred BSDF samples.
        let packets = packets(&scene, 240);
        for strategy in ["mis-power", "mis-power-area", "mis-balance", "cosine"] {
            let s = by_name(strategy).unwrap();
            let Ok(est) = s.bind(scene.view(s.integrand())) else {
                continue;
            };
            for (packet, values) in &packets {
                let (points, packed, probes) = sampled(est.as_ref(), packet, values);
                let points = &points;
                let hits: [Option<SurfaceHit>; LANES] = std::array::from_fn(|lane| {
                    let e = probes[lane]
                        .emission
                        .as_ref()
                        .filter(|_| points[lane].is_some())?;
                    let hit = scene.tracer.intersect(&e.ray)?;
                    scene.world.prim_emitter[hit.prim as usize]?;
                    Some(scene.world.surface(&e.ray, &hit))
                });
                let got = est.emission_weight_packet(packet, &packed, &hits);
                for lane in 0..LANES {
                    let Some(hit) = &hits[lane] else { continue };
                    let (sp, e) = (points[lane].as_ref().unwrap(), &probes[lane].emission);
                    let want = est.emission_weight(sp, e.as_ref().unwrap(), hit);
                    assert_eq!(
                        got[lane].to_bits(),
                        want.to_bits(),
                        "{name} {strategy} lane {lane}: {} against {want}",
                        got[lane]
                    );
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 500, "{checked}");
}
