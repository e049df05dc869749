//! # nlrt-oracle
//!
//! Arbitrary-precision reference computations (GMP rationals and MPFR floats through `rug`)
//! that tell a true answer from a rounding artefact. Unpublished: used by the tests and the
//! reports, never by the renderer.
//!
//! - [`ExactPoly::real_roots`]: every real root of a polynomial of degree <= 3 with f32/f64
//!   coefficients (taken as exact rationals), with multiplicity, to at least
//!   [`ROOT_BITS`] bits.
//! - [`Truth::judge`]: a solver's answer measured against them: error in ulps of the target
//!   type, missed roots, spurious roots, with tolerances scaled by each root's conditioning.
//! - [`families`]: the hard cubic families and random generators shared by tests and reports.
//! - [`crossing`]: exact ray-triangle crossings (rationals), for watertightness.
//! - [`shell`]: the true hit of a world ray on a microtriangle of a prism (Ogaki 2023, Eq. 1-11).
//!
//! Building it needs GMP's build tools (`m4`); the project's test script installs them.

pub mod crossing;
pub mod exact;
pub mod families;
pub mod measure;
pub mod peers;
pub mod shell;

pub use exact::{ExactPoly, ROOT_BITS, RealRoot};
pub use measure::{Tolerance, Truth, Verdict, judge, ulp};
