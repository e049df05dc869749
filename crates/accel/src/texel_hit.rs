//! The texel test of displacement mapping: the nearest hit of a nonlinear ray on one texel's
//! microtriangles, watertight along the texel's edges and the base triangle's (the piece
//! search of `DisplacedSurface::intersect_texel`).

use nlrt_poly::{QuadraticBatch, Real, Vector3, decided_sign, solve_cubic_in, solve_quadratic_in};
use nlrt_shellmap::{
    BaseEdges, Hit, NonlinearRay, Prism, TextureCurve, TexturePlane, alpha_beta_eq11,
    piece_clear_in_f64, planes_agree_in_f64, root_decidedly_outside_in_f64,
};

use crate::displacement::{DisplacedSurface, plane_of};
use crate::leaving::{Exclusion, up_crossing};
use crate::surface_hit::TexelPart;

impl<T: Real> DisplacedSurface<T> {
    /// The nearest hit on texel `(x, y)` with `t` in `[t_min, t_max]`.
    ///
    /// Testing microtriangles independently leaks: each solves its own plane's cubic and
    /// judges its edges from its own hit point, so a hit on or near an edge shared with a
    /// neighbour can land, after rounding, just outside both (measured: every f32 leak of the
    /// mountain and torus scenes was one). So edges are decided once, along the ray: the
    /// curve's heights are split where it crosses the texel's four edge lines and its
    /// diagonal (roots of `U - u_face D`, `V - v_face D` and `U - V - (u0 - v0) D`: the same
    /// quadratics, with the same coefficients, in the neighbouring texel), each piece lies
    /// wholly inside or outside the texel and on one side of the diagonal and is searched with
    /// that side's plane only, and at each split point the planes on its two sides (this
    /// texel's, or the neighbour's across an outer edge) are compared: in exact arithmetic
    /// their cubics have the same sign there (both planes contain the shared edge, above which
    /// the curve point lies), so differing or uncertain signs mean the surface is crossed at
    /// the split point itself, which is reported. A flat texel is the same with one plane.
    pub fn intersect_texel(
        &self,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        x: i32,
        y: i32,
        t_min: T,
        t_max: T,
    ) -> Option<(Hit<T>, TexelPart)> {
        let curve = TextureCurve::new(prism, ray);
        let edges = BaseEdges::new(ray);
        // One texel alone: a decision `f32` cannot make is answered in `f32` here (the prism
        // walks send such a prism to `f64`, whole).
        let mut undecided = 0;
        self.texel_hit(
            prism,
            ray,
            (&edges, &curve, None),
            [x, y],
            [t_min, t_max],
            &mut undecided,
        )
    }

    /// [`DisplacedSurface::intersect_texel`] with the base edges and the texture curve's error
    /// bounds computed once per prism. In `f32`, a decision `f32` cannot make and `f64` makes
    /// otherwise (near a pole of the curve, `D(h)` a tenth of its coefficients: a split
    /// point's two signs below their rounding bounds where `f64` finds the two planes' signs
    /// equal, or a root its cubic's signs cannot vouch for where `f64` finds the curve clear
    /// of the plane; a coarse torus gave an `f32` ghost hit there, `docs/watertightness.md`)
    /// adds one to `undecided`, and the caller traces the prism again in `f64`, whole.
    #[inline(always)]
    pub(crate) fn texel_hit<C: Real>(
        &self,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        (edges, curve, excluded): (&BaseEdges<C>, &TextureCurve<'_, C>, Option<Exclusion>),
        [x, y]: [i32; 2],
        [t_min, t_max]: [C; 2],
        undecided: &mut u32,
    ) -> Option<(Hit<C>, TexelPart)> {
        let (uv, heights) = self.texel_geometry_in::<C>(x, y);
        let ([u0, v0, u1, v1], [h00, h10, h01, h11]) = (uv, heights);
        let flat = h00 == h10 && h00 == h01 && h00 == h11;
        let (part_l, part_u) = if flat {
            (TexelPart::Flat, TexelPart::Flat)
        } else {
            (TexelPart::Lower, TexelPart::Upper)
        };
        let (Some(plane_l), Some(plane_u)) =
            (plane_of(uv, heights, part_l), plane_of(uv, heights, part_u))
        else {
            return None;
        };
        let (cubic_l, cubic_u) = (plane_l.ray_cubic(ray), plane_u.ray_cubic(ray));
        let (abh_l, abh_u) = (plane_l.canonical(prism), plane_u.canonical(prism));
        let h_lo = h00.min(h10).min(h01).min(h11);
        let h_hi = h00.max(h10).max(h01).max(h11);
        // Edge lines times D: faces u = u0, u1, v = v0, v1 and the diagonal u - v = u0 - v0.
        let line = |a: &[C; 3], face: C| -> [C; 3] {
            core::array::from_fn(|i| (-face).mul_add(ray.d[i], a[i]))
        };
        let c = u0 - v0;
        let u_minus_v: [C; 3] = core::array::from_fn(|i| ray.u[i] - ray.v[i]);
        let diagonal = line(&u_minus_v, c);
        // Split points, each tagged with the edge it lies on (0-3 faces, 4 diagonal, 5 other).
        let mut splits = [(C::ZERO, 5u8); 24];
        let mut n = 0;
        for s in [h_lo, h_hi] {
            splits[n] = (s, 5);
            n += 1;
        }
        // Faces, base edges and a pole that the curve cannot reach on [h_lo, h_hi] (an interval
        // bound beyond the rounding of the quadratic and its evaluation) have no root to
        // solve for: the splits are the same, as the solver would find nothing there either;
        // the neighbouring texel decides the shared face by the same quadratic.
        // A flat texel is decided by one point (below): no splits.
        let base_edges = &edges.edges;
        if !flat {
            // The quadratics to solve, each with the tag of its splits, solved on [h_lo, h_hi]
            // together (eight lanes at a time: the same roots as one by one, bit for bit).
            let mut batch = QuadraticBatch::default();
            let faces = [(&ray.u, u0), (&ray.u, u1), (&ray.v, v0), (&ray.v, v1)];
            for (edge, (num, face)) in faces.into_iter().enumerate() {
                if curve.may_cross(edge / 2, face, h_lo, h_hi) {
                    batch.add(line(num, face), edge as u8);
                }
            }
            batch.add(diagonal, 4);
            if edges.may_have_pole(h_lo, h_hi) {
                batch.add(ray.d, 5);
            }
            // The base triangle's edges: alpha = 0, beta = 0, alpha + beta = 1 (times D).
            for (k, q) in base_edges.iter().enumerate() {
                if edges.may_cross(k, h_lo, h_hi) {
                    batch.add(*q, 6 + k as u8);
                }
            }
            batch.solve(h_lo, h_hi, |r, tag| {
                splits[n] = (r, tag);
                n += 1;
            });
        }
        let splits = &mut splits[..n];
        splits.sort_unstable_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(core::cmp::Ordering::Equal));

        // A ray leaving the surface does not hit its own element, nor touch a neighbour at
        // its origin (`Exclusion::skips`).
        let skipped = |part: TexelPart, abh: &[C; 4], point: [C; 3], t: C| {
            excluded.is_some_and(|e| {
                e.skips([x, y], part.index(), t.to_f64(), || {
                    up_crossing(prism, abh, point, ray.ray.dir)
                })
            })
        };
        let mut best: Option<(Hit<C>, TexelPart)> = None;
        let mut t_max = t_max;
        let mut consider = |h: C, abh: &[C; 4], part: TexelPart, t_max: &mut C| {
            let Some((alpha, beta)) = alpha_beta_eq11(ray, abh, h) else {
                return;
            };
            if !(alpha.is_finite() && beta.is_finite()) {
                return;
            }
            // The pieces decide inside-ness; Eq. 11 may put a point on an edge a rounding
            // error outside, so clamp it onto the base triangle.
            let (alpha, beta) = nlrt_shellmap::onto_base_triangle(alpha, beta);
            let t = ray.signed_distance(prism, alpha, beta, h);
            if t >= t_min && t <= *t_max && !skipped(part, abh, [alpha, beta, h], t) {
                *t_max = t;
                best = Some((Hit::at(prism, t, alpha, beta, h), part));
            }
        };
        // Where the piece around `h` lies: None outside the texel, else Some(lower side).
        let locate = |h: C| -> Option<bool> {
            let d = ray.d[2].mul_add(h, ray.d[1]).mul_add(h, ray.d[0]);
            if d == C::ZERO {
                return None;
            }
            let u = ray.u[2].mul_add(h, ray.u[1]).mul_add(h, ray.u[0]) / d;
            let v = ray.v[2].mul_add(h, ray.v[1]).mul_add(h, ray.v[0]) / d;
            if !(u >= u0 && u <= u1 && v >= v0 && v <= v1) {
                return None;
            }
            if !edges.contains(h) {
                return None;
            }
            let f = diagonal[2].mul_add(h, diagonal[1]).mul_add(h, diagonal[0]);
            Some((f >= C::ZERO) == (d > C::ZERO) || f == C::ZERO)
        };
        let side = |lower: bool| {
            if lower {
                (&cubic_l, &abh_l, part_l, &plane_l)
            } else {
                (&cubic_u, &abh_u, part_u, &plane_u)
            }
        };
        // The error window of a base-edge crossing (split tags 6-8).
        let edge_window = |edge: u8, s: C| edges.window(usize::from(edge - 6), s);
        // The curve's point at the height `c` of a horizontal plane, when it lies in the texel
        // (u(h), v(h) are the same numbers in every texel, so neighbours agree) and in the base
        // triangle, where a base edge whose crossing lies within its error window of `c`
        // counts as passed (as the pieces are extended below): `Some(on the lower side of
        // the diagonal or on it, on the upper side or on it)`.
        let point_at = |c: C| -> Option<(bool, bool)> {
            let d = ray.d[2].mul_add(c, ray.d[1]).mul_add(c, ray.d[0]);
            if d == C::ZERO {
                return None;
            }
            let u = ray.u[2].mul_add(c, ray.u[1]).mul_add(c, ray.u[0]) / d;
            let v = ray.v[2].mul_add(c, ray.v[1]).mul_add(c, ray.v[0]) / d;
            let in_texel = u >= u0 && u <= u1 && v >= v0 && v <= v1;
            let positive = d > C::ZERO;
            let edge_ok = |k: usize| {
                let q = &base_edges[k];
                let value = q[2].mul_add(c, q[1]).mul_add(c, q[0]);
                let value = if k == 2 { -value } else { value };
                value == C::ZERO || (value > C::ZERO) == positive || {
                    let w = edge_window(6 + k as u8, c);
                    !solve_quadratic_in(*q, c - w, c + w).is_empty()
                }
            };
            if !(in_texel && edge_ok(0) && edge_ok(1) && edge_ok(2)) {
                return None;
            }
            // The side of the diagonal as `locate` decides it, the diagonal itself on both.
            let f = diagonal[2].mul_add(c, diagonal[1]).mul_add(c, diagonal[0]);
            let lower = (f >= C::ZERO) == positive;
            Some((lower || f == C::ZERO, !lower || f == C::ZERO))
        };
        if flat {
            // The curve meets the plane h = h00 at one point: a hit where `point_at` holds.
            if point_at(h00).is_some() {
                consider(h00, &abh_l, TexelPart::Flat, &mut t_max);
            }
            return best;
        }
        // A horizontal microtriangle (its three corners at one height) at the texel's lowest
        // or highest height: its plane's cubic, `D(h) (h - c)` up to the coefficients'
        // rounding, has its root at an end of the heights searched, where that rounding can
        // move it just outside (the piece search then loses the hit: f32 leaks on coarse
        // prisms, a plateau's texel beside a spike, `docs/watertightness.md`). Decided as a
        // flat texel is, by the curve's point at that height, on this part's side of the
        // diagonal; the piece search below may find the same hit, the nearer one is kept.
        for (horizontal, c, part, abh) in [
            (h00 == h10 && h10 == h11, h00, part_l, &abh_l),
            (h00 == h11 && h11 == h01, h00, part_u, &abh_u),
        ] {
            if horizontal
                && (c == h_lo || c == h_hi)
                && let Some((lower, upper)) = point_at(c)
                && (if part == part_l { lower } else { upper })
            {
                consider(c, abh, part, &mut t_max);
            }
        }
        // The base is a floor under the surface (heights are >= 0): a ray that leaves the shell
        // through the base inside this texel, descending, has met the surface by then. Where it
        // meets it at the base itself (a texel with a corner at 0, the ray through its zero
        // edge or corner), the cubic's value there is 0 up to the rounding of its
        // coefficients, which the piece search cannot see (no sign change): report the floor
        // point. It is never nearer than the true hit, so it adds no ghost; where the search
        // finds a hit, that one is nearer and wins.
        let floor_hit = |b: C, t_max: C| -> Option<Hit<C>> {
            let (alpha, beta) = ray.alpha_beta(C::ZERO)?;
            let t_top = curve.distance(b)?;
            let t = ray.signed_distance(prism, alpha, beta, C::ZERO);
            // Descending (the base is reached after the piece's top), inside the triangle.
            let inside = alpha >= C::ZERO && beta >= C::ZERO && alpha + beta <= C::ONE;
            (t > t_top && inside && t >= t_min && t <= t_max)
                .then(|| Hit::at(prism, t, alpha, beta, C::ZERO))
        };
        // The floor stands for a crossing at the base only where the ray came down from above
        // the surface: where, at the piece's top `b`, the curve is decidedly below this
        // texel's plane, it came in under the sheet (through the prism's side at an open
        // border, or from below) and meets nothing on its way to the base. The cubic is `D`
        // times the plane's value, whose sign along `h` is that of `n_h` above the plane.
        let below_at_top = |cubic: &[C; 4], plane: &TexturePlane<C>, b: C| -> bool {
            match (decided_sign(cubic, b), decided_sign(&ray.d, b)) {
                (Some(value_positive), Some(d_positive)) => {
                    let above = value_positive == (d_positive == (plane.normal.z() > C::ZERO));
                    !above
                }
                _ => false,
            }
        };
        let mut floor: Option<(Hit<C>, TexelPart)> = None;
        let mut previous: Option<bool> = None; // location of the piece before the split point
        for i in 0..splits.len() {
            let (a, edge) = splits[i];
            let here = (i + 1 < splits.len() && splits[i + 1].0 > a)
                .then(|| locate((a + splits[i + 1].0) * C::HALF))
                .flatten();
            // The planes on both sides of this split point must agree in sign: on the
            // diagonal this texel's two, on an outer edge this texel's and the neighbour's
            // (unless the curve only touches the edge from inside).
            let inside_next_to_split = previous.is_some() || here.is_some();
            let pair = match edge {
                _ if i == 0 || !inside_next_to_split => None,
                4 => Some((side(true), Some((plane_u, cubic_u)))),
                0..=3 if previous.is_none() || here.is_none() => {
                    let own = side(here.or(previous).unwrap_or(true));
                    let (nx, ny, part) = match edge {
                        0 => (x - 1, y, TexelPart::Lower),
                        1 => (x + 1, y, TexelPart::Upper),
                        2 => (x, y - 1, TexelPart::Upper),
                        _ => (x, y + 1, TexelPart::Lower),
                    };
                    let other = self
                        .texel_plane_in::<C>(nx, ny, part)
                        .map(|p| (p, p.ray_cubic(ray)));
                    Some((own, other))
                }
                _ => None,
            };
            if let Some(((own_cubic, own_abh, own_part, own_plane), Some((other, other_cubic)))) =
                pair
            {
                let (own_sign, other_sign) =
                    (decided_sign(own_cubic, a), decided_sign(&other_cubic, a));
                if !(own_sign.is_some() && own_sign == other_sign) {
                    // Neither sign decided in `C` where `f64` finds them equal (`f32` near a
                    // pole of the curve): the prism goes to `f64`.
                    if own_sign.is_none()
                        && other_sign.is_none()
                        && planes_agree_in_f64(prism, &ray.ray, [own_plane, &other], a)
                    {
                        *undecided += 1;
                    }
                    consider(a, own_abh, own_part, &mut t_max);
                }
            }
            if let Some(lower) = here {
                let (b, edge_b) = splits[i + 1];
                let (cubic, abh, part, plane) = side(lower);
                if a == C::ZERO
                    && !below_at_top(cubic, plane, b)
                    && let Some(hit) = floor_hit(b, t_max)
                    && !skipped(part, abh, [hit.alpha, hit.beta, C::ZERO], hit.t)
                {
                    t_max = hit.t;
                    floor = Some((hit, part));
                }
                // Where the piece ends on a base-triangle edge, the neighbouring prism computes
                // the same crossing with its own rounding: extend the piece by a bound on this
                // crossing's error so the two prisms' pieces overlap (no gap to slip through);
                // a root found in the extension is reported on the edge.
                let lo = if edge >= 6 {
                    (a - edge_window(edge, a)).max(h_lo)
                } else {
                    a
                };
                let hi = if edge_b >= 6 {
                    (b + edge_window(edge_b, b)).min(h_hi)
                } else {
                    b
                };
                for &r in solve_cubic_in(*cubic, lo, hi).iter() {
                    // A root in an extension is reported only where this prism may own it:
                    // one that lies beyond doubt across the edge is the neighbour's (its piece
                    // covers that height, its window holding the exact crossing), and this
                    // plane's continuation there is no surface (an f32 ghost hit in front of
                    // the neighbour's true one, where the window reaches far outside). Decided
                    // at the f64 root (the f32 root's own error can carry it across the edge
                    // where the surface is crossed at the edge itself). Not where the curve
                    // also crosses the texel's diagonal within the window: the neighbour's
                    // curve, rounded otherwise, may see that crossing on the other side of the
                    // base edge and search the other plane there (one f32 leak of the torus
                    // at 1M rays, each prism leaving the other its root).
                    let across = if r < a && edge >= 6 {
                        Some((edge, a))
                    } else if r > b && edge_b >= 6 {
                        Some((edge_b, b))
                    } else {
                        None
                    };
                    if let Some((edge, at)) = across
                        && !diagonal_beyond(splits, at, r, edge_window(edge, at))
                        && root_decidedly_outside_in_f64(
                            prism,
                            &ray.ray,
                            plane,
                            usize::from(edge - 6),
                            r,
                            [lo, hi],
                        )
                    {
                        continue;
                    }
                    // A root `C` cannot vouch for (its cubic's sign undecided at an end of the
                    // search, or the same at both) where `f64` finds the curve clear of the
                    // plane over the whole search (`f32` near a pole of the curve: a root at
                    // the split point beside the ghost above): the prism goes to `f64`.
                    let (sign_lo, sign_hi) = (decided_sign(cubic, lo), decided_sign(cubic, hi));
                    let vouched = sign_lo.is_some() && sign_hi.is_some() && sign_lo != sign_hi;
                    if !vouched && piece_clear_in_f64(prism, &ray.ray, plane, [lo, hi]) {
                        *undecided += 1;
                    }
                    consider(r.max(a).min(b), abh, part, &mut t_max);
                }
            }
            previous = here;
        }
        match (best, floor) {
            (Some(b), Some(f)) if f.0.t < b.0.t => Some(f),
            (None, f) => f,
            (b, _) => b,
        }
    }
}

/// Whether a crossing of the texel's diagonal (tag 4 of the texel test's splits) lies within
/// `window` of the base-edge crossing `at`, at or beyond the root `r` seen from `at`: the
/// stretch between the two crossings, where `r` lies, may be on the other side of the
/// diagonal in the neighbouring prism's curve. (Crossings of the texel's faces as well kept
/// one more `f32` ghost on the twisted torus at 65,536 rays and closed no leak: left out.)
fn diagonal_beyond<C: Real>(splits: &[(C, u8)], at: C, r: C, window: C) -> bool {
    splits.iter().any(|&(s, tag)| {
        tag == 4 && !((s - at).abs() > window) && (s - at) * (r - at) >= C::ZERO && {
            let (near, far) = ((r - at).abs(), (s - at).abs());
            near <= far
        }
    })
}
