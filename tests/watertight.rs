//! Watertightness on shared edges: a ray through a point exactly on the edge two triangles
//! share hits one of them — closest hit and occlusion, single rays and packets, every backend
//! and ISA (Woop et al. 2013: a watertight test counts an exactly-zero edge function as inside,
//! and decides it consistently for both triangles).

use dibench::geometry::Ray;
use dibench::geometry::triangle::Triangle;
use dibench::simd::Isa;
use dibench::tracer::{Geometry, LANES, RayPacket, Tracer, backends};
use glam::Vec3;
use std::sync::Arc;

/// The unit square in y = 0, split along its diagonal (0,0,0)–(1,0,1), as a quad is traced.
fn split_square() -> Arc<Geometry> {
    let (c, u, v) = (Vec3::ZERO, Vec3::X, Vec3::Z);
    Arc::new(Geometry {
        triangles: vec![
            Triangle::new(c, c + u, c + u + v),
            Triangle::new(c, c + u + v, c + v),
        ],
        spheres: vec![],
    })
}

/// Rays at points exactly on the shared diagonal (t, 0, t), t = k/64: straight down (the
/// point is exactly on the edge in the ray's own frame too), and from oblique origins.
fn edge_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    for k in 1..64 {
        let t = k as f32 / 64.0;
        let p = Vec3::new(t, 0.0, t);
        rays.push(Ray::new(p + Vec3::Y, -Vec3::Y, 2.0));
        for o in [
            Vec3::new(-0.7, 1.3, 0.4),
            Vec3::new(1.9, 0.6, -0.2),
            Vec3::new(0.5, 2.0, 0.5),
        ] {
            let d = p - o;
            rays.push(Ray::new(o, d.normalize(), 2.0 * d.length()));
        }
    }
    rays
}

fn tracers() -> Vec<(String, Box<dyn Tracer>)> {
    let g = split_square();
    let mut v = vec![(
        "obvhs".to_string(),
        backends::build("obvhs", g.clone()).unwrap(),
    )];
    for isa in Isa::available() {
        v.push((
            format!("packet/{}", isa.name()),
            backends::build_isa("packet", g.clone(), Some(isa)).unwrap(),
        ));
    }
    v
}

#[test]
fn rays_through_a_shared_edge_hit_one_of_its_triangles() {
    let rays = edge_rays();
    for (name, tr) in tracers() {
        for r in &rays {
            assert!(
                tr.intersect(r).is_some(),
                "{name}: {r:?} passed through the edge"
            );
            assert!(tr.occluded(r), "{name}: {r:?} not occluded by the edge");
        }
        for chunk in rays.chunks(LANES) {
            let mut p = RayPacket::default();
            for (lane, r) in chunk.iter().enumerate() {
                p.set(lane, r);
            }
            let active = ((1u32 << chunk.len()) - 1) as u16;
            let mut hits = Default::default();
            tr.intersect_packet(&p, active, &mut hits);
            for lane in 0..chunk.len() {
                assert!(
                    hits.get(lane).is_some(),
                    "{name}: packet lane {lane} passed through"
                );
            }
            assert_eq!(
                tr.occluded_packet(&p, active),
                active,
                "{name}: packet occlusion"
            );
        }
    }
}
