//! Animated base meshes: a new pose of the base mesh (vertex positions and normals) per
//! frame. Nonlinear tracing keeps the displacement in texture space, so the height field's
//! pyramid, the shell object's BVH and every triangle's root cells (which depend on the uvs
//! only) stay as they are; only the TLAS over the prisms follows the pose, refitted or
//! rebuilt ([`TlasUpdate`]). The prisms themselves are built on the fly from the mesh (sec.
//! 5.2), so there is no per-prism data to re-derive.

use alloc::vec::Vec;
use nlrt_poly::Real;

use crate::bvh::{Aabb, Bvh4};
use crate::mesh::{MeshError, prism_bounds};
use crate::tlas::PrismTlas;

/// How the TLAS follows a new pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TlasUpdate {
    /// Refit the boxes and keep the tree: cheapest, and as exact as a rebuild (the boxes
    /// hold their prisms), but its SAH cost grows as the pose moves away from the one the
    /// tree was built for.
    Refit,
    /// Build the tree afresh for the pose.
    Rebuild,
    /// Refit, then rebuild when the refitted tree's SAH cost ([`Bvh4::sah_cost`]) exceeds
    /// `max_cost_growth` times the cost of the tree right after its last build.
    Auto {
        /// The growth of the SAH cost tolerated before a rebuild.
        max_cost_growth: f64,
    },
}

impl TlasUpdate {
    /// The default rule: rebuild once the refitted tree's SAH cost has grown by a quarter.
    /// A rebuild of the TLAS costs several times a refit (0.56 ms against 0.09 ms on the
    /// cylinder's 512 prisms, `nlrt animate cylinder --frames 8`, 2026-12-03, 2-core Xeon),
    /// and a refitted cylinder frame at 1.14x the fresh tree's SAH cost rendered at 1.04x its
    /// time; the factor trades the two and is not yet tuned at paper size.
    pub const DEFAULT: Self = Self::Auto {
        max_cost_growth: 1.25,
    };
}

impl Default for TlasUpdate {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What one pose update did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PoseUpdate {
    /// Whether the TLAS was built afresh (else refitted).
    pub rebuilt: bool,
    /// The TLAS's SAH cost now ([`Bvh4::sah_cost`]).
    pub sah_cost: f64,
    /// The TLAS's SAH cost right after its last build (this pose's, when rebuilt).
    pub sah_cost_at_build: f64,
}

impl<T: Real> PrismTlas<T> {
    /// The boxes of every prism of the current pose.
    fn prism_boxes(&self) -> Vec<Aabb<T>> {
        (0..self.mesh.triangle_count())
            .map(|i| prism_bounds(&self.prism(i)))
            .collect()
    }

    /// Moves the base mesh to a new pose and updates the TLAS by `update`.
    pub(crate) fn set_pose(
        &mut self,
        positions: &[T::Vec3],
        normals: &[T::Vec3],
        update: TlasUpdate,
    ) -> Result<PoseUpdate, MeshError> {
        self.mesh.set_pose(positions, normals)?;
        let boxes = self.prism_boxes();
        let refitted = match update {
            TlasUpdate::Rebuild => false,
            TlasUpdate::Refit | TlasUpdate::Auto { .. } => self.tlas.refit(&boxes),
        };
        let sah_cost = self.tlas.sah_cost();
        let too_costly = match update {
            TlasUpdate::Auto { max_cost_growth } => {
                !(sah_cost <= max_cost_growth * self.sah_cost_at_build)
            }
            TlasUpdate::Refit | TlasUpdate::Rebuild => false,
        };
        if refitted && !too_costly {
            return Ok(PoseUpdate {
                rebuilt: false,
                sah_cost,
                sah_cost_at_build: self.sah_cost_at_build,
            });
        }
        self.tlas = Bvh4::build(&boxes, 1);
        self.sah_cost_at_build = self.tlas.sah_cost();
        Ok(PoseUpdate {
            rebuilt: true,
            sah_cost: self.sah_cost_at_build,
            sah_cost_at_build: self.sah_cost_at_build,
        })
    }
}
