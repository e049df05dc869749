//! # nlrt-poly
//!
//! Robust real-root finders for quadratics and cubics, generic over `f32` and `f64`, `no_std`.
//!
//! Every ray-microtriangle test of nonlinear ray tracing (Ogaki 2023, Eq. 9-10) solves a cubic
//! in the height `h` restricted to `[h_in, h_out]`, and every ray-box test in texture space
//! solves quadratics. These solvers are built for that: restricted to an interval, nearest
//! root first, no heap, and accurate to the conditioning of each root on hard inputs (huge
//! root spreads, extreme magnitudes, clusters, multiple and tangential roots) where closed
//! forms fail.
//!
//! Coefficients are given by ascending power: `c[i]` multiplies `x^i`.
//!
//! ```
//! use nlrt_poly::{solve_cubic_in, solve_quadratic};
//! // 2 x^3 - 3 x^2 + x = x (2x - 1)(x - 1), roots in [0.25, 2]:
//! let roots = solve_cubic_in([0.0f64, 1.0, -3.0, 2.0], 0.25, 2.0);
//! assert_eq!(roots.as_slice(), &[0.5, 1.0]);
//! assert_eq!(solve_quadratic([-4.0f32, 0.0, 1.0]).as_slice(), &[-2.0, 2.0]);
//! ```
//!
//! ## Features
//! - `std` (default): float functions from the standard library.
//! - `libm`: float functions from the `libm` crate for `no_std` builds.
//!
//! One of the two must be enabled. Build with the `fma` target feature (the workspace sets
//! `target-cpu=x86-64-v3`) so that [`Real::mul_add`] is one instruction.
#![no_std]
#![warn(missing_docs)]
// `!(a <= b)` is deliberate throughout: it is true when either side is NaN, which is how bad
// input is rejected without a separate NaN test.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("nlrt-poly needs the `std` or the `libm` feature for sqrt, cbrt and fma");

#[cfg(feature = "std")]
extern crate std;

mod batch;
pub mod closed_form;
mod cubic;
mod eval;
mod lanes;
pub mod lanes4;
mod quadratic;
mod quadratic_batch;
mod real;
mod roots;
mod vector;

pub use batch::{CUBIC_BATCH, first_cubic_root_batch_in, solve_cubic_batch_in, solve_cubics_in};
pub use cubic::{first_cubic_root_in, solve_cubic, solve_cubic_in};
pub use eval::{decided_sign, horner, horner_with_bound, horner_with_bound_scaled};
pub use glam;
pub use lanes::LaneMask;
pub use lanes4::Lanes4;
pub use quadratic::{discriminant, quadratic_range, solve_quadratic, solve_quadratic_in};
pub use quadratic_batch::{QUADRATIC_BATCH, QuadraticBatch, solve_quadratic_batch_in};
pub use real::Real;
pub use roots::Roots;
pub use vector::{Vector2, Vector3, difference_of_products};

/// The README's examples, run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
