//! # nlrt-baselines
//!
//! The methods that nonlinear ray tracing (`nlrt-accel`) is measured against, on the same
//! base meshes, height fields and instanced objects, generic over `f32`/`f64`, `no_std` +
//! `alloc`. Each exists to be compared: the report and `nlrt bench` trace them beside the
//! paper's method and the pre-tessellated reference.
//!
//! | method | paper | entry point |
//! |---|---|---|
//! | smooth shell marching | Jeschke et al. 2007, sec. 4.1-4.3 | [`Marching::intersect_marching`] |
//! | curved shell marching (Coons patches) | Jeschke et al. 2007, sec. 3.2, 4.5 | [`Marching::intersect_curved_marching`] |
//! | marching with a 3D distance map | Jeschke et al. 2007, sec. 4.4 | [`Marching::intersect_sphere_traced`], [`DistanceMap`] |
//! | marching a voxelised object | Jeschke et al. 2007, sec. 4.4 | [`VoxelMarching`], [`VoxelObject`] |
//! | tetrahedral shells | Porumbescu et al. 2005 | [`TetrahedralShells::intersect_tetrahedra`] |
//! | tessellation-free displacement | Thonat et al. 2021 | [`AffineTracing::intersect_affine`] |
//! | projective displacement | parallel offset prisms | [`ProjectiveSurface`] |
//! | cone tracing with silhouettes | Ouazzani Chahdi et al. 2021 | [`ConeTraced::intersect_cone_traced`], [`ConeTracing`] |
//! | geometry images | Carr et al. 2006 | [`GeometryImage`] |
//!
//! The methods on the paper's surfaces are extension traits of
//! [`nlrt_accel::DisplacedSurface`] and [`nlrt_accel::ShellSurface`]: bring them into scope
//! (`use nlrt_baselines::Marching;`) and call them like the surface's own `intersect`.
//!
//! ```
//! use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
//! use nlrt_baselines::{MarchOptions, Marching};
//! use nlrt_poly::glam::{DVec2, DVec3};
//! use nlrt_shellmap::Ray;
//! // A unit square lifted by a constant height of 0.5 (scale 1), marched from above.
//! let mesh = BaseMesh::<f64>::new(
//!     vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
//!     vec![DVec3::Z; 4],
//!     vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
//!     vec![[0, 1, 2], [0, 2, 3]],
//! ).unwrap();
//! let field = HeightField::from_unit_heights(8, 8, &[0.5f32; 64], Wrap::Clamp).unwrap();
//! let surface = DisplacedSurface::new(mesh, field, 1.0, 1.0).unwrap();
//! let ray = Ray::new(DVec3::new(0.3, 0.6, 2.0), -DVec3::Z).unwrap();
//! let mut stats = TraversalStats::default();
//! let opts = MarchOptions::default();
//! let hit = surface.intersect_marching(&ray, 0.0, f64::INFINITY, &opts, &mut stats).unwrap();
//! assert!((hit.hit.t - 1.5).abs() < 1e-3);
//! ```
#![no_std]
#![warn(missing_docs)]
// `!(a <= b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("nlrt-baselines needs the `std` or the `libm` feature");

extern crate alloc;

mod affine;
mod cone;
mod distance_map;
mod geometry_image;
mod march;
mod projective;
#[cfg(test)]
mod test_util;
mod tetra;
mod volume;

pub use affine::{AffineHit, AffineTracing};
pub use cone::{
    ConeMap, ConeMapBuilder, ConeOptions, ConeTraced, ConeTracing, Rectification, VertexQuadrics,
};
pub use distance_map::DistanceMap;
pub use geometry_image::{GeometryImage, GeometryImageError, GeometryImageHit};
pub use march::{MarchOptions, Marching};
pub use projective::ProjectiveSurface;
pub use tetra::TetrahedralShells;
pub use volume::{VoxelMarching, VoxelObject};

/// The README's examples, run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
