//! A minimal hand-written FFI to the Embree 3 C API (3.13, `libembree3.so`): only what a
//! triangle-mesh closest-hit / any-hit baseline needs.
//!
//! Layouts are copied from `/usr/include/embree3/rtcore_{common,device,scene,geometry,ray}.h`
//! of Embree 3.13.5, whose `rtcore_config.h` sets `RTC_MAX_INSTANCE_LEVEL_COUNT = 1` and
//! `RTC_MIN_WIDTH = 0` (both change [`RTCIntersectContext`] and the hit structures). The unit
//! tests at the bottom pin sizes and offsets to the C layout.

#![allow(non_camel_case_types, non_snake_case, dead_code)]

use std::ffi::{c_char, c_int, c_uint, c_void};

/// `RTC_MAX_INSTANCE_LEVEL_COUNT` of the installed build.
pub const RTC_MAX_INSTANCE_LEVEL_COUNT: usize = 1;
/// `RTC_INVALID_GEOMETRY_ID`: `geomID` of a ray that hit nothing.
pub const RTC_INVALID_GEOMETRY_ID: c_uint = u32::MAX;

#[repr(C)]
pub struct RTCDeviceTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCSceneTy {
    _private: [u8; 0],
}
#[repr(C)]
pub struct RTCGeometryTy {
    _private: [u8; 0],
}
pub type RTCDevice = *mut RTCDeviceTy;
pub type RTCScene = *mut RTCSceneTy;
pub type RTCGeometry = *mut RTCGeometryTy;

// C enums are `int`-sized; they are passed as plain integers.
pub type RTCError = c_int;
pub const RTC_ERROR_NONE: RTCError = 0;

pub type RTCDeviceProperty = c_int;
pub const RTC_DEVICE_PROPERTY_VERSION: RTCDeviceProperty = 0;
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY4_SUPPORTED: RTCDeviceProperty = 32;
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED: RTCDeviceProperty = 33;
pub const RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED: RTCDeviceProperty = 34;

pub type RTCBuildQuality = c_int;
pub const RTC_BUILD_QUALITY_LOW: RTCBuildQuality = 0;
pub const RTC_BUILD_QUALITY_MEDIUM: RTCBuildQuality = 1;
pub const RTC_BUILD_QUALITY_HIGH: RTCBuildQuality = 2;

pub type RTCSceneFlags = c_int;
pub const RTC_SCENE_FLAG_NONE: RTCSceneFlags = 0;
pub const RTC_SCENE_FLAG_COMPACT: RTCSceneFlags = 1 << 1;
pub const RTC_SCENE_FLAG_ROBUST: RTCSceneFlags = 1 << 2;

pub type RTCGeometryType = c_int;
pub const RTC_GEOMETRY_TYPE_TRIANGLE: RTCGeometryType = 0;

pub type RTCBufferType = c_int;
pub const RTC_BUFFER_TYPE_INDEX: RTCBufferType = 0;
pub const RTC_BUFFER_TYPE_VERTEX: RTCBufferType = 1;

pub type RTCFormat = c_int;
pub const RTC_FORMAT_UINT3: RTCFormat = 0x5003;
pub const RTC_FORMAT_FLOAT3: RTCFormat = 0x9003;

pub type RTCIntersectContextFlags = c_int;
pub const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: RTCIntersectContextFlags = 0;
pub const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: RTCIntersectContextFlags = 1;

/// `RTCFilterFunctionN`; always null here.
pub type RTCFilterFunctionN = Option<unsafe extern "C" fn(args: *const c_void)>;

/// `struct RTCIntersectContext` (no `instStackSize`, no `minWidthDistanceFactor` in this build).
#[repr(C)]
#[derive(Clone, Copy, Debug)]
pub struct RTCIntersectContext {
    pub flags: RTCIntersectContextFlags,
    pub filter: RTCFilterFunctionN,
    pub instID: [c_uint; RTC_MAX_INSTANCE_LEVEL_COUNT],
}

impl RTCIntersectContext {
    /// `rtcInitIntersectContext` (an inline function of `rtcore_common.h`), with the flags given.
    pub fn new(flags: RTCIntersectContextFlags) -> Self {
        Self {
            flags,
            filter: None,
            instID: [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT],
        }
    }
}

/// `struct RTCRay` (16-byte aligned).
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
    pub mask: c_uint,
    pub id: c_uint,
    pub flags: c_uint,
}

/// `struct RTCHit` (16-byte aligned).
#[repr(C, align(16))]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCHit {
    pub Ng_x: f32,
    pub Ng_y: f32,
    pub Ng_z: f32,
    pub u: f32,
    pub v: f32,
    pub primID: c_uint,
    pub geomID: c_uint,
    pub instID: [c_uint; RTC_MAX_INSTANCE_LEVEL_COUNT],
}

/// `struct RTCRayHit`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default)]
pub struct RTCRayHit {
    pub ray: RTCRay,
    pub hit: RTCHit,
}

/// Declares the SoA packet structs `RTCRay{N}`, `RTCHit{N}`, `RTCRayHit{N}` (aligned to
/// `4 * N` bytes, as `RTC_ALIGN(16/32/64)` in `rtcore_ray.h`).
macro_rules! packet_types {
    ($n:literal, $align:literal, $ray:ident, $hit:ident, $rayhit:ident) => {
        #[repr(C, align($align))]
        #[derive(Clone, Copy, Debug)]
        pub struct $ray {
            pub org_x: [f32; $n],
            pub org_y: [f32; $n],
            pub org_z: [f32; $n],
            pub tnear: [f32; $n],
            pub dir_x: [f32; $n],
            pub dir_y: [f32; $n],
            pub dir_z: [f32; $n],
            pub time: [f32; $n],
            pub tfar: [f32; $n],
            pub mask: [c_uint; $n],
            pub id: [c_uint; $n],
            pub flags: [c_uint; $n],
        }

        #[repr(C, align($align))]
        #[derive(Clone, Copy, Debug)]
        pub struct $hit {
            pub Ng_x: [f32; $n],
            pub Ng_y: [f32; $n],
            pub Ng_z: [f32; $n],
            pub u: [f32; $n],
            pub v: [f32; $n],
            pub primID: [c_uint; $n],
            pub geomID: [c_uint; $n],
            pub instID: [[c_uint; $n]; RTC_MAX_INSTANCE_LEVEL_COUNT],
        }

        #[repr(C)]
        #[derive(Clone, Copy, Debug)]
        pub struct $rayhit {
            pub ray: $ray,
            pub hit: $hit,
        }

        impl Default for $rayhit {
            fn default() -> Self {
                // SAFETY: all fields are plain integers / floats, for which all-zero is valid.
                unsafe { std::mem::zeroed() }
            }
        }
    };
}

packet_types!(8, 32, RTCRay8, RTCHit8, RTCRayHit8);
packet_types!(16, 64, RTCRay16, RTCHit16, RTCRayHit16);

#[link(name = "embree3")]
unsafe extern "C" {
    pub fn rtcNewDevice(config: *const c_char) -> RTCDevice;
    pub fn rtcReleaseDevice(device: RTCDevice);
    pub fn rtcGetDeviceError(device: RTCDevice) -> RTCError;
    pub fn rtcGetDeviceProperty(device: RTCDevice, prop: RTCDeviceProperty) -> isize;

    pub fn rtcNewScene(device: RTCDevice) -> RTCScene;
    pub fn rtcReleaseScene(scene: RTCScene);
    pub fn rtcSetSceneBuildQuality(scene: RTCScene, quality: RTCBuildQuality);
    pub fn rtcSetSceneFlags(scene: RTCScene, flags: RTCSceneFlags);
    pub fn rtcAttachGeometry(scene: RTCScene, geometry: RTCGeometry) -> c_uint;
    pub fn rtcCommitScene(scene: RTCScene);

    pub fn rtcNewGeometry(device: RTCDevice, ty: RTCGeometryType) -> RTCGeometry;
    pub fn rtcReleaseGeometry(geometry: RTCGeometry);
    pub fn rtcCommitGeometry(geometry: RTCGeometry);
    pub fn rtcSetGeometryBuildQuality(geometry: RTCGeometry, quality: RTCBuildQuality);
    pub fn rtcSetNewGeometryBuffer(
        geometry: RTCGeometry,
        ty: RTCBufferType,
        slot: c_uint,
        format: RTCFormat,
        byte_stride: usize,
        item_count: usize,
    ) -> *mut c_void;

    pub fn rtcIntersect1(
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit,
    );
    pub fn rtcOccluded1(scene: RTCScene, context: *mut RTCIntersectContext, ray: *mut RTCRay);
    pub fn rtcIntersect8(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit8,
    );
    pub fn rtcIntersect16(
        valid: *const c_int,
        scene: RTCScene,
        context: *mut RTCIntersectContext,
        rayhit: *mut RTCRayHit16,
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, offset_of, size_of};

    /// Sizes, alignments and offsets that the C compiler gives these structs (computed by hand
    /// from the headers: 12 four-byte ray fields, 8 hit fields, instID of one level).
    #[test]
    fn layouts_match_the_c_headers() {
        assert_eq!(size_of::<RTCIntersectContext>(), 24);
        assert_eq!(offset_of!(RTCIntersectContext, filter), 8);
        assert_eq!(offset_of!(RTCIntersectContext, instID), 16);
        assert_eq!((size_of::<RTCRay>(), align_of::<RTCRay>()), (48, 16));
        assert_eq!((size_of::<RTCHit>(), align_of::<RTCHit>()), (32, 16));
        assert_eq!(size_of::<RTCRayHit>(), 80);
        assert_eq!(offset_of!(RTCRayHit, hit), 48);
        assert_eq!(offset_of!(RTCHit, primID), 20);
        assert_eq!((size_of::<RTCRay8>(), align_of::<RTCRay8>()), (384, 32));
        assert_eq!((size_of::<RTCHit8>(), align_of::<RTCHit8>()), (256, 32));
        assert_eq!(offset_of!(RTCRayHit8, hit), 384);
        assert_eq!(offset_of!(RTCRay8, tfar), 8 * 32);
        assert_eq!((size_of::<RTCRay16>(), align_of::<RTCRay16>()), (768, 64));
        assert_eq!((size_of::<RTCHit16>(), align_of::<RTCHit16>()), (512, 64));
        assert_eq!(offset_of!(RTCRayHit16, hit), 768);
        assert_eq!(offset_of!(RTCHit16, geomID), 6 * 64);
    }
}
