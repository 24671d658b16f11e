//! Hand-written FFI for the Embree 4.4 calls we use (no bindgen). Layouts follow
//! `include/embree4/rtcore_ray.h`, `rtcore_geometry.h`, `rtcore_scene.h` and `rtcore_device.h`
//! of Embree 4.4 as built in the embreex 4.4.0.post1 wheel: `EMBREE_GEOMETRY_INSTANCE_ARRAY=ON`
//! (so every hit carries `instPrimID`), `RTC_MAX_INSTANCE_LEVEL_COUNT == 1`, no `RTC_MIN_WIDTH`.
//! The 4.2 headers in `embree4-sys` lack `instPrimID`, which 4.4 writes on every hit.
#![allow(non_camel_case_types, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};
use std::mem::{align_of, offset_of, size_of};

pub type RTCDevice = *mut c_void;
pub type RTCScene = *mut c_void;
pub type RTCGeometry = *mut c_void;

pub const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

// enum RTCDeviceProperty
pub const RTC_DEVICE_PROPERTY_VERSION: c_int = 0;
// enum RTCGeometryType
pub const RTC_GEOMETRY_TYPE_TRIANGLE: c_int = 0;
pub const RTC_GEOMETRY_TYPE_USER: c_int = 120;
// enum RTCBufferType
pub const RTC_BUFFER_TYPE_INDEX: c_int = 0;
pub const RTC_BUFFER_TYPE_VERTEX: c_int = 1;
// enum RTCFormat
pub const RTC_FORMAT_UINT3: c_int = 0x5003;
pub const RTC_FORMAT_FLOAT3: c_int = 0x9003;
// enum RTCBuildQuality
pub const RTC_BUILD_QUALITY_HIGH: c_int = 2;
// enum RTCRayQueryFlags
pub const RTC_RAY_QUERY_FLAG_INCOHERENT: c_uint = 0;
pub const RTC_RAY_QUERY_FLAG_COHERENT: c_uint = 1 << 16;
// enum RTCFeatureFlags
pub const RTC_FEATURE_FLAG_ALL: c_uint = 0xffff_ffff;

/// struct RTCRay (rtcore_ray.h), 16-byte aligned.
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRay {
    pub org_x: f32,
    pub org_y: f32,
    pub org_z: f32,
    pub tnear: f32,
    pub dir_x: f32,
    pub dir_y: f32,
    pub dir_z: f32,
    pub time: f32,
    pub tfar: f32,
    pub mask: u32,
    pub id: u32,
    pub flags: u32,
}

/// struct RTCHit with the 4.4 `instPrimID` (RTC_GEOMETRY_INSTANCE_ARRAY).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCHit {
    pub ng_x: f32,
    pub ng_y: f32,
    pub ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub prim_id: u32,
    pub geom_id: u32,
    pub inst_id: [u32; 1],
    pub inst_prim_id: [u32; 1],
}

#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// struct RTCRay16: each field a 16-lane array.
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRay16 {
    pub org_x: [f32; 16],
    pub org_y: [f32; 16],
    pub org_z: [f32; 16],
    pub tnear: [f32; 16],
    pub dir_x: [f32; 16],
    pub dir_y: [f32; 16],
    pub dir_z: [f32; 16],
    pub time: [f32; 16],
    pub tfar: [f32; 16],
    pub mask: [u32; 16],
    pub id: [u32; 16],
    pub flags: [u32; 16],
}

#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCHit16 {
    pub ng_x: [f32; 16],
    pub ng_y: [f32; 16],
    pub ng_z: [f32; 16],
    pub u: [f32; 16],
    pub v: [f32; 16],
    pub prim_id: [u32; 16],
    pub geom_id: [u32; 16],
    pub inst_id: [[u32; 16]; 1],
    pub inst_prim_id: [[u32; 16]; 1],
}

#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct RTCRayHit16 {
    pub ray: RTCRay16,
    pub hit: RTCHit16,
}

/// The valid mask of a 16-wide query: -1 active, 0 inactive; Embree wants it aligned like the
/// packet (64 bytes).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug)]
pub struct Valid16(pub [c_int; 16]);

/// struct RTCIntersectArguments / RTCOccludedArguments (same layout). The trailing f32 is
/// `minWidthDistanceFactor`, present only with RTC_MIN_WIDTH; passing it zeroed is harmless.
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCQueryArguments {
    pub flags: c_uint,
    pub feature_mask: c_uint,
    pub context: *mut c_void,
    pub filter: *const c_void,
    pub intersect: *const c_void,
    pub min_width_distance_factor: f32,
}

/// struct RTCBounds (rtcore_common.h).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCBounds {
    pub lower_x: f32,
    pub lower_y: f32,
    pub lower_z: f32,
    pub align0: f32,
    pub upper_x: f32,
    pub upper_y: f32,
    pub upper_z: f32,
    pub align1: f32,
}

#[repr(C)]
pub struct RTCBoundsFunctionArguments {
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub time_step: c_uint,
    pub bounds_o: *mut RTCBounds,
}

/// `rayhit` points at an RTCRayHitN: field k of lane i is the 32-bit word k*N + i.
#[repr(C)]
pub struct RTCIntersectFunctionNArguments {
    pub valid: *mut c_int,
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub context: *mut c_void,
    pub rayhit: *mut u32,
    pub n: c_uint,
    pub geom_id: c_uint,
}

/// `ray` points at an RTCRayN (same word layout as above, ray fields only).
#[repr(C)]
pub struct RTCOccludedFunctionNArguments {
    pub valid: *mut c_int,
    pub geometry_user_ptr: *mut c_void,
    pub prim_id: c_uint,
    pub context: *mut c_void,
    pub ray: *mut u32,
    pub n: c_uint,
    pub geom_id: c_uint,
}

/// Word index of each field in an RTCRayHitN (rtcore_ray.h's RTCRayN_*/RTCHitN_* accessors).
pub mod word {
    pub const ORG_X: usize = 0;
    pub const ORG_Y: usize = 1;
    pub const ORG_Z: usize = 2;
    pub const TNEAR: usize = 3;
    pub const DIR_X: usize = 4;
    pub const DIR_Y: usize = 5;
    pub const DIR_Z: usize = 6;
    pub const TFAR: usize = 8;
    pub const NG_X: usize = 12;
    pub const NG_Y: usize = 13;
    pub const NG_Z: usize = 14;
    pub const U: usize = 15;
    pub const V: usize = 16;
    pub const PRIM_ID: usize = 17;
    pub const GEOM_ID: usize = 18;
    pub const INST_ID: usize = 19;
    pub const INST_PRIM_ID: usize = 20;
}

pub type RTCErrorFunction = unsafe extern "C" fn(*mut c_void, c_int, *const c_char);
pub type RTCBoundsFunction = unsafe extern "C" fn(*const RTCBoundsFunctionArguments);
pub type RTCIntersectFunctionN = unsafe extern "C" fn(*const RTCIntersectFunctionNArguments);
pub type RTCOccludedFunctionN = unsafe extern "C" fn(*const RTCOccludedFunctionNArguments);

// Compile-time checks of the 4.4 layouts (sizes from the research probe: RTCRayHit 96 B,
// RTCRayHit16 1344 B).
const _: () = {
    assert!(size_of::<RTCRay>() == 48 && align_of::<RTCRay>() == 16);
    assert!(size_of::<RTCHit>() == 48 && align_of::<RTCHit>() == 16);
    assert!(offset_of!(RTCHit, prim_id) == 20 && offset_of!(RTCHit, inst_prim_id) == 32);
    assert!(size_of::<RTCRayHit>() == 96 && offset_of!(RTCRayHit, hit) == 48);
    assert!(offset_of!(RTCRay, tfar) == 4 * word::TFAR);
    assert!(size_of::<RTCRay16>() == 768 && size_of::<RTCHit16>() == 576);
    assert!(size_of::<RTCRayHit16>() == 1344 && align_of::<RTCRayHit16>() == 64);
    assert!(offset_of!(RTCRayHit16, hit) == 768);
    assert!(
        offset_of!(RTCHit16, prim_id) == 5 * 64 && offset_of!(RTCHit16, inst_prim_id) == 8 * 64
    );
    assert!(size_of::<Valid16>() == 64 && align_of::<Valid16>() == 64);
    assert!(offset_of!(RTCQueryArguments, context) == 8);
    assert!(offset_of!(RTCQueryArguments, intersect) == 24);
    assert!(size_of::<RTCBounds>() == 32);
    assert!(offset_of!(RTCIntersectFunctionNArguments, rayhit) == 32);
    assert!(offset_of!(RTCIntersectFunctionNArguments, n) == 40);
    assert!(offset_of!(RTCIntersectFunctionNArguments, geom_id) == 44);
    assert!(offset_of!(RTCBoundsFunctionArguments, bounds_o) == 16);
};

#[link(name = "embree4")]
unsafe extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceProperty(device: RTCDevice, prop: c_int) -> isize;
    pub fn rtcGetDeviceError(device: RTCDevice) -> c_int;
    pub fn rtcSetDeviceErrorFunction(
        device: RTCDevice,
        f: Option<RTCErrorFunction>,
        user: *mut c_void,
    );

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: c_int);
    pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    pub fn rtcCommitScene(scene: RTCScene);

    pub fn rtcNewGeometry(device: RTCDevice, ty: c_int) -> RTCGeometry;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        ty: c_int,
        slot: c_uint,
        format: c_int,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;
    pub fn rtcSetGeometryUserPrimitiveCount(geometry: RTCGeometry, count: c_uint);
    pub fn rtcSetGeometryUserData(geometry: RTCGeometry, ptr: *mut c_void);
    pub fn rtcSetGeometryBoundsFunction(
        geometry: RTCGeometry,
        f: Option<RTCBoundsFunction>,
        user: *mut c_void,
    );
    pub fn rtcSetGeometryIntersectFunction(geometry: RTCGeometry, f: Option<RTCIntersectFunctionN>);
    pub fn rtcSetGeometryOccludedFunction(geometry: RTCGeometry, f: Option<RTCOccludedFunctionN>);

    pub fn rtcIntersect1(scene: RTCScene, rayhit: *mut RTCRayHit, args: *const RTCQueryArguments);
    pub fn rtcOccluded1(scene: RTCScene, ray: *mut RTCRay, args: *const RTCQueryArguments);
    pub fn rtcIntersect16(
        valid: *const Valid16,
        scene: RTCScene,
        rayhit: *mut RTCRayHit16,
        args: *const RTCQueryArguments,
    );
    pub fn rtcOccluded16(
        valid: *const Valid16,
        scene: RTCScene,
        ray: *mut RTCRay16,
        args: *const RTCQueryArguments,
    );
}
