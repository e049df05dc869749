//! # nlrt-shellmap
//!
//! Shell space, canonical space and texture space of a prism, nonlinear rays, and the
//! primitive intersection tests of nonlinear ray tracing (Ogaki 2023, sec. 3 and 4.1-4.3),
//! generic over `f32`/`f64`, `no_std`, no heap allocation.
//!
//! ```
//! use nlrt_poly::glam::{DVec2, DVec3};
//! use nlrt_shellmap::{NonlinearRay, Prism, Ray, intersect_microtriangle};
//! // A unit right prism over the triangle (0,0,0), (1,0,0), (0,1,0), heights along +z.
//! let z = DVec3::Z;
//! let prism = Prism::<f64>::new([DVec3::ZERO, DVec3::X, DVec3::Y], [z, z, z], [DVec2::ZERO, DVec2::X, DVec2::Y]);
//! // A ray straight down onto the microtriangle at height 0.5.
//! let ray = Ray::new(DVec3::new(0.2, 0.2, 3.0), -z).unwrap();
//! let nl = NonlinearRay::new(&prism, &ray);
//! let tri = [DVec3::new(0.0, 0.0, 0.5), DVec3::new(1.0, 0.0, 0.5), DVec3::new(0.0, 1.0, 0.5)];
//! let hit = intersect_microtriangle(&prism, &nl, &tri, 0.0, 1.0, 0.0, f64::INFINITY).unwrap();
//! assert!((hit.t - 2.5).abs() < 1e-12 && (hit.h - 0.5).abs() < 1e-12);
//! ```
//!
//! The MPFR oracle (`nlrt-oracle`, unpublished) holds high-precision versions of the
//! microtriangle hit, the inverse map and nonlinear-ray evaluation; the integration tests
//! check these functions against it.
#![no_std]
#![warn(missing_docs)]
// `!(a <= b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("nlrt-shellmap needs the `std` or the `libm` feature");

mod curve_box;
mod curved;
mod microtriangle;
mod prism;
mod prism_hit;
mod ray;

pub use curve_box::{BoxSpan, TextureCurve, intersect_box};
pub use curved::coons_displacement;
pub use microtriangle::{
    Hit, TexturePlane, alpha_beta_eq11, facing_unit, inside_triangle, intersect_flat_microtriangle,
    intersect_flat_texel, intersect_microtriangle, world_normal,
};
pub use prism::{Canonical, Prism, onto_base_triangle};
pub use prism_hit::{PrismSpan, intersect_prism};
pub use ray::{
    BaseEdges, NonlinearRay, Ray, WideRay, decidedly_outside_in_f64, in_f64, max_world_coordinate,
    piece_clear_in_f64, planes_agree_in_f64, root_decidedly_outside_in_f64,
};

/// The README's examples, run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
