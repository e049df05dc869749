//! Test polynomials: the named hard families, random ones, and a deterministic generator.
//!
//! Everything is built exactly (rational arithmetic) and rounded once to the target type; the
//! truth is always that of the rounded coefficients, which is what a solver sees.

use nlrt_poly::Real;
use rug::{Float, Rational};

/// A cubic (ascending coefficients) and the interval it is solved on.
#[derive(Clone, Debug)]
pub struct Case<T: Real> {
    /// Family and member, e.g. `"spread/1,1e7,1e14"`.
    pub name: String,
    /// Coefficients, ascending powers.
    pub coeffs: [T; 4],
    /// Interval start (may be -inf).
    pub lo: T,
    /// Interval end (may be +inf).
    pub hi: T,
}

/// Rounds an exact rational to `T` (through a 320-bit float: at most one extra rounding far
/// below `T`'s precision; ties aside, the same as rounding directly).
fn round<T: Real>(r: &Rational) -> T {
    T::from_f64(Float::with_val(320, r).to_f64())
}

/// `scale * prod (x - r_i)` expanded exactly, rounded to `T` once per coefficient.
#[must_use]
pub fn cubic_from_roots<T: Real>(roots: [f64; 3], scale: f64) -> [T; 4] {
    let r: Vec<Rational> = roots
        .iter()
        .map(|&x| Rational::from_f64(x).expect("finite root"))
        .collect();
    let s = Rational::from_f64(scale).expect("finite scale");
    let e1 = Rational::from(&r[0] + &r[1]) + &r[2];
    let e2 = Rational::from(&r[0] * &r[1])
        + Rational::from(&r[0] * &r[2])
        + Rational::from(&r[1] * &r[2]);
    let e3 = Rational::from(&r[0] * &r[1]) * &r[2];
    [
        round(&(-e3 * &s)),
        round(&(e2 * &s)),
        round(&(-e1 * &s)),
        round(&s),
    ]
}

/// `(x - a) ((x - re)^2 + im^2)`: a real root next to a complex pair.
#[must_use]
pub fn cubic_with_complex_pair<T: Real>(a: f64, re: f64, im: f64) -> [T; 4] {
    let a = Rational::from_f64(a).unwrap();
    let re = Rational::from_f64(re).unwrap();
    let im = Rational::from_f64(im).unwrap();
    // (x^2 - 2 re x + re^2 + im^2)(x - a)
    let q0 = Rational::from(&re * &re) + Rational::from(&im * &im);
    let q1 = Rational::from(-2) * &re;
    [
        round(&(-(q0.clone() * &a))),
        round(&(q0 - Rational::from(&q1 * &a))),
        round(&(q1 - &a)),
        T::ONE,
    ]
}

fn case<T: Real>(name: &str, coeffs: [T; 4], lo: f64, hi: f64) -> Case<T> {
    Case {
        name: name.to_string(),
        coeffs,
        lo: T::from_f64(lo),
        hi: T::from_f64(hi),
    }
}

/// The named hard families of the foundation issue, for the type `T`. Each is solved on the
/// whole line, and some also on a bounded interval.
#[must_use]
pub fn hard_cubics<T: Real>() -> Vec<Case<T>> {
    let inf = f64::INFINITY;
    let is_f32 = T::MANTISSA_DIGITS == 24;
    // Extreme magnitudes: the largest coefficient near 1e238 (f64) or 1e37 (f32), and tiny.
    let (huge, tiny) = if is_f32 {
        (1e36, 1e-36)
    } else {
        (1e236, 1e-300)
    };
    let mut v = vec![
        case(
            "spread/1,1e7,1e14",
            cubic_from_roots([1.0, 1e7, 1e14], 1.0),
            -inf,
            inf,
        ),
        case(
            "spread/1,-1,-1e24",
            cubic_from_roots([1.0, -1.0, -1e24], 1.0),
            -inf,
            inf,
        ),
        case(
            "spread/1e-7,1,1e7",
            cubic_from_roots([1e-7, 1.0, 1e7], 1.0),
            -inf,
            inf,
        ),
        case(
            "magnitude/huge",
            cubic_from_roots([1.0, 2.0, 3.0], huge),
            -inf,
            inf,
        ),
        case(
            "magnitude/huge-spread",
            cubic_from_roots([-1.0, 1e3, 1e6], huge / 1e18),
            -inf,
            inf,
        ),
        case(
            "magnitude/tiny",
            cubic_from_roots([1.0, 2.0, 3.0], tiny),
            -inf,
            inf,
        ),
        case(
            "magnitude/tiny-roots",
            cubic_from_roots([1e-30, 2e-30, -3e-30], 1.0),
            -inf,
            inf,
        ),
        case(
            "cluster/1,1+1e-6,1+2e-6",
            cubic_from_roots([1.0, 1.0 + 1e-6, 1.0 + 2e-6], 1.0),
            -inf,
            inf,
        ),
        case(
            "cluster/unit",
            cubic_from_roots([1.0, 1.0 + 1e-6, 1.0 + 2e-6], 1.0),
            0.0,
            2.0,
        ),
        case(
            "double/large-scale",
            cubic_from_roots([1e6, 1e6, -1.0], 1.0),
            -inf,
            inf,
        ),
        case(
            "double/large-scale-2",
            cubic_from_roots([1e10, 1e10, 1.0], 1.0),
            -inf,
            inf,
        ),
        case(
            "double/unit",
            cubic_from_roots([0.5, 0.5, 2.0], 1.0),
            0.0,
            1.0,
        ),
        case(
            "double/at-end",
            cubic_from_roots([0.0, 0.0, 0.5], 1.0),
            0.0,
            1.0,
        ),
        case(
            "triple/quarter",
            cubic_from_roots([0.25, 0.25, 0.25], 1.0),
            -inf,
            inf,
        ),
        case(
            "triple/minus-one",
            cubic_from_roots([-1.0, -1.0, -1.0], 1.0),
            -2.0,
            0.0,
        ),
        case(
            "complex-pair/1e5+-i",
            cubic_with_complex_pair(1e5, 1e5, 1.0),
            -inf,
            inf,
        ),
        case(
            "complex-pair/1,1+-1e7i",
            cubic_with_complex_pair(1.0, 1.0, 1e7),
            -inf,
            inf,
        ),
        case(
            "complex-pair/near",
            cubic_with_complex_pair(0.5, 0.5 + 1e-3, 1e-4),
            0.0,
            1.0,
        ),
        case(
            "kahan",
            [-587_898_164.0, 18_311_811.0, -190_125.0, 658.0].map(T::from_f64),
            -inf,
            inf,
        ),
        case(
            "tiny-leading/1e-20",
            [2.0, -3.0, 1.0, 1e-20].map(T::from_f64),
            -inf,
            inf,
        ),
        case(
            "tiny-leading/1e-10",
            [2.0, -3.0, 1.0, 1e-10].map(T::from_f64),
            -inf,
            inf,
        ),
        case(
            "tiny-leading/unit",
            [0.25, -1.25, 1.0, 1e-20].map(T::from_f64),
            0.0,
            1.0,
        ),
        case(
            "tiny-root/1e-18",
            cubic_from_roots([1e-18, 1.0, 2.0], 1.0),
            -inf,
            inf,
        ),
        case(
            "tiny-root/+-1e-18",
            cubic_from_roots([-1e-18, 1e-18, 1.0], 1.0),
            -inf,
            inf,
        ),
        case(
            "cy/90x^2-on-unit",
            [0.0, 0.0, 90.0, 0.0].map(T::from_f64),
            0.0,
            1.0,
        ),
        case(
            "cy/90x^2(x-1)",
            [0.0, 0.0, -90.0, 90.0].map(T::from_f64),
            0.0,
            1.0,
        ),
        case(
            "cy/linear",
            [-4.0, 2.0, 0.0, 0.0].map(T::from_f64),
            -inf,
            inf,
        ),
        case(
            "cy/outward-search",
            cubic_from_roots([-3e5, 1e-3, 7e8], 1.0),
            -inf,
            inf,
        ),
        case(
            "unit/three",
            cubic_from_roots([0.1, 0.5, 0.9], 1.0),
            0.0,
            1.0,
        ),
        case(
            "unit/ends",
            cubic_from_roots([0.0, 0.5, 1.0], 1.0),
            0.0,
            1.0,
        ),
    ];
    // Roots exactly on, just inside and just outside the ends of the interval.
    let r = cubic_from_roots::<T>([0.25, 0.5, 0.75], 1.0);
    let (a, b) = (T::from_f64(0.25), T::from_f64(0.75));
    for (label, lo, hi) in [
        ("on", a, b),
        ("inside", a.next_up(), b.next_down()),
        ("outside", a.next_down(), b.next_up()),
    ] {
        v.push(Case {
            name: format!("ends/{label}"),
            coeffs: r,
            lo,
            hi,
        });
    }
    v
}

/// SplitMix64: a tiny, seedable, deterministic generator (test inputs must be reproducible).
#[derive(Clone, Debug)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// A generator from a seed.
    #[must_use]
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.unit()
    }
}

/// The random families of the solver report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RandomFamily {
    /// Three roots uniform in [0, 1], solved on [0, 1] (the benchmark case).
    ThreeRootsInUnit,
    /// Coefficients with random signs and magnitudes 2^U(-30, 30), solved on the whole line.
    LogUniformCoefficients,
    /// Roots clustered at random scales: r (1 + k 2^-j), solved on the whole line.
    Clustered,
}

impl RandomFamily {
    /// All families.
    pub const ALL: [RandomFamily; 3] = [
        Self::ThreeRootsInUnit,
        Self::LogUniformCoefficients,
        Self::Clustered,
    ];

    /// Short name for tables.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::ThreeRootsInUnit => "random: 3 roots in [0,1]",
            Self::LogUniformCoefficients => "random: log-uniform coefficients",
            Self::Clustered => "random: clustered roots",
        }
    }

    /// One random member.
    pub fn sample<T: Real>(self, rng: &mut SplitMix64) -> Case<T> {
        let inf = f64::INFINITY;
        match self {
            Self::ThreeRootsInUnit => {
                let roots = [rng.unit(), rng.unit(), rng.unit()];
                Case {
                    name: self.name().into(),
                    coeffs: cubic_from_roots(roots, 1.0),
                    lo: T::ZERO,
                    hi: T::ONE,
                }
            }
            Self::LogUniformCoefficients => {
                let mut c = [T::ZERO; 4];
                for ci in &mut c {
                    let mag = rng.range(-30.0, 30.0).exp2();
                    let sign = if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
                    *ci = T::from_f64(sign * mag);
                }
                Case {
                    name: self.name().into(),
                    coeffs: c,
                    lo: T::from_f64(-inf),
                    hi: T::from_f64(inf),
                }
            }
            Self::Clustered => {
                let scale = rng.range(-20.0, 20.0).exp2()
                    * if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 };
                let j = rng.range(4.0, 40.0).floor();
                let gap = (-j).exp2();
                let roots = [
                    scale,
                    scale * (1.0 + gap),
                    scale * (1.0 + 2.0 * gap * rng.unit()),
                ];
                Case {
                    name: self.name().into(),
                    coeffs: cubic_from_roots(roots, 1.0),
                    lo: T::from_f64(-inf),
                    hi: T::from_f64(inf),
                }
            }
        }
    }
}
