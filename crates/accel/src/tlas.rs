//! The TLAS over a base mesh's prisms (Ogaki 2023, sec. 4.4, 5.2): built on the fly from
//! the base mesh, one prism per leaf, with each triangle's root cells into its BLAS (the
//! implicit quadtree of `cells`). Displacement and shell mapping both stand on it.

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2};
use nlrt_shellmap::{NonlinearRay, Prism, Ray};

use crate::bvh::{Bvh4, SlabRay, sah_excess};
use crate::mesh::{BaseMesh, prism_bounds};
use crate::stats::TraversalStats;

/// Texel coordinates beyond this (in one axis, after tiling) are rejected: they keep every
/// texel corner exactly representable in `f32` (24-bit significand) with room to spare.
pub const MAX_TEXEL_COORDINATE: f64 = (1u64 << 22) as f64;

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
}

/// A base mesh's prisms with their TLAS and per-triangle root cells.
#[derive(Clone, Debug)]
pub(crate) struct PrismTlas<T: Real> {
    pub(crate) mesh: BaseMesh<T>,
    height_scale: T,
    tiling: T,
    roots: Vec<RootNodes>,
    pub(crate) tlas: Bvh4<T>,
    /// The TLAS's SAH cost right after its last build.
    pub(crate) sah_cost_at_build: f64,
    /// The same cost over [`crate::sah_lower_bound`] of the prism boxes then (what
    /// [`crate::TlasUpdate::Auto`] compares with).
    pub(crate) sah_excess_at_build: f64,
}

impl<T: Real> PrismTlas<T> {
    /// `cells_per_unit`: cells per unit of tiled uv (a map's side; 1 for object tiles).
    pub(crate) fn new(
        mesh: BaseMesh<T>,
        height_scale: T,
        tiling: T,
        cells_per_unit: f64,
    ) -> Result<Self, SetupError> {
        if !height_scale.is_finite() {
            return Err(SetupError::HeightScale(height_scale.to_f64()));
        }
        if !(tiling > T::ZERO && tiling.is_finite()) {
            return Err(SetupError::Tiling(tiling.to_f64()));
        }
        let mut roots = Vec::with_capacity(mesh.triangle_count());
        let mut boxes = Vec::with_capacity(mesh.triangle_count());
        for i in 0..mesh.triangle_count() {
            let prism = mesh.prism(i, height_scale, tiling);
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
            roots.push(root_nodes(lo, hi));
        }
        let tlas = Bvh4::build(&boxes, 1);
        let sah_cost_at_build = tlas.sah_cost();
        Ok(Self {
            mesh,
            height_scale,
            tiling,
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
        self.mesh.prism(i, self.height_scale, self.tiling)
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

    /// [`PrismTlas::traverse`], then `blas(triangle, prism, nonlinear ray, t_max)` (which
    /// finds where the ray is inside the prism itself: [`walk_cells`]).
    pub(crate) fn intersect<H>(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
        mut blas: impl FnMut(
            usize,
            &Prism<T>,
            &NonlinearRay<T>,
            T,
            &mut TraversalStats,
        ) -> Option<(H, T)>,
    ) -> Option<H> {
        self.traverse(ray, t_min, t_max, |tri, prism, t_max| {
            stats.prism_tests += 1;
            let nl = NonlinearRay::new(prism, ray);
            blas(tri, prism, &nl, t_max, stats)
        })
    }

    /// Every triangle, no TLAS and no gate: `per_triangle` as in [`PrismTlas::intersect`].
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
            if let Some((hit, t)) = per_triangle(tri, &prism, &nl, t_max) {
                t_max = t;
                best = Some(hit);
            }
        }
        best
    }
}
