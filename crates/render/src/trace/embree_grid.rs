//! The pre-tessellated displaced surface as Embree 3 grid geometry (`embree-grid-f32`, the
//! `embree` feature): one vertex per texel corner ([`GridMesh`]) instead of three per
//! microtriangle, Embree's compact grid BVH over them: the memory-conscious Embree user's
//! choice for a height field. Traced as [`EmbreeTessellated`] is (one ray at a time,
//! `rtcIntersect1`, incoherent), its memory what Embree's monitor counts (the vertex buffer,
//! which Embree allocates, and the BVH) plus the grid records kept for hit ids.
//!
//! [`EmbreeTessellated`]: crate::trace::embree_reference::EmbreeTessellated

use embree::sys;
use nlrt_poly::glam::DVec3;

use crate::scene::scenes::Scene;
use crate::trace::embree_reference::{Isa, MemoryCounter, new_device, scene_of};
use crate::trace::grid_mesh::GridMesh;
use crate::trace::tracer::{TraceHit, Tracer};

/// An Embree device and committed scene of one grid geometry.
pub struct EmbreeGrids {
    device: sys::RTCDevice,
    scene: sys::RTCScene,
    /// The grids without their vertices (Embree holds its copy): hit ids.
    grids: GridMesh,
    allocated: MemoryCounter,
}

// SAFETY: a committed Embree scene is immutable and Embree documents `rtcIntersect1` on it as
// safe from any number of threads; the handles are only released in `drop`.
unsafe impl Send for EmbreeGrids {}
// SAFETY: as above.
unsafe impl Sync for EmbreeGrids {}

impl EmbreeGrids {
    /// The grids of `scene` in an Embree scene with kernels `isa`; `None` when the scene has
    /// no grids ([`GridMesh::new`] says why) or Embree cannot create a device or a buffer.
    #[must_use]
    pub fn new(scene: &Scene, isa: Isa) -> Option<Self> {
        let mut grids = GridMesh::new(scene).ok()?;
        let (device, allocated) = new_device(isa)?;
        // SAFETY: plain calls of Embree's C API on handles created here and checked for null;
        // the buffers are written within the sizes requested from Embree.
        unsafe {
            let geometry = sys::rtcNewGeometry(device, sys::RTCGeometryType::GRID);
            let vertices = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::VERTEX,
                0,
                sys::RTCFormat::FLOAT3,
                3 * std::mem::size_of::<f32>(),
                grids.vertices.len(),
            ) as *mut [f32; 3];
            let records = sys::rtcSetNewGeometryBuffer(
                geometry,
                sys::RTCBufferType::GRID,
                0,
                sys::RTCFormat::GRID,
                std::mem::size_of::<sys::RTCGrid>(),
                grids.grids.len(),
            ) as *mut sys::RTCGrid;
            if vertices.is_null() || records.is_null() {
                sys::rtcReleaseGeometry(geometry);
                sys::rtcReleaseDevice(device);
                return None;
            }
            std::ptr::copy_nonoverlapping(grids.vertices.as_ptr(), vertices, grids.vertices.len());
            for (k, g) in grids.grids.iter().enumerate() {
                *records.add(k) = sys::RTCGrid {
                    startVertexID: g.start,
                    stride: g.stride,
                    width: g.width,
                    height: g.height,
                };
            }
            grids.vertices = Vec::new();
            sys::rtcCommitGeometry(geometry);
            Some(Self {
                device,
                scene: scene_of(device, geometry),
                grids,
                allocated,
            })
        }
    }
}

impl Tracer for EmbreeGrids {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let hit =
            crate::trace::embree_reference::intersect1(self.scene, origin, dir, t_min, t_max)?;
        Some(TraceHit {
            t: hit.t,
            normal: hit.normal,
            id: self
                .grids
                .base_triangle(hit.prim_id as usize, hit.u, hit.v)
                .unwrap_or(0),
        })
    }

    fn memory_bytes(&self) -> usize {
        self.allocated.bytes() + self.grids.memory_bytes()
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        crate::trace::embree_reference::occluded1(self.scene, origin, dir, t_min, t_max)
    }
}

impl Drop for EmbreeGrids {
    fn drop(&mut self) {
        // SAFETY: the handles were created in `new` and are released once, scene first.
        unsafe {
            sys::rtcReleaseScene(self.scene);
            sys::rtcReleaseDevice(self.device);
        }
    }
}
