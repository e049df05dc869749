//! The BLAS walk that displacement and shell mapping share (Ogaki 2023, sec. 4.4, 5.4): the
//! implicit quadtree over one base triangle's texture-space cells (texels of a height map,
//! tiles of an instanced object), traversed nearest first either by box tests
//! ([`traverse_cells`]) or along the nonlinear ray's texture-space curve ([`walk_cells`]).

use nlrt_poly::{Real, Vector2};
use nlrt_shellmap::{BaseEdges, NonlinearRay, Prism, TextureCurve, intersect_box};

use crate::stats::TraversalStats;
use crate::tlas::{RootNodes, texel_floor};

/// The side of a cell in texture units, and how the walk places the boundary `c` cells from
/// the origin: at `c * size` rounded in `T`, or, for a walk in `f64` of a surface whose cells
/// are placed in `f32` (the fallback for ill-conditioned prisms, see
/// `DisplacedSurface::intersect_blas`), at that product rounded to `f32` (it is exact in
/// `f64`: an integer below `2^23` times a 24-bit significand), so that the walk's split lines
/// are the cells' edges as the surface has them, bit for bit.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CellSize<T> {
    /// The side of a cell.
    pub(crate) size: T,
    /// Whether boundaries are rounded to `f32`.
    pub(crate) f32_lines: bool,
}

impl<T: Real> CellSize<T> {
    /// Boundaries rounded in `T`.
    pub(crate) fn new(size: T) -> Self {
        Self {
            size,
            f32_lines: false,
        }
    }

    /// The texture coordinate of the boundary `c` cells from the origin.
    #[inline]
    pub(crate) fn line(self, c: i64) -> T {
        let x = T::from_f64(c as f64) * self.size;
        if self.f32_lines {
            T::from_f64(f64::from(x.to_f64() as f32))
        } else {
            x
        }
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
pub fn traverse_cells<T: Real>(
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
/// A root node's stretch skips the levels that would not split it: where the curve's uv
/// enclosure over the stretch's heights ([`TextureCurve::uv_enclosure`], rounding included)
/// lies strictly inside the square of one descendant, the stretch goes straight to the
/// deepest such, clipped to its height bounds (which lie within every ancestor's, so the
/// levels between would have clipped nothing more). A big base triangle's roots are far
/// coarser than the part of the map one ray's stretch crosses; below the roots the
/// enclosure's two divisions per node cost more time than the levels they would skip.
///
/// Order and culling: along a stretch the distance is monotonic in the height where the
/// shell does not fold (a point of the ray has one height), so children are visited in
/// order of entry height in the stretch's direction, and distances are computed only when
/// they can cull: once a hit has set a finite `t_max`, or for stretches that began before
/// `t_min`, a stretch is skipped when the distances at its ends are both beyond `t_max` or
/// both before `t_min` (as in the box test, exact where the shell does not fold, a sample
/// where it does). Cells whose square misses the triangle's uv triangle (`walk.uv_tri`, in
/// cell units) are skipped; `leaf(x, y, h, t_max, stats)` tests a cell and returns the distance of
/// a hit nearer than `t_max`; `h` holds every height within the cell's height bounds at
/// which this piece of the curve is in the cell and in the prism, rounding windows included
/// (a cell met by several pieces is called once per piece).
///
/// Returns `false` when a node produced more pieces than the fixed stack holds (only
/// possible for curves running within rounding of many split lines at once): the caller then
/// finishes the triangle with [`traverse_cells`], whose answer does not depend on what the
/// leaves saw so far.
///
/// One flat loop over the stack of stretches; the steps it takes are [`CurveWalk`]'s:
/// `push_roots` (the virtual root), `beyond` (the distance cull), `whole_descent` (the
/// roots' level skip) and `split` (a node's stretch cut among its children).
pub(crate) fn traverse_curve_cells<T: Real>(
    stack: &mut [Stretch<T>],
    walk: &CurveWalk<'_, '_, T, impl Fn(u32, i32, i32) -> [T; 2]>,
    root_heights: [T; 2],
    t_min: T,
    t_best: &mut T,
    stats: &mut TraversalStats,
    mut leaf: impl FnMut(i32, i32, [T; 2], T, &mut TraversalStats) -> Option<T>,
) -> bool {
    let Some(mut depth) = walk.push_roots(stack, root_heights, t_min, *t_best, stats) else {
        return false;
    };
    let mut found = [Stretch::empty(); STRETCHES_PER_NODE];
    while depth > 0 {
        depth -= 1;
        let node = stack[depth];
        if walk.beyond(&node, t_min, *t_best) {
            continue;
        }
        if node.level == 0 {
            if let Some(t) = leaf(node.x, node.y, node.h, *t_best, stats) {
                *t_best = t;
            }
            continue;
        }
        if node.level == walk.root.level
            && let Some(deepest) = walk.whole_descent(&node)
        {
            // The stretch goes down whole: the walk would hand it to one child per level,
            // clipped to each level's height bounds, of which the innermost are kept here.
            if let Some(child) = walk.clipped(deepest, node.h, &node, stats) {
                stack[depth] = child;
                depth += 1;
            }
            continue;
        }
        let level = node.level - 1;
        let (x, y) = (node.x * 2, node.y * 2);
        let half = 1i64 << level;
        let lines = [
            Some(walk.cells.line(i64::from(x + 1) * half)),
            Some(walk.cells.line(i64::from(y + 1) * half)),
        ];
        let mut n = 0;
        if !walk.split(&node, lines, (level, x, y), &mut found, &mut n, stats)
            || depth + n > stack.len()
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

/// What every step of the curved walk of one base triangle reads: the roots, the ray's
/// texture-space curve and its base edges, the cells, the triangle's uv triangle in cell
/// units, and the height bounds of a node's content (`node_heights(level, x, y)`).
/// [`traverse_curve_cells`] walks it.
pub(crate) struct CurveWalk<'a, 'c, T: Real, N> {
    pub(crate) root: RootNodes,
    pub(crate) curve: &'a TextureCurve<'c, T>,
    pub(crate) edges: &'a BaseEdges<T>,
    pub(crate) cells: CellSize<T>,
    pub(crate) uv_tri: &'a CellTriangle<T>,
    pub(crate) node_heights: N,
}

impl<T: Real, N: Fn(u32, i32, i32) -> [T; 2]> CurveWalk<'_, '_, T, N> {
    /// Whether node `(level, x, y)` is in the root's texel range and may meet the uv
    /// triangle.
    #[inline(always)]
    fn wanted(&self, level: u32, x: i32, y: i32) -> bool {
        let k = 1i64 << level;
        let (cx0, cy0) = (i64::from(x) * k, i64::from(y) * k);
        let [r0, r1, r2, r3] = self.root.texels.map(i64::from);
        if cx0 > r2 || cy0 > r3 || cx0 + k <= r0 || cy0 + k <= r1 {
            return false;
        }
        let lo = [T::from_f64(cx0 as f64), T::from_f64(cy0 as f64)];
        let hi = [T::from_f64((cx0 + k) as f64), T::from_f64((cy0 + k) as f64)];
        self.uv_tri.meets_square(lo, hi)
    }

    /// `stretch` handed to node `(level, x, y)` with its heights `[h0, h1]` clipped to the
    /// node's height bounds; `None` where the node is not wanted or the clip is empty.
    #[inline(always)]
    fn clipped(
        &self,
        (level, x, y): (u32, i32, i32),
        [h0, h1]: [T; 2],
        stretch: &Stretch<T>,
        stats: &mut TraversalStats,
    ) -> Option<Stretch<T>> {
        if !self.wanted(level, x, y) {
            return None;
        }
        stats.box_tests += 1;
        let [lo, hi] = (self.node_heights)(level, x, y);
        let h = [h0.max(lo), h1.min(hi)];
        (h[0] <= h[1]).then_some(Stretch {
            level,
            x,
            y,
            h,
            ..*stretch
        })
    }

    /// Whether a stretch can be skipped by its distances (they are computed only when they
    /// can cull: once a hit has set a finite `t_best`, or for a stretch that began before
    /// `t_min`): both ends beyond `t_best` or both before `t_min`.
    #[inline]
    fn beyond(&self, node: &Stretch<T>, t_min: T, t_best: T) -> bool {
        (t_best < T::INFINITY || node.check_t_min)
            && matches!(
                (self.curve.distance(node.h[0]), self.curve.distance(node.h[1])),
                (Some(ta), Some(tb)) if ta.min(tb) > t_best || ta.max(tb) < t_min
            )
    }

    /// Where a root's stretch goes down whole: the deepest node whose square holds the
    /// curve's uv enclosure over the stretch's heights ([`deepest_holding`]); `None` where
    /// there is none (no enclosure, or a split line of the root meets it) and the stretch is
    /// split level by level.
    #[inline]
    fn whole_descent(&self, node: &Stretch<T>) -> Option<(u32, i32, i32)> {
        let e = self
            .curve
            .uv_enclosure(node.h[0], node.h[1])
            .filter(|e| e[0] <= e[1] && e[2] <= e[3])?;
        deepest_holding(node.level, node.x, node.y, e, self.cells)
    }

    /// Cuts `stretch` (heights `[a, b]`) at the crossings of the split lines (`None`: no line
    /// on that axis) and hands each piece to its child at `level`, `(x + qx, y + qy)`,
    /// clipped to the child's height bounds, nearest first into `found`; false when `found`
    /// is full.
    #[inline]
    fn split(
        &self,
        stretch: &Stretch<T>,
        lines: [Option<T>; 2],
        (level, x, y): (u32, i32, i32),
        found: &mut [Stretch<T>],
        n: &mut usize,
        stats: &mut TraversalStats,
    ) -> bool {
        let curve = self.curve;
        let [a, b] = stretch.h;
        // The stretch's ends and its crossings of the split lines, each with its window, in
        // increasing order (each line's crossings are; a tie keeps axis 0's first).
        let no_cuts = ([(T::ZERO, T::ZERO); 2], 0);
        let [(x_cuts, kx), (y_cuts, ky)] = core::array::from_fn(|axis| {
            lines[axis].map_or(no_cuts, |line| curve.crossings(axis, line, a, b))
        });
        let mut cuts = [(b, T::ZERO); 6];
        cuts[0] = (a, T::ZERO);
        let (mut i, mut j, mut m) = (0, 0, 1);
        while i < kx || j < ky {
            if j == ky || (i < kx && !(y_cuts[j].0 < x_cuts[i].0)) {
                cuts[m] = x_cuts[i];
                i += 1;
            } else {
                cuts[m] = y_cuts[j];
                j += 1;
            }
            m += 1;
        }
        // `cuts[m]` is the end `b`.
        m += 1;
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
            let middle = (c0 + c1) * T::HALF;
            for (k, line) in lines.iter().enumerate() {
                if let Some(line) = *line {
                    sides[k] = match curve.side_of_line(k, line, middle) {
                        Some(beyond) => [u8::from(beyond); 2],
                        None => [0, 1],
                    };
                }
            }
            let h = [(c0 - w0).max(a), (c1 + w1).min(b)];
            for qy in sides[1][0]..=sides[1][1] {
                for qx in sides[0][0]..=sides[0][1] {
                    let child = (level, x + i32::from(qx), y + i32::from(qy));
                    if let Some(child) = self.clipped(child, h, stretch, stats)
                        && !insert(found, n, child)
                    {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// The ray inside the prism (the curve inside the base triangle, its ends widened as
    /// the texel test widens them) at the roots' heights, as stretches of a virtual node
    /// whose children are the roots, in order of entry distance, split among the roots and
    /// pushed onto `stack`, nearest on top; the stack's depth, or `None` when a stack is
    /// full.
    fn push_roots(
        &self,
        stack: &mut [Stretch<T>],
        [h_lo, h_hi]: [T; 2],
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<usize> {
        let empty = Stretch::empty();
        let mut roots = [(empty, T::ZERO); 4];
        let mut n = 0;
        let mut complete = true;
        self.edges.stretches(h_lo, h_hi, |h_in, h_out| {
            let (t0, t1) = (self.curve.distance(h_in), self.curve.distance(h_out));
            let (t_lo, t_hi, ascending) = match (t0, t1) {
                (Some(a), Some(b)) => (a.min(b), a.max(b), b >= a),
                _ => (T::NEG_INFINITY, T::INFINITY, true),
            };
            if t_hi < t_min || t_lo > t_max {
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
            return None;
        }
        let root = self.root;
        let k = 1i64 << root.level;
        let lines = [
            (root.nx == 2).then(|| self.cells.line(i64::from(root.x + 1) * k)),
            (root.ny == 2).then(|| self.cells.line(i64::from(root.y + 1) * k)),
        ];
        let mut depth = 0;
        for (stretch, _) in roots[..n].iter().rev() {
            let mut found = [empty; STRETCHES_PER_NODE];
            let mut m = 0;
            let base = (root.level, root.x, root.y);
            if !self.split(stretch, lines, base, &mut found, &mut m, stats)
                || depth + m > stack.len()
            {
                return None;
            }
            for s in found[..m].iter().rev() {
                stack[depth] = *s;
                depth += 1;
            }
        }
        Some(depth)
    }
}

/// Sorted insertion into `found[..n]`, nearest first (few entries); false when full. A piece
/// for a child that already has one from the same stretch is merged into it (the hull of
/// their heights: a superset, which the leaf test allows). Without the merge a curve within
/// rounding of the split lines at every level (a ray grazing a long texel row, whose uv
/// errors are then large) sends two pieces to each child per level, and their number doubles
/// with depth; with it a node holds one stretch per stretch of its parent, so a walk visits
/// each node at most once per root stretch.
#[inline(always)]
fn insert<T: Real>(found: &mut [Stretch<T>], n: &mut usize, s: Stretch<T>) -> bool {
    let mut s = s;
    if let Some(j) = found[..*n]
        .iter()
        .position(|f| (f.level, f.x, f.y) == (s.level, s.x, s.y))
    {
        s.h = [found[j].h[0].min(s.h[0]), found[j].h[1].max(s.h[1])];
        found.copy_within(j + 1..*n, j);
        *n -= 1;
    }
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
}

/// The deepest node strictly below node `(level, x, y)` whose square holds the uv rectangle
/// `[u_lo, u_hi] x [v_lo, v_hi]` (`cells`: the cells' side and boundaries) as far as it lies in the
/// node's square: strictly inside the lines that bound it, except where they bound the node
/// too, as the walk's own line values (`cell(c)`) decide; the corners' cells only propose it.
/// `None` when a split line of the node itself meets the rectangle (or it is not a number).
fn deepest_holding<T: Real>(
    level: u32,
    x: i32,
    y: i32,
    [u_lo, u_hi, v_lo, v_hi]: [T; 4],
    cells: CellSize<T>,
) -> Option<(u32, i32, i32)> {
    let cell = |c: i64| cells.line(c);
    let k = 1i64 << level;
    let (x0, y0) = (i64::from(x) * k, i64::from(y) * k);
    let cell_units = T::ONE / cells.size;
    // The cell of `w` clamped to the node's cells `start..start + k` (NaN: `start`).
    let index = |w: T, start: i64| {
        let c = (w * cell_units).to_f64();
        if !(c >= (start + 1) as f64) {
            start
        } else if !(c < (start + k - 1) as f64) {
            start + k - 1
        } else {
            i64::from(texel_floor(c))
        }
    };
    let (ix, iy) = (index(u_lo, x0), index(v_lo, y0));
    let spread = (ix ^ index(u_hi, x0)) | (iy ^ index(v_hi, y0));
    let below = i64::BITS - spread.leading_zeros();
    if below >= level {
        return None;
    }
    let size = 1i64 << below;
    let (cx, cy) = (ix >> below, iy >> below);
    let between = |w_lo: T, w_hi: T, c: i64, start: i64| {
        let (lo, hi) = (c * size, (c + 1) * size);
        (lo == start || w_lo > cell(lo)) && (hi == start + k || w_hi < cell(hi))
    };
    (between(u_lo, u_hi, cx, x0) && between(v_lo, v_hi, cy, y0))
        .then_some((below, cx as i32, cy as i32))
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
    cells: CellSize<T>,
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
    let uv_tri = CellTriangle::new(uv_in_cells(prism, cells.size));
    let mut t = t_max;
    let mut stack = [Stretch::empty(); STACK_LEN];
    let walk = CurveWalk {
        root,
        curve,
        edges,
        cells,
        uv_tri: &uv_tri,
        node_heights: &node_heights,
    };
    let complete = traverse_curve_cells(
        &mut stack,
        &walk,
        [h_lo, h_hi],
        t_min,
        &mut t,
        stats,
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
                texture_box_entry(prism, curve.ray(), cells, (level, x, y), h, t_min, t_max)
            },
            |x, y, t_max, stats| leaf(x, y, [T::NEG_INFINITY, T::INFINITY], t_max, stats),
        );
    }
}

/// The prism's uv triangle in cell units (`cell_size`: the uv side of a cell).
#[must_use]
pub fn uv_in_cells<T: Real>(prism: &Prism<T>, cell_size: T) -> [[T; 2]; 3] {
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
    cells: CellSize<T>,
    (level, x, y): (u32, i32, i32),
    [h_lo, h_hi]: [T; 2],
    t_min: T,
    t_max: T,
) -> Option<T> {
    let k = 1i64 << level;
    let (cx0, cy0) = (i64::from(x) * k, i64::from(y) * k);
    let cell = |c: i64| cells.line(c);
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

/// A base triangle's uv triangle in cell units, set up for [`CellTriangle::meets_square`]:
/// per edge its normal, a point on it and the side the triangle lies on (computed once per
/// prism, not per node of the walk).
#[derive(Clone, Copy, Debug)]
pub struct CellTriangle<T> {
    /// Per edge: a point on it.
    points: [[T; 2]; 3],
    /// Per edge: its normal scaled by the side of the opposite corner (pointing inward), or
    /// zero for an edge that cannot separate (degenerate triangle): a zero normal projects
    /// every corner to exactly 0 with a zero bound, which neither separates nor contains.
    normals: [[T; 2]; 3],
}

impl<T: Real> CellTriangle<T> {
    /// Sets up the triangle `tri` (cell units).
    #[must_use]
    pub fn new(tri: [[T; 2]; 3]) -> Self {
        let gamma5 = gamma5::<T>();
        let normals = core::array::from_fn(|i| {
            let (a, b, c) = (tri[i], tri[(i + 1) % 3], tri[(i + 2) % 3]);
            let n = [a[1] - b[1], b[0] - a[0]];
            let (p0, p1) = (n[0] * (c[0] - a[0]), n[1] * (c[1] - a[1]));
            let side = p0 + p1;
            // Degenerate within rounding: this edge cannot separate.
            if !(side.abs() > gamma5 * (p0.abs() + p1.abs())) {
                return [T::ZERO; 2];
            }
            if side > T::ZERO { n } else { [-n[0], -n[1]] }
        });
        Self {
            points: tri,
            normals,
        }
    }

    /// Whether the axis-aligned square `[lo, hi]` may meet the triangle (separating axis
    /// test over the triangle's three edge normals; the box axes are covered by the root's
    /// texel range). Conservative: a separation is accepted only beyond a bound on the
    /// rounding error of the projections (`gamma(5)` times the sum of the magnitudes of their
    /// terms), so a square touching the triangle within rounding is kept. Degenerate
    /// triangles (a line or a point in uv) keep every square that the texel range allows
    /// along their degenerate direction.
    ///
    /// Per edge only one corner matters: the projection onto the edge's inward normal is
    /// linear, so no point of the square projects beyond the corner farthest along the
    /// normal (chosen by the normal's signs); when that corner is outside beyond its rounding
    /// bound, the whole square is outside exactly.
    #[inline]
    #[must_use]
    pub fn meets_square(&self, lo: [T; 2], hi: [T; 2]) -> bool {
        let gamma5 = gamma5::<T>();
        !(0..3).any(|e| {
            let (a, n) = (self.points[e], self.normals[e]);
            let far = |k: usize| if n[k] > T::ZERO { hi[k] } else { lo[k] };
            let (p0, p1) = (n[0] * (far(0) - a[0]), n[1] * (far(1) - a[1]));
            p0 + p1 < -gamma5 * (p0.abs() + p1.abs())
        })
    }
}

/// `gamma(5) = 5u / (1 - 5u)`: the relative error bound of the projections of
/// [`CellTriangle`] (a difference, two products, a sum).
#[inline(always)]
fn gamma5<T: Real>() -> T {
    let five_u = T::from_i32(5) * T::UNIT_ROUNDOFF;
    five_u / (T::ONE - five_u)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The jump target of a root stretch: the deepest node whose square holds the rectangle
    /// (nothing between it and the rectangle's sides but the node's own boundary), and none
    /// where a split line of the node itself meets the rectangle or it is not a number.
    #[test]
    fn the_jump_goes_to_the_deepest_node_holding_the_rectangle() {
        let cell_size = 1.0 / 256.0;
        let cell = |c: i64| c as f64 * cell_size;
        let (level, x, y) = (6u32, 1i32, 2i32);
        let (x0, y0, k) = (64i64, 128i64, 64i64);
        let mut r = crate::test_util::unit_randoms(7);
        let (mut jumps, mut deep) = (0, 0);
        for _ in 0..20_000 {
            // A rectangle inside the node, of a random size from a cell's fraction to the node.
            let size = cell(k) * 2f64.powf(-10.0 * r());
            let (u_lo, v_lo) = (
                cell(x0) + r() * (cell(k) - size),
                cell(y0) + r() * (cell(k) - size),
            );
            let e = [u_lo, u_lo + size * r(), v_lo, v_lo + size * r()];
            match deepest_holding(level, x, y, e, CellSize::new(cell_size)) {
                Some((l, cx, cy)) => {
                    jumps += 1;
                    assert!(l < level, "{e:?}");
                    let n = 1i64 << l;
                    let (a, b) = (i64::from(cx) * n, i64::from(cy) * n);
                    assert!(
                        (x0..x0 + k).contains(&a) && (y0..y0 + k).contains(&b),
                        "{e:?}"
                    );
                    assert!(
                        e[0] >= cell(a) && e[1] <= cell(a + n),
                        "{e:?} in {l} {cx} {cy}"
                    );
                    assert!(
                        e[2] >= cell(b) && e[3] <= cell(b + n),
                        "{e:?} in {l} {cx} {cy}"
                    );
                    if l > 0 {
                        // Deepest: one of the target's own split lines meets the rectangle.
                        let (mu, mv) = (cell(a + n / 2), cell(b + n / 2));
                        assert!(
                            (e[0] <= mu && mu <= e[1]) || (e[2] <= mv && mv <= e[3]),
                            "{e:?}: {l} {cx} {cy} is not the deepest"
                        );
                    } else {
                        deep += 1;
                    }
                }
                None => {
                    let (mu, mv) = (cell(x0 + k / 2), cell(y0 + k / 2));
                    assert!(
                        (e[0] <= mu && mu <= e[1]) || (e[2] <= mv && mv <= e[3]),
                        "{e:?}: a jump was possible"
                    );
                }
            }
        }
        assert!(
            jumps > 10_000 && deep > 100,
            "{jumps} jumps, {deep} to a cell"
        );
        let nan = [f64::NAN, f64::NAN, cell(y0), cell(y0) + 0.001];
        assert_eq!(
            deepest_holding(level, x, y, nan, CellSize::new(cell_size)),
            None
        );
    }

    /// The uv-triangle test of the walk keeps every square that holds a point of the
    /// triangle (sampled on a fine grid, squares touching it included) and drops squares
    /// clearly apart from it; a degenerate triangle (a segment) drops nothing that the
    /// segment's line meets.
    #[test]
    fn squares_meeting_the_uv_triangle_are_kept() {
        let triangles = [
            [[0.3, 0.2], [7.6, 1.1], [2.5, 6.8]],
            [[5.0, 5.0], [1.0, 6.0], [6.5, 0.5]],
            [[0.0, 0.0], [8.0, 0.0], [0.0, 8.0]],
            [[1.0, 1.0], [7.0, 7.0], [4.0, 4.0]], // a segment
        ];
        for tri in triangles {
            let cells = CellTriangle::new(tri);
            let inside = |p: [f64; 2]| {
                let [a, b, c] = tri;
                let cross = |u: [f64; 2], v: [f64; 2]| {
                    (v[0] - u[0]) * (p[1] - u[1]) - (v[1] - u[1]) * (p[0] - u[0])
                };
                let (d0, d1, d2) = (cross(a, b), cross(b, c), cross(c, a));
                (d0 >= 0.0 && d1 >= 0.0 && d2 >= 0.0) || (d0 <= 0.0 && d1 <= 0.0 && d2 <= 0.0)
            };
            let (mut kept, mut dropped) = (0, 0);
            for y in -2..10 {
                for x in -2..10 {
                    let (lo, hi) = (
                        [f64::from(x), f64::from(y)],
                        [f64::from(x + 1), f64::from(y + 1)],
                    );
                    let touched = (0..=16).any(|j| {
                        (0..=16).any(|i| {
                            inside([lo[0] + f64::from(i) / 16.0, lo[1] + f64::from(j) / 16.0])
                        })
                    });
                    let meets = cells.meets_square(lo, hi);
                    assert!(meets || !touched, "{tri:?}: square {lo:?} holds a point");
                    // All four corners clearly beyond one edge's line (away from the third
                    // vertex): that edge separates, so the square must go. (Squares apart
                    // only along a box axis are left to the root's texel range.)
                    let corners = [lo, [hi[0], lo[1]], [lo[0], hi[1]], hi];
                    let beyond_an_edge = (0..3).any(|e| {
                        let (a, b, c) = (tri[e], tri[(e + 1) % 3], tri[(e + 2) % 3]);
                        let side = |p: [f64; 2]| {
                            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
                        };
                        let s = side(c);
                        s != 0.0 && corners.iter().all(|&p| side(p) * s.signum() < -0.01)
                    });
                    if beyond_an_edge {
                        assert!(!meets, "{tri:?}: square {lo:?} is beyond an edge");
                    }
                    if meets { kept += 1 } else { dropped += 1 }
                }
            }
            assert!(kept > 0 && (dropped > 0 || tri[2] == [4.0, 4.0]), "{tri:?}");
        }
    }
}
