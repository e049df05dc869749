//! Watertight edges between the triangles of a shell-mapped object.
//!
//! Each object triangle is intersected on its own: the plane cubic's root gives a point of the
//! nonlinear ray on the triangle's plane, and an inside test keeps it. Two triangles sharing an
//! edge compute their points from different cubics, so near the edge one may fall a rounding
//! outside the first triangle and the other outside the second: the ray slips through (measured
//! by `nlrt watertight` on the shell scenes). The texel test of displacement mapping closes such
//! gaps by construction (split lines computed alike by both sides, signs compared at the split
//! points); this module does the same for an arbitrary mesh of object triangles, where it is
//! needed:
//! - An edge shared by exactly two triangles gets a *separating plane*: through the edge and
//!   along the sum of the two unit normals (oriented alike), the plane that bisects the two
//!   faces, so the triangles lie on opposite sides of it whatever their dihedral angle. It is
//!   computed once, and both triangles use the same numbers.
//! - Fast path: the plain test, with the shared edges' inside tests made exactly antisymmetric
//!   (each edge function evaluated with its end points in one fixed order), and each such
//!   decision checked against a first-order bound on the point's error. A point beyond the
//!   bound on either side of every shared edge is decided as before.
//! - Otherwise (a point within that bound of a shared edge), the piece search: the ray's curve
//!   is cut where it crosses the triangle's separating planes (roots of the planes' cubics along
//!   the curve, the same numbers in both triangles); the plane cubic is solved on the pieces on
//!   the triangle's side of them; and where the curve passes a separating plane into the
//!   neighbour's side, the two planes' cubics are compared there, and a hit is reported on the
//!   edge unless both signs are certainly the same. The surface along the curve is one
//!   triangle's plane up to the split point and the other's after it, so a sign change lies in
//!   a piece (found by its solver) or at the split point (found by the comparison), as in
//!   `DisplacedSurface::intersect_texel`.
//!
//! Boundary edges, edges of three or more triangles, and pairs whose separating plane does not
//! separate them (faces folded onto each other) keep the plain inside test.

use alloc::vec::Vec;
use nlrt_poly::{
    Real, Vector2, Vector3, decided_sign, horner, horner_with_bound, solve_cubic_in,
    solve_quadratic_in,
};
use nlrt_shellmap::{Hit, NonlinearRay, Prism, TexturePlane, alpha_beta_eq11};

/// No shared edge.
const NONE: u32 = u32::MAX;

/// An edge shared by exactly two object triangles.
#[derive(Clone, Copy, Debug)]
struct SharedEdge<T: Real> {
    /// The separating plane (unit normal), in the unit tile.
    plane: TexturePlane<T>,
    /// The two triangles.
    triangles: [u32; 2],
    /// Whether `triangles[0]` lies on the positive side of `plane` (`triangles[1]` on the
    /// other).
    first_positive: bool,
    /// Whether the two run along the edge in opposite directions (consistent winding: their
    /// planes' normals point to the same side of the surface).
    same_winding: bool,
}

/// The shared edges of an object's triangles.
#[derive(Clone, Debug)]
pub(crate) struct ObjectEdges<T: Real> {
    edges: Vec<SharedEdge<T>>,
    /// Per triangle and edge (edge `e` from vertex `e` to `e + 1`), its index in `edges`, or
    /// [`NONE`].
    of_triangle: Vec<[u32; 3]>,
    /// Per triangle, bit `e` set where edge `e` runs against the fixed vertex order.
    reversed: Vec<u8>,
}

/// A total order on vertices (bit-identical ones equal), fixing each edge's direction.
fn vertex_less<T: Real>(a: T::Vec3, b: T::Vec3) -> bool {
    let key = |p: T::Vec3| [p.x(), p.y(), p.z()];
    let (ka, kb) = (key(a), key(b));
    for i in 0..3 {
        if ka[i] < kb[i] {
            return true;
        }
        if ka[i] > kb[i] {
            return false;
        }
    }
    false
}

/// The value of `plane` at `p`.
fn plane_at<T: Real>(plane: &TexturePlane<T>, p: T::Vec3) -> T {
    plane.normal.dot(p) + plane.k
}

/// `plane` moved by the whole tile `(x, y)` (both triangles of an edge move it alike).
fn shifted_plane<T: Real>(plane: &TexturePlane<T>, [x, y]: [i32; 2]) -> TexturePlane<T> {
    let (nu, nv) = (plane.normal.x(), plane.normal.y());
    TexturePlane {
        normal: plane.normal,
        k: (-nu).mul_add(T::from_i32(x), (-nv).mul_add(T::from_i32(y), plane.k)),
    }
}

/// `c0 + c1 h + c2 h^2 (+ c3 h^3)` and its derivative.
fn value_and_slope<T: Real, const N: usize>(c: &[T; N], h: T) -> (T, T) {
    let (mut v, mut d) = (T::ZERO, T::ZERO);
    for &ci in c.iter().rev() {
        d = d.mul_add(h, v);
        v = v.mul_add(h, ci);
    }
    (v, d)
}

/// The edge function of `q` against the edge `a -> b` in the projection on axes `(i, j)`,
/// evaluated with the end points in their fixed order (`reversed`: `b` comes first, see
/// [`vertex_less`]) and negated back, so that the two triangles of an edge get exactly
/// opposite values at the same point.
fn edge_function<T: Real>(
    a: T::Vec3,
    b: T::Vec3,
    reversed: bool,
    q: T::Vec3,
    (i, j): (usize, usize),
) -> T {
    let (p, r) = if reversed { (b, a) } else { (a, b) };
    let w = nlrt_poly::difference_of_products(
        r.get(i) - p.get(i),
        q.get(j) - p.get(j),
        r.get(j) - p.get(j),
        q.get(i) - p.get(i),
    );
    if reversed { -w } else { w }
}

/// A candidate point of the plain test: `alpha`, `beta`, `h`, and the distance where the flat
/// shortcut gives it.
type Candidate<T> = (T, T, T, Option<T>);

/// Where a candidate point stands against one edge of its triangle.
#[derive(Clone, Copy, PartialEq, Eq)]
enum EdgeSide {
    Inside,
    Outside,
    /// Within the error bound of a shared edge: the piece search decides.
    Unsure,
}

impl<T: Real> ObjectEdges<T> {
    /// The shared edges of `triangles` (vertices compared bit for bit).
    pub(crate) fn new(triangles: &[[T::Vec3; 3]]) -> Self {
        let mut of_triangle = alloc::vec![[NONE; 3]; triangles.len()];
        let reversed = triangles
            .iter()
            .map(|t| {
                (0..3).fold(0u8, |bits, e| {
                    bits | (u8::from(vertex_less::<T>(t[(e + 1) % 3], t[e])) << e)
                })
            })
            .collect();
        // Every edge, its end points in the fixed order, then sorted so that equal edges meet.
        let mut all: Vec<([T::Vec3; 2], u32, u8)> = Vec::with_capacity(3 * triangles.len());
        for (k, t) in triangles.iter().enumerate() {
            for e in 0..3 {
                let (a, b) = (t[e], t[(e + 1) % 3]);
                let ends = if vertex_less::<T>(b, a) {
                    [b, a]
                } else {
                    [a, b]
                };
                all.push((ends, k as u32, e as u8));
            }
        }
        let less = |x: &[T::Vec3; 2], y: &[T::Vec3; 2]| {
            vertex_less::<T>(x[0], y[0]) || (x[0] == y[0] && vertex_less::<T>(x[1], y[1]))
        };
        all.sort_unstable_by(|x, y| {
            if less(&x.0, &y.0) {
                core::cmp::Ordering::Less
            } else if less(&y.0, &x.0) {
                core::cmp::Ordering::Greater
            } else {
                (x.1, x.2).cmp(&(y.1, y.2))
            }
        });
        let mut edges = Vec::new();
        let mut i = 0;
        while i < all.len() {
            let mut j = i + 1;
            while j < all.len() && all[j].0 == all[i].0 {
                j += 1;
            }
            if j == i + 2
                && let Some(edge) = Self::shared(triangles, all[i], all[i + 1])
            {
                let id = edges.len() as u32;
                of_triangle[all[i].1 as usize][usize::from(all[i].2)] = id;
                of_triangle[all[i + 1].1 as usize][usize::from(all[i + 1].2)] = id;
                edges.push(edge);
            }
            i = j;
        }
        Self {
            edges,
            of_triangle,
            reversed,
        }
    }

    /// The separating plane of an edge two triangles share, or `None` when it does not
    /// separate them (a degenerate pair, or faces folded onto each other).
    fn shared(
        triangles: &[[T::Vec3; 3]],
        (ends, k0, e0): ([T::Vec3; 2], u32, u8),
        (_, k1, e1): ([T::Vec3; 2], u32, u8),
    ) -> Option<SharedEdge<T>> {
        let (t0, t1) = (&triangles[k0 as usize], &triangles[k1 as usize]);
        let (n0, n1) = (
            TexturePlane::<T>::through(t0)?.normal,
            TexturePlane::<T>::through(t1)?.normal,
        );
        // Consistent winding runs the edge in opposite directions.
        let same_winding = t0[usize::from(e0)] != t1[usize::from(e1)];
        let m = if same_winding { n0 + n1 } else { n0 - n1 };
        let [a, b] = ends;
        let plane = TexturePlane::<T>::through(&[a, b, a + m])?;
        let third = |t: &[T::Vec3; 3], e: u8| t[(usize::from(e) + 2) % 3];
        let (s0, s1) = (
            plane_at(&plane, third(t0, e0)),
            plane_at(&plane, third(t1, e1)),
        );
        // Strictly on opposite sides, each by more than the plane's own rounding (a few ulps
        // of the tile's unit size: a third vertex that close lies in the plane).
        let slack = T::from_i32(16) * T::EPSILON;
        let separated = (s0 > slack && s1 < -slack) || (s0 < -slack && s1 > slack);
        separated.then_some(SharedEdge {
            plane,
            triangles: [k0, k1],
            first_positive: s0 > T::ZERO,
            same_winding,
        })
    }

    /// Bytes held.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.edges.len() * core::mem::size_of::<SharedEdge<T>>()
            + self.of_triangle.len() * core::mem::size_of::<[u32; 3]>()
            + self.reversed.len()
    }
}

/// The search, in `T`, over edges whose separating planes are stored in `S` (`f32` edges of
/// an `f32` surface traced in `f64`: each plane is widened exactly where it is used, so the
/// two triangles of an edge still see the same plane).
impl<S: Real> ObjectEdges<S> {
    /// Per edge of triangle `k`, its index in `edges`, or [`NONE`].
    fn shared_edges(&self, k: u32) -> [u32; 3] {
        self.of_triangle
            .get(k as usize)
            .copied()
            .unwrap_or([NONE; 3])
    }

    /// The nearest hit with `t` in `[t_min, t_max]` of `ray` (in `prism`) on object triangle
    /// `k`, placed in `tile` as `tri` (`placed` gives any triangle of the object in the same
    /// tile: the neighbours' planes), watertight across its shared edges (see the module),
    /// with the object triangle hit: `k`, or a neighbour across one of its shared edges.
    ///
    /// Where the point lies within its error bound of a shared edge, the piece search may
    /// leave it to the neighbour across, whose own test reports it; but the walk need not
    /// test that neighbour: its box may miss the curve by a rounding (two flat faces meeting
    /// at a corner, each box a plane, the curve past the corner by less than its roots'
    /// error: 3 of 56,661 aimed rays in f32 on a wall of box-shaped bricks). So the
    /// neighbours across `k`'s shared edges are then asked here, each deciding with the same
    /// numbers as when the walk asks it. A neighbour's hit is taken where its own point also
    /// lies within its error bound of a shared edge (a point clear of its edges lies inside
    /// it by more than a rounding, where the walk asks it through its box) and at one of
    /// `heights`, those at which the walk found the curve in the tile and the prism (the
    /// heights its boxes are cut to: a point a neighbour keeps on a base edge from beyond it
    /// is outside them).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn intersect<T: Real>(
        &self,
        k: u32,
        tile: [i32; 2],
        tri: &[T::Vec3; 3],
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        heights: [T; 2],
        placed: impl Fn(u32) -> Option<[T::Vec3; 3]>,
    ) -> Option<(Hit<T>, u32)> {
        let (own, near_shared_edge) =
            self.intersect_alone(k, tile, tri, prism, ray, t_min, t_max, &placed);
        let mut best = own.map(|hit| (hit, k));
        if !near_shared_edge {
            return best;
        }
        let shared = self.shared_edges(k);
        for edge in shared.iter().filter_map(|&e| self.edges.get(e as usize)) {
            let other = if edge.triangles[0] == k {
                edge.triangles[1]
            } else {
                edge.triangles[0]
            };
            let Some(other_tri) = placed(other) else {
                continue;
            };
            let limit = best.map_or(t_max, |(hit, _)| hit.t);
            let (hit, near) =
                self.intersect_alone(other, tile, &other_tri, prism, ray, t_min, limit, &placed);
            if near
                && let Some(hit) = hit
                && hit.h >= heights[0]
                && hit.h <= heights[1]
                && best.is_none_or(|(b, _)| hit.t < b.t)
            {
                best = Some((hit, other));
            }
        }
        best
    }

    /// [`ObjectEdges::intersect`] of triangle `k` alone, and whether its point lay within its
    /// error bound of a shared edge (the piece search decided it).
    #[allow(clippy::too_many_arguments)]
    fn intersect_alone<T: Real>(
        &self,
        k: u32,
        tile: [i32; 2],
        tri: &[T::Vec3; 3],
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        placed: &impl Fn(u32) -> Option<[T::Vec3; 3]>,
    ) -> (Option<Hit<T>>, bool) {
        let Some(plane) = TexturePlane::<T>::through(tri) else {
            return (None, false);
        };
        let axis = plane.normal.max_abs_axis();
        let axes = ((axis + 1) % 3, (axis + 2) % 3);
        // The triangle's orientation in the projection (the sign of its 2D area there, the
        // normal's component on the dropped axis): inside is where every edge function has it.
        let orientation = T::ONE.copysign(plane.normal.get(axis));
        let shared = self.shared_edges(k);
        let reversed = self.reversed.get(k as usize).copied().unwrap_or(0);
        let lo = tri[0].z().min(tri[1].z()).min(tri[2].z());
        let hi = tri[0].z().max(tri[1].z()).max(tri[2].z());
        let cubic = plane.ray_cubic(ray);
        let plane_abh = plane.canonical(prism);
        // Candidate points (alpha, beta, h, and the distance where the flat shortcut of sec.
        // 5.4 gives it): the shortcut's or the plane cubic's roots (a window beyond the
        // triangle's heights, where a root on an edge at its lowest or highest point may fall).
        let mut candidates: [Option<Candidate<T>>; 3] = [None; 3];
        if tri[1].z() == lo && tri[2].z() == lo && tri[0].z() == lo {
            // The crossing outside the base triangle too: a point a rounding beyond the wall
            // is kept on it below, as a root of the cubic is.
            candidates[0] = prism
                .cross_section_crossing(&ray.ray, lo)
                .map(|(t, alpha, beta)| (alpha, beta, lo, Some(t)));
        } else {
            // Solved on the widest window ([`CLAMP_LIMIT`]); a root beyond [`HEIGHT_WINDOW`]
            // (rare) is kept only within its end's [`height_window`], computed then.
            let (near_lo, near_hi) = (lo - HEIGHT_WINDOW::<T>(), hi + HEIGHT_WINDOW::<T>());
            let roots = solve_cubic_in(cubic, lo - CLAMP_LIMIT::<T>(), hi + CLAMP_LIMIT::<T>());
            let mut slot = 0;
            for &h in roots.iter() {
                let window =
                    |end| height_window(&cubic, cubic_rounding(&plane, tri, ray, end), end);
                let beyond =
                    (h < near_lo && lo - h > window(lo)) || (h > near_hi && h - hi > window(hi));
                if beyond {
                    continue;
                }
                candidates[slot] =
                    alpha_beta_eq11(ray, &plane_abh, h).map(|(alpha, beta)| (alpha, beta, h, None));
                slot += 1;
            }
        }
        let mut best: Option<Hit<T>> = None;
        for &(alpha, beta, h, flat_t) in candidates.iter().flatten() {
            let in_prism = alpha >= T::ZERO && beta >= T::ZERO && alpha + beta <= T::ONE;
            if !(in_prism || (alpha.is_finite() && beta.is_finite())) {
                continue;
            }
            let uv = prism.texture_uv(alpha, beta);
            let q = T::Vec3::new(uv.x(), uv.y(), h);
            let formed = cubic_rounding(&plane, tri, ray, h);
            let bound = point_error_bound(&cubic, formed, ray, q, h);
            let (alpha, beta, q, flat_t) = if in_prism {
                (alpha, beta, q, flat_t)
            } else {
                let Some((a, b)) = kept_across_wall(prism, alpha, beta, bound) else {
                    continue;
                };
                let uv = prism.texture_uv(a, b);
                (a, b, T::Vec3::new(uv.x(), uv.y(), h), None)
            };
            let mut inside = true;
            for e in 0..3 {
                let (a, b) = (tri[e], tri[(e + 1) % 3]);
                let w = edge_function::<T>(a, b, reversed & (1 << e) != 0, q, axes) * orientation;
                let side = if shared[e] == NONE {
                    if w >= T::ZERO {
                        EdgeSide::Inside
                    } else {
                        EdgeSide::Outside
                    }
                } else {
                    let span = (b.get(axes.0) - a.get(axes.0))
                        .abs()
                        .max((b.get(axes.1) - a.get(axes.1)).abs());
                    let tolerance = T::TWO * span * bound;
                    if w > tolerance {
                        EdgeSide::Inside
                    } else if w < -tolerance {
                        EdgeSide::Outside
                    } else {
                        EdgeSide::Unsure
                    }
                };
                match side {
                    EdgeSide::Inside => {}
                    EdgeSide::Outside => inside = false,
                    EdgeSide::Unsure => {
                        let hit = self.piece_search(
                            k,
                            tile,
                            tri,
                            &plane,
                            &cubic,
                            prism,
                            ray,
                            [lo, hi],
                            t_min,
                            t_max,
                            placed,
                        );
                        return (hit, true);
                    }
                }
            }
            if !inside {
                continue;
            }
            let t = flat_t.unwrap_or_else(|| ray.signed_distance(prism, alpha, beta, h));
            if t >= t_min && t <= t_max && best.is_none_or(|b| t < b.t) {
                best = Some(Hit {
                    t,
                    alpha,
                    beta,
                    // A root in the window beyond the triangle's heights is reported on them.
                    h: h.max(lo).min(hi),
                    u: q.x(),
                    v: q.y(),
                });
            }
        }
        (best, false)
    }

    /// The piece search of the module's description, over the heights `[lo, hi]` widened by
    /// [`HEIGHT_WINDOW`] (a flat triangle's range is a single height).
    #[allow(clippy::too_many_arguments)]
    #[cold]
    #[inline(never)]
    fn piece_search<T: Real>(
        &self,
        k: u32,
        tile: [i32; 2],
        tri: &[T::Vec3; 3],
        plane: &TexturePlane<T>,
        cubic: &[T; 4],
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        [lo, hi]: [T; 2],
        t_min: T,
        t_max: T,
        placed: &impl Fn(u32) -> Option<[T::Vec3; 3]>,
    ) -> Option<Hit<T>> {
        let shared = self.shared_edges(k);
        // The curve's poles in the object's heights (the same numbers in every triangle).
        let poles = solve_quadratic_in(ray.d, T::ZERO, T::ONE);
        let sides: [Option<Side<T>>; 3] = core::array::from_fn(|e| {
            let edge = self.edges.get(shared[e] as usize)?;
            let first = edge.triangles[0] == k;
            let other = if first {
                edge.triangles[1]
            } else {
                edge.triangles[0]
            };
            let neighbour = TexturePlane::<T>::through(&placed(other)?)?.ray_cubic(ray);
            let neighbour = if edge.same_winding {
                neighbour
            } else {
                neighbour.map(|c| -c)
            };
            let stored = &edge.plane;
            let widen = |c: S| T::from_f64(c.to_f64());
            let plane = TexturePlane::<T> {
                normal: T::Vec3::new(
                    widen(stored.normal.x()),
                    widen(stored.normal.y()),
                    widen(stored.normal.z()),
                ),
                k: widen(stored.k),
            };
            let separating = shifted_plane(&plane, tile);
            Some(Side::new(
                separating,
                [tri[e], tri[(e + 1) % 3]],
                first == edge.first_positive,
                neighbour,
                ray,
                poles.as_slice(),
            ))
        });
        let axis = plane.normal.max_abs_axis();
        let axes = ((axis + 1) % 3, (axis + 2) % 3);
        let orientation = T::ONE.copysign(plane.normal.get(axis));
        let reversed = self.reversed.get(k as usize).copied().unwrap_or(0);
        let plane_abh = plane.canonical(prism);
        let heights = [lo, hi];
        // The triangle's window, and each separating plane's at the same ends (its crossing
        // at an edge on the triangle's highest or lowest height errs by its own conditioning).
        let window = |end: T| {
            sides.iter().flatten().fold(
                height_window(cubic, cubic_rounding(plane, tri, ray, end), end),
                |w, s| {
                    let formed = cubic_rounding(&s.plane, &s.ends, ray, end);
                    w.max(height_window(&s.along, formed, end))
                },
            )
        };
        let (lo, hi) = (lo - window(lo), hi + window(hi));

        // Split points in (lo, hi): the separating planes' crossings (tags 0-2) and the poles
        // (tag 3).
        let mut splits: [(T, u8); 11] = [(T::ZERO, 0); 11];
        let mut n = 0;
        for (e, side) in sides.iter().enumerate() {
            for &r in side.iter().flat_map(|s| s.crossings()) {
                if r > lo && r < hi {
                    splits[n] = (r, e as u8);
                    n += 1;
                }
            }
        }
        for &r in poles.iter() {
            if r > lo && r < hi {
                splits[n] = (r, 3);
                n += 1;
            }
        }
        let splits = &mut splits[..n];
        splits.sort_unstable_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(core::cmp::Ordering::Equal));

        let mut best: Option<Hit<T>> = None;
        let mut consider = |h: T| {
            let Some((alpha, beta)) = alpha_beta_eq11(ray, &plane_abh, h) else {
                return;
            };
            let (alpha, beta) = if alpha >= T::ZERO && beta >= T::ZERO && alpha + beta <= T::ONE {
                (alpha, beta)
            } else {
                let uv = prism.texture_uv(alpha, beta);
                let formed = cubic_rounding(plane, tri, ray, h);
                let q = T::Vec3::new(uv.x(), uv.y(), h);
                let bound = point_error_bound(cubic, formed, ray, q, h);
                let Some(ab) = kept_across_wall(prism, alpha, beta, bound) else {
                    return;
                };
                ab
            };
            let uv = prism.texture_uv(alpha, beta);
            let q = T::Vec3::new(uv.x(), uv.y(), h);
            // Edges without a separating plane keep the plain test.
            for e in 0..3 {
                if sides[e].is_none()
                    && edge_function::<T>(
                        tri[e],
                        tri[(e + 1) % 3],
                        reversed & (1 << e) != 0,
                        q,
                        axes,
                    ) * orientation
                        < T::ZERO
                {
                    return;
                }
            }
            let t = ray.signed_distance(prism, alpha, beta, h);
            if t >= t_min && t <= t_max && best.is_none_or(|b| t < b.t) {
                best = Some(Hit {
                    t,
                    alpha,
                    beta,
                    h: h.max(heights[0]).min(heights[1]),
                    u: q.x(),
                    v: q.y(),
                });
            }
        };
        let mut start = lo;
        let mut previous_ours = false;
        for i in 0..=splits.len() {
            let end = splits.get(i).map_or(hi, |s| s.0);
            let middle = (start + end) * T::HALF;
            let ours = end > start && sides.iter().flatten().all(|s| s.ours_at(middle));
            if ours {
                for &r in solve_cubic_in(*cubic, start, end).iter() {
                    consider(r.max(start).min(end));
                }
            }
            // The split point that starts this piece: where the curve passes a separating
            // plane between our side and the neighbour's, compare the two planes there.
            let split = i.checked_sub(1).map(|j| splits[j]);
            if let Some((split, e)) = split
                && (ours || previous_ours)
                && let Some(Some(side)) = sides.get(usize::from(e))
            {
                let own = decided_sign(cubic, split);
                if !(own.is_some() && own == decided_sign(&side.neighbour, split)) {
                    consider(split);
                }
            }
            if end > start {
                previous_ours = ours;
            }
            start = end;
        }
        best
    }
}

/// Heights a root search extends beyond the triangle's own range at least: a few ulps of the
/// unit height, so that a flat triangle's single height becomes an interval holding its plane's
/// root, and a split point within rounding of the range's end is compared by both triangles.
#[allow(non_snake_case)]
fn HEIGHT_WINDOW<T: Real>() -> T {
    T::from_i32(16) * T::EPSILON
}

/// How far beyond `end` (a height-range end of the triangle) a root of `cubic` may lie and
/// still be a rounding of a root at `end`: the first-order error of a root there (the rounding
/// of the cubic's value at `end`, `formed` from its coefficients and plane by
/// [`cubic_rounding`] and the Horner bound from its evaluation, with the rounding of `h`
/// itself, over the slope, with the safety factor of [`point_error_bound`]), at least
/// [`HEIGHT_WINDOW`] and at most [`CLAMP_LIMIT`] (the farthest a candidate is moved in texture
/// units: beyond it the slope is near zero, a tangency, and a point that far out is no
/// rounding of one on the range). An edge along a triangle's highest or lowest height (the
/// ridge of a feather's vane) puts the root of its two planes there, and an ill-conditioned
/// cubic moves it by more than a fixed few ulps: 20 ulps on feathers in f64, and 285 ulps
/// (7.9e-15) for a separating plane's crossing in a tile 49 units from the origin, whose
/// plane offsets cancel 50-unit terms (`nlrt watertight feathers --rays 65536 --precision
/// f64`, sample 28356).
fn height_window<T: Real>(cubic: &[T; 4], formed: T, end: T) -> T {
    let (_, rounding) = horner_with_bound(cubic, end);
    let slope = value_and_slope(cubic, end).1.abs();
    let error = T::from_i32(16) * (rounding + formed + T::EPSILON * end.abs() * slope) / slope;
    // `!(x <= y)`: a zero slope gives infinity or NaN, both capped.
    let capped = if error <= CLAMP_LIMIT::<T>() {
        error
    } else {
        CLAMP_LIMIT::<T>()
    };
    capped.max(HEIGHT_WINDOW::<T>())
}

/// A bound on the error at height `h` of `plane.ray_cubic(ray)`'s value from the rounding of
/// the cubic's coefficients and of the plane (`points`: points it was made to pass through),
/// before any evaluation. The cubic is `n_u U + n_v V + (k + n_h h) D` (Eq. 8 in Eq. 9), each
/// coefficient four products summed by four roundings, so its value errs by `gamma(4)` times
/// the same sum of absolute terms; the plane's offset `k = -n . p` errs by `gamma(3) sum |n_i
/// p_i|` and its unit normal's rounding moves its value at the points by as much, which `D`
/// multiplies. Both are relative to the size of the coordinates, not to the cubic's
/// coefficients: a plane in a tile far from the origin cancels terms of the tile index's size
/// in every coefficient, which the Horner bound (relative to the coefficients) does not see.
/// `U`, `V` and `D` are the same numbers for every plane of the ray, so their own rounding
/// moves no plane's root against another's and is left out.
fn cubic_rounding<T: Real>(
    plane: &TexturePlane<T>,
    points: &[T::Vec3],
    ray: &NonlinearRay<T>,
    h: T,
) -> T {
    let x = h.abs();
    let magnitude = |c: &[T; 3]| (c[2].abs() * x + c[1].abs()).mul_add(x, c[0].abs());
    let n = plane.normal;
    let (nu, nv, nh) = (n.x().abs(), n.y().abs(), n.z().abs());
    let offset = points.iter().fold(plane.k.abs(), |m, p| {
        m.max(nu.mul_add(p.x().abs(), nv.mul_add(p.y().abs(), nh * p.z().abs())))
    });
    let terms = nu.mul_add(
        magnitude(&ray.u),
        nv.mul_add(magnitude(&ray.v), (offset + nh * x) * magnitude(&ray.d)),
    );
    // gamma(4) for the coefficients and their sums, twice gamma(3) for the plane: below
    // 8 eps / (1 - 8 eps) = gamma(16) with room for the products of the bound's own rounding.
    T::from_i32(16) * T::EPSILON * terms
}

/// A shared edge as the piece search needs it: where the curve crosses its separating plane,
/// and on which side the curve is between crossings. Both triangles of the edge build it from
/// the same numbers (the plane's cubic solved on the object's whole height range `[0, 1]`, not
/// on each triangle's own), so they agree on every side.
struct Side<T: Real> {
    /// The separating plane's crossings in `[0, 1]`, increasing, with the poles (where the
    /// curve's denominator changes sign) among them.
    splits: [T; 5],
    /// Whether each crossing is the plane's (not a pole).
    is_crossing: [bool; 5],
    count: usize,
    /// Per stretch between consecutive splits (from 0 to 1), whether the curve lies on this
    /// triangle's side there.
    ours: [bool; 6],
    /// The neighbour's plane cubic, oriented like this triangle's.
    neighbour: [T; 4],
    /// The separating plane's cubic along the curve.
    along: [T; 4],
    /// The separating plane (in the tile) and the edge's ends, for [`cubic_rounding`].
    plane: TexturePlane<T>,
    ends: [T::Vec3; 2],
}

impl<T: Real> Side<T> {
    fn new(
        plane: TexturePlane<T>,
        ends: [T::Vec3; 2],
        positive: bool,
        neighbour: [T; 4],
        ray: &NonlinearRay<T>,
        poles: &[T],
    ) -> Self {
        let along = plane.ray_cubic(ray);
        let mut splits = [T::ZERO; 5];
        let mut is_crossing = [false; 5];
        let mut count = 0;
        for &r in solve_cubic_in(along, T::ZERO, T::ONE).iter() {
            splits[count] = r;
            is_crossing[count] = true;
            count += 1;
        }
        for &r in poles {
            splits[count] = r;
            count += 1;
        }
        // Insertion sort of at most five, carrying the tags.
        for i in 1..count {
            let mut j = i;
            while j > 0 && splits[j - 1] > splits[j] {
                splits.swap(j - 1, j);
                is_crossing.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut ours = [false; 6];
        for (j, side) in ours.iter_mut().enumerate().take(count + 1) {
            let a = if j == 0 { T::ZERO } else { splits[j - 1] };
            let b = if j == count { T::ONE } else { splits[j] };
            let h = (a + b) * T::HALF;
            let d = horner(&ray.d, h);
            let v = horner(&along, h);
            *side = d != T::ZERO && ((v > T::ZERO) == (d > T::ZERO)) == positive;
        }
        Self {
            splits,
            is_crossing,
            count,
            ours,
            neighbour,
            along,
            plane,
            ends,
        }
    }

    /// The plane's crossings (poles left out).
    fn crossings(&self) -> impl Iterator<Item = &T> {
        self.splits[..self.count]
            .iter()
            .zip(&self.is_crossing)
            .filter(|(_, c)| **c)
            .map(|(r, _)| r)
    }

    /// Whether the curve at `h` (not a split point) lies on this triangle's side.
    fn ours_at(&self, h: T) -> bool {
        let stretch = self.splits[..self.count].iter().filter(|&&r| r < h).count();
        self.ours[stretch]
    }
}

/// The farthest (in texture units, a tile being 1) a candidate point is moved onto the base
/// triangle: 2^-12, twice 16 ulps of a texture coordinate in `f32` at tile index 64 (the
/// largest of the built-in scenes; its ulp is 2^-17), so that points a rounding outside are
/// kept, while in a prism degenerate in world space (a sphere's pole), where the error bound
/// of a point grows without limit with the curve's speed in uv, a point a visible fraction of
/// a tile outside is not pulled onto the wall (a ghost hit in front of the surface).
#[allow(non_snake_case)]
fn CLAMP_LIMIT<T: Real>() -> T {
    T::pow2(-12)
}

/// `(alpha, beta)` of a candidate point outside the base triangle, moved onto it, when the
/// move is within the point's error bound `tolerance` (texture units, at most
/// [`CLAMP_LIMIT`]): the neighbouring prism computes the same wall with its own rounding, so a
/// point on the wall may fall a rounding outside in both, and each keeps it (on the wall). A
/// test of the wall crossing's own window or sign at the candidate's height, as the texel test
/// makes, would miss that the height itself is a rounded root: it rejected such points in both
/// prisms (scales, f32). `None` otherwise.
#[cold]
#[inline(never)]
fn kept_across_wall<T: Real>(prism: &Prism<T>, alpha: T, beta: T, tolerance: T) -> Option<(T, T)> {
    if !(alpha.is_finite() && beta.is_finite()) {
        return None;
    }
    // A point farther out is no rounding of a point on the wall (in a prism degenerate in
    // world space the point's error bound is wide, but the texture coordinates still tell how
    // far out the point is).
    let (a, b) = nlrt_shellmap::onto_base_triangle(alpha, beta);
    let (from, to) = (prism.texture_uv(alpha, beta), prism.texture_uv(a, b));
    let moved = (from.x() - to.x()).abs().max((from.y() - to.y()).abs());
    (moved <= tolerance.min(CLAMP_LIMIT::<T>())).then_some((a, b))
}

/// A first-order bound on the error of a candidate point `q` at height `h` on the curve, in
/// texture units, with a safety factor: the rounding of `q`'s coordinates (a few ulps of their
/// size) plus the root's error moved along the curve (the Horner bound of the plane cubic and
/// `formed`, the rounding of its coefficients and plane from [`cubic_rounding`], over its
/// slope, times the curve's speed `|du/dh| + |dv/dh|`, from `u = U / D`, `v = V / D`). It
/// only chooses between the fast path and the piece search, which is exact on either side of
/// it; the factor 16 keeps the fast path's decisions well clear of the errors it estimates.
/// Without `formed`, two coplanar triangles of a feather's vane in tile [62, 29] (planes whose
/// offsets cancel terms of 62) put their roots 6.8e-13 apart in `h`, each beyond the other's
/// side of their shared edge by more than the bound (3.0e-13 in texture units), and the ray
/// passed between them (`nlrt watertight feathers --rays 1048576 --precision f64`, sample
/// 122007).
fn point_error_bound<T: Real>(
    cubic: &[T; 4],
    formed: T,
    ray: &NonlinearRay<T>,
    q: T::Vec3,
    h: T,
) -> T {
    let eps = T::EPSILON;
    let size = q.x().abs().max(q.y().abs()).max(h.abs()).max(T::ONE);
    let (_, rounding) = horner_with_bound(cubic, h);
    let slope = value_and_slope(cubic, h).1.abs();
    let (d, d_slope) = value_and_slope(&ray.d, h);
    let u_slope = value_and_slope(&ray.u, h).1;
    let v_slope = value_and_slope(&ray.v, h).1;
    // speed = A / |D| + 1 and root error = (Horner bound + formed + eps |h| slope) / slope,
    // as one quotient (infinite where the curve or the cubic is stationary).
    let a = (u_slope - q.x() * d_slope).abs() + (v_slope - q.y() * d_slope).abs();
    let root = rounding + formed + eps * h.abs() * slope;
    let denominator = d.abs() * slope;
    let moved = if denominator > T::ZERO {
        (a + d.abs()) * root / denominator
    } else {
        T::INFINITY
    };
    T::from_i32(16) * (eps * size + moved)
}

#[cfg(test)]
mod tests {
    macro_rules! object_edge_tests {
        ($($t:ident),*) => {$(
            mod $t {
                use super::super::ObjectEdges;
                use nlrt_poly::{Real, Vector3};
                use nlrt_shellmap::{NonlinearRay, Prism, Ray, intersect_microtriangle};
                use alloc::vec;
                use alloc::vec::Vec;
                type T = $t;
                type V3 = <T as Real>::Vec3;
                type V2 = <T as Real>::Vec2;

                fn v(x: f64, y: f64, z: f64) -> V3 {
                    V3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z))
                }

                /// A sheared prism (curved nonlinear rays) over uv `[0, 1]^2`'s lower triangle.
                fn prism() -> Prism<T> {
                    let uv = |x: f64, y: f64| V2::new(T::from_f64(x), T::from_f64(y));
                    Prism::new(
                        [v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.1), v(0.1, 1.0, 0.0)],
                        [v(0.0, 0.0, 0.3), v(0.05, 0.0, 0.3), v(0.0, 0.05, 0.35)],
                        [uv(0.0, 0.0), uv(1.0, 0.0), uv(0.0, 1.0)],
                    )
                }

                /// Two triangles on edge `a b` (in the prism's lower uv triangle), the second
                /// wound consistently or not, folded by the height of `c2`.
                fn pair(c2_height: f64, consistent: bool) -> Vec<[V3; 3]> {
                    let (a, b) = (v(0.15, 0.2, 0.3), v(0.55, 0.25, 0.6));
                    let (c1, c2) = (v(0.25, 0.55, 0.45), v(0.45, 0.05, c2_height));
                    vec![[a, b, c1], if consistent { [b, a, c2] } else { [a, b, c2] }]
                }

                #[test]
                fn a_shared_edge_gets_a_plane_between_its_triangles() {
                    for consistent in [true, false] {
                        for height in [0.1, 0.4, 0.9] {
                            let edges = ObjectEdges::<T>::new(&pair(height, consistent));
                            assert_eq!(edges.edges.len(), 1, "{height} {consistent}");
                            let e = &edges.edges[0];
                            assert_eq!(e.same_winding, consistent);
                            assert_eq!(edges.of_triangle[0].iter().filter(|&&x| x == 0).count(), 1);
                            assert_eq!(edges.of_triangle[1].iter().filter(|&&x| x == 0).count(), 1);
                        }
                    }
                    // A boundary edge and an edge of three triangles get none.
                    let mut three = pair(0.4, true);
                    three.push([three[0][1], three[0][0], v(0.3, 0.1, 0.9)]);
                    assert!(ObjectEdges::<T>::new(&three).edges.is_empty());
                }

                /// Rays aimed at points of the shared edge from many directions hit one of the
                /// two triangles no farther than the aimed point (the plain per-triangle test,
                /// `intersect_microtriangle`, lets some through: counted, so the test can
                /// tell the two apart).
                #[test]
                fn rays_through_a_shared_edge_hit_one_of_its_triangles() {
                    let prism = prism();
                    let mut plain_misses = 0;
                    let mut rays = 0;
                    for consistent in [true, false] {
                        for height in [0.1, 0.4, 0.9] {
                            let tris = pair(height, consistent);
                            let edges = ObjectEdges::<T>::new(&tris);
                            let mut seed = 0x9e37_79b9_u64;
                            let mut next = || {
                                seed ^= seed << 13;
                                seed ^= seed >> 7;
                                seed ^= seed << 17;
                                (seed >> 11) as f64 / (1u64 << 53) as f64
                            };
                            for _ in 0..400 {
                                let s = 0.02 + 0.96 * next();
                                let [a, b] = [tris[0][0], tris[0][1]];
                                let p = a + (b - a) * T::from_f64(s);
                                let target = prism.shell_point(p.x(), p.y(), p.z());
                                // From above the shell, in a random direction of the upper half.
                                let d = v(next() - 0.5, next() - 0.5, -0.3 - next());
                                let Some(ray) = Ray::<T>::new(target - d * T::from_f64(4.0), d) else {
                                    continue;
                                };
                                let aimed = (target - ray.origin).length();
                                let nl = NonlinearRay::new(&prism, &ray);
                                let hit = (0..2u32).filter_map(|k| {
                                    edges.intersect(
                                        k, [0, 0], &tris[k as usize], &prism, &nl,
                                        T::ZERO, T::INFINITY, [T::NEG_INFINITY, T::INFINITY],
                                        |j| tris.get(j as usize).copied(),
                                    ).map(|(h, _)| h)
                                });
                                let nearest = hit.map(|h| h.t).fold(T::INFINITY, T::min);
                                let slack = T::from_f64(1e-3) * aimed;
                                assert!(
                                    nearest <= aimed + slack,
                                    "ray {ray:?} through the edge at s = {s} missed ({nearest} vs {aimed})"
                                );
                                let plain = (0..2).filter_map(|k| {
                                    let t = &tris[k];
                                    let lo = t[0].z().min(t[1].z()).min(t[2].z());
                                    let hi = t[0].z().max(t[1].z()).max(t[2].z());
                                    intersect_microtriangle(&prism, &nl, t, lo, hi, T::ZERO, T::INFINITY)
                                });
                                if plain.map(|h| h.t).fold(T::INFINITY, T::min) > aimed + slack {
                                    plain_misses += 1;
                                }
                                rays += 1;
                            }
                        }
                    }
                    assert!(rays > 2000, "{rays}");
                    // The plain test lets 129 (f32) and 162 (f64) of these 2,400 through.
                    assert!(plain_misses > 0, "the plain test let none of {rays} through");
                }
            }
        )*};
    }
    object_edge_tests!(f32, f64);
}
