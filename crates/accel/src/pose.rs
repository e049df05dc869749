//! Animated base meshes: a new pose of the base mesh (vertex positions and normals) per
//! frame. Nonlinear tracing keeps the displacement in texture space, so the height field's
//! pyramid, the shell object's BVH and every triangle's root cells (which depend on the uvs
//! only) stay as they are; only the TLAS over the prisms follows the pose, refitted or
//! rebuilt ([`TlasUpdate`]). The prisms themselves are built on the fly from the mesh (sec.
//! 5.2), so there is no per-prism data to re-derive.

use alloc::vec::Vec;
use nlrt_poly::Real;

use crate::bvh::{Aabb, Bvh4, sah_excess};
use crate::mesh::{MeshError, prism_bounds};
use crate::tlas::{PrismTlas, beyond_world_range};

/// How the TLAS follows a new pose.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TlasUpdate {
    /// Refit the boxes and keep the tree: cheapest, and as exact as a rebuild (the boxes
    /// hold their prisms), but its SAH cost grows as the pose moves away from the one the
    /// tree was built for.
    Refit,
    /// Build the tree afresh for the pose.
    Rebuild,
    /// Refit, then rebuild when the refitted tree's cost growth ([`PoseUpdate::cost_growth`])
    /// exceeds `max_cost_growth`.
    Auto {
        /// The growth of the SAH cost tolerated before a rebuild.
        max_cost_growth: f64,
    },
}

impl TlasUpdate {
    /// The default rule: rebuild once the refitted tree's cost growth exceeds a quarter. A
    /// TLAS rebuild costs 6 to 8 times a refit (paper-size cylinder, 512 prisms: 0.42 against
    /// 0.06 ms; fur, 8,192 prisms: 7.1 against 0.96 ms). On a strongly twisted cylinder
    /// (`nlrt animate cylinder --deformation twist --amplitude 3`, 16 frames), refitting only
    /// let the SAH cost reach 1.82x a fresh tree's (median 1.35x) and rendered 1.12x slower
    /// than fresh builds; this rule rebuilt 4 times, kept the cost within 1.23x and rendered
    /// within 1.1%. Among the built-in motions only the cylinder's bend rebuilds (once per
    /// cycle). Figures and commands: `docs/measurements.md`, "Animated base meshes".
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
    /// How much worse the tree is than right after its last build, with the prisms' own
    /// growth divided out: the SAH cost over [`crate::sah_lower_bound`] of the current prism boxes,
    /// divided by the same ratio at the last build (1 after a rebuild). A motion that
    /// swells every prism (a twist) raises a fresh tree's cost as much as the refitted
    /// one's, so only the refitted boxes drifting apart from their content counts.
    pub cost_growth: f64,
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
        // Checked before the mesh moves, so a rejected pose leaves the surface as it was.
        for (vertex, (p, n)) in positions.iter().zip(normals).enumerate() {
            let attribute = if beyond_world_range::<T>(p) {
                "position"
            } else if beyond_world_range::<T>(&(*n * self.height_scale)) {
                "normal"
            } else {
                continue;
            };
            return Err(MeshError::BeyondWorldRange { vertex, attribute });
        }
        self.mesh.set_pose(positions, normals)?;
        let boxes = self.prism_boxes();
        let refitted = match update {
            TlasUpdate::Rebuild => false,
            TlasUpdate::Refit | TlasUpdate::Auto { .. } => self.tlas.refit(&boxes),
        };
        let sah_cost = self.tlas.sah_cost();
        let cost_growth = sah_excess(sah_cost, &boxes, &self.tlas) / self.sah_excess_at_build;
        let too_costly = match update {
            TlasUpdate::Auto { max_cost_growth } => !(cost_growth <= max_cost_growth),
            TlasUpdate::Refit | TlasUpdate::Rebuild => false,
        };
        if refitted && !too_costly {
            return Ok(PoseUpdate {
                rebuilt: false,
                sah_cost,
                sah_cost_at_build: self.sah_cost_at_build,
                cost_growth,
            });
        }
        self.tlas = Bvh4::build(&boxes, 1);
        self.sah_cost_at_build = self.tlas.sah_cost();
        self.sah_excess_at_build = sah_excess(self.sah_cost_at_build, &boxes, &self.tlas);
        Ok(PoseUpdate {
            rebuilt: true,
            sah_cost: self.sah_cost_at_build,
            sah_cost_at_build: self.sah_cost_at_build,
            cost_growth: 1.0,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bvh::sah_lower_bound;
    use nlrt_poly::glam::DVec3;

    /// `n` boxes on a jittered line of cells, half-extent `size`.
    fn boxes(n: usize, size: f64) -> Vec<Aabb<f64>> {
        (0..n)
            .map(|i| {
                let c = DVec3::new(i as f64, ((i * 7) % 5) as f64 * 0.1, 0.0);
                Aabb::of_points([c - DVec3::splat(size), c + DVec3::splat(size)])
            })
            .collect()
    }

    #[test]
    fn the_lower_bound_holds_and_only_a_degrading_tree_grows() {
        let rest = boxes(512, 0.3);
        let mut tree = Bvh4::build(&rest, 1);
        let excess_at_build = sah_excess(tree.sah_cost(), &rest, &tree);
        assert!(tree.sah_cost() >= sah_lower_bound(&rest, &tree.bounds()));
        assert!(excess_at_build >= 1.0);
        // Every box swollen in place (a twist's prisms): the refitted and a fresh tree both
        // cost more, so the growth judged stays near 1 while the raw cost rises.
        let swollen = boxes(512, 0.9);
        assert!(tree.refit(&swollen));
        let growth = sah_excess(tree.sah_cost(), &swollen, &tree) / excess_at_build;
        let fresh = Bvh4::build(&swollen, 1);
        let fresh_growth = sah_excess(fresh.sah_cost(), &swollen, &fresh) / excess_at_build;
        assert!(tree.sah_cost() > 1.2 * Bvh4::build(&rest, 1).sah_cost());
        assert!(
            growth < 1.1 * fresh_growth.max(1.0),
            "{growth} vs fresh {fresh_growth}"
        );
        // The boxes' order reversed along the line: every leaf's neighbours now lie far apart,
        // which the refitted tree's boxes must span.
        let mut shuffled = rest.clone();
        shuffled.reverse();
        for (i, b) in shuffled.iter_mut().enumerate() {
            if i % 2 == 0 {
                *b = rest[i];
            }
        }
        let mut tree = Bvh4::build(&rest, 1);
        assert!(tree.refit(&shuffled));
        let growth = sah_excess(tree.sah_cost(), &shuffled, &tree) / excess_at_build;
        assert!(growth > 2.0, "{growth}");
        assert_eq!(sah_lower_bound::<f64>(&[], &Aabb::EMPTY), 0.0);
    }
}
