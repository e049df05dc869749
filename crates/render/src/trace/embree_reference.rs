//! The pre-tessellated reference traced by Embree 3 (the `embree` feature): the same
//! microtriangles as [`Tessellated`], in single precision (Embree's), in one triangle mesh of
//! a scene built at Embree's default quality, one ray at a time (`rtcIntersect1`, incoherent
//! context), so that the report compares against what users of displacement mapping pick today.
//! Its memory is what Embree reports allocating through its memory-monitor callback (BVH and
//! buffers). Embree picks its widest kernels for the CPU unless told otherwise; [`Isa::Build`]
//! pins them to the instruction set this binary is compiled for, so that a comparison with
//! nlrt's kernels is at one vector width.

use std::sync::atomic::{AtomicIsize, Ordering};

use embree::sys;
use nlrt_poly::glam::DVec3;

use crate::scene::scenes::Scene;
use crate::trace::tessellate::Tessellated;
use crate::trace::tracer::{TraceHit, Tracer};

/// An Embree device and committed scene holding a scene's tessellation.
pub struct EmbreeTessellated {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    base: Vec<u32>,
    allocated: MemoryCounter,
}

// SAFETY: a committed Embree scene is immutable and Embree documents `rtcIntersect1` on it as
// safe from any number of threads; the handles are only released in `drop`.
unsafe impl Send for EmbreeTessellated {}
// SAFETY: as above.
unsafe impl Sync for EmbreeTessellated {}

unsafe extern "C" fn count_bytes(ptr: *mut std::ffi::c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: `ptr` is the `AtomicIsize` registered below, alive as long as the device.
    let counter = unsafe { &*(ptr as *const AtomicIsize) };
    counter.fetch_add(bytes, Ordering::Relaxed);
    true
}

/// Bytes an Embree device allocated, counted by its memory-monitor callback (boxed: the
/// callback holds its address).
pub(crate) struct MemoryCounter(Box<AtomicIsize>);

impl MemoryCounter {
    /// Bytes allocated and not freed.
    pub(crate) fn bytes(&self) -> usize {
        self.0.load(Ordering::Relaxed).max(0) as usize
    }
}

/// Which kernels Embree may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Isa {
    /// The instruction set of this build (`avx2` when compiled with it, as for x86-64-v3;
    /// else `sse4.2` with it, else `sse2`): Embree's device config `isa=...`.
    Build,
    /// Embree's choice for this CPU (no device config).
    Native,
}

impl Isa {
    /// Embree's device configuration string (NUL-terminated), `None` for its default.
    fn config(self) -> Option<&'static [u8]> {
        match self {
            Isa::Native => None,
            Isa::Build if cfg!(target_feature = "avx2") => Some(b"isa=avx2\0"),
            Isa::Build if cfg!(target_feature = "sse4.2") => Some(b"isa=sse4.2\0"),
            Isa::Build => Some(b"isa=sse2\0"),
        }
    }
}

/// An Embree device with kernels `isa` and its memory counter; `None` when Embree cannot
/// create one (no supported CPU, or the library refuses).
pub(crate) fn new_device(isa: Isa) -> Option<(sys::RTCDevice, MemoryCounter)> {
    let allocated = MemoryCounter(Box::new(AtomicIsize::new(0)));
    // SAFETY: plain calls of Embree's C API; the counter's address stays valid as long as the
    // device (the caller keeps both and releases the device first).
    unsafe {
        let config = isa
            .config()
            .map_or(std::ptr::null(), |c| c.as_ptr().cast::<std::ffi::c_char>());
        let device = sys::rtcNewDevice(config);
        if device.is_null() {
            return None;
        }
        sys::rtcSetDeviceMemoryMonitorFunction(
            device,
            Some(count_bytes),
            &*allocated.0 as *const AtomicIsize as *mut std::ffi::c_void,
        );
        Some((device, allocated))
    }
}

/// A committed Embree triangle geometry of `triangles` (f32, three vertices each), or `None`
/// when Embree cannot allocate its buffers.
///
/// # Safety
/// `device` is a live Embree device.
pub(crate) unsafe fn triangle_geometry(
    device: sys::RTCDevice,
    triangles: &[[DVec3; 3]],
) -> Option<sys::RTCGeometry> {
    // SAFETY: the buffers are written within the sizes requested from Embree.
    unsafe {
        let geometry = sys::rtcNewGeometry(device, sys::RTCGeometryType::TRIANGLE);
        let count = triangles.len();
        let vertices = sys::rtcSetNewGeometryBuffer(
            geometry,
            sys::RTCBufferType::VERTEX,
            0,
            sys::RTCFormat::FLOAT3,
            3 * std::mem::size_of::<f32>(),
            3 * count,
        ) as *mut f32;
        let indices = sys::rtcSetNewGeometryBuffer(
            geometry,
            sys::RTCBufferType::INDEX,
            0,
            sys::RTCFormat::UINT3,
            3 * std::mem::size_of::<u32>(),
            count,
        ) as *mut u32;
        if vertices.is_null() || indices.is_null() {
            sys::rtcReleaseGeometry(geometry);
            return None;
        }
        for (k, tri) in triangles.iter().enumerate() {
            for (c, p) in tri.iter().enumerate() {
                let v = vertices.add(3 * (3 * k + c));
                *v = p.x as f32;
                *v.add(1) = p.y as f32;
                *v.add(2) = p.z as f32;
                *indices.add(3 * k + c) = (3 * k + c) as u32;
            }
        }
        sys::rtcCommitGeometry(geometry);
        Some(geometry)
    }
}

/// A committed Embree scene of the one committed `geometry` (whose reference passes to the
/// scene).
///
/// # Safety
/// `device` is a live Embree device and `geometry` a committed geometry of it.
pub(crate) unsafe fn scene_of(device: sys::RTCDevice, geometry: sys::RTCGeometry) -> sys::RTCScene {
    // SAFETY: the caller's handles are live; the scene takes its own reference.
    unsafe {
        let scene = sys::rtcNewScene(device);
        sys::rtcAttachGeometry(scene, geometry);
        sys::rtcReleaseGeometry(geometry);
        sys::rtcCommitScene(scene);
        scene
    }
}

impl EmbreeTessellated {
    /// Tessellates `scene` and builds the Embree scene with kernels `isa`; `None` when Embree
    /// cannot create a device (no supported CPU, or the library refuses).
    #[must_use]
    pub fn new(scene: &Scene, isa: Isa) -> Option<Self> {
        let tessellated = Tessellated::new(scene);
        let (device, allocated) = new_device(isa)?;
        // SAFETY: plain calls of Embree's C API on handles created here and checked for null.
        unsafe {
            let Some(geometry) = triangle_geometry(device, tessellated.triangles()) else {
                sys::rtcReleaseDevice(device);
                return None;
            };
            Some(Self {
                device,
                scene: scene_of(device, geometry),
                base: tessellated.base_triangles().to_vec(),
                allocated,
            })
        }
    }
}

/// One hit of [`intersect1`].
pub(crate) struct EmbreeHit {
    pub(crate) t: f64,
    /// Unit geometric normal facing the ray.
    pub(crate) normal: DVec3,
    pub(crate) prim_id: u32,
    pub(crate) geom_id: u32,
    /// The hit's coordinates on the primitive (over the whole grid, for grid geometry).
    pub(crate) u: f32,
    pub(crate) v: f32,
}

/// A renderer ray (f64) as Embree's single-precision ray, its range `[t_min, t_max]` (an
/// infinite `t_max` stays infinite).
fn rtc_ray(origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> sys::RTCRay {
    sys::RTCRay {
        org_x: origin.x as f32,
        org_y: origin.y as f32,
        org_z: origin.z as f32,
        tnear: t_min as f32,
        dir_x: dir.x as f32,
        dir_y: dir.y as f32,
        dir_z: dir.z as f32,
        time: 0.0,
        tfar: if t_max.is_finite() {
            t_max as f32
        } else {
            f32::INFINITY
        },
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

/// The nearest hit of one ray in a committed Embree `scene` (`rtcIntersect1`, incoherent).
pub(crate) fn intersect1(
    scene: sys::RTCScene,
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<EmbreeHit> {
    let mut rayhit = sys::RTCRayHit {
        ray: rtc_ray(origin, dir, t_min, t_max),
        hit: sys::RTCHit {
            Ng_x: 0.0,
            Ng_y: 0.0,
            Ng_z: 0.0,
            u: 0.0,
            v: 0.0,
            primID: u32::MAX,
            geomID: u32::MAX,
            instID: [u32::MAX],
        },
    };
    let mut context = embree::IntersectContext::incoherent();
    // SAFETY: the scene is committed and alive; the structures are Embree's own layout.
    unsafe { sys::rtcIntersect1(scene, &mut context, &mut rayhit) };
    if rayhit.hit.geomID == u32::MAX {
        return None;
    }
    let h = &rayhit.hit;
    let n = DVec3::new(f64::from(h.Ng_x), f64::from(h.Ng_y), f64::from(h.Ng_z));
    let n = n.try_normalize()?;
    Some(EmbreeHit {
        t: f64::from(rayhit.ray.tfar),
        normal: if n.dot(dir) > 0.0 { -n } else { n },
        prim_id: h.primID,
        geom_id: h.geomID,
        u: h.u,
        v: h.v,
    })
}

/// Whether anything in a committed Embree `scene` lies on the ray within `(t_min, t_max)`:
/// Embree's any-hit query (`rtcOccluded1`, incoherent), a shadow ray.
pub(crate) fn occluded1(
    scene: sys::RTCScene,
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> bool {
    let mut ray = rtc_ray(origin, dir, t_min, t_max);
    let mut context = embree::IntersectContext::incoherent();
    // SAFETY: the scene is committed and alive; the ray is Embree's own layout.
    unsafe { sys::rtcOccluded1(scene, &mut context, &mut ray) };
    // Embree marks an occluded ray by setting its `tfar` to minus infinity.
    ray.tfar == f32::NEG_INFINITY
}

impl Tracer for EmbreeTessellated {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let hit = intersect1(self.scene, origin, dir, t_min, t_max)?;
        Some(TraceHit {
            t: hit.t,
            normal: hit.normal,
            id: self.base[hit.prim_id as usize],
        })
    }

    fn memory_bytes(&self) -> usize {
        self.allocated.bytes()
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        occluded1(self.scene, origin, dir, t_min, t_max)
    }
}

impl Drop for EmbreeTessellated {
    fn drop(&mut self) {
        // SAFETY: the handles were created in `new` and are released once, scene first.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}

/// A plain Embree scene of world triangles (kernels `isa`): hits carry the triangle's index
/// as [`TraceHit::id`]. The pre-tessellated side of a comparison with
/// [`crate::trace::embree_user::EmbreeWithSurface`].
pub struct EmbreeTriangles {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    allocated: MemoryCounter,
}

// SAFETY: as for `EmbreeTessellated`.
unsafe impl Send for EmbreeTriangles {}
// SAFETY: as above.
unsafe impl Sync for EmbreeTriangles {}

impl EmbreeTriangles {
    /// The scene of `triangles`; `None` when Embree cannot create a device or a buffer.
    #[must_use]
    pub fn new(triangles: &[[DVec3; 3]], isa: Isa) -> Option<Self> {
        let (device, allocated) = new_device(isa)?;
        // SAFETY: plain calls of Embree's C API on handles created here and checked for null.
        unsafe {
            let Some(geometry) = triangle_geometry(device, triangles) else {
                sys::rtcReleaseDevice(device);
                return None;
            };
            Some(Self {
                device,
                scene: scene_of(device, geometry),
                allocated,
            })
        }
    }
}

impl Tracer for EmbreeTriangles {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let hit = intersect1(self.scene, origin, dir, t_min, t_max)?;
        Some(TraceHit {
            t: hit.t,
            normal: hit.normal,
            id: hit.prim_id,
        })
    }

    fn memory_bytes(&self) -> usize {
        self.allocated.bytes()
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        occluded1(self.scene, origin, dir, t_min, t_max)
    }
}

impl Drop for EmbreeTriangles {
    fn drop(&mut self) {
        // SAFETY: the handles were created in `new` and are released once, scene first.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}
