//! A safe wrapper over one Embree 3 device + scene holding a parallax [`TriangleMesh`]:
//! closest-hit and occlusion queries for single rays and 8/16-wide SoA packets.

use std::ffi::c_int;
use std::ptr;

use parallax_core::Ray;
use parallax_scene::TriangleMesh;

use crate::ffi::*;

/// Writes ray `r` into lane `i` of an SoA packet `p` (any width) and clears its hit.
macro_rules! set_lane {
    ($p:expr, $i:expr, $r:expr) => {{
        let (i, r) = ($i, $r);
        $p.ray.org_x[i] = r.origin.x;
        $p.ray.org_y[i] = r.origin.y;
        $p.ray.org_z[i] = r.origin.z;
        $p.ray.tnear[i] = r.t_min;
        $p.ray.dir_x[i] = r.dir.x;
        $p.ray.dir_y[i] = r.dir.y;
        $p.ray.dir_z[i] = r.dir.z;
        $p.ray.tfar[i] = r.t_max;
        $p.ray.mask[i] = u32::MAX;
        $p.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
        $p.hit.primID[i] = RTC_INVALID_GEOMETRY_ID;
    }};
}

/// Largest packet [`EmbreeScene::closest_hit_packet`] takes.
pub const MAX_PACKET: usize = 16;

/// A closest hit: (triangle index, ray parameter t).
pub type PrimHit = (u32, f32);

/// What went wrong talking to Embree.
#[derive(Debug, thiserror::Error)]
pub enum EmbreeError {
    #[error("Embree call {call} failed with RTCError {code}")]
    Call { call: &'static str, code: i32 },
    #[error("triangle {triangle} indexes vertex {index}, but the mesh has {vertices} vertices")]
    BadIndex {
        triangle: usize,
        index: u32,
        vertices: usize,
    },
    #[error("mesh too large for Embree's 32-bit primitive ids: {0} triangles")]
    TooLarge(usize),
}

/// Embree's BVH build quality (`RTCBuildQuality`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Quality {
    Low,
    /// Embree's default: binned SAH.
    #[default]
    Medium,
    /// Binned SAH with spatial splits (SBVH).
    High,
}

/// Scene build options.
#[derive(Clone, Copy, Debug, Default)]
pub struct BuildOptions {
    pub quality: Quality,
    /// `RTC_SCENE_FLAG_ROBUST`: watertight-leaning traversal and intersection, a bit slower.
    pub robust: bool,
}

/// A committed Embree scene of one triangle geometry (id 0), primitive ids = triangle indices.
pub struct EmbreeScene {
    device: RTCDevice,
    scene: RTCScene,
    native8: bool,
    native16: bool,
}

// SAFETY: a committed Embree scene may be queried from any number of threads at once
// (Embree 3 API docs, "Thread safety"); the handles are only released in Drop.
unsafe impl Send for EmbreeScene {}
unsafe impl Sync for EmbreeScene {}

fn check(device: RTCDevice, call: &'static str) -> Result<(), EmbreeError> {
    // SAFETY: rtcGetDeviceError accepts any device handle, including null (thread error).
    let code = unsafe { rtcGetDeviceError(device) };
    if code == RTC_ERROR_NONE {
        Ok(())
    } else {
        Err(EmbreeError::Call { call, code })
    }
}

impl EmbreeScene {
    /// Builds a scene with default options (medium quality, no robust flag).
    pub fn new(mesh: &TriangleMesh) -> Result<Self, EmbreeError> {
        Self::with_options(mesh, BuildOptions::default())
    }

    /// Creates a device, copies `mesh` into Embree-owned buffers and commits (builds) the BVH.
    pub fn with_options(mesh: &TriangleMesh, opts: BuildOptions) -> Result<Self, EmbreeError> {
        let nv = mesh.positions.len();
        let nt = mesh.indices.len();
        if nt > u32::MAX as usize / 2 || nv > u32::MAX as usize / 2 {
            return Err(EmbreeError::TooLarge(nt));
        }
        for (triangle, tri) in mesh.indices.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= nv) {
                return Err(EmbreeError::BadIndex {
                    triangle,
                    index,
                    vertices: nv,
                });
            }
        }
        // SAFETY: a valid NUL-terminated (empty: defaults) config string.
        let device = unsafe { rtcNewDevice(c"".as_ptr()) };
        if device.is_null() {
            check(ptr::null_mut(), "rtcNewDevice")?;
            return Err(EmbreeError::Call {
                call: "rtcNewDevice",
                code: -1,
            });
        }
        // From here on `out` owns the handles, so every early return releases them.
        let mut out = EmbreeScene {
            device,
            scene: ptr::null_mut(),
            native8: false,
            native16: false,
        };
        // SAFETY: `device` is a live device; every handle created below is checked before use,
        // buffers are written strictly within the item counts given to Embree.
        unsafe {
            out.native8 =
                rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
            out.native16 =
                rtcGetDeviceProperty(device, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
            out.scene = rtcNewScene(device);
            check(device, "rtcNewScene")?;
            let quality = match opts.quality {
                Quality::Low => RTC_BUILD_QUALITY_LOW,
                Quality::Medium => RTC_BUILD_QUALITY_MEDIUM,
                Quality::High => RTC_BUILD_QUALITY_HIGH,
            };
            rtcSetSceneBuildQuality(out.scene, quality);
            let flags = if opts.robust {
                RTC_SCENE_FLAG_ROBUST
            } else {
                RTC_SCENE_FLAG_NONE
            };
            rtcSetSceneFlags(out.scene, flags);
            if nt > 0 {
                let geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
                check(device, "rtcNewGeometry")?;
                let res = fill_geometry(device, geom, mesh, quality);
                if res.is_ok() {
                    rtcAttachGeometry(out.scene, geom);
                }
                // The scene keeps its own reference.
                rtcReleaseGeometry(geom);
                res?;
                check(device, "rtcAttachGeometry")?;
            }
            rtcCommitScene(out.scene);
            check(device, "rtcCommitScene")?;
        }
        Ok(out)
    }

    /// Whether the device has native 8- / 16-wide packet kernels (AVX2 / AVX-512 builds).
    pub fn native_packets(&self) -> (bool, bool) {
        (self.native8, self.native16)
    }

    /// The widest native packet width (16, 8, or 1 when only single rays are native).
    pub fn packet_width(&self) -> usize {
        if self.native16 {
            16
        } else if self.native8 {
            8
        } else {
            1
        }
    }

    /// Closest hit of one ray (`rtcIntersect1`, incoherent context).
    #[inline]
    pub fn closest_hit(&self, ray: &Ray) -> Option<PrimHit> {
        let mut rh = RTCRayHit {
            ray: to_rtc_ray(ray),
            hit: RTCHit {
                geomID: RTC_INVALID_GEOMETRY_ID,
                primID: RTC_INVALID_GEOMETRY_ID,
                instID: [RTC_INVALID_GEOMETRY_ID; RTC_MAX_INSTANCE_LEVEL_COUNT],
                ..Default::default()
            },
        };
        let mut ctx = RTCIntersectContext::new(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: committed scene, properly aligned stack structs.
        unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
        (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID).then_some((rh.hit.primID, rh.ray.tfar))
    }

    /// Whether anything blocks the ray within its segment (`rtcOccluded1`).
    #[inline]
    pub fn occluded(&self, ray: &Ray) -> bool {
        let mut r = to_rtc_ray(ray);
        let mut ctx = RTCIntersectContext::new(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        // SAFETY: committed scene, properly aligned stack struct.
        unsafe { rtcOccluded1(self.scene, &mut ctx, &mut r) };
        // Embree sets tfar to -inf for an occluded ray.
        r.tfar < 0.0 && ray.t_max >= 0.0
    }

    /// Closest hits of up to [`MAX_PACKET`] rays, traced as one packet of the widest native
    /// width (one 16-wide call, or 8-wide calls); lane `i` of the result answers `rays[i]`,
    /// lanes past `rays.len()` are `None`. Uses the coherent context flag: meant for rays of
    /// neighbouring pixels. Panics if `rays.len() > MAX_PACKET`.
    pub fn closest_hit_packet(&self, rays: &[Ray]) -> [Option<PrimHit>; MAX_PACKET] {
        assert!(rays.len() <= MAX_PACKET, "packet of {} rays", rays.len());
        let mut out = [None; MAX_PACKET];
        if self.native16 || !self.native8 && rays.len() > 8 {
            self.closest_hit_packet16(rays, &mut out);
        } else {
            for (chunk, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                self.closest_hit_packet8(chunk, o);
            }
        }
        out
    }

    /// One `rtcIntersect8` call over `rays` (at most 8), results into `out[..rays.len()]`.
    pub fn closest_hit_packet8(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        assert!(rays.len() <= 8 && out.len() >= rays.len());
        let mut p = RTCRayHit8::default();
        let mut valid = [0 as c_int; 8];
        for (i, r) in rays.iter().enumerate() {
            set_lane!(p, i, r);
            valid[i] = -1;
        }
        let mut ctx = RTCIntersectContext::new(RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
        // SAFETY: `p` is 32-byte aligned (repr align), `valid` has 8 lanes, committed scene.
        unsafe { rtcIntersect8(valid.as_ptr(), self.scene, &mut ctx, &mut p) };
        for (i, o) in out.iter_mut().take(rays.len()).enumerate() {
            *o = (p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
                .then_some((p.hit.primID[i], p.ray.tfar[i]));
        }
    }

    /// One `rtcIntersect16` call over `rays` (at most 16), results into `out[..rays.len()]`.
    pub fn closest_hit_packet16(&self, rays: &[Ray], out: &mut [Option<PrimHit>]) {
        assert!(rays.len() <= 16 && out.len() >= rays.len());
        let mut p = RTCRayHit16::default();
        let mut valid = [0 as c_int; 16];
        for (i, r) in rays.iter().enumerate() {
            set_lane!(p, i, r);
            valid[i] = -1;
        }
        let mut ctx = RTCIntersectContext::new(RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
        // SAFETY: `p` is 64-byte aligned (repr align), `valid` has 16 lanes, committed scene.
        unsafe { rtcIntersect16(valid.as_ptr(), self.scene, &mut ctx, &mut p) };
        for (i, o) in out.iter_mut().take(rays.len()).enumerate() {
            *o = (p.hit.geomID[i] != RTC_INVALID_GEOMETRY_ID)
                .then_some((p.hit.primID[i], p.ray.tfar[i]));
        }
    }
}

#[inline]
fn to_rtc_ray(r: &Ray) -> RTCRay {
    RTCRay {
        org_x: r.origin.x,
        org_y: r.origin.y,
        org_z: r.origin.z,
        tnear: r.t_min,
        dir_x: r.dir.x,
        dir_y: r.dir.y,
        dir_z: r.dir.z,
        time: 0.0,
        tfar: r.t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// Copies positions (FLOAT3, 16-byte stride: Embree reads vertices with 16-byte loads) and
/// indices (UINT3) into buffers Embree allocates (with the tail padding it needs), commits.
///
/// # Safety
/// `device` and `geom` are live handles; indices of `mesh` were checked to be in range.
unsafe fn fill_geometry(
    device: RTCDevice,
    geom: RTCGeometry,
    mesh: &TriangleMesh,
    quality: RTCBuildQuality,
) -> Result<(), EmbreeError> {
    let (nv, nt) = (mesh.positions.len(), mesh.indices.len());
    unsafe {
        rtcSetGeometryBuildQuality(geom, quality);
        let vb = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 16, nv)
            as *mut [f32; 4];
        check(device, "rtcSetNewGeometryBuffer(vertex)")?;
        if vb.is_null() && nv > 0 {
            return Err(EmbreeError::Call {
                call: "rtcSetNewGeometryBuffer(vertex)",
                code: -1,
            });
        }
        let verts = std::slice::from_raw_parts_mut(vb, nv);
        for (v, p) in verts.iter_mut().zip(&mesh.positions) {
            *v = [p.x, p.y, p.z, 0.0];
        }
        let ib = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, nt)
            as *mut [u32; 3];
        check(device, "rtcSetNewGeometryBuffer(index)")?;
        if ib.is_null() {
            return Err(EmbreeError::Call {
                call: "rtcSetNewGeometryBuffer(index)",
                code: -1,
            });
        }
        std::slice::from_raw_parts_mut(ib, nt).copy_from_slice(&mesh.indices);
        rtcCommitGeometry(geom);
        check(device, "rtcCommitGeometry")
    }
}

impl Drop for EmbreeScene {
    fn drop(&mut self) {
        // SAFETY: handles created in `with_options`, released exactly once.
        unsafe {
            if !self.scene.is_null() {
                rtcReleaseScene(self.scene);
            }
            rtcReleaseDevice(self.device);
        }
    }
}
