//! nlrt surfaces inside an Embree 3 scene (the `embree` feature): a displaced surface is one
//! Embree user geometry (its bounds the prisms' box; its intersection nlrt's own TLAS and
//! walks, in `f32`), beside ordinary Embree triangles in the same scene, so that a renderer
//! already built on Embree gets displacement without tessellating it. Embree's BVH decides
//! which of the scene's geometries a ray meets first; nlrt decides the displaced one.
//!
//! ```no_run
//! # #[cfg(feature = "embree")] {
//! use nlrt_render::trace::embree_reference::Isa;
//! use nlrt_render::trace::embree_user::EmbreeWithSurface;
//! use nlrt_render::scene::scenes::{builtin, Size};
//! use nlrt_render::trace::tracer::Tracer;
//! use nlrt_poly::glam::DVec3;
//! let scene = builtin("mountain", Size::Small).unwrap();
//! let surface = scene.displaced_surface::<f32>().unwrap();
//! // A wall of two Embree triangles behind the terrain.
//! let wall = [
//!     [DVec3::new(-2.0, 0.0, -1.5), DVec3::new(2.0, 0.0, -1.5), DVec3::new(2.0, 2.0, -1.5)],
//!     [DVec3::new(-2.0, 0.0, -1.5), DVec3::new(2.0, 2.0, -1.5), DVec3::new(-2.0, 2.0, -1.5)],
//! ];
//! let both = EmbreeWithSurface::new(surface, &wall, Isa::Build).unwrap();
//! let hit = both.intersect(scene.camera.eye, DVec3::new(0.0, -0.6, -1.0).normalize(), 0.0, f64::INFINITY);
//! # }
//! ```

use nlrt_accel::{DisplacedSurface, TraversalStats};
use nlrt_poly::glam::{DVec3, Vec3};
use nlrt_shellmap::Ray;

use embree::sys;

use crate::trace::embree_reference::{Isa, MemoryCounter, new_device, triangle_geometry};
use crate::trace::tracer::{TraceHit, Tracer};

/// An Embree scene of ordinary triangles and one nlrt displaced surface as user geometry.
pub struct EmbreeWithSurface {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// The surface, boxed: Embree's callbacks hold its address.
    surface: Box<DisplacedSurface<f32>>,
    /// Embree's geometry id of the surface (the triangles are the other one).
    surface_id: u32,
    allocated: MemoryCounter,
}

// SAFETY: a committed Embree scene is immutable and Embree documents `rtcIntersect1` on it as
// safe from any number of threads; the user geometry's callbacks only read the surface, which
// is `Sync`; the handles are only released in `drop`.
unsafe impl Send for EmbreeWithSurface {}
// SAFETY: as above.
unsafe impl Sync for EmbreeWithSurface {}

/// Embree's bounds callback: the surface's prism boxes' union (one user primitive).
unsafe extern "C" fn surface_bounds(args: *const sys::RTCBoundsFunctionArguments) {
    // SAFETY: Embree passes valid arguments; the user pointer is the boxed surface, alive as
    // long as the scene.
    unsafe {
        let args = &*args;
        let surface = &*(args.geometryUserPtr as *const DisplacedSurface<f32>);
        let b = surface.bounds();
        let out = &mut *args.bounds_o;
        (out.lower_x, out.lower_y, out.lower_z) = (b.lo[0], b.lo[1], b.lo[2]);
        (out.upper_x, out.upper_y, out.upper_z) = (b.hi[0], b.hi[1], b.hi[2]);
    }
}

/// Field `field` of lane `lane` of an Embree ray-hit packet of width `n`: the packet is
/// structure-of-arrays, each field `n` 32-bit values, the ray's 12 fields then the hit's
/// (`RTCRayHitN` in Embree's `rtcore_ray.h`).
///
/// # Safety
/// `packet` points to a packet of width `n`, and `lane < n`.
unsafe fn lane<U>(packet: *mut u32, n: usize, field: usize, lane: usize) -> *mut U {
    // SAFETY: within the packet by the caller's contract.
    unsafe { packet.add(field * n + lane).cast::<U>() }
}

/// The ray fields of `RTCRayN` and the hit fields of `RTCHitN`, in order.
const ORG: usize = 0;
const TNEAR: usize = 3;
const DIR: usize = 4;
const TFAR: usize = 8;
const NG: usize = 12;
const U: usize = 15;
const V: usize = 16;
const PRIM_ID: usize = 17;
const GEOM_ID: usize = 18;
const INST_ID: usize = 19;

/// The nearest nlrt hit of lane `i` of a packet (`t` in Embree's units of the ray's direction,
/// within its `(tnear, tfar)`), with its unit normal facing the ray.
///
/// # Safety
/// As [`lane`].
unsafe fn trace_lane(
    surface: &DisplacedSurface<f32>,
    packet: *mut u32,
    n: usize,
    i: usize,
) -> Option<(f32, Vec3)> {
    // SAFETY: as the caller's contract.
    let read = |field: usize| unsafe { *lane::<f32>(packet, n, field, i) };
    let origin = Vec3::new(read(ORG), read(ORG + 1), read(ORG + 2));
    let dir = Vec3::new(read(DIR), read(DIR + 1), read(DIR + 2));
    let (tnear, tfar) = (read(TNEAR), read(TFAR));
    // nlrt's rays have unit directions: distances scale by the direction's length.
    let length = dir.length();
    let ray = Ray::new(origin, dir)?;
    let hit = surface.intersect(
        &ray,
        tnear.max(0.0) * length,
        tfar * length,
        &mut TraversalStats::default(),
    )?;
    let t = hit.hit.t / length;
    if !(t > tnear && t < tfar) {
        return None;
    }
    let normal = surface.normal(&hit, ray.dir)?;
    Some((t, normal))
}

/// Embree's intersection callback: nlrt's nearest hit, written into the packet where it is
/// nearer than the ray's `tfar`.
unsafe extern "C" fn surface_intersect(args: *const sys::RTCIntersectFunctionNArguments) {
    // SAFETY: Embree passes valid arguments (a packet of `N` lanes with a validity mask); the
    // user pointer is the boxed surface.
    unsafe {
        let args = &*args;
        let surface = &*(args.geometryUserPtr as *const DisplacedSurface<f32>);
        let n = args.N as usize;
        let packet = args.rayhit.cast::<u32>();
        for i in 0..n {
            if *args.valid.add(i) == 0 {
                continue;
            }
            let Some((t, normal)) = trace_lane(surface, packet, n, i) else {
                continue;
            };
            *lane::<f32>(packet, n, TFAR, i) = t;
            *lane::<f32>(packet, n, NG, i) = normal.x;
            *lane::<f32>(packet, n, NG + 1, i) = normal.y;
            *lane::<f32>(packet, n, NG + 2, i) = normal.z;
            *lane::<f32>(packet, n, U, i) = 0.0;
            *lane::<f32>(packet, n, V, i) = 0.0;
            *lane::<u32>(packet, n, PRIM_ID, i) = args.primID;
            *lane::<u32>(packet, n, GEOM_ID, i) = args.geomID;
            *lane::<u32>(packet, n, INST_ID, i) = (*args.context).instID[0];
        }
    }
}

/// Whether nlrt's surface blocks lane `i` of a packet within its `(tnear, tfar)`: its
/// occlusion query, which stops at the first prism holding a hit.
///
/// # Safety
/// As [`lane`].
unsafe fn occluded_lane(
    surface: &DisplacedSurface<f32>,
    packet: *mut u32,
    n: usize,
    i: usize,
) -> bool {
    // SAFETY: as the caller's contract.
    let read = |field: usize| unsafe { *lane::<f32>(packet, n, field, i) };
    let origin = Vec3::new(read(ORG), read(ORG + 1), read(ORG + 2));
    let dir = Vec3::new(read(DIR), read(DIR + 1), read(DIR + 2));
    let (tnear, tfar) = (read(TNEAR), read(TFAR));
    // nlrt's rays have unit directions: distances scale by the direction's length.
    let length = dir.length();
    let Some(ray) = Ray::new(origin, dir) else {
        return false;
    };
    surface.occluded(
        &ray,
        tnear.max(0.0) * length,
        tfar * length,
        &mut TraversalStats::default(),
    )
}

/// Embree's occlusion callback: `tfar` set to `-inf` where nlrt finds any hit.
unsafe extern "C" fn surface_occluded(args: *const sys::RTCOccludedFunctionNArguments) {
    // SAFETY: as `surface_intersect`; an `RTCRayN` packet is the leading part of an
    // `RTCRayHitN` one (the ray's fields).
    unsafe {
        let args = &*args;
        let surface = &*(args.geometryUserPtr as *const DisplacedSurface<f32>);
        let n = args.N as usize;
        let packet = args.ray.cast::<u32>();
        for i in 0..n {
            if *args.valid.add(i) != 0 && occluded_lane(surface, packet, n, i) {
                *lane::<f32>(packet, n, TFAR, i) = f32::NEG_INFINITY;
            }
        }
    }
}

impl EmbreeWithSurface {
    /// An Embree scene (kernels `isa`) of `triangles` and `surface` as one user geometry;
    /// `None` when Embree cannot create a device or a buffer.
    #[must_use]
    pub fn new(surface: DisplacedSurface<f32>, triangles: &[[DVec3; 3]], isa: Isa) -> Option<Self> {
        let surface = Box::new(surface);
        let (device, allocated) = new_device(isa)?;
        // SAFETY: plain calls of Embree's C API on handles created here and checked for null;
        // the user pointer is the boxed surface, which lives as long as the scene.
        unsafe {
            let scene = sys::rtcNewScene(device);
            if !triangles.is_empty() {
                let Some(geometry) = triangle_geometry(device, triangles) else {
                    sys::rtcReleaseScene(scene);
                    sys::rtcReleaseDevice(device);
                    return None;
                };
                sys::rtcAttachGeometry(scene, geometry);
                sys::rtcReleaseGeometry(geometry);
            }
            let user = sys::rtcNewGeometry(device, sys::RTCGeometryType::USER);
            let pointer = (&*surface as *const DisplacedSurface<f32>)
                .cast_mut()
                .cast::<std::ffi::c_void>();
            sys::rtcSetGeometryUserPrimitiveCount(user, 1);
            sys::rtcSetGeometryUserData(user, pointer);
            sys::rtcSetGeometryBoundsFunction(user, Some(surface_bounds), std::ptr::null_mut());
            sys::rtcSetGeometryIntersectFunction(user, Some(surface_intersect));
            sys::rtcSetGeometryOccludedFunction(user, Some(surface_occluded));
            sys::rtcCommitGeometry(user);
            let surface_id = sys::rtcAttachGeometry(scene, user);
            sys::rtcReleaseGeometry(user);
            sys::rtcCommitScene(scene);
            Some(Self {
                device,
                scene,
                surface,
                surface_id,
                allocated,
            })
        }
    }

    /// The surface.
    #[must_use]
    pub fn surface(&self) -> &DisplacedSurface<f32> {
        &self.surface
    }

    /// Whether a hit's `id` ([`TraceHit::id`]) is the surface's (else a triangle's index).
    #[must_use]
    pub fn is_surface(&self, id: u32) -> bool {
        id == SURFACE_ID
    }

    /// Whether anything, triangle or surface, lies on the ray within `(0, t_max)`: Embree's
    /// any-hit query (`rtcOccluded1`), a shadow ray.
    #[must_use]
    pub fn occluded(&self, origin: DVec3, dir: DVec3, t_max: f64) -> bool {
        crate::trace::embree_reference::occluded1(self.scene, origin, dir, 0.0, t_max)
    }

    /// Bytes Embree allocated (its BVH and the triangles' buffers), the surface's own beside.
    #[must_use]
    pub fn embree_bytes(&self) -> usize {
        self.allocated.bytes()
    }
}

/// [`TraceHit::id`] of a hit on the surface (the triangles' hits carry their index).
pub const SURFACE_ID: u32 = u32::MAX - 1;

impl Tracer for EmbreeWithSurface {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let hit =
            crate::trace::embree_reference::intersect1(self.scene, origin, dir, t_min, t_max)?;
        let id = if hit.geom_id == self.surface_id {
            SURFACE_ID
        } else {
            hit.prim_id
        };
        Some(TraceHit {
            t: hit.t,
            normal: hit.normal,
            id,
        })
    }

    fn memory_bytes(&self) -> usize {
        self.allocated.bytes() + self.surface.memory_bytes()
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        crate::trace::embree_reference::occluded1(self.scene, origin, dir, t_min, t_max)
    }
}

impl Drop for EmbreeWithSurface {
    fn drop(&mut self) {
        // SAFETY: the handles were created in `new` and are released once, scene first; the
        // surface outlives them (dropped after this body).
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}
