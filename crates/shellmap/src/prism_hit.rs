//! World ray against a whole prism: the bottom (`h = 0`) and top (`h = 1`) triangles and the
//! three sides, each a bilinear patch in `(s, h)` (Ogaki 2023, sec. 4.4 and 5.4: the entry and
//! exit distances and heights that range reduction needs).

use crate::prism::Prism;
use crate::ray::Ray;
use nlrt_poly::{Real, Vector3, solve_quadratic_in};

/// Where a ray is inside a prism (`0 <= h <= 1`): first entry and last exit along the ray, with
/// the heights there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PrismSpan<T> {
    /// Distance of the first entry (`t_min` when the ray starts inside).
    pub t_in: T,
    /// Distance of the last exit.
    pub t_out: T,
    /// Height at the entry.
    pub h_in: T,
    /// Height at the exit.
    pub h_out: T,
}

/// Crossings of the ray with the side patch between `S_i(h)` and `S_j(h)`: the points
/// `A(s) + h B(s)` with `A(s) = lerp(P_i, P_j, s)` and `B(s) = lerp(N_i, N_j, s)`. For fixed `s`
/// this is a line in `h`; the ray meets it when `(A(s) - o) x B(s) . w = 0`, a quadratic in
/// `s` (the formulation of Reshetov 2019, "Cool Patches", written for this patch). Each root
/// gives `t` and `h` by Cramer's rule on `t w - h B = A - o`. Pushes `(t, h)` for `h` in
/// `[0, 1]`.
fn side_crossings<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    i: usize,
    j: usize,
    out: &mut impl FnMut(T, T),
) {
    let w = ray.dir;
    let a0 = prism.p[i] - ray.origin;
    let a1 = prism.p[j] - prism.p[i];
    let b0 = prism.n[i];
    let b1 = prism.n[j] - prism.n[i];
    let f = [
        a0.cross(b0).dot(w),
        (a0.cross(b1) + a1.cross(b0)).dot(w),
        a1.cross(b1).dot(w),
    ];
    for &s in solve_quadratic_in(f, T::ZERO, T::ONE).iter() {
        let a = a0 + a1 * s;
        let b = b0 + b1 * s;
        let n = w.cross(b);
        let nn = n.dot(n);
        if !(nn > T::ZERO) {
            continue; // the side's line is parallel to the ray
        }
        let t = a.cross(b).dot(n) / nn;
        let h = a.cross(w).dot(n) / nn;
        // A ray leaving through the edge between this side and a cap crosses both at the
        // edge's height; rounding may put the side's `h` just outside [0, 1] and the cap's
        // point just outside its triangle, so that the crossing would be lost (a span with
        // an entry and no exit). Heights within the rounding bound of `h` are the edge's:
        // gamma(16) (at most 16 roundings from the inputs to `h`, with the error of `n`
        // bounded through |a| |w| |n|) of the magnitudes involved.
        let nu = T::from_i32(16) * T::UNIT_ROUNDOFF;
        let slack = nu / (T::ONE - nu) * a.length() * w.length() * n.length() / nn;
        let h = if h < T::ZERO && h >= -slack {
            T::ZERO
        } else if h > T::ONE && h <= T::ONE + slack {
            T::ONE
        } else {
            h
        };
        if h >= T::ZERO && h <= T::ONE {
            out(t, h);
        }
    }
}

/// Crossing of the ray with the cap at height `h` (see [`Prism::cross_section_hit`]).
fn cap_crossing<T: Real>(prism: &Prism<T>, ray: &Ray<T>, h: T, out: &mut impl FnMut(T, T)) {
    if let Some((t, _, _)) = prism.cross_section_hit(ray, h) {
        out(t, h);
    }
}

/// First entry and last exit of `ray` in `prism` (heights `0..=1`) within `[t_min, t_max]`;
/// `None` when it misses. A ray starting inside enters at `t_min` with the height of its
/// origin (found by the inverse map, Eq. 4).
///
/// ```
/// use nlrt_poly::glam::{DVec2, DVec3};
/// use nlrt_shellmap::{Prism, Ray, intersect_prism};
/// let z = DVec3::Z;
/// let prism = Prism::<f64>::new([DVec3::ZERO, DVec3::X, DVec3::Y], [z, z, z], [DVec2::ZERO, DVec2::X, DVec2::Y]);
/// let ray = Ray::new(DVec3::new(-1.0, 0.25, 0.5), DVec3::X).unwrap();
/// let span = intersect_prism(&prism, &ray, 0.0, f64::INFINITY).unwrap();
/// assert!((span.t_in - 1.0).abs() < 1e-12 && (span.t_out - 1.75).abs() < 1e-12);
/// assert!((span.h_in - 0.5).abs() < 1e-12 && (span.h_out - 0.5).abs() < 1e-12);
/// ```
#[must_use]
pub fn intersect_prism<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    t_min: T,
    t_max: T,
) -> Option<PrismSpan<T>> {
    let mut span: Option<PrismSpan<T>> = None;
    let mut add = |t: T, h: T| {
        if !(t >= t_min && t <= t_max) {
            return;
        }
        let s = span.get_or_insert(PrismSpan {
            t_in: t,
            t_out: t,
            h_in: h,
            h_out: h,
        });
        if t < s.t_in {
            s.t_in = t;
            s.h_in = h;
        }
        if t > s.t_out {
            s.t_out = t;
            s.h_out = h;
        }
    };
    cap_crossing(prism, ray, T::ZERO, &mut add);
    cap_crossing(prism, ray, T::ONE, &mut add);
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        side_crossings(prism, ray, i, j, &mut add);
    }
    // A ray starting inside: the entry is its start. The prism lies in the box of its six
    // corners (sides are bilinear patches between them), so a start outside that box skips
    // the inverse map (a cubic).
    let start = ray.at(t_min.max(-T::MAX));
    let in_corner_box = (0..3).all(|axis| {
        let (mut lo, mut hi) = (T::INFINITY, T::NEG_INFINITY);
        for i in 0..3 {
            for c in [prism.p[i], prism.p[i] + prism.n[i]] {
                lo = lo.min(c.get(axis));
                hi = hi.max(c.get(axis));
            }
        }
        start.get(axis) >= lo && start.get(axis) <= hi
    });
    if t_min.is_finite()
        && in_corner_box
        && let Some(c) = prism.world_to_canonical(start, T::ZERO, T::ONE)
        && c.alpha >= T::ZERO
        && c.beta >= T::ZERO
        && c.alpha + c.beta <= T::ONE
    {
        let s = span.get_or_insert(PrismSpan {
            t_in: t_min,
            t_out: t_min,
            h_in: c.h,
            h_out: c.h,
        });
        s.t_in = t_min;
        s.h_in = c.h;
    }
    span
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::{DVec2, DVec3, Vec2, Vec3};

    /// Rays leaving a right prism exactly through an edge between its base and a side (the
    /// cap's inside test and the side's height both at their limits) still have an exit:
    /// found when a marcher lost the whole span of such a ray (entry only). Without the
    /// rounding bound on the side's height, f32 loses the exit of the first ray already.
    #[test]
    fn rays_leaving_through_a_cap_side_edge_keep_their_exit() {
        let prism = Prism::<f64>::new(
            [DVec3::ZERO, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            [DVec3::Z; 3],
            [DVec2::ZERO, DVec2::ONE, DVec2::Y],
        );
        let prism32 = Prism::<f32>::new(
            [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            [Vec3::Z; 3],
            [Vec2::ZERO, Vec2::ONE, Vec2::Y],
        );
        let mut rays = 0;
        for i in 1..40 {
            // A point on the base's diagonal edge and on its top-left edges, aimed at from
            // inside-above through the top cap.
            let s = i as f64 / 40.0;
            for (target, from) in [
                (
                    DVec3::new(s, s, 0.0),
                    DVec3::new(0.1 * s, 0.2 + 0.7 * s, 1.5),
                ),
                (DVec3::new(0.0, s, 0.0), DVec3::new(0.3, 0.4 + 0.5 * s, 1.3)),
                (DVec3::new(s, 1.0, 0.0), DVec3::new(0.2 * s, 0.6, 1.7)),
            ] {
                let dir = target - from;
                let ray = Ray::new(from, dir).unwrap();
                let span = intersect_prism(&prism, &ray, 0.0, f64::INFINITY).unwrap();
                let exit = (target - from).length();
                assert!(
                    (span.t_out - exit).abs() < 1e-9 * exit,
                    "{s}: {span:?} vs {exit}"
                );
                assert!(
                    span.t_out > span.t_in && span.h_out.abs() < 1e-12,
                    "{span:?}"
                );
                let ray32 = Ray::new(from.as_vec3(), dir.as_vec3()).unwrap();
                let span = intersect_prism(&prism32, &ray32, 0.0, f32::INFINITY).unwrap();
                assert!(
                    (f64::from(span.t_out) - exit).abs() < 1e-5 * exit,
                    "{s}: {span:?}"
                );
                rays += 1;
            }
        }
        assert_eq!(rays, 117);
    }
}
