//! Straight rays in affine prisms.
//!
//! Where a base triangle's three displacement directions are equal (a flat terrain, a facade,
//! every flat part of a mesh with one shared normal), the shell map
//! `P(alpha, beta, h) = B(alpha, beta) + h N` is affine, and so is the map from texel space
//! `(x, y, h)` (texture coordinates times the map's side, heights in `[0, 1]`) to the world.
//! A ray is a straight line there, every microtriangle a flat triangle with integer texel
//! corners, and the min-max pyramid is walked as maximum-mipmap height-field tracers walk it
//! (Tevs et al. 2008): a node's four children are slabs in `x` and `y`, the line's heights at
//! a child's entry and exit bound its heights inside, and texels are decided by a watertight
//! ray-triangle test (Woop, Benthin and Wald 2013) instead of the curved path's quadratics and
//! cubics.
//!
//! Watertightness has three parts.
//! - Inside a texel grid: a texel corner is transformed into the test's sheared frame by one
//!   function of the corner alone, and each edge function is a difference of two products of
//!   those numbers, so the two microtriangles that share an edge compute exactly negated
//!   values for it: a ray cannot pass between them.
//! - The walk never loses a texel the test would hit: node boxes are padded by a bound on the
//!   test's rounding (the walk's paddings, set per prism from the line's reach).
//! - Between base triangles: triangles whose affine maps agree are grouped into a patch traced
//!   in one frame, so all of them see the same line, bit for bit, and the same hit points; a
//!   hit belongs to the triangles whose texel-space edges it lies on or inside, each edge's
//!   function computed from its two corners in one canonical order (the same number in both
//!   triangles that share it). A patch is walked straight only when it is a whole connected
//!   part of the mesh (its outer edges are the mesh's border), so that no straight-walked
//!   triangle shares an edge with a curved-walked one; other affine triangles keep the curved
//!   path, whose edge windows join them to their neighbours.

use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Hit, Prism, Ray, onto_base_triangle};

use crate::heightfield::{HEIGHT_ONE, HeightField};
use crate::mesh::BaseMesh;
use crate::stats::TraversalStats;
use crate::tlas::RootNodes;

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

/// The same-map tolerance of `T` (relative).
fn same_map<T: Real>() -> f64 {
    (SAME_MAP_ROUNDOFFS * T::UNIT_ROUNDOFF.to_f64()).max(MIN_SAME_MAP)
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
    fn holds<T: Real>(&self, prism: &Prism<T>, side: f64) -> bool {
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
                (mapped - p[k]).abs() <= same_map::<T>() * scale
            })
        })
    }
}

/// One triangle of a patch in texel space: its corners, its edges for deciding which hits it
/// owns, and the map back to its canonical coordinates.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TexelTriangle<T> {
    corners: [[T; 2]; 3],
    /// Per edge `k` (corners `k`, `k + 1`): its corners in canonical order (the smaller
    /// `(x, y)` first) and whether the triangle lies where the edge function is positive.
    edges: [([T; 2], [T; 2], bool); 3],
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
    fn new(prism: &Prism<T>, side: T) -> Self {
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
            (a, b, side > 0.0)
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

    /// Whether the texel point `q` lies in the triangle or on its edges.
    #[inline]
    fn owns(&self, q: [T; 2]) -> bool {
        self.edges.iter().all(|&(a, b, positive)| {
            let e = edge_function(a, b, q);
            if positive { e >= T::ZERO } else { e <= T::ZERO }
        })
    }

    /// `(alpha, beta)` of the texel point `q`, moved onto the triangle: computed in `f64`
    /// (once per hit), where a thin uv triangle's inverse does not overflow as it may in
    /// `f32`; a coordinate that is still not finite (a uv triangle thinner than `f64` sees) is
    /// taken as 0.
    fn canonical(&self, q: [T; 2]) -> (T, T) {
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
/// triangle, the uvs' bits at those positions.
type EdgeKey = ([[u64; 3]; 2], u32, [[u64; 2]; 2]);

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
    /// The patches of `mesh` displaced by `height_scale` with uvs times `tiling`, on a map of
    /// `side` texels per unit.
    pub(crate) fn find(mesh: &BaseMesh<T>, height_scale: T, tiling: T, side: usize) -> Self {
        let count = mesh.triangle_count();
        let side_f = side as f64;
        let prisms: Vec<Prism<T>> = (0..count)
            .map(|i| mesh.prism(i, height_scale, tiling))
            .collect();
        let frames: Vec<Option<TexelFrame>> = prisms
            .iter()
            .map(|p| TexelFrame::of_prism(p, side_f))
            .collect();
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
                    ([ka, kb], i as u32, [uv(a), uv(b)])
                } else {
                    ([kb, ka], i as u32, [uv(b), uv(a)])
                };
                edges.push(entry);
            }
        }
        edges.sort_unstable_by(|x, y| x.0.cmp(&y.0).then(x.1.cmp(&y.1)));
        let mut parent: Vec<u32> = (0..count as u32).collect();
        let mut blocked = vec![false; count];
        for i in 0..count {
            blocked[i] = frames[i].is_none();
        }
        let mut start = 0;
        while start < edges.len() {
            let mut end = start + 1;
            while end < edges.len() && edges[end].0 == edges[start].0 {
                end += 1;
            }
            let group = &edges[start..end];
            if group.len() > 1 {
                let joined = group.len() == 2 && group[0].1 != group[1].1 && {
                    let (i, j) = (group[0].1 as usize, group[1].1 as usize);
                    group[0].2 == group[1].2
                        && frames[i].is_some_and(|f| f.holds(&prisms[j], side_f))
                        && frames[j].is_some_and(|f| f.holds(&prisms[i], side_f))
                };
                if joined {
                    let (a, b) = (find(&mut parent, group[0].1), find(&mut parent, group[1].1));
                    parent[a.max(b) as usize] = a.min(b);
                } else {
                    for e in group {
                        blocked[e.1 as usize] = true;
                    }
                }
            }
            start = end;
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
            let fits = fitted[r].is_some_and(|f| f.holds(&prisms[i], side_f));
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
            triangles[i] = Some(TexelTriangle::new(&prisms[i], side_t));
        }
        Self {
            patch_of,
            frames: patch_frames,
            boxes,
            triangles,
        }
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
    origin: [T; 3],
    dir: [T; 3],
    inv: [T; 3],
    /// The world ray's `t` at the origin, in `f64` and in `T`.
    t0: (f64, T),
    /// The line in `f64` (before rounding), for the clip.
    wide: ([f64; 3], [f64; 3]),
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

/// Entries of the walk's stack: up to 4 roots, then each popped node pushes at most 4
/// children (3 more than it took), once per level on the way down, 23 levels at most (cell
/// coordinates are below `2^22`).
const STACK: usize = 4 + 3 * 23;

#[derive(Clone, Copy, Default)]
struct Node<T> {
    level: u32,
    x: i32,
    y: i32,
    t_in: T,
    t_out: T,
}

/// A hit of the straight walk: distance, canonical coordinates, height, texel, whether the
/// upper microtriangle (or a flat texel) was hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StraightHit<T: Real> {
    pub(crate) hit: Hit<T>,
    /// The line parameter of the hit.
    tau: T,
    pub(crate) texel: [i32; 2],
    /// 0 lower, 1 upper, 2 flat.
    pub(crate) part: u8,
}

/// The walk's per-prism state: the line, its clip to the triangle, the paddings.
struct Walk<'a, T: Real> {
    line: StraightLine<T>,
    triangle: &'a TexelTriangle<T>,
    /// Woop's frame: the dominant axis of the direction last, shears of the other two.
    axes: [usize; 3],
    shear: [T; 3],
    pad_xy: T,
    /// The line's height at `t` in sample units (`65535` per unit height): `origin + t dir`,
    /// so that node bounds are compared as stored, without a division.
    sample_origin: T,
    sample_dir: T,
    /// The padding of the line's heights, in sample units.
    pad_samples: T,
    /// The world ray's `t` at the line's origin, and the smallest `t` accepted.
    t0: T,
    t_min: T,
}

/// A sample as a height in `[0, 1]`, as the curved path converts it.
#[inline]
fn height<T: Real>(s: u16) -> T {
    T::from_i32(i32::from(s)) / T::from_i32(i32::from(HEIGHT_ONE))
}

/// The `t` interval in which `o + t d` lies in `[lo, hi]` (`inv = 1 / d`).
#[inline]
fn slab<T: Real>(lo: T, hi: T, o: T, d: T, inv: T) -> (T, T) {
    if d == T::ZERO {
        return if o >= lo && o <= hi {
            (-T::INFINITY, T::INFINITY)
        } else {
            (T::INFINITY, -T::INFINITY)
        };
    }
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    (a.min(b), a.max(b))
}

/// A texel corner in Woop's sheared frame: `(X, Y, Z)` relative to the line's origin. A
/// function of the corner alone, so that shared corners transform to the same numbers.
#[inline]
fn sheared<T: Real>(walk: &Walk<'_, T>, p: [T; 3]) -> [T; 3] {
    let [kx, ky, kz] = walk.axes;
    let rel = [
        p[0] - walk.line.origin[0],
        p[1] - walk.line.origin[1],
        p[2] - walk.line.origin[2],
    ];
    [
        (-walk.shear[0]).mul_add(rel[kz], rel[kx]),
        (-walk.shear[1]).mul_add(rel[kz], rel[ky]),
        walk.shear[2] * rel[kz],
    ]
}

/// The watertight test (Woop et al. 2013, two-sided) of the triangle `a, b, c` (sheared
/// corners): `(t, barycentrics)` or `None`. Edge functions are differences of plain products
/// of the corners' numbers: the triangle across an edge computes the same value negated.
#[inline]
fn watertight<T: Real>(a: [T; 3], b: [T; 3], c: [T; 3]) -> Option<(T, [T; 3])> {
    let edge = |p: [T; 3], q: [T; 3]| {
        let e = p[0] * q[1] - p[1] * q[0];
        if e == T::ZERO && T::MANTISSA_DIGITS < 53 {
            // Exact products of 24-bit significands, one rounding of their difference in
            // f64: the sign is exact.
            let w = |v: T| v.to_f64();
            T::from_f64(w(p[0]) * w(q[1]) - w(p[1]) * w(q[0]))
        } else {
            e
        }
    };
    let u = edge(c, b);
    let v = edge(a, c);
    let w = edge(b, a);
    let negative = u < T::ZERO || v < T::ZERO || w < T::ZERO;
    let positive = u > T::ZERO || v > T::ZERO || w > T::ZERO;
    if negative && positive {
        return None;
    }
    let det = u + v + w;
    if det == T::ZERO {
        return None;
    }
    let t = u.mul_add(a[2], v.mul_add(b[2], w * c[2])) / det;
    Some((t, [u / det, v / det, w / det]))
}

impl<T: Real> Walk<'_, T> {
    /// Tests texel `(x, y)`: the nearer of its two microtriangles' hits at line parameters
    /// up to `t_max` (and world distances from `t_min` on) whose point the triangle owns;
    /// the hit's `t` is the world ray's.
    fn texel(&self, x: i32, y: i32, corners: [u16; 4], t_max: T) -> Option<StraightHit<T>> {
        let h = corners.map(height::<T>);
        let (fx, fy) = (T::from_i32(x), T::from_i32(y));
        let (gx, gy) = (fx + T::ONE, fy + T::ONE);
        let p = [
            [fx, fy, h[0]],
            [gx, fy, h[1]],
            [fx, gy, h[2]],
            [gx, gy, h[3]],
        ];
        let s = p.map(|q| sheared(self, q));
        let flat = h[0] == h[1] && h[0] == h[2] && h[0] == h[3];
        let mut best: Option<StraightHit<T>> = None;
        let mut t_max = t_max;
        for (part, [i, j, k]) in [(0u8, [0, 1, 3]), (1u8, [0, 3, 2])] {
            let Some((t, bary)) = watertight(s[i], s[j], s[k]) else {
                continue;
            };
            if !(t <= t_max && self.t0 + t >= self.t_min) {
                continue;
            }
            let point =
                |a: usize| bary[0].mul_add(p[i][a], bary[1].mul_add(p[j][a], bary[2] * p[k][a]));
            let q = [point(0), point(1)];
            if !self.triangle.owns(q) {
                continue;
            }
            let (alpha, beta) = self.triangle.canonical(q);
            t_max = t;
            best = Some(StraightHit {
                tau: t,
                hit: Hit {
                    t: self.t0 + t,
                    alpha,
                    beta,
                    h: point(2).max(T::ZERO).min(T::ONE),
                    u: T::ZERO,
                    v: T::ZERO,
                },
                texel: [x, y],
                part: if flat { 2 } else { part },
            });
        }
        best
    }

    /// The nearest owned hit in the four texels of node `(x, y)` of level 1, whose line
    /// interval is `interval`: their corners are `block[at[1] + j][at[0] + i]`, `i, j` in
    /// `0..3`; texels nearest first, until one lies beyond `t_max`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn level_one<const N: usize>(
        &self,
        block: &[[u16; N]; N],
        at: [usize; 2],
        x: i32,
        y: i32,
        interval: (T, T),
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<StraightHit<T>> {
        let intervals = self.children(1, x, y, interval.0, lesser(interval.1, t_max));
        stats.box_tests += 4;
        let corners = |k: usize| {
            let (i, j) = (at[0] + (k & 1), at[1] + (k >> 1));
            [
                block[j][i],
                block[j][i + 1],
                block[j + 1][i],
                block[j + 1][i + 1],
            ]
        };
        let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
        let mut n = 0;
        for (k, &interval) in intervals.iter().enumerate() {
            let c = corners(k);
            let bounds = [
                c[0].min(c[1]).min(c[2]).min(c[3]),
                c[0].max(c[1]).max(c[2]).max(c[3]),
            ];
            if self.meets(interval, bounds) {
                entries[n] = (interval.0, interval.1, k as i32, 0);
                n += 1;
            }
        }
        sort_entries(&mut entries[..n], false);
        let mut best = None;
        let mut t_max = t_max;
        for &(t_in, _, k, _) in &entries[..n] {
            if t_in > t_max {
                break;
            }
            let k = k as usize;
            let (tx, ty) = (2 * x + (k & 1) as i32, 2 * y + (k >> 1) as i32);
            stats.texel_tests += 1;
            if let Some(hit) = self.texel(tx, ty, corners(k), t_max) {
                t_max = hit.tau;
                best = Some(hit);
            }
        }
        best
    }

    /// The `t` intervals of the line in the four children of node `(x, y)` of `level >= 1`
    /// (in the order `(0, 0), (1, 0), (0, 1), (1, 1)`), each padded, within `[lo, hi]`: the
    /// two split lines' crossings computed once for all four.
    #[inline]
    fn children(&self, level: u32, x: i32, y: i32, lo: T, hi: T) -> [(T, T); 4] {
        let size = T::pow2(level as i32 - 1);
        let l = &self.line;
        let p = self.pad_xy;
        let axis = |a: usize, c: i32| -> [(T, T); 2] {
            let c0 = T::from_i32(c) * (size + size);
            let (cm, c1) = (c0 + size, c0 + size + size);
            if l.dir[a] == T::ZERO {
                let o = l.origin[a];
                let inside = |lo: T, hi: T| {
                    if o >= lo && o <= hi {
                        (-T::INFINITY, T::INFINITY)
                    } else {
                        (T::INFINITY, -T::INFINITY)
                    }
                };
                return [inside(c0 - p, cm + p), inside(cm - p, c1 + p)];
            }
            let t = |v: T| (v - l.origin[a]) * l.inv[a];
            let (a0, a1, b0, b1) = (t(c0 - p), t(cm + p), t(cm - p), t(c1 + p));
            [
                (lesser(a0, a1), greater(a0, a1)),
                (lesser(b0, b1), greater(b0, b1)),
            ]
        };
        let (sx, sy) = (axis(0, x), axis(1, y));
        core::array::from_fn(|k| {
            let (i, j) = (k & 1, k >> 1);
            (
                greater(greater(sx[i].0, sy[j].0), lo),
                lesser(lesser(sx[i].1, sy[j].1), hi),
            )
        })
    }

    /// The `t` interval of the line in node `(x, y)` of `level` (padded), within `[lo, hi]`.
    fn node(&self, level: u32, x: i32, y: i32, lo: T, hi: T) -> (T, T) {
        let size = T::pow2(level as i32);
        let l = &self.line;
        let p = self.pad_xy;
        let (x0, y0) = (T::from_i32(x) * size, T::from_i32(y) * size);
        let (ax, bx) = slab(x0 - p, x0 + size + p, l.origin[0], l.dir[0], l.inv[0]);
        let (ay, by) = slab(y0 - p, y0 + size + p, l.origin[1], l.dir[1], l.inv[1]);
        (ax.max(ay).max(lo), bx.min(by).min(hi))
    }

    /// Whether the line's heights over the nonempty interval `(t_in, t_out)` (padded) may
    /// meet a node's `bounds`.
    #[inline(always)]
    fn meets(&self, (t_in, t_out): (T, T), bounds: [u16; 2]) -> bool {
        if !(t_in <= t_out) {
            return false;
        }
        let ha = t_in.mul_add(self.sample_dir, self.sample_origin);
        let hb = t_out.mul_add(self.sample_dir, self.sample_origin);
        let (line_lo, line_hi) = (
            lesser(ha, hb) - self.pad_samples,
            greater(ha, hb) + self.pad_samples,
        );
        line_lo <= T::from_i32(i32::from(bounds[1])) && line_hi >= T::from_i32(i32::from(bounds[0]))
    }
}

/// The smaller of two numbers that are not NaN (one comparison: the walk's `t` and heights
/// never are NaN, so `Real::min`'s NaN handling is not paid for).
#[inline(always)]
fn lesser<T: Real>(a: T, b: T) -> T {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN (see [`lesser`]).
#[inline(always)]
fn greater<T: Real>(a: T, b: T) -> T {
    if a > b { a } else { b }
}

/// Up to four `(t_in, t_out, x, y)` sorted by `t_in`, farthest first (`descending`) or
/// nearest first.
#[inline]
fn sort_entries<T: Real>(entries: &mut [(T, T, i32, i32)], descending: bool) {
    // An insertion sort: at most four entries.
    for i in 1..entries.len() {
        let mut j = i;
        while j > 0 && ((entries[j].0 > entries[j - 1].0) == descending) {
            entries.swap(j, j - 1);
            j -= 1;
        }
    }
}

/// The nearest hit of the straight `line` on the displaced surface over `triangle` (its root
/// nodes `roots`) with `t` in `[t_min, t_max]`: the min-max pyramid walked nearest first
/// along the line, texels tested by the watertight test.
#[allow(clippy::too_many_arguments)]
pub(crate) fn walk_straight<T: Real>(
    field: &HeightField,
    roots: RootNodes,
    line: StraightLine<T>,
    triangle: &TexelTriangle<T>,
    prism: &Prism<T>,
    t_min: T,
    t_max: T,
    stats: &mut TraversalStats,
) -> Option<StraightHit<T>> {
    // In line parameters (`tau = t - t0`).
    let (t0, _) = line.t0;
    let (t_lo, t_hi) = clip(&line, triangle, t_min.to_f64() - t0, t_max.to_f64() - t0)?;
    let kz = {
        let d = line.dir.map(|v| v.abs());
        if d[0] >= d[1] && d[0] >= d[2] {
            0
        } else if d[1] >= d[2] {
            1
        } else {
            2
        }
    };
    let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
    let shear = [
        line.dir[kx] / line.dir[kz],
        line.dir[ky] / line.dir[kz],
        T::ONE / line.dir[kz],
    ];
    // The test's rounding: four roundings in the shear of a corner, on magnitudes up to twice
    // its distance from the origin (the shears are at most 1), and the same for the line's
    // point at the walk's far end; in texel units, and in heights.
    let far = t_hi.abs().max(t_lo.abs());
    let eps = T::EPSILON;
    let corner = triangle
        .corners
        .iter()
        .fold(T::ONE, |m, c| m.max(c[0].abs()).max(c[1].abs()));
    let reach = |a: usize| line.origin[a].abs() + far * line.dir[a].abs();
    let eight = T::from_i32(8);
    let pad_xy = eight * eps * (reach(0).max(reach(1)) + corner + T::ONE);
    let pad_h = eight * eps * (reach(2) + T::ONE);
    // Heights in sample units: the scaling rounds the origin and direction once more each
    // (two roundings on magnitudes up to the reach).
    let samples = T::from_i32(i32::from(HEIGHT_ONE));
    let pad_samples = samples * (pad_h + T::TWO * eps * (reach(2) + T::ONE));
    let walk = Walk {
        line,
        triangle,
        axes: [kx, ky, kz],
        shear,
        pad_xy,
        sample_origin: line.origin[2] * samples,
        sample_dir: line.dir[2] * samples,
        pad_samples,
        t0: line.t0.1,
        t_min,
    };
    let mut best: Option<StraightHit<T>> = None;
    let mut t_best = t_hi;
    let mut stack = [Node::<T>::default(); STACK];
    let mut top = 0;
    let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
    let mut n = 0;
    for j in 0..i32::from(roots.ny) {
        for i in 0..i32::from(roots.nx) {
            let (x, y) = (roots.x + i, roots.y + j);
            stats.box_tests += 1;
            let bounds = field.texel_bounds(roots.level, i64::from(x), i64::from(y));
            let interval = walk.node(roots.level, x, y, t_lo, t_hi);
            if walk.meets(interval, bounds) {
                entries[n] = (interval.0, interval.1, x, y);
                n += 1;
            }
        }
    }
    sort_entries(&mut entries[..n], true);
    for &(t_in, t_out, x, y) in &entries[..n] {
        stack[top] = Node {
            level: roots.level,
            x,
            y,
            t_in,
            t_out,
        };
        top += 1;
    }
    while top > 0 {
        top -= 1;
        let node = stack[top];
        if node.t_in > t_best {
            continue;
        }
        match node.level {
            0 => {
                // A root texel (a triangle within two texels per axis).
                stats.texel_tests += 1;
                let corners = field.texel_corners(i64::from(node.x), i64::from(node.y));
                if let Some(hit) = walk.texel(node.x, node.y, corners, t_best) {
                    t_best = hit.tau;
                    best = Some(hit);
                }
            }
            1 => {
                let block = field.samples_block::<3>(2 * i64::from(node.x), 2 * i64::from(node.y));
                let interval = (node.t_in, node.t_out);
                if let Some(hit) =
                    walk.level_one(&block, [0, 0], node.x, node.y, interval, t_best, stats)
                {
                    t_best = hit.tau;
                    best = Some(hit);
                }
            }
            2 => {
                // The node's 4 x 4 texels from its 5 x 5 samples, read once: its four children
                // nearest first, each one's texels nearest first.
                let block = field.samples_block::<5>(4 * i64::from(node.x), 4 * i64::from(node.y));
                let intervals =
                    walk.children(2, node.x, node.y, node.t_in, lesser(node.t_out, t_best));
                stats.box_tests += 4;
                let mut n = 0;
                for (k, &interval) in intervals.iter().enumerate() {
                    let (i, j) = (2 * (k & 1), 2 * (k >> 1));
                    let mut b = [u16::MAX, 0];
                    for row in &block[j..j + 3] {
                        for &s in &row[i..i + 3] {
                            b = [b[0].min(s), b[1].max(s)];
                        }
                    }
                    if walk.meets(interval, b) {
                        entries[n] = (interval.0, interval.1, k as i32, 0);
                        n += 1;
                    }
                }
                sort_entries(&mut entries[..n], false);
                for &(t_in, t_out, k, _) in &entries[..n] {
                    if t_in > t_best {
                        break;
                    }
                    let k = k as usize;
                    let (i, j) = (k & 1, k >> 1);
                    let (x, y) = (2 * node.x + i as i32, 2 * node.y + j as i32);
                    if let Some(hit) = walk.level_one(
                        &block,
                        [2 * i, 2 * j],
                        x,
                        y,
                        (t_in, lesser(t_out, t_best)),
                        t_best,
                        stats,
                    ) {
                        t_best = hit.tau;
                        best = Some(hit);
                    }
                }
            }
            level => {
                let intervals =
                    walk.children(level, node.x, node.y, node.t_in, lesser(node.t_out, t_best));
                stats.box_tests += 4;
                let mut n = 0;
                let four =
                    field.four_bounds(level - 1, 2 * i64::from(node.x), 2 * i64::from(node.y));
                for (k, &interval) in intervals.iter().enumerate() {
                    let (x, y) = (2 * node.x + (k & 1) as i32, 2 * node.y + (k >> 1) as i32);
                    if walk.meets(interval, four[k]) {
                        entries[n] = (interval.0, interval.1, x, y);
                        n += 1;
                    }
                }
                // Farthest first onto the stack: the nearest child is popped next; the
                // others' memory is fetched while it is walked.
                sort_entries(&mut entries[..n], true);
                for &(t_in, t_out, x, y) in &entries[..n] {
                    field.prefetch_node(level - 1, i64::from(x), i64::from(y));
                    stack[top] = Node {
                        level: level - 1,
                        x,
                        y,
                        t_in,
                        t_out,
                    };
                    top += 1;
                }
            }
        }
    }
    // The clip's upper end is `t_max - t0` rounded: the nearest hit may lie a rounding
    // beyond `t_max`.
    let best = best.filter(|b| b.hit.t <= t_max);
    best.map(|mut b| {
        let uv = prism.texture_uv(b.hit.alpha, b.hit.beta);
        b.hit.u = uv.x();
        b.hit.v = uv.y();
        b
    })
}

/// The line's `t` interval inside the triangle's texel-space prism, padded by one texel
/// across each base edge and by `1/64` in height (far beyond the rounding of the `T` line
/// against the `f64` one it is computed from: half an ulp of coordinates below `2^22`, at
/// most a quarter texel in `f32`), within `[tau_min, tau_max]` (line parameters); `None` when
/// empty. Computed in
/// `f64` on the unrounded line: it only bounds the walk, the test decides the hits.
fn clip<T: Real>(
    line: &StraightLine<T>,
    triangle: &TexelTriangle<T>,
    tau_min: f64,
    tau_max: f64,
) -> Option<(T, T)> {
    let (o, d) = line.wide;
    let (mut lo, mut hi) = (tau_min, tau_max);
    let mut bound = |value: f64, rate: f64| {
        // value + t rate >= 0
        if rate == 0.0 {
            if value < 0.0 {
                hi = f64::NEG_INFINITY;
            }
        } else if rate > 0.0 {
            lo = lo.max(-value / rate);
        } else {
            hi = hi.min(-value / rate);
        }
    };
    let pad_h = 1.0 / 64.0;
    bound(o[2] + pad_h, d[2]);
    bound(1.0 + pad_h - o[2], -d[2]);
    let c = triangle.corners.map(|c| [c[0].to_f64(), c[1].to_f64()]);
    let orientation =
        (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
    let sign = if orientation > 0.0 { 1.0 } else { -1.0 };
    for k in 0..3 {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let length = (e[0] * e[0] + e[1] * e[1]).sqrt();
        let value = sign * (e[0] * (o[1] - a[1]) - e[1] * (o[0] - a[0])) + length;
        let rate = sign * (e[0] * d[1] - e[1] * d[0]);
        bound(value, rate);
    }
    (lo <= hi).then(|| (T::from_f64(lo), T::from_f64(hi)))
}

#[cfg(test)]
mod tests {
    use crate::test_util::unit_randoms;
    use crate::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
    use alloc::vec::Vec;
    use nlrt_poly::{Real, Vector2, Vector3};
    use nlrt_shellmap::Ray;

    /// A planar grid of `k x k` quads (alternating diagonals, so that base edges cross texel
    /// diagonals), in the plane through `origin` spanned by `e1`, `e2`, with uvs an affine
    /// function of the grid (rotated by `turn` radians, scaled by `scale`, shifted by
    /// `shift`) and one displacement direction `n` for every vertex.
    #[allow(clippy::too_many_arguments)]
    fn grid<T: Real>(
        k: usize,
        origin: [f64; 3],
        e1: [f64; 3],
        e2: [f64; 3],
        n: [f64; 3],
        turn: f64,
        scale: f64,
        shift: [f64; 2],
    ) -> BaseMesh<T> {
        let v3 =
            |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let (mut positions, mut uvs) = (Vec::new(), Vec::new());
        for j in 0..=k {
            for i in 0..=k {
                let (a, b) = (i as f64 / k as f64, j as f64 / k as f64);
                positions.push(v3(core::array::from_fn(|c| {
                    origin[c] + a * e1[c] + b * e2[c]
                })));
                let (c, s) = (turn.cos(), turn.sin());
                uvs.push(T::Vec2::new(
                    T::from_f64(scale * (c * a - s * b) + shift[0]),
                    T::from_f64(scale * (s * a + c * b) + shift[1]),
                ));
            }
        }
        let mut triangles = Vec::new();
        let at = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                if (i + j) % 2 == 0 {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        let normals = alloc::vec![v3(n); positions.len()];
        BaseMesh::new(positions, normals, uvs, triangles).expect("a valid grid")
    }

    fn random_field(side: usize, seed: u64) -> HeightField {
        let mut r = unit_randoms(seed);
        let samples = (0..side * side).map(|_| (r() * 65535.0) as u16).collect();
        HeightField::new(side, samples, Wrap::Repeat).expect("a valid map")
    }

    /// A tilted grid over a random map, displaced along a direction off its normal.
    fn tilted_surface<T: Real>(seed: u64) -> DisplacedSurface<T> {
        let mesh = grid::<T>(
            3,
            [0.3, -0.2, 0.1],
            [1.7, 0.2, -0.1],
            [-0.1, 0.3, 1.6],
            [0.25, 1.0, 0.1],
            0.4,
            1.3,
            [0.2, -0.7],
        );
        DisplacedSurface::new(mesh, random_field(16, seed), T::from_f64(0.6), T::ONE)
            .expect("a valid surface")
    }

    /// `mesh` widened to `f64`, exactly.
    fn widened<T: Real>(mesh: &BaseMesh<T>) -> BaseMesh<f64> {
        BaseMesh::new(
            mesh.positions().iter().map(|p| p.to_dvec3()).collect(),
            mesh.normals().iter().map(|p| p.to_dvec3()).collect(),
            mesh.uvs().iter().map(|p| p.to_dvec2()).collect(),
            (0..mesh.triangle_count())
                .map(|i| mesh.triangle(i))
                .collect(),
        )
        .expect("a valid mesh stays valid")
    }

    /// The straight walk in `T` finds the hits of the curved walk in `f64` on the same mesh
    /// (widened exactly) on rays from every direction at a tilted, sheared grid whose base
    /// edges cross texel diagonals: the same hit or miss on every ray, distances within `T`'s
    /// rounding, the same microtriangle but where a hit lies within rounding of an edge; and
    /// brute force in `T` (every texel of every triangle, the curved test) agrees on whether
    /// the ray hits. Returns how many rays the curved walk in `T` answers otherwise than
    /// `f64` (hit or miss, or a distance off by more than the tolerance).
    fn straight_walk_matches_f64<T: Real>(t_tolerance: f64) -> usize {
        let mut surface = tilted_surface::<T>(7);
        let wide = widened(surface.mesh());
        let mut reference =
            DisplacedSurface::new(wide, random_field(16, 7), 0.6, 1.0).expect("a valid surface");
        reference.set_straight_walk(false);
        assert_eq!(
            surface.straight_triangles(),
            18,
            "every triangle of the grid"
        );
        let mut r = unit_randoms(11);
        let (mut hits, mut same_part, mut curved_off) = (0, 0, 0);
        for _ in 0..3000 {
            // Aim at a point of the shell from a random direction.
            let target = [0.3 + r() * 1.6, -0.2 + r() * 1.0, 0.1 + r() * 1.5];
            let d = loop {
                let d = [r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0];
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if l > 0.1 && l <= 1.0 {
                    break d.map(|c| c / l);
                }
            };
            let o = core::array::from_fn::<f64, 3, _>(|c| target[c] - 3.0 * d[c]);
            let v =
                |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
            let ray = Ray::new(v(o), v(d)).expect("a valid ray");
            let (wide_o, wide_d) = (Vector3::to_dvec3(ray.origin), Vector3::to_dvec3(ray.dir));
            let wide_ray: Ray<f64> = Ray::new(wide_o, wide_d).expect("a valid ray");
            let mut stats = TraversalStats::default();
            surface.set_straight_walk(true);
            let straight = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            surface.set_straight_walk(false);
            let curved = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            let truth = reference.intersect(&wide_ray, 0.0, f64::INFINITY, &mut stats);
            let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
            assert_eq!(
                straight.is_some(),
                truth.is_some(),
                "{ray:?}: {straight:?} vs {truth:?}"
            );
            assert_eq!(straight.is_some(), brute.is_some(), "{ray:?}");
            let close = |a: Option<T>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) => (a.to_f64() - b).abs() <= t_tolerance * b,
                (None, None) => true,
                _ => false,
            };
            curved_off += usize::from(!close(curved.map(|c| c.hit.t), truth.map(|c| c.hit.t)));
            if let (Some(s), Some(c)) = (straight, truth) {
                hits += 1;
                assert!(
                    close(Some(s.hit.t), Some(c.hit.t)),
                    "{s:?} vs {c:?}: {ray:?}"
                );
                same_part += usize::from(s.texel == c.texel && s.triangle == c.triangle);
                let (ps, pc) = (s.hit.u.to_f64(), c.hit.u);
                assert!((ps - pc).abs() < 1e-3, "u {ps} vs {pc}");
            }
        }
        assert!(hits > 1000, "{hits} hits: the rays test the surface");
        // A hit within rounding of a texel or triangle edge may be reported on either side.
        assert!(same_part * 100 >= hits * 99, "{same_part} of {hits}");
        curved_off
    }

    #[test]
    fn straight_walk_matches_f64_in_f32() {
        // The curved walk in f32 differs from f64 on one of these rays (a nearer hit where
        // f64 has none: docs/watertightness.md, "Straight rays in affine prisms"); the
        // straight walk on none.
        let curved_off = straight_walk_matches_f64::<f32>(1e-4);
        assert!(curved_off <= 1, "{curved_off}");
    }

    #[test]
    fn straight_walk_matches_f64_in_f64() {
        assert_eq!(straight_walk_matches_f64::<f64>(1e-10), 0);
    }

    /// Rays aimed at points exactly on the base edges between triangles (and on texel
    /// corners there), from above and at a slant: every one hits, in f32 and f64.
    fn base_edges_do_not_leak<T: Real>() {
        let surface = tilted_surface::<T>(3);
        let mesh = surface.mesh();
        let mut r = unit_randoms(5);
        let mut rays = 0;
        for tri in (0..mesh.triangle_count()).map(|i| mesh.triangle(i)) {
            for k in 0..3 {
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                for _ in 0..40 {
                    let s = r();
                    let p = |v: T::Vec3| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()];
                    let (pa, pb) = (p(mesh.positions()[a]), p(mesh.positions()[b]));
                    // A point on the edge, raised into the shell along the direction.
                    let lift = 0.6 * r();
                    let n = p(mesh.normals()[a]);
                    let target: [f64; 3] =
                        core::array::from_fn(|c| pa[c] + s * (pb[c] - pa[c]) + lift * n[c]);
                    // From the side the directions point to: down through the shell's top.
                    let tilt = [r() - 0.5, r() - 0.5, r() - 0.5];
                    let d: [f64; 3] = core::array::from_fn(|c| -n[c] + 0.5 * tilt[c]);
                    let o: [f64; 3] = core::array::from_fn(|c| target[c] - 4.0 * d[c]);
                    let v = |a: [f64; 3]| {
                        T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]))
                    };
                    let ray = Ray::new(v(o), v(d)).expect("a valid ray");
                    let hit = surface.intersect(
                        &ray,
                        T::ZERO,
                        T::INFINITY,
                        &mut TraversalStats::default(),
                    );
                    // Inside the mesh's interior the ray must meet the surface (it enters the
                    // shell's top and reaches the base); at the border it may pass beside.
                    let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
                    if brute.is_some() {
                        rays += 1;
                        assert!(hit.is_some(), "{ray:?} leaked");
                    }
                }
            }
        }
        assert!(rays > 1500, "{rays}");
    }

    #[test]
    fn base_edges_do_not_leak_f32() {
        base_edges_do_not_leak::<f32>();
    }

    #[test]
    fn base_edges_do_not_leak_f64() {
        base_edges_do_not_leak::<f64>();
    }

    /// Which triangles are walked straight: a flat grid all; a grid whose directions differ
    /// in one vertex, one folded along an edge, or one with a uv seam inside: none (every
    /// triangle of a patch that touches a curved or foreign neighbour keeps the curved walk);
    /// a flat grid beside a curved one in the same mesh: the flat one only.
    #[test]
    fn affine_patches_are_whole_flat_parts_of_the_mesh() {
        let flat = grid::<f64>(
            2,
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            0.0,
            1.0,
            [0.0; 2],
        );
        let field = || random_field(8, 1);
        let build = |m: BaseMesh<f64>| DisplacedSurface::new(m, field(), 0.2, 1.0).expect("valid");
        assert_eq!(build(flat.clone()).straight_triangles(), 8);

        let mut normals = flat.normals().to_vec();
        normals[4] = nlrt_poly::glam::DVec3::new(0.0, 0.1, 1.0);
        let bent = BaseMesh::new(
            flat.positions().to_vec(),
            normals,
            flat.uvs().to_vec(),
            (0..flat.triangle_count())
                .map(|i| flat.triangle(i))
                .collect::<Vec<_>>(),
        )
        .expect("valid");
        assert_eq!(build(bent).straight_triangles(), 0);

        let mut positions = flat.positions().to_vec();
        for p in positions.iter_mut().filter(|p| p.x > 0.75) {
            p.z += 0.3 * (p.x - 0.5);
        }
        let folded = BaseMesh::new(
            positions,
            flat.normals().to_vec(),
            flat.uvs().to_vec(),
            (0..flat.triangle_count())
                .map(|i| flat.triangle(i))
                .collect::<Vec<_>>(),
        )
        .expect("valid");
        assert_eq!(build(folded).straight_triangles(), 0);

        // Two copies side by side, the second with its own vertices and bent directions.
        let mut positions = flat.positions().to_vec();
        let mut normals = flat.normals().to_vec();
        let mut uvs = flat.uvs().to_vec();
        let mut triangles = (0..flat.triangle_count())
            .map(|i| flat.triangle(i))
            .collect::<Vec<_>>();
        let base = positions.len() as u32;
        positions.extend(
            flat.positions()
                .iter()
                .map(|p| *p + nlrt_poly::glam::DVec3::new(3.0, 0.0, 0.0)),
        );
        normals.extend(
            flat.positions()
                .iter()
                .map(|p| nlrt_poly::glam::DVec3::new(p.x * 0.2, 0.0, 1.0)),
        );
        uvs.extend(flat.uvs().iter().copied());
        triangles.extend((0..flat.triangle_count()).map(|i| flat.triangle(i).map(|v| v + base)));
        let both = BaseMesh::new(positions, normals, uvs, triangles).expect("valid");
        assert_eq!(build(both).straight_triangles(), 8);
    }
}
