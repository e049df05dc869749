//! Judging a floating-point solver's answer against the exact roots.
//!
//! For every true root `r` the *attainable radius* is the half-width of the set of points
//! around `r` where `|p(x)|` is below the rounding noise of evaluating `p` in the target type
//! (the pseudo-zero set, with noise `2 n u sum |c_i| |x|^i`, the bound of
//! `nlrt_poly::horner_with_bound`). No method working in that type can promise better: the
//! radius is `~ noise / |p'(r)|` for a simple root, `~ (2 noise / |p''(r)|)^(1/2)` for a double
//! one, and so on. A computed root matches `r` when it lies within
//! `max(ulps * ulp(r), radius_factor * radius(r))`.

use crate::exact::{ExactPoly, RealRoot};
use nlrt_poly::Real;
use rug::Float;
use std::cmp::Ordering;

const PREC: u32 = 320;

/// How close a computed root must be to a true root to count as finding it.
#[derive(Clone, Copy, Debug)]
pub struct Tolerance {
    /// Always allowed: this many ulps of the target type at the root.
    pub ulps: f64,
    /// Allowed on top for ill-conditioned roots: this multiple of the attainable radius.
    pub radius_factor: f64,
}

impl Tolerance {
    /// The tolerance the project's solvers are held to: 4 ulps, or 2x the attainable radius
    /// for ill-conditioned roots.
    pub const SOLVER: Tolerance = Tolerance {
        ulps: 4.0,
        radius_factor: 2.0,
    };
}

/// What a solver got right and wrong on one polynomial.
#[derive(Clone, Debug, Default)]
pub struct Verdict {
    /// For each computed root matched to a true root: its error in ulps of the target type.
    pub errors_ulps: Vec<f64>,
    /// For each matched root: error divided by its tolerance (<= 1 for every match).
    pub error_over_tolerance: Vec<f64>,
    /// True roots inside the interval with no computed root within tolerance.
    pub missed: usize,
    /// Computed roots near no true root that are not even roots of a polynomial within
    /// rounding of the input (backward error above the evaluation noise).
    pub spurious: usize,
    /// Computed roots near no true root but with backward error within the evaluation noise:
    /// roots of a polynomial indistinguishable from the input in this type (e.g. a reported
    /// tangency where the exact discriminant is barely negative). Reported, not failed.
    pub pseudo: usize,
    /// Number of true roots inside the interval.
    pub true_roots: usize,
}

impl Verdict {
    /// No missed and no spurious roots.
    #[must_use]
    pub fn passes(&self) -> bool {
        self.missed == 0 && self.spurious == 0
    }

    /// Largest error in ulps (0 when nothing matched).
    #[must_use]
    pub fn max_ulps(&self) -> f64 {
        self.errors_ulps.iter().copied().fold(0.0, f64::max)
    }
}

/// The exact roots of one polynomial with their attainable radii for the type `T`.
#[derive(Clone, Debug)]
pub struct Truth {
    poly: ExactPoly,
    roots: Vec<RealRoot>,
    radii: Vec<Float>,
    noise_scale: Float,
}

impl Truth {
    /// Exact roots of `coeffs` (ascending powers; f32 or f64 values, converted exactly) with
    /// radii for evaluation in the type `T`. `None` for non-finite coefficients.
    #[must_use]
    pub fn new<T: Real>(coeffs: &[T]) -> Option<Self> {
        let c: Vec<f64> = coeffs.iter().map(|x| x.to_f64()).collect();
        let poly = ExactPoly::from_f64s(&c)?;
        let roots = poly.real_roots();
        let degree = poly.degree().unwrap_or(0).max(1) as u32;
        // 2 n u, the noise factor of `horner_with_bound`.
        let noise_scale = Float::with_val(PREC, 2 * degree) >> T::MANTISSA_DIGITS;
        let mut truth = Self {
            poly,
            roots,
            radii: vec![],
            noise_scale,
        };
        truth.radii = truth
            .roots
            .iter()
            .map(|r| truth.attainable_radius::<T>(&r.value))
            .collect();
        Some(truth)
    }

    /// The exact roots.
    #[must_use]
    pub fn roots(&self) -> &[RealRoot] {
        &self.roots
    }

    /// The attainable radius of the i-th root, as f64.
    #[must_use]
    pub fn radius(&self, i: usize) -> f64 {
        self.radii[i].to_f64()
    }

    fn below_noise(&self, x: &Float) -> bool {
        let (v, m) = self.poly.eval_with_magnitude(x, PREC);
        v.abs() <= m * &self.noise_scale
    }

    /// Smallest power of two `d >= ulp(r)` such that both `r - d` and `r + d` are outside the
    /// pseudo-zero set.
    fn attainable_radius<T: Real>(&self, r: &Float) -> Float {
        let mut j = ulp_exponent::<T>(r);
        let top = T::MAX_EXPONENT + 1;
        while j < top {
            let d = Float::with_val(PREC, 1) << j;
            let left = Float::with_val(PREC, r - &d);
            let right = Float::with_val(PREC, r + &d);
            if !self.below_noise(&left) && !self.below_noise(&right) {
                return d;
            }
            j += 1;
        }
        Float::with_val(PREC, 1) << top
    }

    /// Judges the roots a solver reported for the interval `[lo, hi]`.
    #[must_use]
    pub fn judge<T: Real>(&self, computed: &[T], lo: T, hi: T, tol: Tolerance) -> Verdict {
        let lo_f = Float::with_val(PREC, lo.to_f64());
        let hi_f = Float::with_val(PREC, hi.to_f64());
        let tolerances: Vec<Float> = self
            .roots
            .iter()
            .zip(&self.radii)
            .map(|(r, rad)| {
                let a = Float::with_val(PREC, ulp::<T>(&r.value)) * tol.ulps;
                let b = Float::with_val(PREC, rad * tol.radius_factor);
                a.max(&b)
            })
            .collect();
        let inside = |r: &Float| *r >= lo_f && *r <= hi_f;
        let mut v = Verdict {
            true_roots: self.roots.iter().filter(|r| inside(&r.value)).count(),
            ..Verdict::default()
        };
        let mut found = vec![false; self.roots.len()];
        for &x in computed {
            let xf = Float::with_val(PREC, x.to_f64());
            // Every true root within tolerance is found by this computed root (a cluster
            // inside the noise is rightly reported as one root).
            for (i, r) in self.roots.iter().enumerate() {
                if Float::with_val(PREC, &xf - &r.value).abs() <= tolerances[i] {
                    found[i] = true;
                }
            }
            let best = self
                .roots
                .iter()
                .enumerate()
                .map(|(i, r)| {
                    let err = Float::with_val(PREC, &xf - &r.value).abs();
                    let ratio = Float::with_val(PREC, &err / &tolerances[i]);
                    (i, err, ratio)
                })
                .min_by(|a, b| a.2.partial_cmp(&b.2).unwrap_or(Ordering::Equal));
            match best {
                Some((i, err, ratio)) if ratio <= 1 => {
                    v.errors_ulps
                        .push((err / ulp::<T>(&self.roots[i].value)).to_f64());
                    v.error_over_tolerance.push(ratio.to_f64());
                }
                _ => {
                    if self.below_noise(&xf) {
                        v.pseudo += 1;
                    } else {
                        v.spurious += 1;
                    }
                }
            }
        }
        for (i, r) in self.roots.iter().enumerate() {
            if inside(&r.value) && !found[i] {
                v.missed += 1;
            }
        }
        v
    }
}

/// Exponent of one ulp of the type `T` at `r` (subnormal spacing below the normal range).
fn ulp_exponent<T: Real>(r: &Float) -> i32 {
    let p = T::MANTISSA_DIGITS as i32;
    let e = r
        .get_exp()
        .map_or(T::MIN_EXPONENT, |e| (e - 1).max(T::MIN_EXPONENT));
    e - (p - 1)
}

/// One ulp of the type `T` at `r`.
#[must_use]
pub fn ulp<T: Real>(r: &Float) -> Float {
    Float::with_val(PREC, 1) << ulp_exponent::<T>(r)
}

/// Convenience: exact roots and the verdict in one call.
///
/// ```
/// use nlrt_oracle::{judge, Tolerance};
/// let c = [-6.0f64, 11.0, -6.0, 1.0];
/// let v = judge(&c, &nlrt_poly::solve_cubic(c), f64::NEG_INFINITY, f64::INFINITY, Tolerance::SOLVER);
/// assert!(v.passes() && v.max_ulps() <= 4.0);
/// ```
#[must_use]
pub fn judge<T: Real>(coeffs: &[T], computed: &[T], lo: T, hi: T, tol: Tolerance) -> Verdict {
    match Truth::new(coeffs) {
        Some(t) => t.judge(computed, lo, hi, tol),
        None => Verdict {
            spurious: computed.len(),
            ..Verdict::default()
        },
    }
}
