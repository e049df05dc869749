//! Nonlinear ray against an axis-aligned box in texture space (Ogaki 2023, sec. 4.4): where the
//! curve `h -> (u(h), v(h), h)` is inside `[u_lo, u_hi] x [v_lo, v_hi] x [h_lo, h_hi]`.

use crate::prism::Prism;
use crate::ray::NonlinearRay;
use nlrt_poly::{Real, Vector2, solve_quadratic_in};

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
/// (then the distance is monotonic along a piece), a sample otherwise.
#[must_use]
pub fn intersect_box<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    lo: [T; 3],
    hi: [T; 3],
    t_min: T,
    t_max: T,
) -> Option<BoxSpan<T>> {
    let (h_lo, h_hi) = (lo[2], hi[2]);
    if !(h_lo <= h_hi && lo[0] <= hi[0] && lo[1] <= hi[1]) {
        return None;
    }
    let [t0, t1, t2] = prism.uv;
    let (du1, du2) = ((t1.x() - t0.x()).abs(), (t2.x() - t0.x()).abs());
    let (dv1, dv2) = ((t1.y() - t0.y()).abs(), (t2.y() - t0.y()).abs());
    let magnitude = |i: usize, base: T, e1: T, e2: T| {
        ray.d[i].abs().mul_add(
            base.abs(),
            ray.alpha[i].abs().mul_add(e1, ray.beta[i].abs() * e2),
        )
    };
    let mu: [T; 3] = core::array::from_fn(|i| magnitude(i, t0.x(), du1, du2));
    let mv: [T; 3] = core::array::from_fn(|i| magnitude(i, t0.y(), dv1, dv2));
    let md: [T; 3] = core::array::from_fn(|i| ray.d[i].abs());
    let eight_u = T::from_i32(8) * T::UNIT_ROUNDOFF;
    let gamma8 = eight_u / (T::ONE - eight_u);
    let abs_at = |c: &[T; 3], h: T| c[2].mul_add(h, c[1]).mul_add(h, c[0]);
    // Early rejection by interval arithmetic: the ranges of U, V and D over [h_lo, h_hi]
    // (ends and vertex of each quadratic), then u = U / D and v = V / D by interval division
    // where D keeps one sign, widened by the same rounding bound as the exact test below.
    // Sound (never rejects what the exact test keeps) and cheap; most boxes of a traversal
    // are rejected here without solving a quadratic.
    let range = |c: &[T; 3]| {
        let at = |h: T| c[2].mul_add(h, c[1]).mul_add(h, c[0]);
        let (mut lo_q, mut hi_q) = (at(h_lo).min(at(h_hi)), at(h_lo).max(at(h_hi)));
        if c[2] != T::ZERO {
            let vertex = -c[1] / (T::TWO * c[2]);
            if vertex > h_lo && vertex < h_hi {
                lo_q = lo_q.min(at(vertex));
                hi_q = hi_q.max(at(vertex));
            }
        }
        (lo_q, hi_q)
    };
    let (d_lo, d_hi) = range(&ray.d);
    let h_abs = h_lo.abs().max(h_hi.abs());
    let d_err = gamma8 * abs_at(&md, h_abs);
    if d_lo - d_err > T::ZERO || d_hi + d_err < T::ZERO {
        let (d_min, d_max) = if d_lo > T::ZERO {
            (d_lo - d_err, d_hi + d_err)
        } else {
            (-(d_hi + d_err), -(d_lo - d_err))
        };
        let sign = if d_lo > T::ZERO { T::ONE } else { -T::ONE };
        let quotient = |c: &[T; 3], m: &[T; 3]| {
            let (q_lo, q_hi) = range(c);
            let err = gamma8 * abs_at(m, h_abs);
            let (q_lo, q_hi) = if sign > T::ZERO {
                (q_lo - err, q_hi + err)
            } else {
                (-(q_hi + err), -(q_lo - err))
            };
            // q / d for q in [q_lo, q_hi], d in [d_min, d_max] with d_min > 0.
            let lo_r = if q_lo >= T::ZERO {
                q_lo / d_max
            } else {
                q_lo / d_min
            };
            let hi_r = if q_hi >= T::ZERO {
                q_hi / d_min
            } else {
                q_hi / d_max
            };
            // One more relative rounding of the divisions.
            (lo_r - lo_r.abs() * eight_u, hi_r + hi_r.abs() * eight_u)
        };
        let (u_lo, u_hi) = quotient(&ray.u, &mu);
        let (v_lo, v_hi) = quotient(&ray.v, &mv);
        if u_hi < lo[0] || u_lo > hi[0] || v_hi < lo[1] || v_lo > hi[1] {
            return None;
        }
    }
    let mut candidates = [T::ZERO; MAX_CANDIDATES];
    let mut n = 0;
    let mut push = |h: T| {
        candidates[n] = h;
        n += 1;
    };
    push(h_lo);
    push(h_hi);
    let d = &ray.d;
    let faces = [
        (&ray.u, lo[0]),
        (&ray.u, hi[0]),
        (&ray.v, lo[1]),
        (&ray.v, hi[1]),
    ];
    for (num, face) in faces {
        let q = [
            (-face).mul_add(d[0], num[0]),
            (-face).mul_add(d[1], num[1]),
            (-face).mul_add(d[2], num[2]),
        ];
        for &h in solve_quadratic_in(q, h_lo, h_hi).iter() {
            push(h);
        }
    }
    let poles = solve_quadratic_in(*d, h_lo, h_hi);
    for &h in poles.iter() {
        push(h);
    }
    let candidates = &mut candidates[..n];
    candidates.sort_unstable_by(|a, b| a.partial_cmp(b).unwrap_or(core::cmp::Ordering::Equal));

    let mut span: Option<BoxSpan<T>> = None;
    let mut include = |h: T, t_lo: T, t_hi: T| {
        let s = span.get_or_insert(BoxSpan {
            h_in: h,
            h_out: h,
            t_in: t_lo,
            t_out: t_hi,
        });
        s.h_in = s.h_in.min(h);
        s.h_out = s.h_out.max(h);
        s.t_in = s.t_in.min(t_lo);
        s.t_out = s.t_out.max(t_hi);
    };
    for &h in poles.iter() {
        include(h, t_min, t_max);
    }
    // The distance along the ray at height h, when the curve is defined there.
    let distance = |h: T| {
        ray.alpha_beta(h)
            .map(|(alpha, beta)| ray.signed_distance(prism, alpha, beta, h))
    };
    // Inside-ness is judged with the faces moved out by a bound on the rounding error of
    // u(h) and v(h): the error of each coefficient of U, V and D (sums of three products of
    // accurately computed terms) and of evaluating them, both below gamma(8) times the same
    // polynomials with absolute-valued terms. Without it, a curve running along a face (a
    // base triangle degenerate in uv onto a texel edge) is put on either side of the face by
    // rounding, and a box whose microtriangles the curve hits is culled.
    let inside = |h: T| {
        let a = h.abs();
        let d = d[2].mul_add(h, d[1]).mul_add(h, d[0]);
        if d == T::ZERO {
            return false;
        }
        let (u, v) = (
            ray.u[2].mul_add(h, ray.u[1]).mul_add(h, ray.u[0]) / d,
            ray.v[2].mul_add(h, ray.v[1]).mul_add(h, ray.v[0]) / d,
        );
        let (d_abs, inv) = (abs_at(&md, a), gamma8 / d.abs());
        let eu = (abs_at(&mu, a) + u.abs() * d_abs) * inv;
        let ev = (abs_at(&mv, a) + v.abs() * d_abs) * inv;
        u >= lo[0] - eu && u <= hi[0] + eu && v >= lo[1] - ev && v <= hi[1] + ev
    };
    // Between consecutive candidates inside-ness cannot change, so the midpoint decides a
    // whole piece, ends included (they lie on faces, where rounding alone could put them
    // out). Off the poles the distance t(h) is continuous and, where the shell does not fold
    // over itself, monotonic on a piece (a point of the ray has one height), so the piece's
    // distances lie between those of its ends.
    let mut previous_inside = false;
    for i in 0..candidates.len() {
        let c = candidates[i];
        let piece_inside = i + 1 < candidates.len() && {
            let next = candidates[i + 1];
            next > c && inside((c + next) * T::HALF)
        };
        if piece_inside {
            let next = candidates[i + 1];
            if let (Some(ta), Some(tb)) = (distance(c), distance(next)) {
                let (lo_t, hi_t) = (ta.min(tb).max(t_min), ta.max(tb).min(t_max));
                if lo_t <= hi_t {
                    // The heights at the clamped distances are not needed: the piece's full
                    // height range is kept (conservative).
                    include(c, lo_t, hi_t);
                    include(next, lo_t, hi_t);
                }
            }
        } else if !previous_inside
            && inside(c)
            && let Some(t) = distance(c).filter(|&t| t >= t_min && t <= t_max)
        {
            // An isolated inside point: the curve touches the box at a face or edge.
            include(c, t, t);
        }
        previous_inside = piece_inside;
    }
    span
}
