//! Solver speed, side by side in one run: nlrt-poly, the closed-form baseline and the `roots`
//! crate for f32 and f64, and the f64-only `kurbo::common::solve_cubic` (Blinn's method) and
//! `polycool` (Yuksel's interval solver, target accuracy 1e-15), on the same cubics: all roots
//! in `[0, 1]` and on the whole line. Accuracy of the same solvers on the oracle's families is
//! measured by `nlrt solvers`. The fair harness (`cubic_fair_in_unit`, `cubic_peer_wrapper`)
//! times each solver through one loop over 200,000 distinct cubics, kurbo also called
//! directly, and the peer wrapper's own cost.
//!
//! `cargo bench -p nlrt-poly --bench solvers` (the fair harness alone:
//! `cargo bench -p nlrt-poly --bench solvers -- 'cubic_fair|cubic_peer'`)

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nlrt_oracle::families::{RandomFamily, SplitMix64, cubic_from_roots};
use nlrt_oracle::peers;
use nlrt_poly::closed_form::solve_cubic_closed_form_in;
use nlrt_poly::{
    CUBIC_BATCH, QUADRATIC_BATCH, Real, Roots, first_cubic_root_batch_in, first_cubic_root_in,
    solve_cubic_in, solve_cubics_in, solve_quadratic, solve_quadratic_batch_in, solve_quadratic_in,
};
use std::hint::black_box;

const SAMPLES: usize = 100_000;

fn unit_cubics<T: Real>() -> Vec<[T; 4]> {
    let mut rng = SplitMix64::new(0x5eed);
    (0..SAMPLES)
        .map(|_| RandomFamily::ThreeRootsInUnit.sample::<T>(&mut rng).coeffs)
        .collect()
}

/// Cubics with one root in `[0, 1/16]` and two in `[1/2, 1]` (uniform in those ranges).
fn near_start_cubics<T: Real>() -> Vec<[T; 4]> {
    let mut rng = SplitMix64::new(0xf1257);
    (0..SAMPLES)
        .map(|_| {
            let roots = [
                rng.range(0.0, 0.0625),
                rng.range(0.5, 1.0),
                rng.range(0.5, 1.0),
            ];
            cubic_from_roots::<T>(roots, 1.0)
        })
        .collect()
}

/// `first_cubic_root_in` against `solve_cubic_in` on the same cubics.
fn bench_first_root<T: Real>(crit: &mut Criterion, group: &str, cubics: &[[T; 4]], lo: T, hi: T) {
    let mut g = crit.benchmark_group(format!("{group}/{}", T::NAME));
    g.throughput(Throughput::Elements(cubics.len() as u64));
    g.bench_function(BenchmarkId::from_parameter("first"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .filter_map(|&c| first_cubic_root_in(black_box(c), lo, hi))
                .count()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("all"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .filter_map(|&c| solve_cubic_in(black_box(c), lo, hi).first().copied())
                .count()
        })
    });
    g.finish();
}

/// The f64-only peers on the same cubics, on `[lo, hi]`.
fn bench_f64_peers(crit: &mut Criterion, group: &str, cubics: &[[f64; 4]], lo: f64, hi: f64) {
    let mut g = crit.benchmark_group(format!("{group}/f64"));
    g.throughput(Throughput::Elements(cubics.len() as u64));
    g.bench_function(BenchmarkId::from_parameter("kurbo"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| peers::kurbo_cubic(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("polycool"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| peers::polycool_cubic(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    g.finish();
}

/// nlrt-poly, the closed form and the `roots` crate on `[lo, hi]`.
fn bench_all_roots<T: Real + roots::FloatType>(
    crit: &mut Criterion,
    group: &str,
    cubics: &[[T; 4]],
    lo: T,
    hi: T,
) {
    let mut g = crit.benchmark_group(format!("{group}/{}", T::NAME));
    g.throughput(Throughput::Elements(cubics.len() as u64));
    g.bench_function(BenchmarkId::from_parameter("nlrt"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| solve_cubic_in(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("closed_form"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| solve_cubic_closed_form_in(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("roots_crate"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| peers::roots_crate_cubic(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    g.finish();
}

/// The batch API against the scalar calls on the same cubics, all on `[lo, hi]`: all roots
/// through `solve_cubics_in`, and the first root eight at a time.
fn bench_batch<T: Real>(crit: &mut Criterion, group: &str, cubics: &[[T; 4]], lo: T, hi: T) {
    let mut g = crit.benchmark_group(format!("{group}/{}", T::NAME));
    g.throughput(Throughput::Elements(cubics.len() as u64));
    let (los, his) = (vec![lo; cubics.len()], vec![hi; cubics.len()]);
    let mut out = vec![Roots::none(); cubics.len()];
    g.bench_function(BenchmarkId::from_parameter("scalar_all"), |b| {
        b.iter(|| {
            for (o, &c) in out.iter_mut().zip(cubics) {
                *o = solve_cubic_in(black_box(c), lo, hi);
            }
            out.iter().map(|r| r.len()).sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("batch_all"), |b| {
        b.iter(|| {
            solve_cubics_in(black_box(cubics), &los, &his, &mut out);
            out.iter().map(|r| r.len()).sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("scalar_first"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .filter_map(|&c| first_cubic_root_in(black_box(c), lo, hi))
                .count()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("batch_first"), |b| {
        let (l, h) = ([lo; CUBIC_BATCH], [hi; CUBIC_BATCH]);
        b.iter(|| {
            cubics
                .chunks_exact(CUBIC_BATCH)
                .map(|chunk| {
                    let c: &[[T; 4]; CUBIC_BATCH] =
                        chunk.try_into().unwrap_or_else(|_| unreachable!());
                    first_cubic_root_batch_in(black_box(c), &l, &h)
                        .iter()
                        .flatten()
                        .count()
                })
                .sum::<usize>()
        })
    });
    g.finish();
}

/// The texel test's case: quadratics solved on a short interval (most roots outside it, each
/// then checked at the end it crossed), one by one against eight at a time.
fn bench_quadratic_batch<T: Real>(crit: &mut Criterion, quadratics: &[[T; 3]], lo: T, hi: T) {
    let mut g = crit.benchmark_group(format!("quadratic_batch_on_a_short_interval/{}", T::NAME));
    g.throughput(Throughput::Elements(quadratics.len() as u64));
    g.bench_function(BenchmarkId::from_parameter("scalar"), |b| {
        b.iter(|| {
            quadratics
                .iter()
                .map(|&c| solve_quadratic_in(black_box(c), lo, hi).len())
                .sum::<usize>()
        })
    });
    // Gathered by coefficient beforehand, as `QuadraticBatch` gathers them.
    let batches: Vec<[[T; QUADRATIC_BATCH]; 3]> = quadratics
        .chunks_exact(QUADRATIC_BATCH)
        .map(|chunk| core::array::from_fn(|k| core::array::from_fn(|i| chunk[i][k])))
        .collect();
    g.bench_function(BenchmarkId::from_parameter("batch"), |b| {
        let (l, h) = ([lo; QUADRATIC_BATCH], [hi; QUADRATIC_BATCH]);
        b.iter(|| {
            batches
                .iter()
                .map(|c| {
                    solve_quadratic_batch_in(black_box(c), &l, &h)
                        .iter()
                        .map(|r| r.len())
                        .sum::<usize>()
                })
                .sum::<usize>()
        })
    });
    g.finish();
}

fn bench_type<T: Real + roots::FloatType>(crit: &mut Criterion) {
    let cubics = unit_cubics::<T>();
    let (lo, hi) = (T::ZERO, T::ONE);

    bench_all_roots(crit, "cubic_all_roots_in_unit", &cubics, lo, hi);
    bench_all_roots(
        crit,
        "cubic_all_roots_whole_line",
        &cubics,
        T::NEG_INFINITY,
        T::INFINITY,
    );

    bench_batch(crit, "cubic_batch_in_unit", &cubics, lo, hi);
    bench_batch(crit, "cubic_batch_near_start", &near_start_cubics(), lo, hi);

    bench_first_root(crit, "cubic_first_root_in_unit", &cubics, lo, hi);
    // The texel test's case: the nearest root early in the interval, the others later.
    bench_first_root(
        crit,
        "cubic_first_root_near_start",
        &near_start_cubics(),
        lo,
        hi,
    );

    let quadratics: Vec<[T; 3]> = cubics
        .iter()
        .map(|c| [c[1], c[2] * T::TWO, c[3] * T::THREE])
        .collect();
    bench_quadratic_batch(crit, &quadratics, T::from_f64(0.25), T::from_f64(0.5));

    let mut g = crit.benchmark_group(format!("quadratic/{}", T::NAME));
    g.throughput(Throughput::Elements(SAMPLES as u64));
    g.bench_function(BenchmarkId::from_parameter("nlrt"), |b| {
        b.iter(|| {
            quadratics
                .iter()
                .map(|&c| solve_quadratic(black_box(c)).len())
                .sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("roots_crate"), |b| {
        b.iter(|| {
            quadratics
                .iter()
                .map(|&c| roots::find_roots_quadratic(c[2], c[1], c[0]).as_ref().len())
                .sum::<usize>()
        })
    });
    g.finish();
}

/// Distinct cubics in the fair harness: many more than fit the branch predictor's history,
/// so no solver is timed on a pattern it has learnt.
const FAIR_SAMPLES: usize = 200_000;

/// The sum of the roots in `[lo, hi]` that `solve` reports over `cubics`: every solver of the
/// fair harness is timed through this one loop, summing its roots so that none of its work
/// can be optimised away.
#[inline(always)]
fn root_sum<T: Real>(cubics: &[[T; 4]], mut solve: impl FnMut([T; 4]) -> Roots<T>) -> T {
    cubics.iter().fold(T::ZERO, |sum, &c| {
        solve(black_box(c)).iter().fold(sum, |s, &r| s + r)
    })
}

/// The fair harness (same process, same loop, distinct random cubics with three roots in
/// `[0, 1]`, solved on `[0, 1]`): nlrt-poly in f64 and f32; `kurbo::common::solve_cubic`
/// called directly with its roots filtered to `[0, 1]` in the loop, as a user of kurbo would
/// write it (unsorted, repeats kept: less than nlrt-poly's contract); and kurbo through
/// `nlrt_oracle::peers::kurbo_cubic`, which adds the sort and the distinctness that make its
/// answer comparable (the `cubic_peer_wrapper` group times that addition alone).
fn bench_fair(crit: &mut Criterion) {
    let mut rng = SplitMix64::new(0xfa1e);
    let cubics: Vec<[f64; 4]> = (0..FAIR_SAMPLES)
        .map(|_| {
            RandomFamily::ThreeRootsInUnit
                .sample::<f64>(&mut rng)
                .coeffs
        })
        .collect();
    let narrow: Vec<[f32; 4]> = cubics.iter().map(|c| c.map(|v| v as f32)).collect();
    let mut g = crit.benchmark_group("cubic_fair_in_unit");
    g.throughput(Throughput::Elements(FAIR_SAMPLES as u64));
    g.bench_function("nlrt/f64", |b| {
        b.iter(|| root_sum(&cubics, |c| solve_cubic_in(c, 0.0, 1.0)))
    });
    g.bench_function("kurbo_filtered/f64", |b| {
        b.iter(|| {
            cubics.iter().fold(0.0, |sum, &c| {
                let c = black_box(c);
                kurbo::common::solve_cubic(c[0], c[1], c[2], c[3])
                    .iter()
                    .filter(|&&r| (0.0..=1.0).contains(&r))
                    .fold(sum, |s, &r| s + r)
            })
        })
    });
    g.bench_function("kurbo_wrapped/f64", |b| {
        b.iter(|| root_sum(&cubics, |c| peers::kurbo_cubic(c, 0.0, 1.0)))
    });
    g.bench_function("nlrt/f32", |b| {
        b.iter(|| root_sum(&narrow, |c| solve_cubic_in(c, 0.0, 1.0)))
    });
    g.finish();

    // The wrapper alone: kurbo's answers computed beforehand, then filtered in the loop (as
    // above) or passed through `peers::roots_in` (filter, sort, repeats once).
    let found: Vec<([f64; 3], usize)> = cubics
        .iter()
        .map(|c| {
            let r = kurbo::common::solve_cubic(c[0], c[1], c[2], c[3]);
            let mut a = [0.0; 3];
            a[..r.len()].copy_from_slice(&r);
            (a, r.len())
        })
        .collect();
    let mut g = crit.benchmark_group("cubic_peer_wrapper");
    g.throughput(Throughput::Elements(FAIR_SAMPLES as u64));
    g.bench_function("filter_in_loop/f64", |b| {
        b.iter(|| {
            found.iter().fold(0.0, |sum, (a, n)| {
                black_box(&a[..*n])
                    .iter()
                    .filter(|&&r| (0.0..=1.0).contains(&r))
                    .fold(sum, |s, &r| s + r)
            })
        })
    });
    g.bench_function("roots_in/f64", |b| {
        b.iter(|| {
            found.iter().fold(0.0, |sum, (a, n)| {
                peers::roots_in(black_box(&a[..*n]), 0.0, 1.0)
                    .iter()
                    .fold(sum, |s, &r| s + r)
            })
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_fair(c);
    bench_type::<f64>(c);
    let cubics = unit_cubics::<f64>();
    bench_f64_peers(c, "cubic_all_roots_in_unit", &cubics, 0.0, 1.0);
    bench_f64_peers(
        c,
        "cubic_all_roots_whole_line",
        &cubics,
        f64::NEG_INFINITY,
        f64::INFINITY,
    );
    bench_type::<f32>(c);
}

criterion_group! {
    name = solvers;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(2));
    targets = benches
}
criterion_main!(solvers);
