//! Every real root, with its multiplicity, of a polynomial of degree <= 3 whose coefficients are
//! floating-point numbers (exact rationals), to at least [`ROOT_BITS`] bits.
//!
//! Method: multiple roots of a rational cubic are rational (they are roots of
//! `gcd(p, p')`, of degree <= 2), so they are found exactly; what is left is square-free and
//! its roots are isolated exactly (discriminants and the inflection value are exact
//! rationals), then refined by bracketed Newton/bisection in MPFR, where every sign decision
//! is checked against a rigorous error bound and the precision is doubled when it cannot be
//! made.

use rug::ops::Pow;
use rug::{Float, Rational};
use std::cmp::Ordering;

/// Relative accuracy of every reported root: at least this many bits.
pub const ROOT_BITS: u32 = 200;
/// Working precision of MPFR evaluations; raised on demand.
const START_PREC: u32 = 320;
/// Give up raising the precision beyond this (never reached for f32/f64 inputs in practice:
/// the separation of distinct roots of a cubic with such coefficients is far above 2^-16000).
const MAX_PREC: u32 = 1 << 16;

/// A real root of the exact polynomial.
#[derive(Clone, Debug)]
pub struct RealRoot {
    /// The root, correct to at least [`ROOT_BITS`] bits (exact when rational and found so).
    pub value: Float,
    /// Its multiplicity (1, 2 or 3).
    pub multiplicity: u32,
}

impl RealRoot {
    /// The root rounded to `f64` (for display).
    #[must_use]
    pub fn to_f64(&self) -> f64 {
        self.value.to_f64()
    }
}

/// A polynomial with exact rational coefficients, ascending powers, no leading zeros.
#[derive(Clone, Debug, PartialEq)]
pub struct ExactPoly {
    coeffs: Vec<Rational>,
}

impl ExactPoly {
    /// From floating-point coefficients (ascending powers). `None` if any is NaN or infinite.
    #[must_use]
    pub fn from_f64s(c: &[f64]) -> Option<Self> {
        let coeffs = c
            .iter()
            .map(|&x| Rational::from_f64(x))
            .collect::<Option<Vec<_>>>()?;
        Some(Self::from_rationals(coeffs))
    }

    /// From rational coefficients (ascending powers); leading zeros are dropped.
    #[must_use]
    pub fn from_rationals(mut coeffs: Vec<Rational>) -> Self {
        while coeffs.last().is_some_and(|c| c.cmp0() == Ordering::Equal) {
            coeffs.pop();
        }
        Self { coeffs }
    }

    /// Degree; `None` for the zero polynomial.
    #[must_use]
    pub fn degree(&self) -> Option<usize> {
        self.coeffs.len().checked_sub(1)
    }

    /// Coefficients, ascending powers.
    #[must_use]
    pub fn coeffs(&self) -> &[Rational] {
        &self.coeffs
    }

    /// Exact value at a rational point.
    #[must_use]
    pub fn eval(&self, x: &Rational) -> Rational {
        let mut r = Rational::new();
        for c in self.coeffs.iter().rev() {
            r *= x;
            r += c;
        }
        r
    }

    /// Value at `x` in MPFR at precision `prec`, and `sum |c_i| |x|^i` (the scale of its
    /// rounding errors, and of a floating-point evaluation's).
    #[must_use]
    pub fn eval_with_magnitude(&self, x: &Float, prec: u32) -> (Float, Float) {
        let mut r = Float::new(prec);
        let mut m = Float::new(prec);
        let ax = Float::with_val(prec, x.abs_ref());
        for c in self.coeffs.iter().rev() {
            r *= x;
            r += c;
            m *= &ax;
            m += Float::with_val(prec, c.clone().abs());
        }
        (r, m)
    }

    /// Value at `x` in MPFR at precision `prec`, with a rigorous bound on its error.
    #[must_use]
    pub fn eval_float(&self, x: &Float, prec: u32) -> (Float, Float) {
        let (r, m) = self.eval_with_magnitude(x, prec);
        // Each of the 2n roundings of Horner (plus the rounding of each coefficient) is
        // bounded by 2^-prec relative to the running sum of magnitudes; 4(n+1) 2^-prec m
        // covers them with margin, and the bound's own rounding is far below that margin.
        let n = self.coeffs.len() as u32;
        let bound = (m * Float::with_val(prec, 4 * (n + 1))) >> prec;
        (r, bound)
    }

    /// The derivative.
    #[must_use]
    pub fn derivative(&self) -> Self {
        let coeffs = self
            .coeffs
            .iter()
            .enumerate()
            .skip(1)
            .map(|(i, c)| c * Rational::from(i as u32))
            .collect();
        Self::from_rationals(coeffs)
    }

    /// Quotient and remainder of polynomial division (divisor non-zero).
    fn div_rem(&self, d: &ExactPoly) -> (ExactPoly, ExactPoly) {
        let dd = d.degree().expect("division by the zero polynomial");
        let mut rem = self.coeffs.clone();
        let n = self.coeffs.len();
        if n <= dd {
            return (ExactPoly { coeffs: vec![] }, self.clone());
        }
        let mut quot = vec![Rational::new(); n - dd];
        let lead = &d.coeffs[dd];
        for i in (0..n - dd).rev() {
            let q = Rational::from(&rem[i + dd] / lead);
            for (j, dc) in d.coeffs.iter().enumerate() {
                rem[i + j] -= Rational::from(&q * dc);
            }
            quot[i] = q;
        }
        rem.truncate(dd);
        (
            ExactPoly::from_rationals(quot),
            ExactPoly::from_rationals(rem),
        )
    }

    fn gcd(&self, other: &ExactPoly) -> ExactPoly {
        let (mut a, mut b) = (self.clone(), other.clone());
        while b.degree().is_some() {
            let (_, r) = a.div_rem(&b);
            a = b;
            b = r;
        }
        a
    }

    /// Every real root with its multiplicity, in increasing order. Degree <= 3 only.
    ///
    /// # Panics
    /// For degree above 3.
    #[must_use]
    pub fn real_roots(&self) -> Vec<RealRoot> {
        let Some(deg) = self.degree() else {
            return vec![];
        };
        assert!(deg <= 3, "the oracle handles degree <= 3");
        let mut roots = Vec::new();
        let mut rest = self.clone();
        // A repeated root is a root of gcd(p, p'); for degree <= 3 it is rational.
        let g = self.gcd(&self.derivative());
        if let Some(gd @ 1..) = g.degree() {
            // g = (x - r)^gd up to a constant
            let r =
                -(g.coeffs[gd - 1].clone()) / (g.coeffs[gd].clone() * Rational::from(gd as u32));
            let mult = gd as u32 + 1;
            for _ in 0..mult {
                let lin = ExactPoly::from_rationals(vec![Rational::from(-&r), Rational::from(1)]);
                rest = rest.div_rem(&lin).0;
            }
            roots.push(RealRoot {
                value: Float::with_val(START_PREC, &r),
                multiplicity: mult,
            });
        }
        for value in rest.squarefree_roots() {
            roots.push(RealRoot {
                value,
                multiplicity: 1,
            });
        }
        roots.sort_by(|a, b| a.value.partial_cmp(&b.value).unwrap_or(Ordering::Equal));
        roots
    }

    /// Roots of a square-free polynomial of degree <= 3.
    fn squarefree_roots(&self) -> Vec<Float> {
        let c = &self.coeffs;
        match self.degree() {
            None | Some(0) => vec![],
            Some(1) => vec![Float::with_val(START_PREC, -(c[0].clone()) / &c[1])],
            Some(2) => quadratic_roots(&c[0], &c[1], &c[2]),
            Some(3) => self.cubic_roots(),
            Some(_) => unreachable!(),
        }
    }

    fn cubic_roots(&self) -> Vec<Float> {
        let c = &self.coeffs;
        let lead_positive = c[3].cmp0() == Ordering::Greater;
        // Cauchy's bound: every root has |x| < 1 + max |c_i / c_3|.
        let mut bound = Rational::new();
        for ci in &c[..3] {
            let r = (ci.clone() / &c[3]).abs();
            if r > bound {
                bound = r;
            }
        }
        bound += 1;
        let lo_end = Float::with_val(START_PREC, -(bound.clone()));
        let hi_end = Float::with_val(START_PREC, &bound);
        let d = self.derivative();
        // Discriminant of p' = d0 + d1 x + d2 x^2.
        let dd: Rational =
            d.coeffs[1].clone().pow(2) - Rational::from(4) * &d.coeffs[2] * &d.coeffs[0];
        if dd.cmp0() != Ordering::Greater {
            // Monotonic: one real root. Sign at -bound is -sign(lead).
            return vec![self.refine(lo_end, hi_end, !lead_positive)];
        }
        let crit = quadratic_roots(&d.coeffs[0], &d.coeffs[1], &d.coeffs[2]);
        let (c1, c2) = (crit[0].clone(), crit[1].clone());
        let disc = cubic_discriminant(c);
        if disc.cmp0() == Ordering::Greater {
            // Three real roots, one per monotonic piece; the signs at the critical points are
            // those of a local maximum above and a local minimum below the axis.
            vec![
                self.refine(lo_end, c1.clone(), !lead_positive),
                self.refine(c1, c2.clone(), lead_positive),
                self.refine(c2, hi_end, !lead_positive),
            ]
        } else {
            // One real root. p(inflection) = (p(c1) + p(c2)) / 2 has the sign of both critical
            // values, and is an exact rational.
            let inflection = -(c[2].clone()) / (Rational::from(3) * &c[3]);
            let s = self.eval(&inflection).cmp0();
            let critical_positive = s == Ordering::Greater;
            // A critical point is only approximate, but a root on the wrong side of it is
            // within its approximation error, far below 2^-ROOT_BITS.
            if critical_positive == lead_positive {
                vec![self.refine(lo_end, c1, !lead_positive)]
            } else {
                vec![self.refine(c2, hi_end, !lead_positive)]
            }
        }
    }

    /// The single root in `(lo, hi)`, where `p` is monotonic and changes sign, with `p(lo) > 0`
    /// iff `lo_positive`. Bisection steered by signs that are certified against the
    /// evaluation bound; an uncertain sign raises the precision.
    fn refine(&self, lo: Float, hi: Float, lo_positive: bool) -> Float {
        let mut prec = START_PREC.max(lo.prec()).max(hi.prec());
        let (mut lo, mut hi) = (lo, hi);
        let d = self.derivative();
        let mut x = Float::with_val(prec, &lo + &hi) / 2u32;
        loop {
            // Converged: the bracket is below 2^-(ROOT_BITS + 8) relative to the root.
            let width = Float::with_val(prec, &hi - &lo);
            let scale =
                Float::with_val(prec, lo.abs_ref()).max(&Float::with_val(prec, hi.abs_ref()));
            if width.is_zero()
                || (!scale.is_zero()
                    && (width.clone() / &scale).get_exp().unwrap_or(i32::MIN)
                        < -(ROOT_BITS as i32) - 8)
            {
                return Float::with_val(prec, &lo + &hi) / 2u32;
            }
            if scale.is_zero() {
                return lo;
            }
            let (v, bound) = self.eval_float(&x, prec);
            let (dv, _) = d.eval_float(&x, prec);
            let converged_at = |dist: Float| {
                let rel = dist / Float::with_val(prec, x.abs_ref());
                rel.is_zero() || rel.get_exp().is_some_and(|e| e < -(ROOT_BITS as i32) - 8)
            };
            if Float::with_val(prec, v.abs_ref()) <= bound {
                if v.is_zero() && bound.is_zero() {
                    return x; // exact zero
                }
                // The sign is uncertain, so x is within bound / |p'(x)| of the root (first
                // order; p' is far from zero for a simple root at this precision).
                if !dv.is_zero() && converged_at(Float::with_val(prec, &bound / &dv).abs()) {
                    return x;
                }
                if prec >= MAX_PREC {
                    return x;
                }
                prec *= 2;
                lo.set_prec(prec);
                hi.set_prec(prec);
                x.set_prec(prec);
                continue;
            }
            if (v.cmp0() == Some(Ordering::Greater)) == lo_positive {
                lo = x.clone();
            } else {
                hi = x.clone();
            }
            // Newton from x; fall back to bisection when it leaves the bracket.
            let step = Float::with_val(prec, &v / &dv);
            let mut next = Float::with_val(prec, &x - &step);
            if next > lo && next < hi && converged_at(step.abs()) {
                return next; // quadratic convergence: the next error is far smaller still
            }
            if !(next > lo && next < hi && next.is_finite()) {
                next = Float::with_val(prec, &lo + &hi) / 2u32;
            }
            if next == x {
                next = Float::with_val(prec, &lo + &hi) / 2u32;
                if next == lo || next == hi {
                    return next;
                }
            }
            x = next;
        }
    }
}

/// `18abcd - 4b^3 d + b^2 c^2 - 4ac^3 - 27a^2 d^2` for `a x^3 + b x^2 + c x + d` (exact).
fn cubic_discriminant(c: &[Rational]) -> Rational {
    let (d, cc, b, a) = (&c[0], &c[1], &c[2], &c[3]);
    let r = |x: i32| Rational::from(x);
    let t1 = r(18) * a * b * cc * d;
    let t2 = r(4) * Rational::from(b.pow(3u32)) * d;
    let t3 = Rational::from(b.pow(2u32)) * Rational::from(cc.pow(2u32));
    let t4 = r(4) * a * Rational::from(cc.pow(3u32));
    let t5 = r(27) * Rational::from(a.pow(2u32)) * Rational::from(d.pow(2u32));
    t1 - t2 + t3 - t4 - t5
}

/// Roots of a square-free quadratic `c0 + c1 x + c2 x^2` (exact discriminant sign, stable
/// formula in MPFR), increasing.
fn quadratic_roots(c0: &Rational, c1: &Rational, c2: &Rational) -> Vec<Float> {
    let disc: Rational = c1.clone().pow(2) - Rational::from(4) * c2 * c0;
    match disc.cmp0() {
        Ordering::Less => vec![],
        Ordering::Equal => vec![Float::with_val(
            START_PREC,
            -(c1.clone()) / (Rational::from(2) * c2),
        )],
        Ordering::Greater => {
            let prec = START_PREC + 64;
            let s = Float::with_val(prec, &disc).sqrt();
            let b = Float::with_val(prec, c1);
            // q = -(b + sign(b) sqrt(D)) / 2: no cancellation.
            let q = if b.cmp0() == Some(Ordering::Less) {
                (s - b) / 2u32
            } else {
                -(s + b) / 2u32
            };
            let r1 = Float::with_val(prec, &q / &Float::with_val(prec, c2));
            let r2 = Float::with_val(prec, &Float::with_val(prec, c0) / &q);
            let mut v = vec![r1, r2];
            v.sort_by(|a, b| a.partial_cmp(b).unwrap_or(Ordering::Equal));
            v
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn roots(c: &[f64]) -> Vec<(f64, u32)> {
        ExactPoly::from_f64s(c)
            .unwrap()
            .real_roots()
            .iter()
            .map(|r| (r.to_f64(), r.multiplicity))
            .collect()
    }

    #[test]
    fn simple_cubic() {
        assert_eq!(
            roots(&[-6.0, 11.0, -6.0, 1.0]),
            vec![(1.0, 1), (2.0, 1), (3.0, 1)]
        );
    }

    #[test]
    fn multiplicities_are_exact() {
        // (x - 0.5)^2 (x + 3) = x^3 + 2x^2 - 2.75x + 0.75
        assert_eq!(roots(&[0.75, -2.75, 2.0, 1.0]), vec![(-3.0, 1), (0.5, 2)]);
        // (x - 0.25)^3
        assert_eq!(
            roots(&[-1.0 / 64.0, 3.0 / 16.0, -0.75, 1.0]),
            vec![(0.25, 3)]
        );
        // x^2 (x - 1)
        assert_eq!(roots(&[0.0, 0.0, -1.0, 1.0]), vec![(0.0, 2), (1.0, 1)]);
        assert_eq!(roots(&[0.0, 0.0, 90.0]), vec![(0.0, 2)]);
    }

    #[test]
    fn one_real_root_on_either_side() {
        // x^3 + x + 1: one real root -0.6823278038280193...
        let r = roots(&[1.0, 1.0, 0.0, 1.0]);
        assert_eq!(r.len(), 1);
        assert!((r[0].0 + 0.682_327_803_828_019_3).abs() < 1e-15);
        // (x - 10)(x^2 + 1): critical points exist (3x^2 - 20x + 1), root right of them.
        let r = roots(&[-10.0, 1.0, -10.0, 1.0]);
        assert_eq!(r, vec![(10.0, 1)]);
        // (x + 10)(x^2 + 1)
        let r = roots(&[10.0, 1.0, 10.0, 1.0]);
        assert_eq!(r, vec![(-10.0, 1)]);
    }

    #[test]
    fn near_double_root_is_resolved_to_200_bits() {
        // (x - 1)(x - (1 + 2^-50))(x - 3): two roots 2^-50 apart.
        let e = 2f64.powi(-50);
        let (a, b, c) = (
            Rational::from(1),
            Rational::from(1) + Rational::from_f64(e).unwrap(),
            Rational::from(3),
        );
        let coeffs = vec![
            -(a.clone() * &b * &c),
            Rational::from(&a * &b) + Rational::from(&a * &c) + Rational::from(&b * &c),
            -(a.clone() + &b + &c),
            Rational::from(1),
        ];
        let p = ExactPoly::from_rationals(coeffs);
        let r = p.real_roots();
        assert_eq!(r.len(), 3);
        let err = Float::with_val(400, &r[1].value - &b).abs();
        assert!(err < Float::with_val(400, 1) >> 210u32, "{err}");
    }

    #[test]
    fn kahan_cubic() {
        // 658x^3 - 190125x^2 + 18311811x - 587898164: one real root near 96.23.
        let r = roots(&[-587_898_164.0, 18_311_811.0, -190_125.0, 658.0]);
        assert_eq!(r.len(), 1, "{r:?}");
        assert!((r[0].0 - 96.229_639_34).abs() < 1e-6, "{r:?}");
    }
}
