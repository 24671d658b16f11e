//! The one generator of fixed, seeded ray sets drawn from a scene, for the throughput harness
//! (`dibench rays`, the criterion benches) and the backend cross-check: camera rays through
//! pixel centres in 4×4 tiles (or, [`Packing::Pixel`], 16 jittered samples of one pixel per
//! packet, as a render packs them), and from each surface point a primary ray hits (found with
//! the scene's own tracer, offset off the surface) a shadow ray to a light sample, a shadow ray
//! towards a fixed distant direction, and a uniformly random direction into the hemisphere
//! facing the camera. Secondary rays stay in their primary's packet lane, as the renderer
//! groups them; a lane without a ray of that class is inactive.

use crate::film::TileLayout;
use crate::geometry::Ray;
use crate::math::{mix64, offset_ray_origin};
use crate::prepare::PreparedScene;
use crate::render::camera_ray;
use crate::sampling::warp::sample_uniform_sphere;
use crate::tracer::{HitPacket, LANES, LaneMask, RayPacket};
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    Closest,
    Occluded,
}

/// What a packet's 16 camera rays are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Packing {
    /// The centres of a 4×4 tile of pixels.
    Tile,
    /// 16 jittered samples of one pixel, as a render's passes in groups trace them
    /// (docs/tracer.md, stop 42): their hit points lie within one pixel's footprint, so the
    /// secondary rays of a packet share their origins but for that spread. The image is a
    /// quarter as wide and high, so a set holds as many rays as with tiles.
    Pixel,
}

/// One ray class as 16-ray packets (see [`Packing`]) with their active masks.
pub struct RaySet {
    pub class: &'static str,
    /// The class's natural query: occlusion for shadow rays, closest hit otherwise.
    pub query: Query,
    /// Packets of this set are coherent (camera tiles), so backends may use a coherent kernel.
    pub coherent: bool,
    pub packets: Vec<RayPacket>,
    pub masks: Vec<LaneMask>,
}

/// The classes, in generation order.
pub const CLASSES: [(&str, Query); 4] = [
    ("primary", Query::Closest),
    ("shadow_area", Query::Occluded),
    ("shadow_distant", Query::Occluded),
    ("incoherent", Query::Closest),
];

impl RaySet {
    /// Active rays.
    pub fn rays(&self) -> u64 {
        self.masks.iter().map(|m| m.count_ones() as u64).sum()
    }

    /// The active rays, packet by packet, lane by lane.
    pub fn flat(&self) -> Vec<Ray> {
        let mut out = Vec::with_capacity(self.rays() as usize);
        for (p, &m) in self.packets.iter().zip(&self.masks) {
            out.extend((0..LANES).filter(|l| m & (1 << l) != 0).map(|l| p.get(l)));
        }
        out
    }

    /// A set from a flat list: consecutive runs of 16 rays form the packets.
    pub fn from_rays(class: &'static str, query: Query, coherent: bool, rays: &[Ray]) -> Self {
        let mut set = RaySet {
            class,
            query,
            coherent,
            packets: vec![],
            masks: vec![],
        };
        for chunk in rays.chunks(LANES) {
            let mut p = RayPacket::default();
            for (l, r) in chunk.iter().enumerate() {
                p.set(l, r);
            }
            set.packets.push(p);
            set.masks.push(((1u32 << chunk.len()) - 1) as LaneMask);
        }
        set
    }
}

/// Uniform [0, 1) from a hashed key: fixed ray sets without RNG state.
fn u01(key: u64) -> f32 {
    (mix64(key) >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// The four classes of [`CLASSES`] for a `width`×`height` image of the scene's camera, in
/// 4×4 tiles.
pub fn generate(scene: &PreparedScene, width: u32, height: u32, seed: u64) -> Vec<RaySet> {
    generate_packed(scene, width, height, seed, Packing::Tile)
}

/// [`generate`] with the camera rays packed as `packing` says: `width`×`height` rays per
/// class either way (with [`Packing::Pixel`], the samples of a (width/4)×(height/4) image,
/// sides rounded up).
pub fn generate_packed(
    scene: &PreparedScene,
    width: u32,
    height: u32,
    seed: u64,
    packing: Packing,
) -> Vec<RaySet> {
    let cam = &scene.scene.camera;
    let layout = TileLayout::new(width, height);
    let (pw, ph) = (width.div_ceil(4), height.div_ceil(4));
    let distant = Vec3::new(0.35, 1.0, 0.25).normalize();
    let mut sets: Vec<RaySet> = CLASSES
        .into_iter()
        .map(|(class, query)| RaySet {
            class,
            query,
            coherent: class == "primary",
            packets: vec![],
            masks: vec![],
        })
        .collect();
    let mut hits = HitPacket::default();
    let packets = match packing {
        Packing::Tile => layout.tile_count(),
        Packing::Pixel => (pw * ph) as usize,
    };
    for tile in 0..packets {
        let mut p = [RayPacket::default(); 4];
        let mut m = [0 as LaneMask; 4];
        for lane in 0..LANES {
            let ray = match packing {
                Packing::Tile => layout
                    .lane_pixel(tile, lane)
                    .map(|(x, y)| camera_ray(cam, width, height, x, y, [0.5, 0.5])),
                Packing::Pixel => {
                    let (x, y) = (tile as u32 % pw, tile as u32 / pw);
                    let key = seed ^ 0x6a09_e667 ^ ((tile as u64) << 4 | lane as u64) << 8;
                    let u = [u01(key), u01(key.wrapping_add(1))];
                    Some(camera_ray(cam, pw, ph, x, y, u))
                }
            };
            if let Some(ray) = ray {
                p[0].set(lane, &ray);
                m[0] |= 1 << lane;
            }
        }
        scene.tracer.intersect_packet(&p[0], m[0], &mut hits);
        for lane in 0..LANES {
            let Some(hit) = hits.get(lane) else { continue };
            let ray = p[0].get(lane);
            let surf = scene.surface(&ray, &hit);
            let n = if surf.ng.dot(ray.dir) < 0.0 {
                surf.ng
            } else {
                -surf.ng
            };
            let o = offset_ray_origin(surf.p, surf.p_error, n);
            let key = seed ^ ((tile as u64) << 4 | lane as u64) << 8;
            let u = |i: u64| u01(key.wrapping_add(i));
            if let Some((_, ls)) = scene.sample_light(
                o,
                u(1),
                [u(2), u(3), u(4)],
                &crate::lights::LightMethods::BASIC,
            ) && let Some(r) = ls.shadow_ray(o)
            {
                p[1].set(lane, &r);
                m[1] |= 1 << lane;
            }
            p[2].set(lane, &Ray::new(o, distant, f32::INFINITY));
            m[2] |= 1 << lane;
            let d = sample_uniform_sphere([u(5), u(6)]);
            let d = if d.dot(n) < 0.0 { -d } else { d };
            p[3].set(lane, &Ray::new(o, d, f32::INFINITY));
            m[3] |= 1 << lane;
        }
        for k in 0..4 {
            if m[k] != 0 {
                sets[k].packets.push(p[k]);
                sets[k].masks.push(m[k]);
            }
        }
    }
    sets
}
