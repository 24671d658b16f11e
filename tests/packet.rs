//! The packet backend's contract: the same hits as the single-ray obvhs baseline, bit for bit
//! (primitive, t and barycentrics; ties on shared edges resolved by the same rule), for packets
//! and single rays, on every available ISA (portable always, so CI without AVX-512/AVX2 still
//! covers the kernel logic), hence identical across ISAs. Negative controls: a leaf test without
//! the conservative-t rule and a traversal visiting children far to near must be caught.

use dibench::film::Film;
use dibench::geometry::Ray;
use dibench::geometry::triangle::{Triangle, WatertightRay};
use dibench::harness::rays::{self, Packing, Query};
use dibench::prepare::PreparedScene;
use dibench::render::Renderer;
use dibench::scene::Scene;
use dibench::simd::Isa;
use dibench::strategy::registry;
use dibench::tracer::bvh::ObvhsTracer;
use dibench::tracer::packet::{FAULT_FAR_FIRST, FAULT_NO_T_BOUND, PacketTracer, TraceStats};
use dibench::tracer::{Geometry, HitPacket, LANES, LaneMask, NO_HIT, RayPacket, Tracer};
use glam::Vec3;
use rand_core::{RngCore, SeedableRng};

fn scene(name: &str) -> PreparedScene {
    PreparedScene::new(Scene::load(&Scene::resolve(name).unwrap()).unwrap())
}

/// A hit as its bits: equality means bit-identical.
fn bits(h: Option<dibench::geometry::Hit>) -> Option<(u32, u32, u32, u32)> {
    h.map(|h| (h.prim, h.t.to_bits(), h.u.to_bits(), h.v.to_bits()))
}

/// Random rays over the scene's bounds: random masks, some finite tmax, and directions with
/// exactly-zero components.
fn random_packets(sc: &PreparedScene, n: usize, seed: u64) -> Vec<(RayPacket, LaneMask)> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut f = move || (rng.next_u32() >> 8) as f32 / (1 << 24) as f32;
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for t in &sc.world.geometry.triangles {
        for v in [t.v0, t.v1, t.v2] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let ext = hi - lo;
    (0..n)
        .map(|_| {
            let mut p = RayPacket::default();
            let base = lo + ext * Vec3::new(f(), f(), f());
            for lane in 0..LANES {
                let jitter = ext * 0.05 * Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5);
                let mut d = Vec3::new(f() - 0.5, f() - 0.5, f() - 0.5);
                let zero = (f() * 5.0) as usize;
                if zero < 3 {
                    d[zero] = 0.0; // zero direction components: safe inverse needed
                }
                let d = d.normalize();
                let tmax = if f() < 0.5 {
                    f() * ext.length()
                } else {
                    f32::INFINITY
                };
                p.set(lane, &Ray::new(base + jitter, d, tmax));
            }
            let mask = (f() * 65536.0) as LaneMask | if f() < 0.3 { u16::MAX } else { 0 };
            (p, mask)
        })
        .collect()
}

#[derive(Default, Debug)]
struct Tally {
    rays: usize,
    hits: usize,
}

fn check_closest(
    base: &ObvhsTracer,
    tr: &PacketTracer,
    p: &RayPacket,
    m: LaneMask,
    tally: &mut Tally,
) {
    let mut h = HitPacket::default();
    tr.intersect_packet(p, m, &mut h);
    let mut hc = HitPacket::default();
    tr.intersect_packet_coherent(p, m, &mut hc);
    for lane in 0..LANES {
        if m & (1 << lane) == 0 {
            assert_eq!(h.prim[lane], NO_HIT, "inactive lane {lane} reported a hit");
            continue;
        }
        let ray = p.get(lane);
        let want = bits(base.intersect(&ray));
        tally.rays += 1;
        tally.hits += want.is_some() as usize;
        for (what, got) in [
            ("packet", bits(h.get(lane))),
            ("coherent packet", bits(hc.get(lane))),
            ("single", bits(tr.intersect(&ray))),
        ] {
            assert_eq!(got, want, "{:?} {what}: ({ray:?})", tr.isa());
        }
    }
}

fn check_occluded(base: &ObvhsTracer, tr: &PacketTracer, p: &RayPacket, m: LaneMask) {
    let got = tr.occluded_packet(p, m);
    assert_eq!(got & !m, 0, "inactive lanes reported occluded");
    for lane in 0..LANES {
        if m & (1 << lane) != 0 {
            let ray = p.get(lane);
            let want = base.occluded(&ray);
            assert_eq!(
                got & (1 << lane) != 0,
                want,
                "{:?}: occluded ({ray:?})",
                tr.isa()
            );
            assert_eq!(tr.occluded(&ray), want, "single-ray occluded ({ray:?})");
        }
    }
}

fn agree_on(sc: &PreparedScene, name: &str) {
    let base = ObvhsTracer::build(sc.world.geometry.clone());
    // Both packings: a pixel's 16 samples are the render's packets, nearly one ray 16 times.
    let mut sets = rays::generate(sc, 48, 7);
    sets.extend(rays::generate_packed(sc, 48, 7, Packing::Pixel));
    let random = random_packets(sc, 400, 11);
    for isa in Isa::available() {
        let tr = PacketTracer::build(sc.world.geometry.clone(), isa).unwrap();
        let mut tally = Tally::default();
        for set in &sets {
            for (p, &m) in set.packets.iter().zip(&set.masks) {
                // Also a partial mask of the same packet.
                for mask in [m, m & 0b0110_1001_1001_0110] {
                    match set.query {
                        Query::Closest => check_closest(&base, &tr, p, mask, &mut tally),
                        Query::Occluded => check_occluded(&base, &tr, p, mask),
                    }
                }
            }
        }
        for (p, m) in &random {
            check_closest(&base, &tr, p, *m, &mut tally);
            check_occluded(&base, &tr, p, *m);
        }
        eprintln!("{name} {isa:?}: {tally:?}");
        assert!(
            tally.hits > 1000,
            "{name}: too few hits to test anything: {tally:?}"
        );
    }
}

/// `rays --packets pixel`: packet i's camera rays are 16 samples of pixel i (row-major) of the
/// quarter-size image (each direction, projected back onto the screen, lands in it), and a
/// set holds as many rays as with tiles. Control: a tile's lanes span four pixels.
#[test]
fn pixel_packets_hold_one_pixels_samples() {
    let sc = scene("cornell");
    let cam = &sc.scene.camera;
    let size = 48u32;
    // Screen position of direction d in an image of side n (camera_ray's mapping inverted).
    let screen = |d: Vec3, n: u32| {
        let f = d.dot(cam.forward);
        let sx = d.dot(cam.right) / f / cam.tan_half_fov_y;
        let sy = d.dot(cam.up) / f / cam.tan_half_fov_y;
        ((sx + 1.0) * 0.5 * n as f32, (1.0 - sy) * 0.5 * n as f32)
    };
    // Per packet, the pixel box its lanes' screen positions span (smallest and largest).
    let spans = |packing: Packing, n: u32| -> Vec<[f32; 4]> {
        let sets = rays::generate_packed(&sc, size, 3, packing);
        let primary = sets.iter().find(|s| s.class == "primary").unwrap();
        assert_eq!(primary.rays(), (size * size) as u64, "{packing:?}");
        primary
            .packets
            .iter()
            .zip(&primary.masks)
            .map(|(p, &m)| {
                let mut b = [f32::MAX, f32::MAX, f32::MIN, f32::MIN];
                for l in (0..LANES).filter(|l| m >> l & 1 != 0) {
                    let (x, y) = screen(p.get(l).dir, n);
                    b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
                }
                b
            })
            .collect()
    };
    let n = size / 4;
    let pixels = spans(Packing::Pixel, n);
    assert_eq!(pixels.len(), (n * n) as usize);
    let slack = 1e-3;
    for (i, b) in pixels.iter().enumerate() {
        let (x, y) = ((i as u32 % n) as f32, (i as u32 / n) as f32);
        assert!(
            b[0] >= x - slack
                && b[2] <= x + 1.0 + slack
                && b[1] >= y - slack
                && b[3] <= y + 1.0 + slack,
            "packet {i} spans {b:?}, not pixel ({x}, {y})"
        );
    }
    // Control: the tiles' lanes, in their own image, span four pixels in x and in y.
    let tiles = spans(Packing::Tile, size);
    assert!(tiles.iter().all(|b| b[2] - b[0] > 2.5 && b[3] - b[1] > 2.5));
}

#[test]
fn packet_agrees_with_obvhs_bunny() {
    agree_on(&scene("bunny"), "bunny");
}

#[test]
fn packet_agrees_with_obvhs_cornell() {
    agree_on(&scene("cornell"), "cornell");
}

#[test]
fn packet_agrees_with_obvhs_sphere_light() {
    agree_on(&scene("sphere_light"), "sphere_light");
}

#[test]
fn packet_agrees_with_obvhs_mesh_light() {
    agree_on(&scene("mesh_light"), "mesh_light");
}

/// The ≥100k-triangle scene, when scripts/fetch-dragon.sh has fetched it.
#[test]
fn packet_agrees_with_obvhs_dragon() {
    match Scene::resolve("dragon").and_then(|p| Scene::load(&p)) {
        Ok(s) => agree_on(&PreparedScene::new(s), "dragon"),
        Err(e) => eprintln!("skipping the dragon ({e}); run scripts/fetch-dragon.sh"),
    }
}

/// Ties on shared edges: vertical rays through dyadic points of the shared diagonals of quads
/// (exact arithmetic: both triangles are hit at the same t) get the smaller primitive id from
/// every backend and kernel, whichever triangle of the quad has it.
#[test]
fn ties_resolve_to_the_smaller_primitive_everywhere() {
    let mut tris = vec![];
    for k in 0..24 {
        let x = 4.0 * k as f32;
        let (p0, p1, p2, p3) = (
            Vec3::new(x - 1.0, 0.0, -1.0),
            Vec3::new(x + 1.0, 0.0, -1.0),
            Vec3::new(x + 1.0, 0.0, 1.0),
            Vec3::new(x - 1.0, 0.0, 1.0),
        );
        // Alternate which triangle of the quad gets the smaller id.
        if k % 2 == 0 {
            tris.push(Triangle::new(p0, p1, p2));
            tris.push(Triangle::new(p0, p2, p3));
        } else {
            tris.push(Triangle::new(p0, p2, p3));
            tris.push(Triangle::new(p0, p1, p2));
        }
    }
    let g = std::sync::Arc::new(Geometry {
        triangles: tris,
        spheres: vec![],
    });
    let base = ObvhsTracer::build(g.clone());
    let mut packets = vec![];
    for k in 0..24 {
        let mut p = RayPacket::default();
        for lane in 0..LANES {
            let s = (lane as f32 - 7.5) / 8.0;
            let o = Vec3::new(4.0 * k as f32 + s, 3.0, s);
            p.set(lane, &Ray::new(o, Vec3::new(0.0, -1.0, 0.0), f32::INFINITY));
        }
        packets.push(p);
    }
    let mut ties = 0;
    for p in &packets {
        for lane in 0..LANES {
            let ray = p.get(lane);
            let wr = WatertightRay::new(ray.dir);
            let hits: Vec<_> = g
                .triangles
                .iter()
                .enumerate()
                .filter_map(|(i, t)| t.intersect(&ray, &wr).map(|h| (h.t, i)))
                .collect();
            let tmin = hits.iter().map(|h| h.0).fold(f32::INFINITY, f32::min);
            let at_min: Vec<usize> = hits.iter().filter(|h| h.0 == tmin).map(|h| h.1).collect();
            if at_min.len() > 1 {
                ties += 1;
                let want = at_min.iter().min().copied();
                assert_eq!(base.intersect(&ray).map(|h| h.prim as usize), want);
            }
        }
    }
    assert!(ties > 300, "the rays must produce ties to test: {ties}");
    for isa in Isa::available() {
        let tr = PacketTracer::build(g.clone(), isa).unwrap();
        let mut tally = Tally::default();
        for p in &packets {
            check_closest(&base, &tr, p, u16::MAX, &mut tally);
        }
    }
}

/// A 2.4 × 2.4 wall in the plane x = 0, 72 triangles.
fn wall() -> (Vec<Triangle>, std::sync::Arc<Geometry>) {
    let mut tris = vec![];
    for i in 0..6 {
        for j in 0..6 {
            let (y, z) = (i as f32 * 0.4, j as f32 * 0.4);
            let (a, b, c, d) = (
                Vec3::new(0.0, y, z),
                Vec3::new(0.0, y + 0.4, z),
                Vec3::new(0.0, y + 0.4, z + 0.4),
                Vec3::new(0.0, y, z + 0.4),
            );
            tris.push(Triangle::new(a, b, c));
            tris.push(Triangle::new(a, c, d));
        }
    }
    let g = std::sync::Arc::new(Geometry {
        triangles: tris.clone(),
        spheres: vec![],
    });
    (tris, g)
}

/// Rays that start a hair behind the wall (x = −10⁻⁸) meet it at a t inside the f32 test's
/// error bound, which only t in f64 settles: a real hit, unless the ray's tmax ends before
/// it, or ends within rounding of it. The occlusion kernels (packet and single-ray) settle
/// such lanes with the scalar test's f64 step alone, the closest-hit ones with the whole scalar
/// test; all must agree with obvhs on both outcomes, and the rays are chosen so that both
/// occur. An occlusion kernel whose f64 step ignored tmax fails here, and so does one that
/// never finds these hits.
#[test]
fn near_hits_settled_in_f64_keep_tmax() {
    let (tris, g) = wall();
    let base = ObvhsTracer::build(g.clone());
    let mut packets = vec![];
    let (mut real, mut cut) = (0, 0);
    for i in 0..60 {
        let mut p = RayPacket::default();
        for lane in 0..LANES {
            let k = i * LANES + lane;
            let t = &tris[k % tris.len()];
            let (b1, b2) = ((k % 43) as f32 / 97.0, (k % 31) as f32 / 71.0);
            let behind = [1e-8f32, 3e-8, 1e-7][k % 3];
            let o = t.point(b1, b2) - Vec3::new(behind, 0.0, 0.0);
            let a = k as f32 * 0.0031;
            let d = Vec3::new(0.3 + 0.2 * a.sin(), 0.6 * a.cos(), -0.75).normalize();
            // t to the plane, in f64; tmax after it, or just before it: by less than the
            // f32 test's rounding of t, so f32 alone may place the hit on either side.
            let t_plane = (behind as f64 / d.x as f64) as f32;
            let tmax = match k % 6 {
                5 => t_plane * 2.0,
                j => t_plane * (1.0 - [1e-6, 1e-5, 1e-4, 1e-3, 1e-2][j]),
            };
            let ray = Ray::new(o, d, tmax);
            match base.intersect(&ray) {
                Some(_) => real += 1,
                None if base.intersect(&Ray::new(o, d, f32::INFINITY)).is_some() => cut += 1,
                None => {}
            }
            p.set(lane, &ray);
        }
        packets.push(p);
    }
    assert!(
        real > 100 && cut > 100,
        "real near hits {real}, cut by tmax {cut}"
    );
    for isa in Isa::available() {
        let tr = PacketTracer::build(g.clone(), isa).unwrap();
        let mut tally = Tally::default();
        for p in &packets {
            check_closest(&base, &tr, p, u16::MAX, &mut tally);
            check_occluded(&base, &tr, p, u16::MAX);
        }
        assert_eq!(tally.hits, real, "{isa:?}");
    }
}

/// Rays leaving points exactly on a wall (x = 0) must not hit the wall itself: the SIMD leaf
/// keeps the conservative-t rule. Negative control: the same kernel without the rule reports
/// self-hits, and the comparison with obvhs catches it.
#[test]
fn leaf_keeps_the_conservative_t_rule() {
    let (tris, g) = wall();
    let base = ObvhsTracer::build(g.clone());
    let mut packets = vec![];
    for i in 0..80 {
        let mut p = RayPacket::default();
        for lane in 0..LANES {
            let k = i * LANES + lane;
            let t = &tris[k % tris.len()];
            let (b1, b2) = ((k % 43) as f32 / 97.0, (k % 31) as f32 / 71.0);
            let o = t.point(b1, b2);
            assert_eq!(o.x, 0.0);
            let a = k as f32 * 0.0031;
            let d = Vec3::new(0.3 + 0.2 * a.sin(), 0.6 * a.cos(), -0.75).normalize();
            p.set(lane, &Ray::new(o, d, f32::INFINITY));
        }
        packets.push(p);
    }
    for isa in Isa::available() {
        let tr = PacketTracer::build(g.clone(), isa).unwrap();
        let (mut good, mut faulty) = (0, 0);
        for p in &packets {
            let mut h = HitPacket::default();
            tr.closest_packet::<0>(p, u16::MAX, &mut h, &mut TraceStats::default());
            let occ = tr.occluded_packet_fault::<0>(p, u16::MAX, &mut TraceStats::default());
            let mut hf = HitPacket::default();
            tr.closest_packet::<FAULT_NO_T_BOUND>(p, u16::MAX, &mut hf, &mut TraceStats::default());
            for lane in 0..LANES {
                let ray = p.get(lane);
                assert_eq!(base.intersect(&ray), None);
                good += h.get(lane).is_some() as u32 + (occ >> lane & 1) as u32;
                let single =
                    tr.closest_single::<FAULT_NO_T_BOUND>(&ray, &mut TraceStats::default());
                faulty += (hf.get(lane).is_some() || single.is_some()) as u32;
            }
        }
        assert_eq!(good, 0, "{isa:?}: self-hits");
        assert!(
            faulty > 20,
            "{isa:?}: the negative control found only {faulty} self-hits"
        );
    }
}

/// Camera packets take both paths of the closest-hit kernel: some nodes' children are entered
/// on the interval test alone (few children overlap the packet, or every lane is sure to meet
/// them), on the bunny others with per-lane slab tests; on those packets the hits are obvhs's,
/// bit for bit. Without the counts the interval-only path could be dead code that the contract
/// tests never reach.
#[test]
fn camera_packets_take_the_interval_path() {
    for (name, both) in [("bunny", true), ("cornell", false)] {
        let sc = scene(name);
        let base = ObvhsTracer::build(sc.world.geometry.clone());
        let sets = rays::generate(&sc, 48, 7);
        let primary = sets.iter().find(|s| s.class == "primary").unwrap();
        assert!(primary.coherent);
        for isa in Isa::available() {
            let tr = PacketTracer::build(sc.world.geometry.clone(), isa).unwrap();
            let mut stats = TraceStats::default();
            let mut tally = Tally::default();
            for (p, &m) in primary.packets.iter().zip(&primary.masks) {
                tr.intersect_packet_stats(p, m, &mut HitPacket::default(), &mut stats);
                check_closest(&base, &tr, p, m, &mut tally);
            }
            assert!(
                stats.frustum_nodes > 0 && (!both || stats.frustum_nodes < stats.packet_nodes),
                "{name} {isa:?}: {} of {} packet visits on the interval test alone",
                stats.frustum_nodes,
                stats.packet_nodes
            );
            assert!(tally.hits > 1000, "{name}: too few hits: {tally:?}");
        }
    }
}

/// Closest hit visits children near to far: through a stack of 40 parallel quads a ray stops
/// after the nearest leaf (the others are culled behind its hit), for single rays and packets:
/// a packet of parallel rays (per-lane slab tests) and a camera packet, whose rays share an
/// origin (the interval test alone, with the hull's entry distances as keys). Negative control:
/// the far-to-near kernel, still correct, tests many more leaves.
#[test]
fn closest_hit_visits_near_to_far() {
    let mut tris = vec![];
    for k in 0..40 {
        let z = -(k as f32) * 0.5;
        let (a, b, c, d) = (
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(1.0, -1.0, z),
            Vec3::new(1.0, 1.0, z),
            Vec3::new(-1.0, 1.0, z),
        );
        tris.push(Triangle::new(a, b, c));
        tris.push(Triangle::new(a, c, d));
    }
    let g = std::sync::Arc::new(Geometry {
        triangles: tris,
        spheres: vec![],
    });
    let base = ObvhsTracer::build(g.clone());
    let grid = |lane: usize| {
        (
            (lane % 4) as f32 * 0.1 - 0.15,
            (lane / 4) as f32 * 0.1 - 0.15,
        )
    };
    let (mut parallel, mut camera) = (RayPacket::default(), RayPacket::default());
    for lane in 0..LANES {
        let (x, y) = grid(lane);
        let down = Vec3::new(0.0, 0.0, -1.0);
        parallel.set(lane, &Ray::new(Vec3::new(x, y, 5.0), down, f32::INFINITY));
        let eye = Vec3::new(-0.3, -0.25, 5.0);
        let d = (Vec3::new(x, y, 0.0) - eye).normalize();
        camera.set(lane, &Ray::new(eye, d, f32::INFINITY));
    }
    for isa in Isa::available() {
        let tr = PacketTracer::build(g.clone(), isa).unwrap();
        for (what, p) in [("parallel", &parallel), ("camera", &camera)] {
            let (mut near, mut far) = (TraceStats::default(), TraceStats::default());
            let mut h = HitPacket::default();
            tr.closest_packet::<0>(p, u16::MAX, &mut h, &mut near);
            let mut hf = HitPacket::default();
            tr.closest_packet::<FAULT_FAR_FIRST>(p, u16::MAX, &mut hf, &mut far);
            for lane in 0..LANES {
                let ray = p.get(lane);
                let want = bits(base.intersect(&ray));
                assert!(want.is_some(), "{what}: lane {lane} misses the stack");
                assert_eq!(bits(h.get(lane)), want);
                assert_eq!(bits(hf.get(lane)), want, "far to near is slower, not wrong");
                let (mut s1, mut s2) = (TraceStats::default(), TraceStats::default());
                assert_eq!(bits(tr.closest_single::<0>(&ray, &mut s1)), want);
                assert_eq!(
                    bits(tr.closest_single::<FAULT_FAR_FIRST>(&ray, &mut s2)),
                    want
                );
                assert!(
                    s1.leaves <= 2,
                    "{isa:?} {what}: single ray tested {} leaves",
                    s1.leaves
                );
                assert!(
                    s2.leaves >= 4,
                    "{isa:?} {what}: negative control tested {} leaves",
                    s2.leaves
                );
            }
            assert!(
                near.leaves <= 2,
                "{isa:?} {what}: packet tested {} leaves",
                near.leaves
            );
            assert!(
                far.leaves >= 4,
                "{isa:?} {what}: negative control tested {} leaves",
                far.leaves
            );
        }
    }
}

/// Same hits ⇒ same image: the renderer sees identical (t, prim, u, v) from both backends,
/// so the images are compared bit for bit.
#[test]
fn packet_renders_same_image_as_obvhs() {
    let path = Scene::resolve("cornell").unwrap();
    let a = PreparedScene::new(Scene::load(&path).unwrap());
    for isa in Isa::available() {
        let b = PreparedScene::with_tracer(Scene::load(&path).unwrap(), |g| {
            Box::new(PacketTracer::build(g, isa).unwrap())
        });
        for s in registry() {
            if dibench::strategy::applies(s.as_ref(), &a).is_err() {
                continue;
            }
            let img = |sc: &PreparedScene| {
                let mut r = Renderer::new(sc, s.as_ref(), 3).unwrap();
                let mut film = Film::new(sc.scene.width, sc.scene.height);
                for _ in 0..2 {
                    r.add_pass(&mut film);
                }
                film.mean()
            };
            let (ia, ib) = (img(&a), img(&b));
            assert!(
                ia.pixels == ib.pixels,
                "{isa:?} {}: images differ",
                s.name()
            );
        }
    }
}

/// The wide BVH's shape and build time (printed; the docs quote it): nodes are well filled and
/// blocks hold several triangles on average.
#[test]
fn wide_bvh_shape() {
    let mut scenes = vec![("bunny", scene("bunny"))];
    if let Ok(s) = Scene::resolve("dragon").and_then(|p| Scene::load(&p)) {
        scenes.push(("dragon", PreparedScene::new(s)));
    }
    for (name, sc) in &scenes {
        let tr = PacketTracer::build(sc.world.geometry.clone(), Isa::Portable).unwrap();
        let w = tr.wide();
        eprintln!(
            "{name}: {} triangles: {}",
            sc.world.geometry.triangles.len(),
            w.describe()
        );
        let children: u32 = w.nodes.iter().map(|n| n.count).sum();
        assert!(
            children as f64 >= 4.0 * w.nodes.len() as f64,
            "{name}: sparse nodes"
        );
        assert!(
            w.blocks.len() * 2 <= sc.world.geometry.triangles.len(),
            "{name}: blocks hold too few triangles"
        );
    }
}
