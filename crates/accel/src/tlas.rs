//! The TLAS over a base mesh's prisms (Ogaki 2023, sec. 4.4, 5.2): built on the fly from
//! the base mesh, one prism per leaf, with each triangle's root cells into its BLAS (the
//! implicit quadtree of `cells`). Displacement and shell mapping both stand on it.

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{NonlinearRay, Prism, Ray, max_world_coordinate};

use crate::bvh::{Bvh4, SlabRay, sah_excess};
use crate::mesh::{BaseMesh, prism_bounds};

/// Texel coordinates beyond this (in one axis, after tiling) are rejected: they keep every
/// texel corner exactly representable in `f32` (24-bit significand) with room to spare.
pub const MAX_TEXEL_COORDINATE: f64 = (1u64 << 22) as f64;

/// The largest texel (or tile) range a base triangle may span on either axis, `2^16`: a
/// 16,384^2 map tiled four times over one quad, and every built-in scene, fit (the largest
/// spans 4,097). A ray's work in a prism is linear in the texels its curve crosses, so a
/// wider triangle lets one grazing ray cost seconds (fuzz/slow, docs/testing.md); such a
/// triangle is refused at set-up and the base mesh is to be subdivided instead.
pub const MAX_TEXEL_RANGE: f64 = (1u64 << 16) as f64;

/// Where a base triangle's traversal starts: the smallest pyramid level at which the
/// triangle's uv box spans at most 2 x 2 nodes, and those nodes (sec. 5.4, root selection).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RootNodes {
    /// Level (0 = texels).
    pub level: u32,
    /// First node.
    pub x: i32,
    /// First node.
    pub y: i32,
    /// Nodes along u (1 or 2).
    pub nx: u8,
    /// Nodes along v (1 or 2).
    pub ny: u8,
    /// Texel range of the uv box, inclusive: `[x0, y0, x1, y1]`.
    pub texels: [i32; 4],
}

/// `floor(x)` of a texel coordinate without std or libm; exact for `|x| <`
/// [`MAX_TEXEL_COORDINATE`] (far within `i32`), saturating beyond it.
#[must_use]
#[inline]
pub(crate) fn texel_floor(x: f64) -> i32 {
    let t = x as i32;
    if f64::from(t) > x { t - 1 } else { t }
}

/// The smallest level at which texels `floor(lo)..=floor(hi)` span at most 2 nodes per axis.
pub(crate) fn root_nodes(lo: [f64; 2], hi: [f64; 2]) -> RootNodes {
    // |x| < MAX_TEXEL_COORDINATE is checked by the caller.
    let floor = texel_floor;
    let t0 = [floor(lo[0]), floor(lo[1])];
    let t1 = [floor(hi[0]), floor(hi[1])];
    let mut level = 0;
    while ((t1[0] >> level) - (t0[0] >> level)) > 1 || ((t1[1] >> level) - (t0[1] >> level)) > 1 {
        level += 1;
    }
    RootNodes {
        level,
        x: t0[0] >> level,
        y: t0[1] >> level,
        nx: ((t1[0] >> level) - (t0[0] >> level) + 1) as u8,
        ny: ((t1[1] >> level) - (t0[1] >> level) + 1) as u8,
        texels: [t0[0], t0[1], t1[0], t1[1]],
    }
}

/// Why the prisms of a mesh could not be set up.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum SetupError {
    /// The height scale is not finite.
    HeightScale(f64),
    /// The tiling is not finite and positive.
    Tiling(f64),
    /// A triangle's cells reach beyond [`MAX_TEXEL_COORDINATE`].
    UvOutOfRange(usize),
    /// A triangle spans more than [`MAX_TEXEL_RANGE`] cells along u or v: the triangle and
    /// its extent in cells on both axes.
    RangeTooLarge(usize, [f64; 2]),
    /// A triangle's prism (positions, normals times the height scale) reaches beyond
    /// [`max_world_coordinate`].
    WorldOutOfRange(usize),
}

/// Whether a coordinate of `v` (a position, or a normal times the height scale) lies beyond
/// [`max_world_coordinate`]. NaN is not beyond: the mesh's own checks name it.
pub(crate) fn beyond_world_range<T: Real>(v: &T::Vec3) -> bool {
    let limit = max_world_coordinate::<T>();
    (0..3).any(|i| v.get(i).abs() > limit)
}

/// Whether every position and scaled normal of `prism` lies within [`max_world_coordinate`]
/// (then every ray whose line passes within it of the prism has a finite nonlinear ray in it).
pub(crate) fn within_world_range<T: Real>(prism: &Prism<T>) -> bool {
    !prism
        .p
        .iter()
        .chain(prism.n.iter())
        .any(beyond_world_range::<T>)
}

/// What a TLAS walk looks for: the nearest hit, or any (an occlusion query).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Query {
    /// The nearest hit.
    Nearest,
    /// Any hit: the first prism holding one ends the walk.
    Any,
}

impl Query {
    /// The TLAS's range's upper end after a hit at `t`: `t` for the nearest hit; for any
    /// hit, below every box's entry, which ends the walk.
    #[inline]
    pub(crate) fn range_after<T: Real>(self, t: T) -> T {
        match self {
            Query::Nearest => t,
            Query::Any => T::NEG_INFINITY,
        }
    }

    /// Whether the walk has what it looks for, given the range's upper end (the prisms of a
    /// leaf after the one that ended an any-hit walk are not walked).
    #[inline]
    pub(crate) fn is_done<T: Real>(self, t_max: T) -> bool {
        self == Query::Any && t_max == T::NEG_INFINITY
    }
}

/// A base mesh's prisms with their TLAS and per-triangle root cells.
#[derive(Clone, Debug)]
pub(crate) struct PrismTlas<T: Real> {
    pub(crate) mesh: BaseMesh<T>,
    pub(crate) height_scale: T,
    /// What the mesh's uvs are multiplied by per axis ([`BaseMesh::prism`]).
    pub(crate) uv_scale: [T; 2],
    roots: Vec<RootNodes>,
    pub(crate) tlas: Bvh4<T>,
    /// The TLAS's SAH cost right after its last build.
    pub(crate) sah_cost_at_build: f64,
    /// The same cost over [`crate::sah_lower_bound`] of the prism boxes then (what
    /// [`crate::TlasUpdate::Auto`] compares with).
    pub(crate) sah_excess_at_build: f64,
}

impl<T: Real> PrismTlas<T> {
    /// `uv_scale`: what uvs are multiplied by per axis (the tiling, per axis for a map that
    /// is not square); `cells_per_unit`: cells per unit of scaled uv (a map's
    /// [`crate::HeightField::grid_side`]; 1 for object tiles).
    pub(crate) fn new(
        mesh: BaseMesh<T>,
        height_scale: T,
        uv_scale: [T; 2],
        cells_per_unit: f64,
    ) -> Result<Self, SetupError> {
        if !height_scale.is_finite() {
            return Err(SetupError::HeightScale(height_scale.to_f64()));
        }
        if let Some(&bad) = uv_scale.iter().find(|s| !(**s > T::ZERO && s.is_finite())) {
            return Err(SetupError::Tiling(bad.to_f64()));
        }
        let mut roots = Vec::with_capacity(mesh.triangle_count());
        let mut boxes = Vec::with_capacity(mesh.triangle_count());
        for i in 0..mesh.triangle_count() {
            let prism = mesh.prism(i, height_scale, uv_scale);
            if !within_world_range(&prism) {
                return Err(SetupError::WorldOutOfRange(i));
            }
            boxes.push(prism_bounds(&prism));
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for uv in prism.uv {
                for (a, c) in [uv.x(), uv.y()].into_iter().enumerate() {
                    let cells = c.to_f64() * cells_per_unit;
                    lo[a] = lo[a].min(cells);
                    hi[a] = hi[a].max(cells);
                }
            }
            let extent = lo[0]
                .abs()
                .max(lo[1].abs())
                .max(hi[0].abs())
                .max(hi[1].abs());
            if !(extent < MAX_TEXEL_COORDINATE) {
                return Err(SetupError::UvOutOfRange(i));
            }
            let range = [hi[0] - lo[0], hi[1] - lo[1]];
            if range.iter().any(|&r| r > MAX_TEXEL_RANGE) {
                return Err(SetupError::RangeTooLarge(i, range));
            }
            roots.push(root_nodes(lo, hi));
        }
        let tlas = Bvh4::build(&boxes, 1);
        let sah_cost_at_build = tlas.sah_cost();
        Ok(Self {
            mesh,
            height_scale,
            uv_scale,
            roots,
            sah_cost_at_build,
            sah_excess_at_build: sah_excess(sah_cost_at_build, &boxes, &tlas),
            tlas,
        })
    }

    pub(crate) fn roots(&self, i: usize) -> RootNodes {
        self.roots[i]
    }

    #[inline]
    pub(crate) fn prism(&self, i: usize) -> Prism<T> {
        self.mesh.prism(i, self.height_scale, self.uv_scale)
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.tlas.memory_bytes() + self.roots.len() * core::mem::size_of::<RootNodes>()
    }

    /// TLAS traversal (conservative slab tests, nearest first): `per_prism(triangle, prism,
    /// t_max)` for each prism whose box the ray enters before `t_max`, which returns a hit and
    /// its distance when it finds one nearer than `t_max`.
    pub(crate) fn traverse<H>(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        mut per_prism: impl FnMut(usize, &Prism<T>, T) -> Option<(H, T)>,
    ) -> Option<H> {
        let slab = SlabRay::new(ray.origin, ray.dir);
        let mut best = None;
        self.tlas.traverse(&slab, t_min, t_max, |tri, t_max| {
            let prism = self.prism(tri as usize);
            let (hit, t) = per_prism(tri as usize, &prism, t_max)?;
            best = Some(hit);
            Some(t)
        });
        best
    }

    /// Every triangle, no TLAS and no gate: `per_triangle(triangle, prism, nonlinear ray, t_max)` per triangle, returning a hit and the new `t_max`.
    pub(crate) fn intersect_brute_force<H>(
        &self,
        ray: &Ray<T>,
        t_max: T,
        mut per_triangle: impl FnMut(usize, &Prism<T>, &NonlinearRay<T>, T) -> Option<(H, T)>,
    ) -> Option<H> {
        let mut best = None;
        let mut t_max = t_max;
        for tri in 0..self.mesh.triangle_count() {
            let prism = self.prism(tri);
            let nl = NonlinearRay::new(&prism, ray);
            if !nl.is_finite() {
                // The ray's line passes farther from the prism than `max_world_coordinate`,
                // beyond the prism's extent: it cannot meet it (and would test every cell).
                continue;
            }
            if let Some((hit, t)) = per_triangle(tri, &prism, &nl, t_max) {
                t_max = t;
                best = Some(hit);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use crate::{BaseMesh, DisplacedSurface, DisplacementError, HeightField, MeshError};
    use crate::{TlasUpdate, TraversalStats, Wrap};
    use alloc::vec;
    use nlrt_poly::{Real, Vector2, Vector3};
    use nlrt_shellmap::{Ray, max_world_coordinate};

    /// One unit triangle in the z = 0 plane, normals up (a flat map at height 0.5 puts the
    /// surface at z = 0.5 times the height scale), moved by `shift` along x.
    fn triangle<T: Real>(shift: T) -> BaseMesh<T> {
        let v = |x: f64, y: f64| T::Vec3::new(T::from_f64(x) + shift, T::from_f64(y), T::ZERO);
        let up = T::Vec3::new(T::ZERO, T::ZERO, T::ONE);
        let uv = |x: f64, y: f64| T::Vec2::new(T::from_f64(x), T::from_f64(y));
        let mesh = BaseMesh::new(
            vec![v(0.0, 0.0), v(1.0, 0.0), v(0.0, 1.0)],
            vec![up; 3],
            vec![uv(0.0, 0.0), uv(1.0, 0.0), uv(0.0, 1.0)],
            vec![[0, 1, 2]],
        );
        mesh.expect("a valid triangle")
    }

    fn flat_map() -> HeightField {
        HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).expect("a valid map")
    }

    /// Meshes within `max_world_coordinate` build, beyond it they are refused by name (at
    /// construction and in a new pose, which leaves the surface as it was); rays from far
    /// away still hit (the traversal asserts in debug builds that no prism it sets up has a
    /// non-finite nonlinear ray), and the test reference skips the far prisms whose
    /// nonlinear ray overflows.
    fn world_range_is_checked<T: Real>() {
        let limit = max_world_coordinate::<T>();
        let at_limit = limit - T::from_i32(2).max(limit * T::EPSILON * T::TWO);
        assert!(DisplacedSurface::new(triangle(at_limit), flat_map(), T::ONE, T::ONE).is_ok());
        let far = limit * T::TWO;
        let refused = DisplacedSurface::new(triangle(far), flat_map(), T::ONE, T::ONE);
        assert_eq!(
            refused.err(),
            Some(DisplacementError::WorldOutOfRange { triangle: 0 })
        );
        let tall = DisplacedSurface::new(triangle(T::ZERO), flat_map(), far, T::ONE);
        assert_eq!(
            tall.err(),
            Some(DisplacementError::WorldOutOfRange { triangle: 0 })
        );

        let mut surface = DisplacedSurface::new(triangle(T::ZERO), flat_map(), T::ONE, T::ONE)
            .expect("a unit triangle builds");
        let moved = triangle(far);
        let error = surface.set_pose(moved.positions(), moved.normals(), TlasUpdate::Refit);
        assert!(matches!(
            error,
            Err(MeshError::BeyondWorldRange {
                vertex: 0,
                attribute: "position"
            })
        ));
        assert_eq!(surface.mesh().positions()[1].x(), T::ONE);

        let down = T::Vec3::new(T::ZERO, T::ZERO, -T::ONE);
        let aim = |z: T| {
            Ray::new(T::Vec3::new(T::from_f64(0.25), T::from_f64(0.25), z), down)
                .expect("a valid ray")
        };
        let mut stats = TraversalStats::default();
        let hit = surface.intersect(&aim(T::TWO), T::ZERO, T::INFINITY, &mut stats);
        let t = hit.expect("the flat surface at height 0.5").hit.t;
        assert!((t - T::from_f64(1.5)).abs() < T::from_f64(1e-3), "{t:?}");
        // From far above, straight down: Eq. 6 sees only the offset across the ray.
        let mut stats = TraversalStats::default();
        let hit = surface.intersect(&aim(T::MAX / T::pow2(4)), T::ZERO, T::INFINITY, &mut stats);
        assert!(hit.is_some(), "{stats:?}");
        // Passing far beside it: every prism is set up by the test reference, which skips
        // the ones whose nonlinear ray overflows (they are far off the ray's line).
        let beside = Ray::new(T::Vec3::new(T::ZERO, T::MAX / T::pow2(4), T::ONE), down)
            .expect("a valid ray");
        assert!(
            surface
                .intersect_brute_force(&beside, T::ZERO, T::INFINITY)
                .is_none()
        );
    }

    #[test]
    fn world_range_is_checked_f32() {
        world_range_is_checked::<f32>();
    }

    #[test]
    fn world_range_is_checked_f64() {
        world_range_is_checked::<f64>();
    }
}
