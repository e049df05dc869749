//! Closed-form cubic solver, kept as the baseline that benches and reports compare against.
//! Not for production: it loses roots and accuracy on the hard families (huge spreads,
//! clusters, tiny leading coefficients), which is what the reports measure.

use crate::{Real, Roots};

/// All real roots of `c[0] + c[1] x + c[2] x^2 + c[3] x^3` by the trigonometric / Cardano
/// closed form (Numerical Recipes, 3rd ed., sec. 5.6), sorted. `c[3] == 0` or non-finite input
/// gives no roots.
///
/// ```
/// use nlrt_poly::closed_form::solve_cubic_closed_form;
/// let r = solve_cubic_closed_form([-6.0f64, 11.0, -6.0, 1.0]);
/// assert!((r[2] - 3.0).abs() < 1e-12);
/// ```
#[must_use]
pub fn solve_cubic_closed_form<T: Real>(c: [T; 4]) -> Roots<T> {
    if c[3] == T::ZERO || !(c[0] + c[1] + c[2] + c[3]).is_finite() {
        return Roots::none();
    }
    let inv = T::ONE / c[3];
    let (a, b, cc) = (c[2] * inv, c[1] * inv, c[0] * inv);
    let nine = T::from_i32(9);
    let q = (a * a - T::THREE * b) / nine;
    let r = (T::TWO * a * a * a - nine * a * b + T::from_i32(27) * cc) / T::from_i32(54);
    let a3 = a / T::THREE;
    let q3 = q * q * q;
    let mut roots = Roots::none();
    if r * r < q3 {
        let theta = (r / q3.sqrt()).max(-T::ONE).min(T::ONE).acos();
        let m = -T::TWO * q.sqrt();
        let two_pi = T::from_f64(core::f64::consts::TAU);
        roots.push(m * (theta / T::THREE).cos() - a3);
        roots.push(m * ((theta + two_pi) / T::THREE).cos() - a3);
        roots.push(m * ((theta - two_pi) / T::THREE).cos() - a3);
        roots.sort();
    } else {
        let big_a = -(r.abs() + (r * r - q3).sqrt()).cbrt().copysign(r);
        let big_b = if big_a == T::ZERO { T::ZERO } else { q / big_a };
        let x = big_a + big_b - a3;
        if x.is_finite() {
            roots.push(x);
        }
    }
    roots
}

/// [`solve_cubic_closed_form`] restricted to `[lo, hi]` by filtering.
#[must_use]
pub fn solve_cubic_closed_form_in<T: Real>(c: [T; 4], lo: T, hi: T) -> Roots<T> {
    solve_cubic_closed_form(c).within(lo, hi)
}
