//! Affine patches: which base triangles share one affine map from texel space to the world,
//! their texel frames and triangles, and a ray's straight line in a patch (see the parent
//! module).

use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Prism, Ray, onto_base_triangle};

use crate::mesh::BaseMesh;

/// The relative difference within which two triangles' affine maps are taken as one map (a
/// patch traced in one frame), in units of `T`'s unit roundoff: vertices given in `T` carry
/// half an ulp of rounding each, which a frame fitted on three spanning vertices of a patch
/// carries to the others with a factor of a few; 16 leaves room for that, and a triangle
/// traced in its patch's frame then lies within 16 units of roundoff of its own vertices (a
/// modeller's crease or fold is many orders larger). Never below [`MIN_SAME_MAP`].
const SAME_MAP_ROUNDOFFS: f64 = 16.0;

/// The floor of the same-map tolerance: the `f64` error of a frame whose condition is below
/// [`MAX_FRAME_CONDITION`] (condition times a few units of `2^-53`) stays below `2^-40`.
const MIN_SAME_MAP: f64 = 1.0 / (1u64 << 40) as f64;

/// The same-map tolerance for vertices given in a precision of unit roundoff `roundoff`
/// (relative).
fn same_map(roundoff: f64) -> f64 {
    (SAME_MAP_ROUNDOFFS * roundoff).max(MIN_SAME_MAP)
}

/// Frames more ill-conditioned than this (the displacement direction nearly in the base
/// plane) are traced on the curved path: `2^10` keeps the inverse's `f64` error (condition
/// times a few units of `2^-53`) below [`MIN_SAME_MAP`] by a factor of more than `2^2`.
const MAX_FRAME_CONDITION: f64 = 1024.0;

/// No patch: the triangle is traced on the curved path.
const CURVED: u32 = u32::MAX;

/// The map between the world and a patch's texel space `(x, y, h)`: world
/// `p = origin + A (x, y, h)`, and back `q = to_texel (p - origin)`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct TexelFrame {
    /// Columns of `A`: the world step per texel along `x`, along `y`, and the displacement
    /// direction (times the height scale) per unit height.
    columns: [[f64; 3]; 3],
    /// `A^-1`, by rows.
    to_texel: [[f64; 3]; 3],
    /// The world point of texel-space `(0, 0, 0)`.
    origin: [f64; 3],
}

fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm3(a: [f64; 3]) -> f64 {
    dot3(a, a).sqrt()
}

fn to_array<T: Real>(v: T::Vec3) -> [f64; 3] {
    [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()]
}

impl TexelFrame {
    /// The frame of `prism` (uvs tiled, directions scaled) on a map of `side` texels per unit,
    /// or `None` where its three directions differ in a bit, its uv triangle is degenerate or
    /// the frame's condition exceeds [`MAX_FRAME_CONDITION`].
    fn of_prism<T: Real>(prism: &Prism<T>, side: f64) -> Option<Self> {
        if prism.n[0] != prism.n[1] || prism.n[0] != prism.n[2] {
            return None;
        }
        let x = prism
            .uv
            .map(|uv| [uv.x().to_f64() * side, uv.y().to_f64() * side]);
        Self::of_points(prism.p.map(to_array::<T>), x, to_array::<T>(prism.n[0]))
    }

    /// The affine map carrying texel points `x` (height 0) onto world points `p`, with the
    /// displacement direction `n` per unit height; `None` as [`TexelFrame::of_prism`].
    fn of_points(p: [[f64; 3]; 3], x: [[f64; 2]; 3], n: [f64; 3]) -> Option<Self> {
        let (e1, e2) = (
            [x[1][0] - x[0][0], x[1][1] - x[0][1]],
            [x[2][0] - x[0][0], x[2][1] - x[0][1]],
        );
        let det_uv = e1[0] * e2[1] - e2[0] * e1[1];
        if !(det_uv != 0.0 && det_uv.is_finite()) {
            return None;
        }
        // (alpha, beta) = inverse(e1 e2) (x - x0): its rows.
        let inv = [
            [e2[1] / det_uv, -e2[0] / det_uv],
            [-e1[1] / det_uv, e1[0] / det_uv],
        ];
        let (f1, f2) = (sub3(p[1], p[0]), sub3(p[2], p[0]));
        let along = |j: usize| -> [f64; 3] {
            core::array::from_fn(|k| f1[k] * inv[0][j] + f2[k] * inv[1][j])
        };
        let columns = [along(0), along(1), n];
        let origin: [f64; 3] =
            core::array::from_fn(|k| p[0][k] - columns[0][k] * x[0][0] - columns[1][k] * x[0][1]);
        let rows = [
            cross3(columns[1], columns[2]),
            cross3(columns[2], columns[0]),
            cross3(columns[0], columns[1]),
        ];
        let det = dot3(columns[0], rows[0]);
        let volume = norm3(columns[0]) * norm3(columns[1]) * norm3(columns[2]);
        if !(det.abs() * MAX_FRAME_CONDITION > volume && det.is_finite()) {
            return None;
        }
        let to_texel = rows.map(|r| r.map(|v| v / det));
        Some(Self {
            columns,
            to_texel,
            origin,
        })
    }

    /// Whether this map carries `prism`'s three corners onto its vertices within the
    /// same-map tolerance of `T` and its displacement direction is this one's, bit for bit.
    fn holds<T: Real>(&self, prism: &Prism<T>, side: f64, roundoff: f64) -> bool {
        let n = to_array::<T>(prism.n[0]);
        if prism.n.iter().any(|m| to_array::<T>(*m) != self.columns[2]) || n != self.columns[2] {
            return false;
        }
        (0..3).all(|i| {
            let (x, y) = (
                prism.uv[i].x().to_f64() * side,
                prism.uv[i].y().to_f64() * side,
            );
            let p = to_array::<T>(prism.p[i]);
            (0..3).all(|k| {
                let a = self.columns[0][k] * x;
                let b = self.columns[1][k] * y;
                let mapped = self.origin[k] + a + b;
                let scale = self.origin[k].abs() + a.abs() + b.abs() + p[k].abs();
                (mapped - p[k]).abs() <= same_map(roundoff) * scale
            })
        })
    }
}

/// One triangle of a patch in texel space: its corners, its edges for deciding which hits it
/// owns, and the map back to its canonical coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TexelTriangle<T> {
    pub(super) corners: [[T; 2]; 3],
    /// Per edge `k` (corners `k`, `k + 1`): its corners in canonical order (the smaller
    /// `(x, y)` first), whether the triangle lies where the edge function is positive, and
    /// the edge's length where it is open (shared with a triangle outside the patch, which
    /// sees another line or a curve: hits up to the walk's window beyond it are owned), 0
    /// where it is closed (shared inside the patch, decided exactly, or the mesh's border).
    edges: [([T; 2], [T; 2], bool, T); 3],
    /// Rows of the map from `(x, y) - corners[0]` to `(alpha, beta)`.
    to_canonical: [[f64; 2]; 2],
}

/// The edge function of `(a, b)` at `q`, with plain products: the same number for the same
/// arguments in every triangle.
#[inline]
fn edge_function<T: Real>(a: [T; 2], b: [T; 2], q: [T; 2]) -> T {
    let p = (b[0] - a[0]) * (q[1] - a[1]);
    let r = (b[1] - a[1]) * (q[0] - a[0]);
    p - r
}

impl<T: Real> TexelTriangle<T> {
    /// The triangle of `prism` on a map of `side` texels per unit, with its edges `k`
    /// (corners `k`, `k + 1`) open where `open[k]`.
    pub(super) fn new(prism: &Prism<T>, side: T, open: [bool; 3]) -> Self {
        let corners = prism.uv.map(|uv| [uv.x() * side, uv.y() * side]);
        let wide = corners.map(|c| [c[0].to_f64(), c[1].to_f64()]);
        let edges = core::array::from_fn(|k| {
            let (a, b) = (corners[k], corners[(k + 1) % 3]);
            let (a, b) = if (a[0], a[1]) < (b[0], b[1]) {
                (a, b)
            } else {
                (b, a)
            };
            let (aw, bw) = (
                [a[0].to_f64(), a[1].to_f64()],
                [b[0].to_f64(), b[1].to_f64()],
            );
            let c = wide[(k + 2) % 3];
            let side = (bw[0] - aw[0]) * (c[1] - aw[1]) - (bw[1] - aw[1]) * (c[0] - aw[0]);
            let length = if open[k] {
                {
                    let (dx, dy) = (bw[0] - aw[0], bw[1] - aw[1]);
                    T::from_f64((dx * dx + dy * dy).sqrt())
                }
            } else {
                T::ZERO
            };
            (a, b, side > 0.0, length)
        });
        let (e1, e2) = (
            [wide[1][0] - wide[0][0], wide[1][1] - wide[0][1]],
            [wide[2][0] - wide[0][0], wide[2][1] - wide[0][1]],
        );
        let det = e1[0] * e2[1] - e2[0] * e1[1];
        let to_canonical = [[e2[1] / det, -e2[0] / det], [-e1[1] / det, e1[0] / det]];
        Self {
            corners,
            edges,
            to_canonical,
        }
    }

    /// Whether the texel point `q` lies in the triangle or on its edges, or beyond an open
    /// edge by at most `window` texels (a finite bound on the error of `q`).
    #[inline]
    pub(super) fn owns(&self, q: [T; 2], window: T) -> bool {
        self.edges.iter().all(|&(a, b, positive, length)| {
            // The edge function is the distance from the edge times its length; a closed
            // edge's length is 0, so its bound is 0 (the exact decision).
            let e = edge_function(a, b, q);
            let slack = window * length;
            if positive { e >= -slack } else { e <= slack }
        })
    }

    /// Whether any edge is open.
    #[cfg(test)]
    pub(super) fn has_open_edge(&self) -> bool {
        self.edges.iter().any(|e| e.3 > T::ZERO)
    }

    /// `(alpha, beta)` of the texel point `q`, moved onto the triangle: computed in `f64`
    /// (once per hit), where a thin uv triangle's inverse does not overflow as it may in
    /// `f32`; a coordinate that is still not finite (a uv triangle thinner than `f64` sees) is
    /// taken as 0.
    pub(crate) fn canonical(&self, q: [T; 2]) -> (T, T) {
        let c = self.corners[0];
        let d = [q[0].to_f64() - c[0].to_f64(), q[1].to_f64() - c[1].to_f64()];
        let m = &self.to_canonical;
        let finite = |v: f64| if v.is_finite() { v } else { 0.0 };
        let (alpha, beta) = onto_base_triangle(
            finite(m[0][0] * d[0] + m[0][1] * d[1]),
            finite(m[1][0] * d[0] + m[1][1] * d[1]),
        );
        let (alpha, beta) = (T::from_f64(alpha), T::from_f64(beta));
        // Rounding to `T` may carry the sum 1 ulp past 1.
        onto_base_triangle(alpha, beta)
    }
}

/// The affine patches of a mesh: per triangle its patch (or the curved path) and its texel
/// triangle, per patch the frame all its triangles are traced in.
#[derive(Clone, Debug)]
pub(crate) struct AffinePatches<T> {
    patch_of: Vec<u32>,
    frames: Vec<TexelFrame>,
    /// Per patch, its texel-space box `[x0, y0, x1, y1]` (heights `[0, 1]`): where each ray's
    /// line is rebased, the same point for every triangle of the patch.
    boxes: Vec<[f64; 4]>,
    triangles: Vec<Option<TexelTriangle<T>>>,
}

/// A base edge as patches are found: its two positions' bits (the smaller first), its
/// triangle, the uvs' bits at those positions, its index in the triangle (corners `k`,
/// `k + 1`).
type EdgeKey = ([[u64; 3]; 2], u32, [[u64; 2]; 2], u8);

/// Whether a group of edges with the same two positions is one edge shared by two triangles
/// with the same uvs at its ends (a manifold edge inside one uv chart).
fn is_clean_pair(group: &[EdgeKey]) -> bool {
    group.len() == 2 && group[0].1 != group[1].1 && group[0].2 == group[1].2
}

/// Union-find root with path halving.
fn find(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        let p = parent[parent[i as usize] as usize];
        parent[i as usize] = p;
        i = p;
    }
    i
}

impl<T: Real> AffinePatches<T> {
    /// The patches of `mesh` displaced by `height_scale` with uvs times `uv_scale`, on a grid
    /// of `side` texels per unit.
    pub(crate) fn find(mesh: &BaseMesh<T>, height_scale: T, uv_scale: [T; 2], side: usize) -> Self {
        let prisms: Vec<Prism<T>> = (0..mesh.triangle_count())
            .map(|i| mesh.prism(i, height_scale, uv_scale))
            .collect();
        Self::from_prisms(&prisms, side, T::UNIT_ROUNDOFF.to_f64())
    }

    /// The patches of the base triangles' `prisms` (uvs tiled, directions scaled) on a grid
    /// of `side` texels per unit, their vertices given to a unit roundoff of `roundoff` (that
    /// of `T`, or of a narrower type they were widened from exactly).
    pub(crate) fn from_prisms(prisms: &[Prism<T>], side: usize, roundoff: f64) -> Self {
        let count = prisms.len();
        let side_f = side as f64;
        let frames: Vec<Option<TexelFrame>> = prisms
            .iter()
            .map(|p| TexelFrame::of_prism(p, side_f))
            .collect();
        if frames.iter().all(Option::is_none) {
            // No affine prism (a smooth curved mesh, every pose of an animation): no patch,
            // and no edge to sort.
            return Self {
                patch_of: vec![CURVED; count],
                frames: Vec::new(),
                boxes: Vec::new(),
                triangles: vec![None; count],
            };
        }
        // Edges keyed by their two positions' bits (the smaller key first), with the uvs at
        // those positions: triangles meeting there share the edge.
        let key = |v: T::Vec3| to_array::<T>(v).map(f64::to_bits);
        let mut edges: Vec<EdgeKey> = Vec::with_capacity(3 * count);
        for (i, prism) in prisms.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (k, (k + 1) % 3);
                let uv = |j: usize| {
                    [
                        prism.uv[j].x().to_f64().to_bits(),
                        prism.uv[j].y().to_f64().to_bits(),
                    ]
                };
                let (ka, kb) = (key(prism.p[a]), key(prism.p[b]));
                let entry = if ka <= kb {
                    ([ka, kb], i as u32, [uv(a), uv(b)], k as u8)
                } else {
                    ([kb, ka], i as u32, [uv(b), uv(a)], k as u8)
                };
                edges.push(entry);
            }
        }
        edges.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut groups: Vec<(usize, usize)> = Vec::new();
        let mut start = 0;
        while start < edges.len() {
            let mut end = start + 1;
            while end < edges.len() && edges[end].0 == edges[start].0 {
                end += 1;
            }
            groups.push((start, end));
            start = end;
        }
        // A triangle with an edge shared by more than two triangles or across a uv seam keeps
        // the curved path (its seam walls are the curved path's); so does one without a frame.
        let mut blocked: Vec<bool> = frames.iter().map(Option::is_none).collect();
        for &(start, end) in &groups {
            let group = &edges[start..end];
            if group.len() > 1 && !is_clean_pair(group) {
                for e in group {
                    blocked[e.1 as usize] = true;
                }
            }
        }
        // Neighbours whose maps agree are joined into one patch; neighbours whose maps differ
        // (a crease, a bent direction) stay apart, each side's edge open.
        let mut parent: Vec<u32> = (0..count as u32).collect();
        for &(start, end) in &groups {
            let group = &edges[start..end];
            if !is_clean_pair(group) {
                continue;
            }
            let (i, j) = (group[0].1 as usize, group[1].1 as usize);
            let joined = !blocked[i]
                && !blocked[j]
                && frames[i].is_some_and(|f| f.holds(&prisms[j], side_f, roundoff))
                && frames[j].is_some_and(|f| f.holds(&prisms[i], side_f, roundoff));
            if joined {
                let (a, b) = (find(&mut parent, group[0].1), find(&mut parent, group[1].1));
                parent[a.max(b) as usize] = a.min(b);
            }
        }
        // Each patch's frame is fitted on three of its vertices that span it (the root's first
        // corner, the vertex farthest from it in texel space, the vertex farthest from the line
        // through both), so that rounding in one small triangle is not carried across the
        // patch; a patch is usable when none of its triangles is blocked and each lies in that
        // frame.
        let roots: Vec<u32> = (0..count as u32).map(|i| find(&mut parent, i)).collect();
        let texel = |i: usize, k: usize| {
            let uv = prisms[i].uv[k];
            [uv.x().to_f64() * side_f, uv.y().to_f64() * side_f]
        };
        let mut span: Vec<[(usize, usize); 3]> = (0..count).map(|i| [(i, 0); 3]).collect();
        let distance = |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]).abs() + (b[1] - a[1]).abs();
        for (i, &r) in roots.iter().enumerate() {
            let r = r as usize;
            let a = texel(r, 0);
            for k in 0..3 {
                let current = texel(span[r][1].0, span[r][1].1);
                if distance(a, texel(i, k)) > distance(a, current) {
                    span[r][1] = (i, k);
                }
            }
        }
        for (i, &r) in roots.iter().enumerate() {
            let r = r as usize;
            let (a, b) = (texel(r, 0), texel(span[r][1].0, span[r][1].1));
            let area =
                |c: [f64; 2]| ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])).abs();
            for k in 0..3 {
                if area(texel(i, k)) > area(texel(span[r][2].0, span[r][2].1)) {
                    span[r][2] = (i, k);
                }
            }
        }
        let fitted: Vec<Option<TexelFrame>> = (0..count)
            .map(|r| {
                if roots[r] as usize != r || frames[r].is_none() {
                    return None;
                }
                let points = span[r].map(|(i, k)| to_array::<T>(prisms[i].p[k]));
                let texels = span[r].map(|(i, k)| texel(i, k));
                TexelFrame::of_points(points, texels, to_array::<T>(prisms[r].n[0]))
            })
            .collect();
        let mut usable: Vec<bool> = fitted.iter().map(Option::is_some).collect();
        for i in 0..count {
            let r = roots[i] as usize;
            let fits = fitted[r].is_some_and(|f| f.holds(&prisms[i], side_f, roundoff));
            if blocked[i] || !fits {
                usable[r] = false;
            }
        }
        let mut patch_index = vec![CURVED; count];
        let mut patch_frames = Vec::new();
        let mut patch_of = vec![CURVED; count];
        let mut triangles = vec![None; count];
        let mut boxes = Vec::new();
        let side_t = T::from_f64(side_f);
        for i in 0..count {
            let r = roots[i] as usize;
            if !usable[r] {
                continue;
            }
            if patch_index[r] == CURVED {
                patch_index[r] = patch_frames.len() as u32;
                // Usable: the patch's frame exists.
                patch_frames.extend(fitted[r]);
                boxes.push([
                    f64::INFINITY,
                    f64::INFINITY,
                    f64::NEG_INFINITY,
                    f64::NEG_INFINITY,
                ]);
            }
            patch_of[i] = patch_index[r];
            let b = &mut boxes[patch_index[r] as usize];
            for k in 0..3 {
                let [x, y] = texel(i, k);
                *b = [b[0].min(x), b[1].min(y), b[2].max(x), b[3].max(y)];
            }
        }
        // An edge is open where the triangle across it is in another patch or curved; closed
        // inside a patch and on the mesh's border.
        let mut open = vec![[false; 3]; count];
        for &(start, end) in &groups {
            let group = &edges[start..end];
            if !is_clean_pair(group) {
                continue;
            }
            let (i, j) = (group[0].1 as usize, group[1].1 as usize);
            if patch_of[i] != patch_of[j] {
                open[i][usize::from(group[0].3)] = true;
                open[j][usize::from(group[1].3)] = true;
            }
        }
        for i in 0..count {
            if patch_of[i] != CURVED {
                triangles[i] = Some(TexelTriangle::new(&prisms[i], side_t, open[i]));
            }
        }
        Self {
            patch_of,
            frames: patch_frames,
            boxes,
            triangles,
        }
    }

    /// Per triangle, its texel triangle where it is walked straight.
    #[cfg(test)]
    pub(super) fn triangles(&self) -> &[Option<TexelTriangle<T>>] {
        &self.triangles
    }

    /// Whether triangle `tri` is in a patch (walked straight).
    #[inline]
    pub(crate) fn is_straight(&self, tri: usize) -> bool {
        self.patch_of[tri] != CURVED
    }

    /// Triangles walked straight.
    pub(crate) fn straight_triangles(&self) -> usize {
        self.triangles.iter().flatten().count()
    }

    /// Bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.patch_of.len() * 4
            + self.frames.len() * (core::mem::size_of::<TexelFrame>() + 32)
            + self.triangles.len() * core::mem::size_of::<Option<TexelTriangle<T>>>()
    }

    /// The straight line of `ray` in triangle `tri`'s patch from `t_min` on, with the
    /// triangle; `None` for a curved triangle (`Some((None, _))` where the line misses the
    /// patch's box).
    #[inline]
    pub(crate) fn line(
        &self,
        tri: usize,
        ray: &Ray<T>,
        t_min: T,
    ) -> Option<(Option<StraightLine<T>>, &TexelTriangle<T>)> {
        let patch = self.patch_of[tri];
        if patch == CURVED {
            return None;
        }
        let patch = patch as usize;
        let triangle = self.triangles[tri].as_ref()?;
        let line = StraightLine::new(&self.frames[patch], &self.boxes[patch], ray, t_min);
        Some((line, triangle))
    }
}

/// A ray in a patch's texel space, `q(t0 + tau) = origin + tau dir`, rebased to where it
/// enters the patch's box (padded) or to `t_min` beyond that, so that a far origin (a camera
/// hundreds of thousands of sample units above a terrain) costs no precision; computed in
/// `f64` and rounded to `T`. The rebase point depends on the ray and the patch alone: every
/// triangle of the patch sees the same line.
#[derive(Clone, Copy, Debug)]
pub(crate) struct StraightLine<T> {
    pub(super) origin: [T; 3],
    pub(super) dir: [T; 3],
    pub(super) inv: [T; 3],
    /// The world ray's `t` at the origin, in `f64` and in `T`.
    pub(super) t0: (f64, T),
    /// The line in `f64` (before rounding), for the clip.
    pub(super) wide: ([f64; 3], [f64; 3]),
}

impl<T: Real> StraightLine<T> {
    fn new(frame: &TexelFrame, bx: &[f64; 4], ray: &Ray<T>, t_min: T) -> Option<Self> {
        let o = sub3(to_array::<T>(ray.origin), frame.origin);
        let d = to_array::<T>(ray.dir);
        let o64 = frame.to_texel.map(|r| dot3(r, o));
        let d64 = frame.to_texel.map(|r| dot3(r, d));
        // The box padded by a texel and 1/64 in height, as the per-triangle clip is.
        let lo = [bx[0] - 1.0, bx[1] - 1.0, -1.0 / 64.0];
        let hi = [bx[2] + 1.0, bx[3] + 1.0, 1.0 + 1.0 / 64.0];
        let (mut t_in, mut t_out) = (t_min.to_f64(), f64::INFINITY);
        for a in 0..3 {
            if d64[a] == 0.0 {
                if !(o64[a] >= lo[a] && o64[a] <= hi[a]) {
                    return None;
                }
                continue;
            }
            let (p, q) = ((lo[a] - o64[a]) / d64[a], (hi[a] - o64[a]) / d64[a]);
            t_in = t_in.max(p.min(q));
            t_out = t_out.min(p.max(q));
        }
        if !(t_in <= t_out) {
            return None;
        }
        let origin64: [f64; 3] = core::array::from_fn(|a| d64[a].mul_add(t_in, o64[a]));
        let dir = d64.map(T::from_f64);
        Some(Self {
            origin: origin64.map(T::from_f64),
            dir,
            inv: dir.map(|v| T::ONE / v),
            t0: (t_in, T::from_f64(t_in)),
            wide: (origin64, d64),
        })
    }
}
