//! `nlrt solvers`: speed against error of the cubic solvers, for f32 and f64, on random
//! families and the named hard families, judged by the MPFR oracle.

use nlrt_oracle::families::{Case, RandomFamily, SplitMix64, hard_cubics};
use nlrt_oracle::{Tolerance, Truth, Verdict, peers};
use nlrt_poly::closed_form::solve_cubic_closed_form_in;
use nlrt_poly::{Real, Roots, solve_cubic_in};
use rayon::prelude::*;
use std::fmt::Write as _;
use std::hint::black_box;
use std::io::IsTerminal;
use std::time::Instant;

/// A solver of all roots of a cubic in `[lo, hi]`.
type Solver<T> = fn([T; 4], T, T) -> Roots<T>;

/// A solver under test: all roots in `[lo, hi]` (`None` for a type the solver lacks).
#[derive(Clone, Copy)]
pub struct Method {
    /// Name in the table.
    pub name: &'static str,
    f32: Option<Solver<f32>>,
    f64: Option<Solver<f64>>,
}

/// The methods compared.
pub const METHODS: [Method; 5] = [
    Method {
        name: "nlrt-poly",
        f32: Some(solve_cubic_in::<f32>),
        f64: Some(solve_cubic_in::<f64>),
    },
    Method {
        name: "closed form",
        f32: Some(solve_cubic_closed_form_in::<f32>),
        f64: Some(solve_cubic_closed_form_in::<f64>),
    },
    Method {
        name: "roots crate",
        f32: Some(peers::roots_crate_cubic::<f32>),
        f64: Some(peers::roots_crate_cubic::<f64>),
    },
    Method {
        name: "kurbo",
        f32: None,
        f64: Some(peers::kurbo_cubic),
    },
    Method {
        name: "polycool",
        f32: None,
        f64: Some(peers::polycool_cubic),
    },
];

/// Per-type access to a method's function.
trait Pick: Real {
    fn pick(m: &Method) -> Option<Solver<Self>>;
}
impl Pick for f32 {
    fn pick(m: &Method) -> Option<Solver<f32>> {
        m.f32
    }
}
impl Pick for f64 {
    fn pick(m: &Method) -> Option<Solver<f64>> {
        m.f64
    }
}

/// One row of the table.
#[derive(Clone, Debug)]
pub struct Row {
    /// Method name.
    pub method: &'static str,
    /// "f32" or "f64".
    pub precision: &'static str,
    /// Family name.
    pub family: String,
    /// Polynomials solved.
    pub cases: usize,
    /// Median over timed passes of the mean time per solve, in ns.
    pub ns_per_solve: f64,
    /// Median error of matched roots, ulps.
    pub median_ulps: f64,
    /// Largest error of matched roots, ulps.
    pub max_ulps: f64,
    /// True roots in the interval, summed.
    pub true_roots: usize,
    /// Missed roots, summed.
    pub missed: usize,
    /// Spurious roots, summed.
    pub spurious: usize,
    /// Pseudo roots (within rounding of the input), summed.
    pub pseudo: usize,
}

/// Options of the solver report.
#[derive(Clone, Debug)]
pub struct Options {
    /// Random polynomials per precision, split evenly over the random families.
    pub samples: usize,
    /// Seed of the random families.
    pub seed: u64,
    /// Timed passes per row (the median is reported).
    pub passes: usize,
}

impl Default for Options {
    fn default() -> Self {
        Self {
            samples: 300_000,
            seed: 2026,
            passes: 5,
        }
    }
}

/// Which target features this binary was compiled with (they decide whether `mul_add` is one
/// instruction).
#[must_use]
pub fn target_features() -> String {
    let f = target_feature_list();
    if f.is_empty() {
        "none (software fma)".to_string()
    } else {
        f.join(", ")
    }
}

/// The target features this binary was compiled with that its kernels use (fma, avx2,
/// avx512f), as a list.
#[must_use]
pub fn target_feature_list() -> Vec<&'static str> {
    let mut f = Vec::new();
    if cfg!(target_feature = "fma") {
        f.push("fma");
    }
    if cfg!(target_feature = "avx2") {
        f.push("avx2");
    }
    if cfg!(target_feature = "avx512f") {
        f.push("avx512f");
    }
    f
}

fn progress(msg: &str) {
    if std::io::stderr().is_terminal() {
        eprint!("\r\x1b[2K{msg}");
    }
}

fn family_rows<T: Pick>(family: &str, cases: &[Case<T>], opts: &Options) -> Vec<Row> {
    progress(&format!(
        "{} {family}: oracle on {} polynomials",
        T::NAME,
        cases.len()
    ));
    let truths: Vec<Truth> = cases
        .par_iter()
        .map(|c| Truth::new(&c.coeffs).expect("finite coefficients"))
        .collect();
    METHODS
        .iter()
        .filter_map(|m| T::pick(m).map(|solve| (m, solve)))
        .map(|(m, solve)| {
            progress(&format!("{} {family}: {}", T::NAME, m.name));
            let answers: Vec<Roots<T>> =
                cases.iter().map(|c| solve(c.coeffs, c.lo, c.hi)).collect();
            // Timing: whole passes over the family, single thread, median of the passes.
            let mut times: Vec<f64> = (0..opts.passes)
                .map(|_| {
                    let t = Instant::now();
                    let mut n = 0usize;
                    for c in cases {
                        n += solve(black_box(c.coeffs), c.lo, c.hi).len();
                    }
                    black_box(n);
                    t.elapsed().as_nanos() as f64 / cases.len() as f64
                })
                .collect();
            times.sort_by(f64::total_cmp);
            let verdicts: Vec<Verdict> = cases
                .par_iter()
                .zip(&truths)
                .zip(&answers)
                .map(|((c, t), a)| t.judge(a, c.lo, c.hi, Tolerance::SOLVER))
                .collect();
            let mut errors: Vec<f64> = verdicts
                .iter()
                .flat_map(|v| v.errors_ulps.iter().copied())
                .collect();
            errors.sort_by(f64::total_cmp);
            Row {
                method: m.name,
                precision: T::NAME,
                family: family.to_string(),
                cases: cases.len(),
                ns_per_solve: times[times.len() / 2],
                median_ulps: errors.get(errors.len() / 2).copied().unwrap_or(0.0),
                max_ulps: errors.last().copied().unwrap_or(0.0),
                true_roots: verdicts.iter().map(|v| v.true_roots).sum(),
                missed: verdicts.iter().map(|v| v.missed).sum(),
                spurious: verdicts.iter().map(|v| v.spurious).sum(),
                pseudo: verdicts.iter().map(|v| v.pseudo).sum(),
            }
        })
        .collect()
}

fn rows_for<T: Pick>(opts: &Options) -> Vec<Row> {
    let mut rows = Vec::new();
    let per_family = (opts.samples / RandomFamily::ALL.len()).max(1);
    for (i, family) in RandomFamily::ALL.into_iter().enumerate() {
        let mut rng = SplitMix64::new(opts.seed.wrapping_add(i as u64));
        let cases: Vec<Case<T>> = (0..per_family).map(|_| family.sample(&mut rng)).collect();
        rows.extend(family_rows(family.name(), &cases, opts));
    }
    rows.extend(family_rows(
        "hard families (all)",
        &hard_cubics::<T>(),
        opts,
    ));
    rows
}

/// Runs the whole comparison.
#[must_use]
pub fn run(opts: &Options) -> Vec<Row> {
    let mut rows = rows_for::<f32>(opts);
    rows.extend(rows_for::<f64>(opts));
    progress("");
    rows
}

/// The table as Markdown.
#[must_use]
pub fn markdown(rows: &[Row], opts: &Options) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "Cubic solvers, speed against error ({} random cubics per precision, seed {}, median of {} timed passes, \
         single thread; target features: {}). Errors in ulps of the solver's type against the MPFR oracle; a root \
         is missed when no answer lies within max(4 ulps, 2x its attainable radius); pseudo roots are answers \
         within rounding of the input polynomial.\n",
        opts.samples,
        opts.seed,
        opts.passes,
        target_features()
    );
    let _ = writeln!(
        s,
        "| method | type | family | cubics | ns/solve | median ulps | max ulps | true roots | missed | spurious | pseudo |"
    );
    let _ = writeln!(s, "|---|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.1} | {:.2} | {} | {} | {} | {} | {} |",
            r.method,
            r.precision,
            r.family,
            r.cases,
            r.ns_per_solve,
            r.median_ulps,
            fmt_ulps(r.max_ulps),
            r.true_roots,
            r.missed,
            r.spurious,
            r.pseudo
        );
    }
    s
}

fn fmt_ulps(x: f64) -> String {
    if x < 1e4 {
        format!("{x:.2}")
    } else {
        format!("{x:.2e}")
    }
}
