//! Every named hard family, for f32 and f64, judged by the MPFR oracle.

use nlrt_oracle::families::{Case, hard_cubics};
use nlrt_oracle::{Tolerance, Truth};
use nlrt_poly::{Real, first_cubic_root_in, solve_cubic_in};

fn check_all<T: Real>() {
    let mut failures = Vec::new();
    for Case {
        name,
        coeffs,
        lo,
        hi,
    } in hard_cubics::<T>()
    {
        let truth = Truth::new(&coeffs).expect("finite coefficients");
        let roots = solve_cubic_in(coeffs, lo, hi);
        let v = truth.judge(&roots, lo, hi, Tolerance::SOLVER);
        println!(
            "{:<6}{:<28} true {} found {} max {:>8.2} ulp  missed {} spurious {} pseudo {}  {:?}",
            T::NAME,
            name,
            v.true_roots,
            roots.len(),
            v.max_ulps(),
            v.missed,
            v.spurious,
            v.pseudo,
            roots
        );
        if !v.passes() {
            failures.push(format!(
                "{name}: {v:?} roots {roots:?} truth {:?}",
                truth.roots()
            ));
        }
        // The nearest-root variant agrees with the first of all roots.
        let first = first_cubic_root_in(coeffs, lo, hi);
        assert_eq!(first, roots.first().copied(), "{name}: first root differs");
    }
    assert!(
        failures.is_empty(),
        "{} failures:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

#[test]
fn hard_families_f64() {
    check_all::<f64>();
}

#[test]
fn hard_families_f32() {
    check_all::<f32>();
}
