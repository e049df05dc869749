//! Property tests of the solvers against the MPFR oracle, for f32 and f64 from one macro body.
//!
//! Case counts: 256 per property by default; `NLRT_EXTENSIVE=1` runs 20,000 (or set
//! `PROPTEST_CASES` directly).

mod common;

use nlrt_oracle::families::cubic_from_roots;
use nlrt_oracle::{Tolerance, Truth};
use nlrt_poly::{
    Real, first_cubic_root_in, solve_cubic, solve_cubic_in, solve_quadratic, solve_quadratic_in,
};
use proptest::prelude::*;

fn config() -> ProptestConfig {
    common::proptest_config(256, 20000)
}

/// A root: a signed mantissa in [0.5, 1) times 2^e, with e over a wide but type-safe range.
fn root(max_exp: i32) -> impl Strategy<Value = f64> {
    (0.5f64..1.0, -max_exp..=max_exp, any::<bool>()).prop_map(|(m, e, neg)| {
        let r = m * 2f64.powi(e);
        if neg { -r } else { r }
    })
}

/// Three roots: independent scales, a shared scale, or a cluster around one value.
fn three_roots(max_exp: i32) -> impl Strategy<Value = [f64; 3]> {
    prop_oneof![
        (root(max_exp), root(max_exp), root(max_exp)).prop_map(|(a, b, c)| [a, b, c]),
        (root(max_exp), -1.0f64..1.0, -1.0f64..1.0).prop_map(|(a, u, v)| [
            a,
            a * (1.0 + u),
            a * (1.0 + v)
        ]),
        (root(max_exp), 4i32..40, 0.0f64..2.0).prop_map(|(a, j, u)| {
            let gap = 2f64.powi(-j);
            [a, a * (1.0 + gap), a * (1.0 + u * gap)]
        }),
    ]
}

fn judge_all<T: Real>(coeffs: &[T], roots: &[T], lo: T, hi: T) -> Result<(), TestCaseError> {
    let truth = Truth::new(coeffs).expect("finite coefficients");
    let v = truth.judge(roots, lo, hi, Tolerance::SOLVER);
    prop_assert!(
        v.passes(),
        "coeffs {:?} on [{:e}, {:e}]: got {:?}, truth {:?}, verdict {:?}",
        coeffs,
        lo,
        hi,
        roots,
        truth
            .roots()
            .iter()
            .map(|r| (r.to_f64(), r.multiplicity))
            .collect::<Vec<_>>(),
        v
    );
    for &x in roots {
        prop_assert!(x >= lo && x <= hi, "root {x:e} outside [{lo:e}, {hi:e}]");
    }
    Ok(())
}

macro_rules! solver_properties {
    ($($t:ident: $max_exp:expr),*) => {$(
        mod $t {
            use super::*;
            type T = $t;

            proptest! {
                #![proptest_config(config())]

                /// Cubics from chosen roots at random scales, whole line.
                #[test]
                fn cubic_from_roots_whole_line(roots in three_roots($max_exp), scale in root(20)) {
                    let c: [T; 4] = cubic_from_roots(roots, scale);
                    prop_assume!(c.iter().all(|x| x.is_finite()) && c[3] != 0.0);
                    judge_all(&c, &solve_cubic(c), T::NEG_INFINITY, T::INFINITY)?;
                }

                /// Cubics with roots in [0, 1] on [0, 1] (the ray tracer's shape), and the
                /// nearest-root call agreeing with the first of all roots.
                #[test]
                fn cubic_on_unit_interval(roots in prop::array::uniform3(-0.5f64..1.5), scale in root(10)) {
                    let c: [T; 4] = cubic_from_roots(roots, scale);
                    let all = solve_cubic_in(c, 0.0, 1.0);
                    judge_all(&c, &all, 0.0, 1.0)?;
                    prop_assert_eq!(first_cubic_root_in(c, 0.0, 1.0), all.first().copied());
                }

                /// Interval ends exactly on, one ulp inside and one ulp outside a true root.
                #[test]
                fn cubic_interval_ends_at_roots(roots in three_roots(8), width in 0.0f64..4.0, which in 0usize..3, side in 0usize..3) {
                    let c: [T; 4] = cubic_from_roots(roots, 1.0);
                    prop_assume!(c.iter().all(|x| x.is_finite()));
                    let truth = Truth::new(&c).unwrap();
                    prop_assume!(!truth.roots().is_empty());
                    let r = T::from_f64(truth.roots()[which % truth.roots().len()].to_f64());
                    let end = match side { 0 => r, 1 => r.next_up(), _ => r.next_down() };
                    let w = T::from_f64(width) * r.abs().max(1.0);
                    // The root as the lower end, then as the upper end.
                    judge_all(&c, &solve_cubic_in(c, end, end + w), end, end + w)?;
                    judge_all(&c, &solve_cubic_in(c, end - w, end), end - w, end)?;
                }

                /// Quadratics with random coefficients over a wide range of magnitudes.
                #[test]
                fn quadratic_random(c0 in root($max_exp), c1 in root($max_exp), c2 in root($max_exp)) {
                    let c = [c0, c1, c2].map(T::from_f64);
                    judge_all(&c, &solve_quadratic(c), T::NEG_INFINITY, T::INFINITY)?;
                    judge_all(&c, &solve_quadratic_in(c, -1.0, 1.0), -1.0, 1.0)?;
                }

                /// Quadratics from chosen roots, including double roots.
                #[test]
                fn quadratic_from_roots(a in root($max_exp / 2), b in root($max_exp / 2), double in any::<bool>()) {
                    let b = if double { a } else { b };
                    let c = [a * b, -(a + b), 1.0].map(T::from_f64);
                    prop_assume!(c.iter().all(|x| x.is_finite()));
                    judge_all(&c, &solve_quadratic(c), T::NEG_INFINITY, T::INFINITY)?;
                }
            }
        }
    )*};
}

// Root exponents stay where the cubic's coefficients (products of three roots) are finite.
solver_properties!(f32: 40, f64: 300);
