//! Fixed, seeded ray sets drawn from a scene, for backend cross-checks and throughput runs:
//! camera rays in 4×4 tiles, shadow rays to area-light samples, incoherent hemisphere rays.
//! Every set is a flat list whose consecutive runs of 16 form the packets.

use crate::film::TileLayout;
use crate::geometry::Ray;
use crate::prepare::PreparedScene;
use crate::render::camera_ray;
use crate::sampling::stream::{SampleStream, name_id};
use crate::sampling::warp::sample_uniform_sphere;
use crate::strategy::ShadingPoint;
use crate::tracer::LANES;

pub struct RaySet {
    pub name: &'static str,
    pub rays: Vec<Ray>,
    /// Packets of this set are coherent (camera tiles), so backends may use a coherent kernel.
    pub coherent: bool,
}

impl RaySet {
    /// The rays as packets of up to 16 (the last one may be partial).
    pub fn packets(&self) -> impl Iterator<Item = &[Ray]> {
        self.rays.chunks(LANES)
    }
}

pub const SET_NAMES: [&str; 3] = ["primary", "shadow_area", "incoherent"];

/// Camera rays (one per pixel, jittered, tile by tile), then from each surface the primary rays
/// hit (found with the scene's own tracer): a shadow ray to a light sample in front of the
/// surface (finite tmax) and a uniformly random direction into the hemisphere facing the
/// camera (infinite tmax). Shadow rays need a light with positive power; the set is empty
/// otherwise.
pub fn generate(scene: &PreparedScene, seed: u64) -> Vec<RaySet> {
    let camera = &scene.scene.camera;
    let (w, h) = (scene.scene.width, scene.scene.height);
    let layout = TileLayout::new(w, h);
    let mut primary = Vec::with_capacity((w * h) as usize);
    let mut shadow = Vec::new();
    let mut incoherent = Vec::new();
    let salt = name_id("raysets");
    for tile in 0..layout.tile_count() {
        for lane in 0..LANES {
            if let Some((x, y)) = layout.lane_pixel(tile, lane) {
                let pixel = y as u64 * w as u64 + x as u64;
                let mut rng = SampleStream::new(seed, salt, pixel, 0);
                primary.push((camera_ray(camera, w, h, x, y, rng.next_2d()), rng));
            }
        }
    }
    for (ray, rng) in &mut primary {
        let Some(hit) = scene.tracer.intersect(ray) else {
            continue;
        };
        let surf = scene.surface(ray, &hit);
        let white = crate::bsdf::Bsdf::lambertian(glam::Vec3::ONE);
        let sp = ShadingPoint::with_error(surf.p, surf.p_error, surf.ng, ray.dir, &white);
        let u_select = rng.next_1d();
        let u = [rng.next_1d(), rng.next_1d(), rng.next_1d()];
        if let Some(r) = scene
            .sample_light(sp.p, u_select, u, &crate::lights::LightMethods::BASIC)
            .and_then(|(_, ls)| ls.shadow_ray(sp.origin))
            // Only the rays a renderer traces: a light behind the surface is never tested
            // (and the origin is offset to the front side only).
            .filter(|r| r.dir.dot(sp.n) > 0.0)
        {
            shadow.push(r);
        }
        let d = sample_uniform_sphere(rng.next_2d());
        let d = if d.dot(sp.n) < 0.0 { -d } else { d };
        incoherent.push(Ray::new(sp.origin, d, f32::INFINITY));
    }
    vec![
        RaySet {
            name: SET_NAMES[0],
            rays: primary.into_iter().map(|(r, _)| r).collect(),
            coherent: true,
        },
        RaySet {
            name: SET_NAMES[1],
            rays: shadow,
            coherent: false,
        },
        RaySet {
            name: SET_NAMES[2],
            rays: incoherent,
            coherent: false,
        },
    ]
}
