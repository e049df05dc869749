//! What displacement and shell mapping share: the TLAS over a base mesh's prisms (built on the
//! fly, one per leaf) with each triangle's root cells, and the implicit quadtree over
//! texture-space cells (texels of a height map, tiles of an instanced object) traversed by a
//! nonlinear ray nearest first.

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{BaseEdges, NonlinearRay, Prism, Ray, TextureCurve, intersect_box};

use crate::bvh::{Bvh4, SlabRay};
use crate::displacement::{
    CellTriangle, MAX_TEXEL_COORDINATE, RootNodes, TraversalStats, root_nodes,
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
    uv_tri: &CellTriangle<T>,
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
            if !uv_tri.meets_square(lo, hi) {
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

/// A stretch of a nonlinear ray's curve inside a node's uv square: the node, the heights
/// `h` of the stretch (clipped to the node's height bounds), the direction in which the
/// distance along the ray grows with the height, and whether its distances must be checked
/// against `t_min` (its root stretch began before it).
#[derive(Clone, Copy)]
pub(crate) struct Stretch<T> {
    level: u32,
    x: i32,
    y: i32,
    h: [T; 2],
    ascending: bool,
    check_t_min: bool,
}

impl<T: Real> Stretch<T> {
    /// An unused entry (all zero bits: arrays of it are initialised by a memset).
    fn empty() -> Self {
        Self {
            level: 0,
            x: 0,
            y: 0,
            h: [T::ZERO; 2],
            ascending: false,
            check_t_min: false,
        }
    }

    /// Sort key, nearest first: the height at which the curve enters, signed by direction.
    fn order(&self) -> T {
        if self.ascending {
            self.h[0]
        } else {
            -self.h[1]
        }
    }
}

/// Stretches one node may hand to its children before the traversal gives up on stretches
/// (see [`traverse_curve_cells`]): a stretch meets each of the two split lines at most twice
/// (they are quadratics), so it falls into at most 5 pieces, each in one child; only a piece
/// within rounding of a split line goes to both sides.
const STRETCHES_PER_NODE: usize = 8;
/// Entries of the stretch stack. A walk holds at most the pending siblings of each level on
/// its path, typically one or two (a stretch crosses few split lines); the worst case, 7 per
/// level, would make the stack 5 KiB, which costs more to initialise per prism than the walk
/// of a thick shell's many prisms. So it is sized for 3 per level of a 4096^2 map (12
/// levels) and the rare walk that needs more is finished by the box-test traversal
/// (`walk_cells`), counted in [`TraversalStats::fallbacks`].
pub(crate) const CURVE_STACK: usize = 48;

/// The implicit quadtree over the cells of one base triangle walked along the nonlinear ray's
/// texture-space curve, nearest first (the BLAS traversal of Ogaki 2023, sec. 4.4, without a
/// box test per node).
///
/// It starts from the heights at which the ray is inside the prism ([`BaseEdges::stretches`]
/// on `root_heights`, the roots' height bounds; no separate ray-prism test is needed). A
/// node's stretch is cut where the curve crosses the node's two split lines (the roots of two
/// quadratics on the stretch's height interval,
/// [`TextureCurve::crossings`]); between two cuts the curve stays on one side of each line,
/// so whatever of the piece lies in the node's square lies in one child, found from the
/// piece's midpoint, and the piece goes there with its heights clipped to the child's height
/// bounds: a child whose bounds miss the piece's heights cannot hold a hit there. The roots
/// are the children of a virtual node split between them. Two quadratics per node replace
/// the four box tests of the children (each up to five quadratics). Rounding is covered as
/// in the box test: a piece's ends at a crossing are widened by the crossing's error window,
/// and a piece whose midpoint is within the rounding bound of a split line goes to both
/// sides (a curve running along a texel edge).
///
/// Order and culling: along a stretch the distance is monotonic in the height where the
/// shell does not fold (a point of the ray has one height), so children are visited in
/// order of entry height in the stretch's direction, and distances are computed only when
/// they can cull: once a hit has set a finite `t_max`, or for stretches that began before
/// `t_min`, a stretch is skipped when the distances at its ends are both beyond `t_max` or
/// both before `t_min` (as in the box test, exact where the shell does not fold, a sample
/// where it does). Cells whose square misses the triangle's uv triangle `uv_tri` (in cell
/// units) are skipped; `leaf(x, y, h, t_max, stats)` tests a cell and returns the distance of
/// a hit nearer than `t_max`; `h` holds every height within the cell's height bounds at
/// which this piece of the curve is in the cell and in the prism, rounding windows included
/// (a cell met by several pieces is called once per piece).
///
/// Returns `false` when a node produced more pieces than the fixed stack holds (only
/// possible for curves running within rounding of many split lines at once): the caller then
/// finishes the triangle with [`traverse_cells`], whose answer does not depend on what the
/// leaves saw so far.
#[allow(clippy::too_many_arguments)]
pub(crate) fn traverse_curve_cells<T: Real>(
    stack: &mut [Stretch<T>],
    root: RootNodes,
    root_heights: [T; 2],
    curve: &TextureCurve<'_, T>,
    edges: &BaseEdges<T>,
    cell_size: T,
    uv_tri: &CellTriangle<T>,
    t_min: T,
    t_max: &mut T,
    stats: &mut TraversalStats,
    node_heights: impl Fn(u32, i32, i32) -> [T; 2],
    mut leaf: impl FnMut(i32, i32, [T; 2], T, &mut TraversalStats) -> Option<T>,
) -> bool {
    let empty = Stretch::empty();
    let mut depth = 0;
    let cell = |c: i64| T::from_f64(c as f64) * cell_size;
    // Whether node (level, x, y) is in the root's texel range and may meet the uv triangle.
    let wanted = |level: u32, x: i32, y: i32| {
        let k = 1i64 << level;
        let (cx0, cy0) = (i64::from(x) * k, i64::from(y) * k);
        let [r0, r1, r2, r3] = root.texels.map(i64::from);
        if cx0 > r2 || cy0 > r3 || cx0 + k <= r0 || cy0 + k <= r1 {
            return false;
        }
        let lo = [T::from_f64(cx0 as f64), T::from_f64(cy0 as f64)];
        let hi = [T::from_f64((cx0 + k) as f64), T::from_f64((cy0 + k) as f64)];
        uv_tri.meets_square(lo, hi)
    };
    // Sorted insertion, nearest first (few entries); false when full.
    let insert = |found: &mut [Stretch<T>], n: &mut usize, s: Stretch<T>| -> bool {
        if *n == found.len() {
            return false;
        }
        let mut i = *n;
        while i > 0 && found[i - 1].order() > s.order() {
            found[i] = found[i - 1];
            i -= 1;
        }
        found[i] = s;
        *n += 1;
        true
    };
    // Cuts `stretch` (heights `[a, b]`) at the crossings of the split lines (`None`: no line
    // on that axis) and hands each piece to its child at `level`, `(x + qx, y + qy)`, clipped
    // to the child's height bounds, nearest first into `found`; false when `found` is full.
    let split = |stretch: &Stretch<T>,
                 lines: [Option<T>; 2],
                 (level, x, y): (u32, i32, i32),
                 found: &mut [Stretch<T>],
                 n: &mut usize,
                 stats: &mut TraversalStats|
     -> bool {
        let [a, b] = stretch.h;
        // The stretch's ends and its crossings of the split lines, each with its window.
        let mut cuts = [(a, T::ZERO); 6];
        let mut m = 1;
        for (axis, line) in lines.iter().enumerate() {
            if let Some(line) = *line {
                let (roots, k) = curve.crossings(axis, line, a, b);
                for &r in &roots[..k] {
                    cuts[m] = r;
                    m += 1;
                }
            }
        }
        cuts[m] = (b, T::ZERO);
        m += 1;
        let cuts = &mut cuts[..m];
        cuts.sort_unstable_by(|p, q| p.0.partial_cmp(&q.0).unwrap_or(core::cmp::Ordering::Equal));
        for i in 0..m - 1 {
            let ((c0, w0), (c1, w1)) = (cuts[i], cuts[i + 1]);
            // Zero-length pieces lie on a cut; a stretch that is one point is one piece.
            if !(c1 > c0 || (a == b && i == 0)) {
                continue;
            }
            // Children on each axis: first and last of {0, 1}. Between two cuts the piece
            // stays on one side of each line (the inside of the node's square is then in one
            // child; what lies outside the square is never inside a child's).
            let mut sides = [[0u8, 0]; 2];
            let uv = curve.uv_with_error((c0 + c1) * T::HALF);
            for (k, line) in lines.iter().enumerate() {
                if let Some(line) = *line {
                    sides[k] = match uv {
                        Some((uv, e)) => [
                            u8::from(uv[k] > line + e[k]),
                            u8::from(uv[k] >= line - e[k]),
                        ],
                        None => [0, 1],
                    };
                }
            }
            let (lo_h, hi_h) = ((c0 - w0).max(a), (c1 + w1).min(b));
            for qy in sides[1][0]..=sides[1][1] {
                for qx in sides[0][0]..=sides[0][1] {
                    let (cx, cy) = (x + i32::from(qx), y + i32::from(qy));
                    if !wanted(level, cx, cy) {
                        continue;
                    }
                    stats.box_tests += 1;
                    let [lo, hi] = node_heights(level, cx, cy);
                    let (h0, h1) = (lo_h.max(lo), hi_h.min(hi));
                    if !(h0 <= h1) {
                        continue;
                    }
                    let child = Stretch {
                        level,
                        x: cx,
                        y: cy,
                        h: [h0, h1],
                        ..*stretch
                    };
                    if !insert(found, n, child) {
                        return false;
                    }
                }
            }
        }
        true
    };
    {
        // The ray inside the prism (the curve inside the base triangle, its ends widened as
        // the texel test widens them) at the roots' heights, as stretches of a virtual node
        // whose children are the roots, in order of entry distance.
        let [h_lo, h_hi] = root_heights;
        let mut roots = [(empty, T::ZERO); 4];
        let mut n = 0;
        let mut complete = true;
        edges.stretches(h_lo, h_hi, |h_in, h_out| {
            let (t0, t1) = (curve.distance(h_in), curve.distance(h_out));
            let (t_lo, t_hi, ascending) = match (t0, t1) {
                (Some(a), Some(b)) => (a.min(b), a.max(b), b >= a),
                _ => (T::NEG_INFINITY, T::INFINITY, true),
            };
            if t_hi < t_min || t_lo > *t_max {
                return;
            }
            if n == roots.len() {
                complete = false;
                return;
            }
            let stretch = Stretch {
                h: [h_in, h_out],
                ascending,
                check_t_min: !(t_lo >= t_min),
                ..empty
            };
            let mut i = n;
            while i > 0 && roots[i - 1].1 > t_lo {
                roots[i] = roots[i - 1];
                i -= 1;
            }
            roots[i] = (stretch, t_lo);
            n += 1;
        });
        if !complete {
            return false;
        }
        let k = 1i64 << root.level;
        let lines = [
            (root.nx == 2).then(|| cell(i64::from(root.x + 1) * k)),
            (root.ny == 2).then(|| cell(i64::from(root.y + 1) * k)),
        ];
        for (stretch, _) in roots[..n].iter().rev() {
            let mut found = [empty; STRETCHES_PER_NODE];
            let mut m = 0;
            let base = (root.level, root.x, root.y);
            if !split(stretch, lines, base, &mut found, &mut m, stats) || depth + m > stack.len() {
                return false;
            }
            for s in found[..m].iter().rev() {
                stack[depth] = *s;
                depth += 1;
            }
        }
    }
    while depth > 0 {
        depth -= 1;
        let node = stack[depth];
        if (*t_max < T::INFINITY || node.check_t_min)
            && let (Some(ta), Some(tb)) = (curve.distance(node.h[0]), curve.distance(node.h[1]))
            && (ta.min(tb) > *t_max || ta.max(tb) < t_min)
        {
            continue;
        }
        if node.level == 0 {
            if let Some(t) = leaf(node.x, node.y, node.h, *t_max, stats) {
                *t_max = t;
            }
            continue;
        }
        let level = node.level - 1;
        let (x, y) = (node.x * 2, node.y * 2);
        let half = 1i64 << level;
        let lines = [
            Some(cell(i64::from(x + 1) * half)),
            Some(cell(i64::from(y + 1) * half)),
        ];
        let mut found = [empty; STRETCHES_PER_NODE];
        let mut n = 0;
        if !split(&node, lines, (level, x, y), &mut found, &mut n, stats) || depth + n > stack.len()
        {
            return false;
        }
        for s in found[..n].iter().rev() {
            stack[depth] = *s;
            depth += 1;
        }
    }
    true
}

/// The nonlinear BLAS walk of one base triangle shared by displacement and shell mapping:
/// [`traverse_curve_cells`], finished by the box-test traversal [`traverse_cells`] in the
/// rare case it gives up. `node_heights(level, x, y)` bounds the heights of a node's
/// content; `leaf(x, y, h, t_max, stats)` as in [`traverse_curve_cells`] (after a fallback
/// `h` is every height).
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk_cells<T: Real, const STACK_LEN: usize>(
    root: RootNodes,
    prism: &Prism<T>,
    curve: &TextureCurve<'_, T>,
    edges: &BaseEdges<T>,
    cell_size: T,
    t_min: T,
    t_max: T,
    stats: &mut TraversalStats,
    node_heights: impl Fn(u32, i32, i32) -> [T; 2],
    mut leaf: impl FnMut(i32, i32, [T; 2], T, &mut TraversalStats) -> Option<T>,
) {
    // The roots' heights, and the cheap rejection of a prism the ray misses (most of the
    // overlapping boxes of a thick shell's prisms) before anything else is set up.
    let (mut h_lo, mut h_hi) = (T::INFINITY, T::NEG_INFINITY);
    for j in 0..i32::from(root.ny) {
        for i in 0..i32::from(root.nx) {
            let [lo, hi] = node_heights(root.level, root.x + i, root.y + j);
            h_lo = h_lo.min(lo);
            h_hi = h_hi.max(hi);
        }
    }
    if !(h_lo <= h_hi) || edges.misses(h_lo, h_hi) {
        return;
    }
    let uv_tri = CellTriangle::new(uv_in_cells(prism, cell_size));
    let mut t = t_max;
    let mut stack = [Stretch::empty(); STACK_LEN];
    let complete = traverse_curve_cells(
        &mut stack,
        root,
        [h_lo, h_hi],
        curve,
        edges,
        cell_size,
        &uv_tri,
        t_min,
        &mut t,
        stats,
        &node_heights,
        &mut leaf,
    );
    if !complete {
        stats.fallbacks += 1;
        traverse_cells(
            root,
            &uv_tri,
            t,
            stats,
            |level, x, y, t_max| {
                let h = node_heights(level, x, y);
                texture_box_entry(
                    prism,
                    curve.ray(),
                    cell_size,
                    (level, x, y),
                    h,
                    t_min,
                    t_max,
                )
            },
            |x, y, t_max, stats| leaf(x, y, [T::NEG_INFINITY, T::INFINITY], t_max, stats),
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
