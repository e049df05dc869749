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

/// One lane of a batch: a cubic from three roots (the ray tracer's kind, on an interval
/// around them, or around only some of them) or raw bit patterns (anything at all).
fn batch_lane<T: Real>() -> impl Strategy<Value = ([T; 4], T, T)> {
    let from_roots = (three_roots(8), -300.0f64..300.0, -300.0f64..300.0).prop_map(|(r, a, b)| {
        let lo = r.iter().fold(f64::INFINITY, |m, &x| m.min(x));
        let span = r.iter().fold(f64::NEG_INFINITY, |m, &x| m.max(x)) - lo;
        // ends from just outside all roots to inside the spread
        let (x, y) = (lo + span * a / 200.0, lo + span * b / 200.0);
        (
            cubic_from_roots::<T>(r, 1.0),
            T::from_f64(x.min(y)),
            T::from_f64(x.max(y)),
        )
    });
    let raw = (any::<[u64; 4]>(), any::<u64>(), any::<u64>()).prop_map(|(c, lo, hi)| {
        (
            c.map(T::from_bits_u64),
            T::from_bits_u64(lo),
            T::from_bits_u64(hi),
        )
    });
    prop_oneof![3 => from_roots, 1 => raw]
}

/// `solve_cubic_batch_in` and `first_cubic_root_batch_in` against the scalar calls, every lane
/// bit for bit, on batches that mix lanes of both kinds.
fn batch_matches_scalar<T: Real>(lanes: &[([T; 4], T, T)]) -> Result<(), TestCaseError> {
    use nlrt_poly::{CUBIC_BATCH, first_cubic_root_batch_in, solve_cubic_batch_in};
    let c: [[T; 4]; CUBIC_BATCH] = core::array::from_fn(|i| lanes[i].0);
    let lo: [T; CUBIC_BATCH] = core::array::from_fn(|i| lanes[i].1);
    let hi: [T; CUBIC_BATCH] = core::array::from_fn(|i| lanes[i].2);
    let all = solve_cubic_batch_in(&c, &lo, &hi);
    let first = first_cubic_root_batch_in(&c, &lo, &hi);
    let bits = |r: &[T]| r.iter().map(|v| v.to_bits_u64()).collect::<Vec<_>>();
    for i in 0..CUBIC_BATCH {
        let scalar = solve_cubic_in(c[i], lo[i], hi[i]);
        prop_assert_eq!(bits(&all[i]), bits(&scalar), "lane {}: {:?}", i, lanes[i]);
        let scalar_first = first_cubic_root_in(c[i], lo[i], hi[i]);
        prop_assert_eq!(
            bits(first[i].as_slice()),
            bits(scalar_first.as_slice()),
            "first root, lane {}: {:?}",
            i,
            lanes[i]
        );
    }
    Ok(())
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn batch_equals_scalar_f32(lanes in prop::collection::vec(batch_lane::<f32>(), 8)) {
        batch_matches_scalar(&lanes)?;
    }

    #[test]
    fn batch_equals_scalar_f64(lanes in prop::collection::vec(batch_lane::<f64>(), 8)) {
        batch_matches_scalar(&lanes)?;
    }
}
