//! The Embree 4 backend (`--features embree`): triangles as an Embree triangle geometry,
//! spheres as a user geometry whose callbacks run our exact [`Sphere::intersect`], so hits
//! match the sphere sampler (Embree's SPHERE_POINT is a ray-facing disc-like point sphere, not
//! an exact sphere). Scene primitive ids are recovered from (geomID, primID).

mod ffi;

use super::{Geometry, HitPacket, LANES, LaneMask, NO_HIT, RayPacket, Tracer};
use crate::error::{Error, Result};
use crate::geometry::sphere::Sphere;
use crate::geometry::{Hit, Ray};
use ffi::word;
use glam::Vec3;
use std::ffi::{CStr, c_char, c_int, c_void};
use std::sync::{Arc, Mutex};

/// Minimum Embree version (RTC_DEVICE_PROPERTY_VERSION encodes 4.4.0 as 40400): the struct
/// layouts in `ffi.rs` are those of 4.4.
pub const MIN_VERSION: isize = 40400;

/// Ray-coherence hint for packet queries (RTC_RAY_QUERY_FLAG_COHERENT / INCOHERENT). Coherent
/// packets (camera tiles) run ~3× faster with the hint; incoherent ones run slower with it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coherence {
    Coherent,
    Incoherent,
}

pub struct EmbreeTracer {
    geometry: Arc<Geometry>,
    device: ffi::RTCDevice,
    scene: ffi::RTCScene,
    tri_geom: u32,
    sphere_geom: u32,
    /// How long building the scene took (set-up and commit; Embree's builder uses its own
    /// threads).
    build_time: std::time::Duration,
    /// Receives messages from Embree's error callback; boxed so its address is stable.
    _errors: Box<Mutex<Vec<String>>>,
}

// SAFETY: a committed Embree scene is immutable and its query functions are thread-safe
// (Embree API docs, rtcIntersect1: "can be called from multiple threads"); the geometry our
// callbacks read is behind an Arc we hold.
unsafe impl Send for EmbreeTracer {}
unsafe impl Sync for EmbreeTracer {}

unsafe extern "C" fn on_error(user: *mut c_void, code: c_int, msg: *const c_char) {
    let text = if msg.is_null() {
        String::new()
    } else {
        // SAFETY: Embree passes a NUL-terminated message.
        unsafe { CStr::from_ptr(msg) }
            .to_string_lossy()
            .into_owned()
    };
    // SAFETY: `user` is the boxed Mutex owned by the tracer, alive as long as the device.
    let errors = unsafe { &*(user as *const Mutex<Vec<String>>) };
    if let Ok(mut e) = errors.lock() {
        e.push(format!("Embree error {code}: {text}"));
    }
}

unsafe extern "C" fn sphere_bounds(args: *const ffi::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid args; the user pointer is our Geometry.
    unsafe {
        let a = &*args;
        let g = &*(a.geometry_user_ptr as *const Geometry);
        let s = &g.spheres[a.prim_id as usize];
        *a.bounds_o = ffi::RTCBounds {
            lower_x: s.center.x - s.radius,
            lower_y: s.center.y - s.radius,
            lower_z: s.center.z - s.radius,
            align0: 0.0,
            upper_x: s.center.x + s.radius,
            upper_y: s.center.y + s.radius,
            upper_z: s.center.z + s.radius,
            align1: 0.0,
        };
    }
}

/// Reads lane `i` of an RTCRayN (N lanes, field k at word k*N + i) as our ray with tmax = tfar.
/// SAFETY: `w` points at an RTCRayN of `n` lanes.
unsafe fn ray_n(w: *const u32, n: usize, i: usize) -> Ray {
    let f = |k: usize| unsafe { f32::from_bits(*w.add(k * n + i)) };
    Ray::new(
        Vec3::new(f(word::ORG_X), f(word::ORG_Y), f(word::ORG_Z)),
        Vec3::new(f(word::DIR_X), f(word::DIR_Y), f(word::DIR_Z)),
        f(word::TFAR),
    )
}

fn sphere_hit(s: &Sphere, ray: &Ray, tnear: f32) -> Option<f32> {
    s.intersect(ray).filter(|&t| t >= tnear)
}

unsafe extern "C" fn sphere_intersect(args: *const ffi::RTCIntersectFunctionNArguments) {
    // SAFETY: Embree passes valid args with `n` lanes of RTCRayHitN and a valid mask.
    unsafe {
        let a = &*args;
        let g = &*(a.geometry_user_ptr as *const Geometry);
        let s = &g.spheres[a.prim_id as usize];
        let n = a.n as usize;
        for i in 0..n {
            if *a.valid.add(i) == 0 {
                continue;
            }
            let ray = ray_n(a.rayhit, n, i);
            let tnear = f32::from_bits(*a.rayhit.add(word::TNEAR * n + i));
            if let Some(t) = sphere_hit(s, &ray, tnear) {
                let ng = ray.at(t) - s.center;
                let put = |k: usize, bits: u32| *a.rayhit.add(k * n + i) = bits;
                put(word::TFAR, t.to_bits());
                put(word::NG_X, ng.x.to_bits());
                put(word::NG_Y, ng.y.to_bits());
                put(word::NG_Z, ng.z.to_bits());
                put(word::U, 0);
                put(word::V, 0);
                put(word::PRIM_ID, a.prim_id);
                put(word::GEOM_ID, a.geom_id);
                put(word::INST_ID, ffi::RTC_INVALID_GEOMETRY_ID);
                put(word::INST_PRIM_ID, ffi::RTC_INVALID_GEOMETRY_ID);
            }
        }
    }
}

unsafe extern "C" fn sphere_occluded(args: *const ffi::RTCOccludedFunctionNArguments) {
    // SAFETY: as above, with an RTCRayN.
    unsafe {
        let a = &*args;
        let g = &*(a.geometry_user_ptr as *const Geometry);
        let s = &g.spheres[a.prim_id as usize];
        let n = a.n as usize;
        for i in 0..n {
            if *a.valid.add(i) == 0 {
                continue;
            }
            let ray = ray_n(a.ray, n, i);
            let tnear = f32::from_bits(*a.ray.add(word::TNEAR * n + i));
            if sphere_hit(s, &ray, tnear).is_some() {
                // An occluded ray is marked by tfar = -inf (rtcOccluded1 docs).
                *a.ray.add(word::TFAR * n + i) = f32::NEG_INFINITY.to_bits();
            }
        }
    }
}

fn args(c: Coherence) -> ffi::RTCQueryArguments {
    ffi::RTCQueryArguments {
        flags: match c {
            Coherence::Coherent => ffi::RTC_RAY_QUERY_FLAG_COHERENT,
            Coherence::Incoherent => ffi::RTC_RAY_QUERY_FLAG_INCOHERENT,
        },
        feature_mask: ffi::RTC_FEATURE_FLAG_ALL,
        context: std::ptr::null_mut(),
        filter: std::ptr::null(),
        intersect: std::ptr::null(),
        min_width_distance_factor: 0.0,
    }
}

fn ray1(ray: &Ray) -> ffi::RTCRay {
    ffi::RTCRay {
        org_x: ray.origin.x,
        org_y: ray.origin.y,
        org_z: ray.origin.z,
        tnear: 0.0,
        dir_x: ray.dir.x,
        dir_y: ray.dir.y,
        dir_z: ray.dir.z,
        time: 0.0,
        tfar: ray.tmax,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

fn ray16(rays: &RayPacket) -> ffi::RTCRay16 {
    ffi::RTCRay16 {
        org_x: rays.ox,
        org_y: rays.oy,
        org_z: rays.oz,
        tnear: [0.0; 16],
        dir_x: rays.dx,
        dir_y: rays.dy,
        dir_z: rays.dz,
        time: [0.0; 16],
        tfar: rays.tmax,
        mask: [u32::MAX; 16],
        id: [0; 16],
        flags: [0; 16],
    }
}

fn valid16(active: LaneMask) -> ffi::Valid16 {
    ffi::Valid16(std::array::from_fn(|i| {
        if active & (1 << i) != 0 { -1 } else { 0 }
    }))
}

impl EmbreeTracer {
    pub fn build(geometry: Arc<Geometry>) -> Result<Self> {
        let start = std::time::Instant::now();
        let errors: Box<Mutex<Vec<String>>> = Box::default();
        // SAFETY: plain FFI calls on handles we created; every handle is checked for null and
        // the device's error state is checked after the build.
        unsafe {
            let device = ffi::rtcNewDevice(std::ptr::null());
            if device.is_null() {
                return Err(Error::Backend(format!(
                    "Embree: cannot create a device (error code {})",
                    ffi::rtcGetDeviceError(std::ptr::null_mut())
                )));
            }
            let errs_ptr = &*errors as *const Mutex<Vec<String>> as *mut c_void;
            ffi::rtcSetDeviceErrorFunction(device, Some(on_error), errs_ptr);
            let version = ffi::rtcGetDeviceProperty(device, ffi::RTC_DEVICE_PROPERTY_VERSION);
            if version < MIN_VERSION {
                ffi::rtcReleaseDevice(device);
                return Err(Error::Backend(format!(
                    "Embree {version} is too old: dibench's FFI needs Embree >= 4.4.0 ({MIN_VERSION}); run scripts/setup-embree.sh"
                )));
            }
            let scene = ffi::rtcNewScene(device);
            let mut tracer = EmbreeTracer {
                geometry,
                device,
                scene,
                tri_geom: ffi::RTC_INVALID_GEOMETRY_ID,
                sphere_geom: ffi::RTC_INVALID_GEOMETRY_ID,
                build_time: std::time::Duration::ZERO,
                _errors: errors,
            };
            if scene.is_null() {
                return Err(tracer.error("cannot create a scene"));
            }
            ffi::rtcSetSceneBuildQuality(scene, ffi::RTC_BUILD_QUALITY_HIGH);
            let g = tracer.geometry.clone();
            if !g.triangles.is_empty() {
                tracer.tri_geom = tracer.attach_triangles(&g)?;
            }
            if !g.spheres.is_empty() {
                tracer.sphere_geom = tracer.attach_spheres(&g)?;
            }
            ffi::rtcCommitScene(scene);
            tracer.check("committing the scene")?;
            tracer.build_time = start.elapsed();
            Ok(tracer)
        }
    }

    /// How long [`Self::build`] took.
    pub fn build_time(&self) -> std::time::Duration {
        self.build_time
    }

    fn error(&self, what: &str) -> Error {
        let msgs = self
            ._errors
            .lock()
            .map(|e| e.join("; "))
            .unwrap_or_default();
        // SAFETY: the device handle is valid for the tracer's life.
        let code = unsafe { ffi::rtcGetDeviceError(self.device) };
        Error::Backend(format!("Embree: {what} failed (code {code}) {msgs}"))
    }

    fn check(&self, what: &str) -> Result<()> {
        let has_msgs = self._errors.lock().map(|e| !e.is_empty()).unwrap_or(true);
        if has_msgs {
            Err(self.error(what))
        } else {
            Ok(())
        }
    }

    /// SAFETY: device valid; the buffers are filled before commit.
    unsafe fn attach_triangles(&self, g: &Geometry) -> Result<u32> {
        unsafe {
            let geom = ffi::rtcNewGeometry(self.device, ffi::RTC_GEOMETRY_TYPE_TRIANGLE);
            if geom.is_null() {
                return Err(self.error("creating the triangle geometry"));
            }
            let n = g.triangles.len();
            let vb = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::RTC_BUFFER_TYPE_VERTEX,
                0,
                ffi::RTC_FORMAT_FLOAT3,
                12,
                3 * n,
            ) as *mut f32;
            let ib = ffi::rtcSetNewGeometryBuffer(
                geom,
                ffi::RTC_BUFFER_TYPE_INDEX,
                0,
                ffi::RTC_FORMAT_UINT3,
                12,
                n,
            ) as *mut u32;
            if vb.is_null() || ib.is_null() {
                ffi::rtcReleaseGeometry(geom);
                return Err(self.error("allocating triangle buffers"));
            }
            // Unshared vertices, in our order, so primID == our triangle index and Embree's
            // (u, v) are barycentrics of (v0, v1, v2) as ours are.
            let verts = std::slice::from_raw_parts_mut(vb, 9 * n);
            let idx = std::slice::from_raw_parts_mut(ib, 3 * n);
            for (k, t) in g.triangles.iter().enumerate() {
                for (j, v) in [t.v0, t.v1, t.v2].into_iter().enumerate() {
                    verts[9 * k + 3 * j..9 * k + 3 * j + 3].copy_from_slice(&v.to_array());
                    idx[3 * k + j] = (3 * k + j) as u32;
                }
            }
            ffi::rtcCommitGeometry(geom);
            let id = ffi::rtcAttachGeometry(self.scene, geom);
            ffi::rtcReleaseGeometry(geom);
            self.check("building the triangle geometry")?;
            Ok(id)
        }
    }

    /// SAFETY: device valid; `g` outlives the scene (the tracer holds the Arc).
    unsafe fn attach_spheres(&self, g: &Geometry) -> Result<u32> {
        unsafe {
            let geom = ffi::rtcNewGeometry(self.device, ffi::RTC_GEOMETRY_TYPE_USER);
            if geom.is_null() {
                return Err(self.error("creating the sphere user geometry"));
            }
            let user = g as *const Geometry as *mut c_void;
            ffi::rtcSetGeometryUserPrimitiveCount(geom, g.spheres.len() as u32);
            ffi::rtcSetGeometryUserData(geom, user);
            ffi::rtcSetGeometryBoundsFunction(geom, Some(sphere_bounds), user);
            ffi::rtcSetGeometryIntersectFunction(geom, Some(sphere_intersect));
            ffi::rtcSetGeometryOccludedFunction(geom, Some(sphere_occluded));
            ffi::rtcCommitGeometry(geom);
            let id = ffi::rtcAttachGeometry(self.scene, geom);
            ffi::rtcReleaseGeometry(geom);
            self.check("building the sphere geometry")?;
            Ok(id)
        }
    }

    /// Our primitive id of an Embree (geomID, primID).
    fn prim_id(&self, geom: u32, prim: u32) -> u32 {
        if geom == self.tri_geom {
            prim
        } else if geom == self.sphere_geom {
            self.geometry.triangles.len() as u32 + prim
        } else {
            NO_HIT
        }
    }

    /// 16-wide closest hit with a coherence hint (rtcIntersect16).
    pub fn intersect16(
        &self,
        rays: &RayPacket,
        active: LaneMask,
        hits: &mut HitPacket,
        hint: Coherence,
    ) {
        *hits = HitPacket::default();
        if active == 0 {
            return;
        }
        let valid = valid16(active);
        let mut rh = ffi::RTCRayHit16 {
            ray: ray16(rays),
            hit: ffi::RTCHit16 {
                ng_x: [0.0; 16],
                ng_y: [0.0; 16],
                ng_z: [0.0; 16],
                u: [0.0; 16],
                v: [0.0; 16],
                prim_id: [ffi::RTC_INVALID_GEOMETRY_ID; 16],
                geom_id: [ffi::RTC_INVALID_GEOMETRY_ID; 16],
                inst_id: [[ffi::RTC_INVALID_GEOMETRY_ID; 16]],
                inst_prim_id: [[ffi::RTC_INVALID_GEOMETRY_ID; 16]],
            },
        };
        let a = args(hint);
        // SAFETY: valid and rh are 64-byte aligned 16-lane structs of the 4.4 layout.
        unsafe { ffi::rtcIntersect16(&valid, self.scene, &mut rh, &a) };
        for lane in 0..LANES {
            let geom = rh.hit.geom_id[lane];
            if active & (1 << lane) == 0 || geom == ffi::RTC_INVALID_GEOMETRY_ID {
                continue;
            }
            hits.t[lane] = rh.ray.tfar[lane];
            hits.u[lane] = rh.hit.u[lane];
            hits.v[lane] = rh.hit.v[lane];
            hits.prim[lane] = self.prim_id(geom, rh.hit.prim_id[lane]);
        }
    }

    /// 16-wide occlusion with a coherence hint (rtcOccluded16); occluded lanes get tfar = -inf.
    pub fn occluded16(&self, rays: &RayPacket, active: LaneMask, hint: Coherence) -> LaneMask {
        if active == 0 {
            return 0;
        }
        let valid = valid16(active);
        let mut r = ray16(rays);
        let a = args(hint);
        // SAFETY: as in intersect16.
        unsafe { ffi::rtcOccluded16(&valid, self.scene, &mut r, &a) };
        let mut out = 0;
        for lane in 0..LANES {
            if active & (1 << lane) != 0 && r.tfar[lane] == f32::NEG_INFINITY {
                out |= 1 << lane;
            }
        }
        out
    }
}

impl Drop for EmbreeTracer {
    fn drop(&mut self) {
        // SAFETY: handles created in build and released once.
        unsafe {
            if !self.scene.is_null() {
                ffi::rtcReleaseScene(self.scene);
            }
            ffi::rtcReleaseDevice(self.device);
        }
    }
}

impl Tracer for EmbreeTracer {
    fn name(&self) -> &'static str {
        "embree"
    }

    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        let mut rh = ffi::RTCRayHit {
            ray: ray1(ray),
            hit: ffi::RTCHit {
                geom_id: ffi::RTC_INVALID_GEOMETRY_ID,
                prim_id: ffi::RTC_INVALID_GEOMETRY_ID,
                inst_id: [ffi::RTC_INVALID_GEOMETRY_ID],
                inst_prim_id: [ffi::RTC_INVALID_GEOMETRY_ID],
                ..Default::default()
            },
        };
        let a = args(Coherence::Incoherent);
        // SAFETY: rh has the 4.4 RTCRayHit layout (96 B, including instPrimID).
        unsafe { ffi::rtcIntersect1(self.scene, &mut rh, &a) };
        (rh.hit.geom_id != ffi::RTC_INVALID_GEOMETRY_ID).then(|| Hit {
            t: rh.ray.tfar,
            prim: self.prim_id(rh.hit.geom_id, rh.hit.prim_id),
            u: rh.hit.u,
            v: rh.hit.v,
        })
    }

    fn occluded(&self, ray: &Ray) -> bool {
        let mut r = ray1(ray);
        let a = args(Coherence::Incoherent);
        // SAFETY: r has the RTCRay layout.
        unsafe { ffi::rtcOccluded1(self.scene, &mut r, &a) };
        r.tfar == f32::NEG_INFINITY
    }

    fn intersect_packet(&self, rays: &RayPacket, active: LaneMask, hits: &mut HitPacket) {
        self.intersect16(rays, active, hits, Coherence::Incoherent);
    }

    fn intersect_packet_coherent(&self, rays: &RayPacket, active: LaneMask, hits: &mut HitPacket) {
        self.intersect16(rays, active, hits, Coherence::Coherent);
    }

    fn occluded_packet(&self, rays: &RayPacket, active: LaneMask) -> LaneMask {
        self.occluded16(rays, active, Coherence::Incoherent)
    }
}
