//! The Embree scene through the `embree3` bindings (built with the `embree` feature).

use embree3::{
    BufferUsage, BuildQuality, Device, DeviceProperty, Format, GeometryKind, Hit8, Hit16,
    IntersectContext, Ray8, Ray16, RayHit, RayHit8, RayHit16, Scene, SceneFlags, ValidMask,
    ValidMaskN,
};
use parallax_core::Ray;
use parallax_scene::TriangleMesh;

use crate::mxcsr::FastFloats;
use crate::{EmbreeError, EmbreeHit, Options, Quality};

/// Rays handed to one `rtcIntersect1M` call (a stack buffer of this many `RTCRayHit`s).
const STREAM_CHUNK: usize = 256;

/// Writes the rays of `p` into the lanes of SoA packet `rh` and marks them valid.
macro_rules! fill {
    ($rh:expr, $valid:expr, $p:expr) => {
        for (i, r) in $p.iter().enumerate() {
            $rh.ray.org_x[i] = r.origin.x;
            $rh.ray.org_y[i] = r.origin.y;
            $rh.ray.org_z[i] = r.origin.z;
            $rh.ray.tnear[i] = r.t_min;
            $rh.ray.dir_x[i] = r.dir.x;
            $rh.ray.dir_y[i] = r.dir.y;
            $rh.ray.dir_z[i] = r.dir.z;
            $rh.ray.tfar[i] = r.t_max;
            $rh.ray.mask[i] = u32::MAX;
            $rh.ray.flags[i] = 0;
            $rh.ray.time[i] = 0.0;
            $rh.hit.geomID[i] = embree3::INVALID_ID;
            $rh.hit.primID[i] = embree3::INVALID_ID;
            $valid.lanes_mut()[i] = ValidMask::Valid;
        }
    };
}

/// Reads the hits of SoA packet `rh` into `o` (one entry per lane of `o`).
macro_rules! read {
    ($rh:expr, $o:expr) => {
        for (i, o) in $o.iter_mut().enumerate() {
            *o = ($rh.hit.geomID[i] != embree3::INVALID_ID).then_some(EmbreeHit {
                prim: $rh.hit.primID[i],
                t: $rh.ray.tfar[i],
                u: $rh.hit.u[i],
                v: $rh.hit.v[i],
            });
        }
    };
}

/// A committed Embree scene of one triangle geometry (id 0), primitive ids = triangle indices.
pub struct EmbreeScene {
    scene: Scene<'static>,
    native: [bool; 3],
}

fn err(call: &'static str, code: embree3::Error) -> EmbreeError {
    EmbreeError::Call {
        call,
        code: format!("{code:?}"),
    }
}

impl EmbreeScene {
    /// Creates a device, copies `mesh` into Embree-owned buffers and commits (builds) the BVH
    /// with `opts`. The build's wall time is the caller's to measure around this call.
    pub fn new(mesh: &TriangleMesh, opts: Options) -> Result<Self, EmbreeError> {
        crate::validate(mesh)?;
        let device = Device::new().map_err(|e| err("rtcNewDevice", e))?;
        let prop = |p| device.get_property(p).map(|v| v != 0).unwrap_or(false);
        let native = [
            prop(DeviceProperty::NATIVE_RAY4_SUPPORTED),
            prop(DeviceProperty::NATIVE_RAY8_SUPPORTED),
            prop(DeviceProperty::NATIVE_RAY16_SUPPORTED),
        ];
        let flags = if opts.robust {
            SceneFlags::ROBUST
        } else {
            SceneFlags::NONE
        };
        let mut scene = device.create_scene().map_err(|e| err("rtcNewScene", e))?;
        scene.set_flags(flags);
        let quality = match opts.quality {
            Quality::Low => BuildQuality::LOW,
            Quality::Medium => BuildQuality::MEDIUM,
            Quality::High => BuildQuality::HIGH,
        };
        scene.set_build_quality(quality);
        let (nv, nt) = (mesh.positions.len(), mesh.indices.len());
        if nt > 0 {
            let mut geom = device
                .create_geometry(GeometryKind::TRIANGLE)
                .map_err(|e| err("rtcNewGeometry", e))?;
            geom.set_build_quality(quality);
            // FLOAT3 with a 16-byte stride: Embree reads vertices with 16-byte loads.
            let mut vb = geom
                .set_new_buffer::<[f32; 4]>(BufferUsage::VERTEX, 0, Format::FLOAT3, 16, nv)
                .map_err(|e| err("rtcSetNewGeometryBuffer(vertex)", e))?;
            for (v, p) in vb.iter_mut().zip(&mesh.positions) {
                *v = [p.x, p.y, p.z, 0.0];
            }
            geom.set_new_buffer::<[u32; 3]>(BufferUsage::INDEX, 0, Format::UINT3, 12, nt)
                .map_err(|e| err("rtcSetNewGeometryBuffer(index)", e))?
                .copy_from_slice(&mesh.indices);
            let geom = geom.commit();
            scene.attach_geometry(&geom);
        }
        scene.commit();
        match scene.device().get_error() {
            embree3::Error::NONE => Ok(Self { scene, native }),
            e => Err(err("rtcCommitScene", e)),
        }
    }

    /// Whether the device has native 4-, 8- and 16-wide packet kernels (SSE / AVX2 / AVX-512).
    pub fn native_packets(&self) -> [bool; 3] {
        self.native
    }

    /// Closest hits of single rays, one `rtcIntersect1` each (incoherent context):
    /// `out[i]` answers `rays[i]`. Panics if `out` is shorter than `rays`.
    pub fn closest_hits(&self, rays: &[Ray], out: &mut [Option<EmbreeHit>]) {
        assert!(out.len() >= rays.len());
        let _ftz = FastFloats::new();
        let mut ctx = IntersectContext::incoherent();
        for (r, o) in rays.iter().zip(out) {
            let mut rh = RayHit::from_ray(to_rtc(r));
            self.scene.intersect(&mut ctx, &mut rh);
            *o = (rh.hit.geomID != embree3::INVALID_ID).then_some(EmbreeHit {
                prim: rh.hit.primID,
                t: rh.ray.tfar,
                u: rh.hit.u,
                v: rh.hit.v,
            });
        }
    }

    /// Whether anything blocks each ray within its segment (`rtcOccluded1`).
    pub fn occluded(&self, rays: &[Ray], out: &mut [bool]) {
        assert!(out.len() >= rays.len());
        let _ftz = FastFloats::new();
        let mut ctx = IntersectContext::incoherent();
        for (r, o) in rays.iter().zip(out) {
            let mut ray = to_rtc(r);
            *o = self.scene.occluded(&mut ctx, &mut ray);
        }
    }

    /// Closest hits of `rays` as packets of `width` (8 or 16) consecutive rays, one
    /// `rtcIntersect8` / `rtcIntersect16` call per packet (coherent context; the last packet
    /// may be partial, its unused lanes invalid). Panics on another width or a short `out`.
    pub fn closest_hit_packets(&self, rays: &[Ray], width: usize, out: &mut [Option<EmbreeHit>]) {
        assert!(out.len() >= rays.len());
        let _ftz = FastFloats::new();
        let mut ctx = IntersectContext::coherent();
        match width {
            8 => {
                for (p, o) in rays.chunks(8).zip(out.chunks_mut(8)) {
                    let mut rh = RayHit8 {
                        ray: Ray8::default(),
                        hit: Hit8::default(),
                    };
                    let mut valid = ValidMaskN::<8>::new([ValidMask::Invalid; 8]);
                    fill!(rh, valid, p);
                    self.scene.intersect8(&mut ctx, &mut rh, &valid);
                    read!(rh, o);
                }
            }
            16 => {
                for (p, o) in rays.chunks(16).zip(out.chunks_mut(16)) {
                    let mut rh = RayHit16 {
                        ray: Ray16::default(),
                        hit: Hit16::default(),
                    };
                    let mut valid = ValidMaskN::<16>::new([ValidMask::Invalid; 16]);
                    fill!(rh, valid, p);
                    self.scene.intersect16(&mut ctx, &mut rh, &valid);
                    read!(rh, o);
                }
            }
            w => panic!("closest_hit_packets: width {w} (8 or 16)"),
        }
    }

    /// Closest hits of `rays` as ray streams (`rtcIntersect1M`, chunks of 256 rays from a
    /// stack buffer), with the coherent or incoherent context flag (Embree regroups the stream
    /// into packets internally).
    pub fn closest_hit_stream(&self, rays: &[Ray], coherent: bool, out: &mut [Option<EmbreeHit>]) {
        assert!(out.len() >= rays.len());
        let _ftz = FastFloats::new();
        let mut ctx = if coherent {
            IntersectContext::coherent()
        } else {
            IntersectContext::incoherent()
        };
        let mut buf = [RayHit::default(); STREAM_CHUNK];
        for (c, o) in rays.chunks(STREAM_CHUNK).zip(out.chunks_mut(STREAM_CHUNK)) {
            for (b, r) in buf.iter_mut().zip(c) {
                *b = RayHit::from_ray(to_rtc(r));
            }
            // SAFETY: `buf[..c.len()]` are initialised, 16-byte aligned `RTCRayHit`s with the
            // stride given; the scene is committed and outlives the call.
            unsafe {
                embree3::sys::rtcIntersect1M(
                    self.scene.handle(),
                    &mut ctx,
                    buf.as_mut_ptr(),
                    c.len() as u32,
                    size_of::<RayHit>(),
                );
            }
            for (o, rh) in o.iter_mut().zip(&buf) {
                *o = (rh.hit.geomID != embree3::INVALID_ID).then_some(EmbreeHit {
                    prim: rh.hit.primID,
                    t: rh.ray.tfar,
                    u: rh.hit.u,
                    v: rh.hit.v,
                });
            }
        }
    }
}

#[inline(always)]
fn to_rtc(r: &Ray) -> embree3::Ray {
    embree3::Ray::segment(r.origin.to_array(), r.dir.to_array(), r.t_min, r.t_max)
}
