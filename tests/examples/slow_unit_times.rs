//! Times one slow unit (`fuzz/slow/<displacement|shell>_<f32|f64>/<unit>`) on nonlinear
//! tracing (and, for displacement, on the compared methods the fuzz target runs), with the
//! walk's counters:
//!
//! `cargo run --release -p nlrt-tests --example slow_unit_times -- fuzz/slow/displacement_f32/long-column-miss f32 [brute]`
//!
//! `brute` also tests every cell of the triangle's range (seconds to minutes on these units).
//! A unit is decoded as its directory's fuzz target decodes it (a `shell_` directory: the
//! shell target).

use nlrt_accel::TraversalStats;
use nlrt_baselines::{AffineTracing, MarchOptions, Marching};
use nlrt_poly::Real;
use nlrt_tests::fuzz_input::{affine_displacement_case, displacement_case, shell_case};
use std::time::Instant;

/// The unit's case, or `None` after saying why it does not set up.
fn set_up<C>(case: Result<C, String>) -> Option<C> {
    case.map_err(|e| println!("the unit does not set up: {e}"))
        .ok()
}

/// Runs `trace` once, timed, and prints its hit distance and counters under `label`.
fn timed(label: &str, trace: impl FnOnce(&mut TraversalStats) -> Option<f64>) {
    let t = Instant::now();
    let mut stats = TraversalStats::default();
    let distance = trace(&mut stats);
    println!("{label}: {:?}, hit {distance:?}, {stats:?}", t.elapsed());
}

fn run<T: Real>(data: &[u8], brute: bool) {
    let Some((surface, ray)) = set_up(displacement_case::<T>(data)) else {
        return;
    };
    println!("texel range of triangle 0: {:?}", surface.roots(0));
    timed("nonlinear", |stats| {
        let hit = surface.intersect(&ray, T::ZERO, T::INFINITY, stats);
        hit.map(|h| h.hit.t.to_f64())
    });
    // The triangle made affine (its first direction at every corner), as the fuzz target
    // also traces it: the straight walk where the frame allows.
    if let Ok((affine, _)) = affine_displacement_case::<T>(data) {
        let label = if affine.straight_triangles() > 0 {
            "nonlinear, the triangle made affine (straight walk)"
        } else {
            "nonlinear, the triangle made affine (curved walk: frame refused)"
        };
        timed(label, |stats| {
            let hit = affine.intersect(&ray, T::ZERO, T::INFINITY, stats);
            hit.map(|h| h.hit.t.to_f64())
        });
    }
    timed("tessellation-free (affine)", |stats| {
        let hit = surface.intersect_affine(&ray, T::ZERO, T::INFINITY, stats);
        hit.map(|h| h.t.to_f64())
    });
    let opts = MarchOptions {
        max_samples: 256,
        ..MarchOptions::default()
    };
    let t = Instant::now();
    let mut stats = TraversalStats::default();
    let _ = surface.intersect_marching(&ray, T::ZERO, T::INFINITY, &opts, &mut stats);
    println!("marching: {:?}", t.elapsed());
    if brute {
        let t = Instant::now();
        let hit = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
        let distance = hit.map(|h| h.hit.t.to_f64());
        println!("every texel: {:?}, hit {distance:?}", t.elapsed());
    }
}

fn run_shell<T: Real>(data: &[u8], brute: bool) {
    let Some((surface, ray)) = set_up(shell_case::<T>(data)) else {
        return;
    };
    println!("tile range of triangle 0: {:?}", surface.roots(0));
    timed("nonlinear", |stats| {
        let hit = surface.intersect(&ray, T::ZERO, T::INFINITY, stats);
        hit.map(|h| h.hit.t.to_f64())
    });
    if brute {
        let t = Instant::now();
        let hit = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
        let distance = hit.map(|h| h.hit.t.to_f64());
        println!("every tile: {:?}, hit {distance:?}", t.elapsed());
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (Some(path), Some(precision)) = (args.get(1), args.get(2)) else {
        eprintln!("usage: slow_unit_times <unit file> <f32|f64> [brute]");
        std::process::exit(2);
    };
    let data = match std::fs::read(path) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{path}: {e}");
            std::process::exit(2);
        }
    };
    let brute = args.get(3).is_some_and(|a| a == "brute");
    let shell = path.contains("shell_");
    match (precision.as_str(), shell) {
        ("f32", false) => run::<f32>(&data, brute),
        ("f64", false) => run::<f64>(&data, brute),
        ("f32", true) => run_shell::<f32>(&data, brute),
        ("f64", true) => run_shell::<f64>(&data, brute),
        _ => {
            eprintln!("precision must be f32 or f64");
            std::process::exit(2);
        }
    }
}
