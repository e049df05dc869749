//! Instruction counts of `first_cubic_root_in` against `solve_cubic_in` on the criterion
//! bench's two families, with a checksum of the roots that tells whether a change to the
//! solver altered any answer. Counts do not depend on the load of a shared machine:
//!
//! `valgrind --tool=callgrind --toggle-collect='*solve_all*' target/release/examples/first_root_counts f32 near`
//!
//! Arguments: `f32` or `f64`; `unit` (three roots in `[0, 1]`), `near` (one root in
//! `[0, 1/16]`, two in `[1/2, 1]`), or one of the oracle's whole-line families, `log-uniform`
//! (coefficients) and `clustered` (roots), solved on the whole line.

use nlrt_oracle::families::{RandomFamily, SplitMix64, cubic_from_roots};
use nlrt_poly::{Real, first_cubic_root_in, solve_cubic_in};
use std::hint::black_box;

const CUBICS: usize = 20_000;

/// The family's cubics and the interval they are solved on.
fn cubics<T: Real>(family: &str) -> (Vec<[T; 4]>, T, T) {
    let mut rng = SplitMix64::new(0xf1257);
    let whole_line = match family {
        "log-uniform" => Some(RandomFamily::LogUniformCoefficients),
        "clustered" => Some(RandomFamily::Clustered),
        _ => None,
    };
    if let Some(f) = whole_line {
        let c = (0..CUBICS)
            .map(|_| f.sample::<T>(&mut rng).coeffs)
            .collect();
        return (c, T::NEG_INFINITY, T::INFINITY);
    }
    let c = (0..CUBICS)
        .map(|_| match family {
            "near" => cubic_from_roots::<T>(
                [
                    rng.range(0.0, 0.0625),
                    rng.range(0.5, 1.0),
                    rng.range(0.5, 1.0),
                ],
                1.0,
            ),
            _ => RandomFamily::ThreeRootsInUnit.sample::<T>(&mut rng).coeffs,
        })
        .collect();
    (c, T::ZERO, T::ONE)
}

/// Checksum of every first root by `first_cubic_root_in`.
#[inline(never)]
fn solve_all_first<T: Real>(cubics: &[[T; 4]], lo: T, hi: T) -> u64 {
    cubics.iter().fold(0u64, |sum, &c| {
        let r = first_cubic_root_in(black_box(c), lo, hi);
        sum.rotate_left(3) ^ r.map_or(1, |r| r.to_f64().to_bits())
    })
}

/// Checksum of every root by `solve_cubic_in`.
#[inline(never)]
fn solve_all_roots<T: Real>(cubics: &[[T; 4]], lo: T, hi: T) -> u64 {
    cubics.iter().fold(0u64, |sum, &c| {
        let roots = solve_cubic_in(black_box(c), lo, hi);
        roots
            .iter()
            .fold(sum, |s, r| s.rotate_left(3) ^ r.to_f64().to_bits())
    })
}

fn run<T: Real>(family: &str) {
    let (c, lo, hi) = cubics::<T>(family);
    println!(
        "{} {family}: first {:016x}, all {:016x}",
        T::NAME,
        solve_all_first(&c, lo, hi),
        solve_all_roots(&c, lo, hi)
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let family = args.get(2).map_or("unit", String::as_str);
    match args.get(1).map(String::as_str) {
        Some("f64") => run::<f64>(family),
        _ => run::<f32>(family),
    }
}
