//! Profiling driver: solves cubics with three roots in [0, 1] (the benchmark distribution)
//! repeatedly. `cargo run --release -p nlrt-tests --example solve_loop [f32|f64] [closed] [whole]`
use nlrt_oracle::families::{RandomFamily, SplitMix64};
use nlrt_poly::Real;

fn run<T: Real>(closed: bool, whole_line: bool) {
    let mut rng = SplitMix64::new(1);
    let cases: Vec<[T; 4]> = (0..100_000)
        .map(|_| {
            if whole_line {
                RandomFamily::LogUniformCoefficients
                    .sample::<T>(&mut rng)
                    .coeffs
            } else {
                let (a, b, c) = (rng.unit(), rng.unit(), rng.unit());
                [-(a * b * c), a * b + a * c + b * c, -(a + b + c), 1.0].map(T::from_f64)
            }
        })
        .collect();
    let (lo, hi) = if whole_line {
        (T::NEG_INFINITY, T::INFINITY)
    } else {
        (T::ZERO, T::ONE)
    };
    let reps = std::env::var("REPS")
        .ok()
        .and_then(|r| r.parse().ok())
        .unwrap_or(20);
    let t = std::time::Instant::now();
    let mut n = 0usize;
    for _ in 0..reps {
        for c in &cases {
            let c = std::hint::black_box(*c);
            n += if closed {
                nlrt_poly::closed_form::solve_cubic_closed_form_in(c, lo, hi).len()
            } else {
                nlrt_poly::solve_cubic_in(c, lo, hi).len()
            };
        }
    }
    println!(
        "{} {}: {n} roots, {:.1} ns/solve",
        T::NAME,
        if closed { "closed form" } else { "nlrt" },
        t.elapsed().as_nanos() as f64 / (reps as f64 * 1e5)
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let closed = args.iter().any(|a| a == "closed");
    let whole = args.iter().any(|a| a == "whole");
    if args.iter().any(|a| a == "f32") {
        run::<f32>(closed, whole)
    } else {
        run::<f64>(closed, whole)
    }
}
