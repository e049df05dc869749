//! Nonlinear ray against an axis-aligned box in texture space (Ogaki 2023, sec. 4.4): where the
//! curve `h -> (u(h), v(h), h)` is inside `[u_lo, u_hi] x [v_lo, v_hi] x [h_lo, h_hi]`.

use crate::prism::Prism;
use crate::ray::NonlinearRay;
use nlrt_poly::{LaneMask, Lanes4, Real, Roots, Vector2, quadratic_range, solve_quadratic_in};

/// Where a nonlinear ray is inside a texture-space box: the range of heights and the range of
/// distances along the world ray that the accelerators use for ordering and range reduction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BoxSpan<T> {
    /// Smallest height inside.
    pub h_in: T,
    /// Largest height inside.
    pub h_out: T,
    /// Smallest distance along the ray inside (sampled; see [`intersect_box`]).
    pub t_in: T,
    /// Largest distance along the ray inside (sampled; see [`intersect_box`]).
    pub t_out: T,
}

/// Most candidate heights: the two `h` faces, two roots for each of the four `u`/`v` faces and
/// two for the denominator's zeros.
const MAX_CANDIDATES: usize = 12;

/// A nonlinear ray's texture-space curve `h -> (u(h), v(h))` with bounds on the rounding
/// errors of evaluating it, for the accelerators that walk it through a grid of cells: the
/// box test ([`TextureCurve::box_pieces`]), the crossings of grid lines
/// ([`TextureCurve::crossings`]) and the side of a line a stretch of the curve is on
/// ([`TextureCurve::uv_with_error`]). Built once per ray and prism.
#[derive(Clone, Copy, Debug)]
pub struct TextureCurve<'a, T: Real> {
    prism: &'a Prism<T>,
    ray: &'a NonlinearRay<T>,
    /// `U`, `V` and `D` with every term's magnitude: the error bounds' polynomials.
    mu: [T; 3],
    mv: [T; 3],
    md: [T; 3],
    gamma8: T,
}

impl<'a, T: Real> TextureCurve<'a, T> {
    /// The curve of `ray` in `prism`.
    #[must_use]
    pub fn new(prism: &'a Prism<T>, ray: &'a NonlinearRay<T>) -> Self {
        let [t0, t1, t2] = prism.uv;
        let (du1, du2) = ((t1.x() - t0.x()).abs(), (t2.x() - t0.x()).abs());
        let (dv1, dv2) = ((t1.y() - t0.y()).abs(), (t2.y() - t0.y()).abs());
        let magnitude = |i: usize, base: T, e1: T, e2: T| {
            ray.d[i].abs().mul_add(
                base.abs(),
                ray.alpha[i].abs().mul_add(e1, ray.beta[i].abs() * e2),
            )
        };
        // The coefficients of U, V and D are sums of three products of accurately computed
        // terms; they and their evaluation err by less than gamma(8) times the same
        // polynomials with absolute-valued terms.
        let eight_u = T::from_i32(8) * T::UNIT_ROUNDOFF;
        Self {
            prism,
            ray,
            mu: core::array::from_fn(|i| magnitude(i, t0.x(), du1, du2)),
            mv: core::array::from_fn(|i| magnitude(i, t0.y(), dv1, dv2)),
            md: core::array::from_fn(|i| ray.d[i].abs()),
            gamma8: eight_u / (T::ONE - eight_u),
        }
    }

    /// The nonlinear ray.
    #[must_use]
    pub fn ray(&self) -> &NonlinearRay<T> {
        self.ray
    }

    /// `(u(h), v(h))` and bounds on their rounding errors; `None` where the denominator is 0.
    #[must_use]
    #[inline]
    pub fn uv_with_error(&self, h: T) -> Option<([T; 2], [T; 2])> {
        let ray = self.ray;
        let d = quadratic(&ray.d, h);
        if d == T::ZERO {
            return None;
        }
        let (u, v) = (quadratic(&ray.u, h) / d, quadratic(&ray.v, h) / d);
        let a = h.abs();
        let (d_abs, inv) = (quadratic(&self.md, a), self.gamma8 / d.abs());
        let eu = (quadratic(&self.mu, a) + u.abs() * d_abs) * inv;
        let ev = (quadratic(&self.mv, a) + v.abs() * d_abs) * inv;
        Some(([u, v], [eu, ev]))
    }

    /// On which side of the line `u = c` (`axis` 0) or `v = c` (`axis` 1) the curve is at
    /// height `h`: `Some(true)` beyond it (`u > c`), `Some(false)` before it, `None` where
    /// rounding cannot tell (on the line within the bound, or `D(h)` within its own). The
    /// sign of `u - c` is that of `(U - c D) D`: the line quadratic of
    /// [`TextureCurve::crossings`] decided against the same `gamma(8)` bound, and `D`
    /// against its evaluation bound, without the divisions of
    /// [`TextureCurve::uv_with_error`].
    #[must_use]
    #[inline]
    pub fn side_of_line(&self, axis: usize, c: T, h: T) -> Option<bool> {
        let x = h.abs();
        let d = quadratic(&self.ray.d, h);
        let d_magnitude = quadratic(&self.md, x);
        if !(d.abs() > self.gamma8 * d_magnitude) {
            return None;
        }
        let (q, mag) = self.line(axis, c);
        let margin = self.gamma8 * c.abs().mul_add(d_magnitude, quadratic(mag, x));
        let value = quadratic(&q, h);
        let signed = if d > T::ZERO { value } else { -value };
        if signed > margin {
            Some(true)
        } else if signed < -margin {
            Some(false)
        } else {
            None
        }
    }

    /// The distance along the world ray at height `h`; `None` where the denominator is 0.
    #[must_use]
    #[inline]
    pub fn distance(&self, h: T) -> Option<T> {
        self.ray
            .alpha_beta(h)
            .map(|(alpha, beta)| self.ray.signed_distance(self.prism, alpha, beta, h))
    }

    /// Heights in `[a, b]` where the curve crosses the line `u = c` (`axis` 0) or `v = c`
    /// (`axis` 1), increasing, each with the half-width of a window around it that holds the
    /// crossing of the exact curve: the rounding bound of `U - c D` at the root (as in
    /// [`TextureCurve::uv_with_error`]) over its slope there, doubled for the second-order
    /// term and the solver's last-bit error; infinite where the slope is 0 (a tangency, or a
    /// curve running along the line).
    #[must_use]
    #[inline]
    pub fn crossings(&self, axis: usize, c: T, a: T, b: T) -> ([(T, T); 2], usize) {
        let (q, mag) = self.line(axis, c);
        let mut out = [(T::ZERO, T::ZERO); 2];
        let mut n = 0;
        if !self.may_vanish(&q, mag, c, a, b) {
            return (out, 0);
        }
        let roots = solve_quadratic_in(q, a, b);
        for &r in roots.iter() {
            let x = r.abs();
            let err = self.gamma8 * c.abs().mul_add(quadratic(&self.md, x), quadratic(mag, x));
            let slope = (T::TWO * q[2]).mul_add(r, q[1]).abs();
            let w = if slope > T::ZERO {
                T::TWO * (err / slope + x * T::UNIT_ROUNDOFF)
            } else {
                T::INFINITY
            };
            out[n] = (r, w);
            n += 1;
        }
        (out, n)
    }

    /// [`intersect_box`] on this curve: the hull of [`TextureCurve::box_pieces`] (for many
    /// boxes tested along one curve, which set up their error bounds once).
    #[must_use]
    pub fn box_span(&self, lo: [T; 3], hi: [T; 3], t_min: T, t_max: T) -> Option<BoxSpan<T>> {
        self.box_span_in(self.uv_enclosure(lo[2], hi[2]), lo, hi, t_min, t_max)
    }

    /// [`TextureCurve::box_span`] given the curve's uv enclosure over the box's heights
    /// (`uv_enclosure(lo[2], hi[2])`, which a caller that also uses it computes once).
    #[must_use]
    pub fn box_span_in(
        &self,
        enclosure: Option<[T; 4]>,
        lo: [T; 3],
        hi: [T; 3],
        t_min: T,
        t_max: T,
    ) -> Option<BoxSpan<T>> {
        let mut span: Option<BoxSpan<T>> = None;
        self.box_pieces_in(enclosure, lo, hi, t_min, t_max, |p| {
            let s = span.get_or_insert(p);
            s.h_in = s.h_in.min(p.h_in);
            s.h_out = s.h_out.max(p.h_out);
            s.t_in = s.t_in.min(p.t_in);
            s.t_out = s.t_out.max(p.t_out);
        });
        span
    }

    /// Whether the curve may cross the line `u = c` (`axis` 0) or `v = c` (`axis` 1) at a
    /// height in `[a, b]`: false only where `U - c D` keeps one sign there by more than its
    /// rounding bound (the `gamma(8)` bound of [`TextureCurve::crossings`], beyond the
    /// evaluation bound by which a solver on `[a, b]` would report an end as a root), so that
    /// neither `crossings` nor a solver on `[a, b]` would find a root.
    #[must_use]
    #[inline]
    pub fn may_cross(&self, axis: usize, c: T, a: T, b: T) -> bool {
        let (q, mag) = self.line(axis, c);
        self.may_vanish(&q, mag, c, a, b)
    }

    /// The line `u = c` (`axis` 0) or `v = c` (`axis` 1) seen along the curve: the quadratic
    /// `U - c D` (`V - c D`), zero where the curve is on the line, and the coefficient
    /// magnitudes of `U` (`V`) for its error bound.
    #[inline]
    fn line(&self, axis: usize, c: T) -> ([T; 3], &[T; 3]) {
        let (num, mag) = if axis == 0 {
            (&self.ray.u, &self.mu)
        } else {
            (&self.ray.v, &self.mv)
        };
        let d = &self.ray.d;
        (core::array::from_fn(|i| (-c).mul_add(d[i], num[i])), mag)
    }

    /// Whether `q = N - c D` (`N` the curve's `U` or `V`, with coefficient magnitudes `mag`)
    /// may vanish on `[a, b]`. Most stretches of curve stay on one side of a line: the range
    /// of `q` over `[a, b]` (ends and vertex), away from 0 by more than the error bound of its
    /// coefficients and their evaluation (the gamma(8) bound of [`TextureCurve::crossings`],
    /// which also exceeds the bound by which the solver would report an end of `[a, b]` as a
    /// root), has no root, which the solver would confirm at more cost.
    #[inline]
    fn may_vanish(&self, q: &[T; 3], mag: &[T; 3], c: T, a: T, b: T) -> bool {
        let x = a.abs().max(b.abs());
        let margin = self.gamma8 * c.abs().mul_add(quadratic(&self.md, x), quadratic(mag, x));
        let (lo, hi) = quadratic_range(q, a, b);
        !(lo > margin || hi < -margin)
    }

    /// An enclosure `[u_lo, u_hi, v_lo, v_hi]` of the curve's `(u(h), v(h))` for `h` in
    /// `[h_lo, h_hi]`, widened by the rounding bound of [`TextureCurve::crossings`], so that a
    /// box whose uv rectangle misses it holds no piece of [`TextureCurve::box_pieces`] at
    /// those heights, and a line `u = c` outside `[u_lo, u_hi]` has no crossing there (nor at
    /// any heights inside them: the same enclosure covers every sub-interval). `None` where
    /// the denominator may vanish on the interval (no bound).
    ///
    /// In centred form around the interval's midpoint `m` (half-width `r`): with `c` the
    /// curve's `u` there, `u - c = q / D` for the line quadratic `q = U - c D` of
    /// [`TextureCurve::crossings`], and on the interval `|q| <= |q(m)| + |q'(m)| r + |q_2| r^2`
    /// (Taylor at `m`, exact for a quadratic; `q(m)` is nearly 0 by the choice of `c`) while
    /// `|D| >= |D(m)| - |D'(m)| r - |D_2| r^2`. The bound shrinks with the interval (as
    /// `|u'(m)| r`), unlike a quotient of the ranges of `U` and `D` (whose width stays
    /// `|u| ΔD / D`), which makes it the better early rejection for the short height
    /// intervals of a walk's pieces (the shell's tile search); it costs two divisions.
    /// Rounding: the `gamma(8)` bound of the coefficients and an evaluation, once more for
    /// the evaluations at `m`, and `8 u` relative on each sum and quotient.
    #[must_use]
    #[inline]
    pub fn uv_enclosure(&self, h_lo: T, h_hi: T) -> Option<[T; 4]> {
        let ray = self.ray;
        let gamma8 = self.gamma8;
        let eight_u = T::from_i32(8) * T::UNIT_ROUNDOFF;
        let up = |x: T| x + (x.abs() * eight_u + T::MIN_POSITIVE);
        let down = |x: T| x - (x.abs() * eight_u + T::MIN_POSITIVE);
        let m = (h_lo + h_hi) * T::HALF;
        let r = up((h_hi - m).max(m - h_lo));
        let x = h_lo.abs().max(h_hi.abs());
        // `|p(m)| + |p'(m)| r + |p_2| r^2` for a quadratic `p` on the interval.
        let spread = |p: &[T; 3]| {
            let slope = (T::TWO * p[2]).mul_add(m, p[1]);
            (p[2].abs() * r).mul_add(r, slope.abs() * r)
        };
        let d = &ray.d;
        let d_abs = quadratic(&self.md, x);
        let d_m = quadratic(d, m);
        let d_min = down(d_m.abs() - up(spread(d) + T::TWO * gamma8 * d_abs));
        if !(d_min > T::ZERO) {
            return None;
        }
        let (inv_m, inv_min) = (T::ONE / d_m, up(T::ONE / d_min));
        let around = |axis: usize| {
            // Any centre gives an enclosure; the midpoint's value gives the tightest.
            let num = if axis == 0 { &ray.u } else { &ray.v };
            let c = quadratic(num, m) * inv_m;
            let (q, mag) = self.line(axis, c);
            let err = gamma8 * c.abs().mul_add(d_abs, quadratic(mag, x));
            let q_max = up(quadratic(&q, m).abs() + up(spread(&q) + T::TWO * err));
            let bound = up(q_max * inv_min);
            (down(c - bound), up(c + bound))
        };
        let (u_lo, u_hi) = around(0);
        let (v_lo, v_hi) = around(1);
        Some([u_lo, u_hi, v_lo, v_hi])
    }

    /// [`TextureCurve::uv_enclosure`] of four height intervals (`[h_lo[k], h_hi[k]]`, each
    /// finite and not empty) in one vector step ([`Real::Four`], lane `k` interval `k`):
    /// the four children of an object-BVH node in one step. The same operations lane by lane
    /// as `uv_enclosure`, so the same bits (tested).
    #[must_use]
    #[inline]
    pub fn uv_enclosures(&self, h_lo: [T; 4], h_hi: [T; 4]) -> [Option<[T; 4]>; 4] {
        self.uv_enclosures_in::<T::Four>(h_lo, h_hi)
    }

    /// [`TextureCurve::uv_enclosures`] in lanes `L`: `uv_enclosure`'s steps, `Real::max` as
    /// `greater` (the same number: the operands are not NaN for finite intervals, and equal
    /// ones are equal numbers, both `+0` where both are zero).
    #[inline(always)]
    fn uv_enclosures_in<L: Lanes4<T>>(&self, h_lo: [T; 4], h_hi: [T; 4]) -> [Option<[T; 4]>; 4] {
        let ray = self.ray;
        let s = L::splat;
        let (eight_u, tiny) = (s(T::from_i32(8) * T::UNIT_ROUNDOFF), s(T::MIN_POSITIVE));
        let up = |x: L| x + (x.abs() * eight_u + tiny);
        let down = |x: L| x - (x.abs() * eight_u + tiny);
        let quad = |c: &[T; 3], h: L| s(c[2]).mul_add(h, s(c[1])).mul_add(h, s(c[0]));
        let quad_lanes = |c: &[L; 3], h: L| c[2].mul_add(h, c[1]).mul_add(h, c[0]);
        let (h_lo, h_hi) = (L::from_array(h_lo), L::from_array(h_hi));
        let m = (h_lo + h_hi) * s(T::HALF);
        let r = up((h_hi - m).greater(m - h_lo));
        let x = h_lo.abs().greater(h_hi.abs());
        let spread = |p: &[L; 3]| {
            let slope = (s(T::TWO) * p[2]).mul_add(m, p[1]);
            (p[2].abs() * r).mul_add(r, slope.abs() * r)
        };
        let d = ray.d.map(s);
        let d_abs = quad(&self.md, x);
        let d_m = quad_lanes(&d, m);
        let two_gamma8 = s(T::TWO * self.gamma8);
        let d_min = down(d_m.abs() - up(spread(&d) + two_gamma8 * d_abs));
        let exists = d_min.gt(s(T::ZERO)).bits();
        let (inv_m, inv_min) = (s(T::ONE) / d_m, up(s(T::ONE) / d_min));
        let around = |num: &[T; 3], mag: &[T; 3]| {
            let c = quad(num, m) * inv_m;
            let q: [L; 3] = core::array::from_fn(|i| (-c).mul_add(d[i], s(num[i])));
            let err = s(self.gamma8) * c.abs().mul_add(d_abs, quad(mag, x));
            let q_max = up(quad_lanes(&q, m).abs() + up(spread(&q) + s(T::TWO) * err));
            let bound = up(q_max * inv_min);
            (down(c - bound).to_array(), up(c + bound).to_array())
        };
        let (u_lo, u_hi) = around(&ray.u, &self.mu);
        let (v_lo, v_hi) = around(&ray.v, &self.mv);
        core::array::from_fn(|k| {
            (exists >> k & 1 == 1).then_some([u_lo[k], u_hi[k], v_lo[k], v_hi[k]])
        })
    }

    /// Calls `piece` for each stretch of the curve inside the texture-space box `lo..=hi`
    /// (each `(u, v, h)`) whose distances along the world ray meet `[t_min, t_max]`: its
    /// heights `h_in..=h_out` and distances `t_in..=t_out` (clamped to `[t_min, t_max]`).
    /// A curve only touching the box gives a piece with `h_in == h_out`. See
    /// [`intersect_box`] for how inside-ness is decided.
    pub fn box_pieces(
        &self,
        lo: [T; 3],
        hi: [T; 3],
        t_min: T,
        t_max: T,
        piece: impl FnMut(BoxSpan<T>),
    ) {
        if !(lo[2] <= hi[2]) {
            return;
        }
        let enclosure = self.uv_enclosure(lo[2], hi[2]);
        self.box_pieces_in(enclosure, lo, hi, t_min, t_max, piece);
    }

    /// [`TextureCurve::box_pieces`] given `enclosure`, the curve's uv enclosure over the
    /// box's heights ([`TextureCurve::uv_enclosure`]`(lo[2], hi[2])`).
    fn box_pieces_in(
        &self,
        enclosure: Option<[T; 4]>,
        lo: [T; 3],
        hi: [T; 3],
        t_min: T,
        t_max: T,
        mut piece: impl FnMut(BoxSpan<T>),
    ) {
        let (h_lo, h_hi) = (lo[2], hi[2]);
        if !(h_lo <= h_hi && lo[0] <= hi[0] && lo[1] <= hi[1]) {
            return;
        }
        // Early rejection by interval arithmetic (see `uv_enclosure`): sound (never rejects
        // what the exact test keeps) and cheap; most boxes of a traversal are rejected here
        // without solving a quadratic.
        if let Some([u_lo, u_hi, v_lo, v_hi]) = enclosure
            && (u_hi < lo[0] || u_lo > hi[0] || v_hi < lo[1] || v_lo > hi[1])
        {
            return;
        }
        let d_keeps_sign = enclosure.is_some();
        let ray = self.ray;
        let mut candidates = [T::ZERO; MAX_CANDIDATES];
        let mut n = 0;
        let mut push = |h: T| {
            candidates[n] = h;
            n += 1;
        };
        push(h_lo);
        push(h_hi);
        for (axis, face) in [(0, lo[0]), (0, hi[0]), (1, lo[1]), (1, hi[1])] {
            // Nor a face outside the enclosure on its axis.
            if let Some(e) = enclosure
                && (face < e[2 * axis] || face > e[2 * axis + 1])
            {
                continue;
            }
            let (q, mag) = self.line(axis, face);
            // A face the curve cannot reach on [h_lo, h_hi] has no root there to solve for.
            if !self.may_vanish(&q, mag, face, h_lo, h_hi) {
                continue;
            }
            for &h in solve_quadratic_in(q, h_lo, h_hi).iter() {
                push(h);
            }
        }
        // Where D keeps its sign by more than its error bound (checked above), no pole.
        let poles = if d_keeps_sign {
            Roots::none()
        } else {
            solve_quadratic_in(ray.d, h_lo, h_hi)
        };
        for &h in poles.iter() {
            push(h);
        }
        let candidates = &mut candidates[..n];
        candidates.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(core::cmp::Ordering::Equal));

        // At a pole the ray runs parallel to the prism's cross-section: that height is kept
        // as inside with the whole distance range (conservative).
        for &h in poles.iter() {
            piece(BoxSpan {
                h_in: h,
                h_out: h,
                t_in: t_min,
                t_out: t_max,
            });
        }
        // Inside-ness is judged with the faces moved out by the rounding bounds of u(h) and
        // v(h). Without it, a curve running along a face (a base triangle degenerate in uv
        // onto a texel edge) is put on either side of the face by rounding, and a box whose
        // microtriangles the curve hits is culled.
        let inside = |h: T| {
            self.uv_with_error(h).is_some_and(|([u, v], [eu, ev])| {
                u >= lo[0] - eu && u <= hi[0] + eu && v >= lo[1] - ev && v <= hi[1] + ev
            })
        };
        // Between consecutive candidates inside-ness cannot change, so the midpoint decides a
        // whole piece, ends included (they lie on faces, where rounding alone could put them
        // out). Off the poles the distance t(h) is continuous and, where the shell does not
        // fold over itself, monotonic on a piece (a point of the ray has one height), so the
        // piece's distances lie between those of its ends.
        let mut previous_inside = false;
        for i in 0..candidates.len() {
            let c = candidates[i];
            let piece_inside = i + 1 < candidates.len() && {
                let next = candidates[i + 1];
                next > c && inside((c + next) * T::HALF)
            };
            if piece_inside {
                let next = candidates[i + 1];
                if let (Some(ta), Some(tb)) = (self.distance(c), self.distance(next)) {
                    let (lo_t, hi_t) = (ta.min(tb).max(t_min), ta.max(tb).min(t_max));
                    if lo_t <= hi_t {
                        // The heights at the clamped distances are not needed: the piece's
                        // full height range is kept (conservative).
                        piece(BoxSpan {
                            h_in: c,
                            h_out: next,
                            t_in: lo_t,
                            t_out: hi_t,
                        });
                    }
                }
            } else if !previous_inside
                && inside(c)
                && let Some(t) = self.distance(c).filter(|&t| t >= t_min && t <= t_max)
            {
                // An isolated inside point: the curve touches the box at a face or edge.
                piece(BoxSpan {
                    h_in: c,
                    h_out: c,
                    t_in: t,
                    t_out: t,
                });
            }
            previous_inside = piece_inside;
        }
    }
}

#[inline]
fn quadratic<T: Real>(c: &[T; 3], h: T) -> T {
    c[2].mul_add(h, c[1]).mul_add(h, c[0])
}

/// Where `ray` is inside the texture-space box `lo..=hi` (each `(u, v, h)`), with the distance
/// along the world ray in `[t_min, t_max]`; `None` when it never is.
///
/// The `u` and `v` faces are met where `U(h) - u_face D(h) = 0`, a quadratic (Eq. 8 with the
/// denominator cleared); the `h` faces are the ends of the height range. Between consecutive
/// such heights (and the denominator's zeros) the curve is entirely inside or entirely
/// outside, so testing each candidate and each midpoint decides it exactly up to rounding.
/// At a zero of the denominator the ray runs parallel to the prism's cross-section (its height
/// is constant over a stretch of the ray): that height is kept as inside with the whole
/// `[t_min, t_max]`, which is conservative. `t_in`/`t_out` come from the ends of the inside
/// pieces, clamped to `[t_min, t_max]`: exact where the shell does not fold over itself
/// (then the distance is monotonic along a piece), a sample otherwise. The span is the hull
/// of [`TextureCurve::box_pieces`].
#[must_use]
pub fn intersect_box<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    lo: [T; 3],
    hi: [T; 3],
    t_min: T,
    t_max: T,
) -> Option<BoxSpan<T>> {
    TextureCurve::new(prism, ray).box_span(lo, hi, t_min, t_max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Ray;
    use nlrt_poly::Vector3;
    use nlrt_poly::lanes4::Portable4;

    /// The four-lane enclosures against four scalar ones and the portable lanes, bit for bit:
    /// sheared prisms, rays from every side (some nearly parallel to the base, whose curves
    /// have poles), intervals from a whole shell down to a deep node's sliver, some reaching
    /// below the base and above the top.
    fn enclosures_agree<T: Real>() {
        let mut state = 0x4646_u64;
        let mut r = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let v =
            |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
        let w = |x: f64, y: f64| T::Vec2::new(T::from_f64(x), T::from_f64(y));
        let (mut some, mut none) = (0, 0);
        for _ in 0..3_000 {
            let prism = Prism::new(
                [
                    v(0.1 * r(), 0.1 * r(), 0.1 * r()),
                    v(1.0 + 0.1 * r(), 0.1 * r(), 0.1 * r()),
                    v(0.1 * r(), 1.0 + 0.1 * r(), 0.1 * r()),
                ],
                [
                    v(0.5 * r(), 0.5 * r(), 1.0 + 0.3 * r()),
                    v(0.5 * r(), 0.5 * r(), 1.0 + 0.3 * r()),
                    v(0.5 * r(), 0.5 * r(), 1.0 + 0.3 * r()),
                ],
                [
                    w(3.0 + 0.2 * r(), 5.0 + 0.2 * r()),
                    w(4.0 + 0.2 * r(), 5.0 + 0.2 * r()),
                    w(3.0 + 0.2 * r(), 6.0 + 0.2 * r()),
                ],
            );
            let origin = v(2.0 * r(), 2.0 * r(), 3.0 * r());
            let grazing = r() < -0.6;
            let dir = if grazing {
                v(r(), r(), 1e-3 * r())
            } else {
                v(r(), r(), r())
            };
            let Some(ray) = Ray::new(origin, dir) else {
                continue;
            };
            let nl = NonlinearRay::new(&prism, &ray);
            if !nl.is_finite() {
                continue;
            }
            let curve = TextureCurve::new(&prism, &nl);
            let mut interval = || {
                let a = 0.6 * r() + 0.4;
                let b = a + (r() + 1.0) * 10f64.powf(-6.0 * (r() + 1.0) / 2.0);
                [T::from_f64(a), T::from_f64(b)]
            };
            let hs: [[T; 2]; 4] = core::array::from_fn(|_| interval());
            let (lo, hi) = (hs.map(|h| h[0]), hs.map(|h| h[1]));
            let scalar = hs.map(|[a, b]| curve.uv_enclosure(a, b));
            let bits = |e: [Option<[T; 4]>; 4]| e.map(|e| e.map(|e| e.map(T::to_bits)));
            assert_eq!(bits(curve.uv_enclosures(lo, hi)), bits(scalar));
            assert_eq!(
                bits(curve.uv_enclosures_in::<Portable4<T>>(lo, hi)),
                bits(scalar)
            );
            some += scalar.iter().filter(|e| e.is_some()).count();
            none += scalar.iter().filter(|e| e.is_none()).count();
        }
        assert!(some > 5_000 && none > 100, "{some} {none}");
    }

    #[test]
    fn the_vector_enclosures_are_the_scalar_ones() {
        enclosures_agree::<f32>();
        enclosures_agree::<f64>();
    }
}
