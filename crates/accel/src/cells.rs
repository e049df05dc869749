//! What displacement and shell mapping share: the TLAS over a base mesh's prisms (built on the
//! fly, one per leaf) with each triangle's root cells, and the implicit quadtree over
//! texture-space cells (texels of a height map, tiles of an instanced object) traversed by a
//! nonlinear ray nearest first.

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{NonlinearRay, Prism, Ray, intersect_box, intersect_prism};

use crate::bvh::{Bvh4, SlabRay};
use crate::displacement::{
    MAX_TEXEL_COORDINATE, RootNodes, TraversalStats, root_nodes, square_meets_triangle,
};
use crate::mesh::{BaseMesh, prism_bounds};

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
        Ok(Self {
            mesh,
            height_scale,
            tiling,
            roots,
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

    /// [`PrismTlas::traverse`] with the exact ray-prism test as a gate, then `blas(triangle,
    /// prism, nonlinear ray, t_max)`.
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
            intersect_prism(prism, ray, t_min, t_max)?;
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

#[derive(Clone, Copy)]
struct Pending<T> {
    level: u32,
    x: i32,
    y: i32,
    t_in: T,
}

/// Highest root level: cell coordinates are below 2^22 in magnitude
/// ([`MAX_TEXEL_COORDINATE`]), so a triangle's cell range spans fewer than 2^23 cells and
/// fits 2 nodes of level 23.
const MAX_ROOT_LEVEL: usize = 23;
/// Entries of the quadtree stack: up to 4 roots, then each popped inner node pushes at most
/// 4 children (3 more than it took), once per level on the way down. Kept small: the array
/// is initialised per prism test.
const STACK: usize = 4 + 3 * MAX_ROOT_LEVEL;

/// The implicit quadtree over the cells of one base triangle, nearest first: per node an
/// entry test (`node_entry(level, x, y, t_max)`: the entry distance of the node's volume, cells
/// `[x 2^l, (x + 1) 2^l)`, or `None` when the ray misses it before `t_max`), cells whose square
/// misses the triangle's uv triangle `uv_tri` (in cell units) skipped, nodes entered beyond the
/// current `t_max` skipped; `leaf(x, y, t_max, stats)` tests a cell and returns the distance of
/// a hit nearer than `t_max`.
pub(crate) fn traverse_cells<T: Real>(
    root: RootNodes,
    uv_tri: [[T; 2]; 3],
    mut t_max: T,
    stats: &mut TraversalStats,
    node_entry: impl Fn(u32, i32, i32, T) -> Option<T>,
    mut leaf: impl FnMut(i32, i32, T, &mut TraversalStats) -> Option<T>,
) {
    let mut stack = [Pending {
        level: 0,
        x: 0,
        y: 0,
        t_in: T::ZERO,
    }; STACK];
    let mut depth = 0;
    // Box-test candidates (the roots, or a node's children), sort them, push farthest first.
    let push = |level: u32,
                nodes: &mut dyn Iterator<Item = (i32, i32)>,
                t_max: T,
                stack: &mut [Pending<T>; STACK],
                depth: &mut usize,
                stats: &mut TraversalStats| {
        let mut found = [Pending {
            level,
            x: 0,
            y: 0,
            t_in: T::ZERO,
        }; 4];
        let mut n = 0;
        for (x, y) in nodes {
            let k = 1i64 << level;
            let (cx0, cy0) = (i64::from(x) * k, i64::from(y) * k);
            let [r0, r1, r2, r3] = root.texels.map(i64::from);
            if cx0 > r2 || cy0 > r3 || cx0 + k <= r0 || cy0 + k <= r1 {
                continue;
            }
            let lo = [T::from_f64(cx0 as f64), T::from_f64(cy0 as f64)];
            let hi = [T::from_f64((cx0 + k) as f64), T::from_f64((cy0 + k) as f64)];
            if !square_meets_triangle(lo, hi, &uv_tri) {
                continue;
            }
            stats.box_tests += 1;
            if let Some(t_in) = node_entry(level, x, y, t_max) {
                let mut i = n;
                while i > 0 && found[i - 1].t_in > t_in {
                    found[i] = found[i - 1];
                    i -= 1;
                }
                found[i] = Pending { level, x, y, t_in };
                n += 1;
            }
        }
        for p in found[..n].iter().rev() {
            stack[*depth] = *p;
            *depth += 1;
        }
    };
    let mut roots = (0..i32::from(root.ny))
        .flat_map(|j| (0..i32::from(root.nx)).map(move |i| (root.x + i, root.y + j)));
    push(root.level, &mut roots, t_max, &mut stack, &mut depth, stats);
    while depth > 0 {
        depth -= 1;
        let node = stack[depth];
        if node.t_in > t_max {
            continue;
        }
        if node.level == 0 {
            if let Some(t) = leaf(node.x, node.y, t_max, stats) {
                t_max = t;
            }
            continue;
        }
        let (x, y) = (node.x * 2, node.y * 2);
        let mut children = [(x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)].into_iter();
        push(
            node.level - 1,
            &mut children,
            t_max,
            &mut stack,
            &mut depth,
            stats,
        );
    }
}

/// The prism's uv triangle in cell units (`cell_size`: the uv side of a cell).
pub(crate) fn uv_in_cells<T: Real>(prism: &Prism<T>, cell_size: T) -> [[T; 2]; 3] {
    let cells_per_unit = T::ONE / cell_size;
    prism
        .uv
        .map(|t| [t.x() * cells_per_unit, t.y() * cells_per_unit])
}

/// Entry distance of the nonlinear ray into the texture-space box of node `(level, x, y)`
/// with heights `h` (the node test of nonlinear tracing).
#[allow(clippy::too_many_arguments)]
#[inline]
pub(crate) fn texture_box_entry<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    cell_size: T,
    (level, x, y): (u32, i32, i32),
    [h_lo, h_hi]: [T; 2],
    t_min: T,
    t_max: T,
) -> Option<T> {
    let k = 1i64 << level;
    let (cx0, cy0) = (i64::from(x) * k, i64::from(y) * k);
    let cell = |c: i64| T::from_f64(c as f64) * cell_size;
    intersect_box(
        prism,
        ray,
        [cell(cx0), cell(cy0), h_lo],
        [cell(cx0 + k), cell(cy0 + k), h_hi],
        t_min,
        t_max,
    )
    .map(|span| span.t_in)
}

/// `n` (a world normal from Eq. 13, any length and sign) as a unit vector facing against the
/// ray direction `dir`; `None` where it is zero (the shell degenerates to a line or point).
pub(crate) fn facing_unit<T: Real>(n: T::Vec3, dir: T::Vec3) -> Option<T::Vec3> {
    let len = n.length();
    if !(len > T::ZERO && len.is_finite()) {
        return None;
    }
    let n = n * (T::ONE / len);
    Some(if n.dot(dir) > T::ZERO { -n } else { n })
}
