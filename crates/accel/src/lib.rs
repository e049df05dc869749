//! # nlrt-accel
//!
//! The acceleration structures of nonlinear ray tracing (Ogaki 2023, sec. 4.4, 5.1, 5.2,
//! 5.4), generic over `f32`/`f64`, `no_std` + `alloc`:
//!
//! - [`Bvh4`]: a 4-ary binned-SAH BVH with a conservative slab test, used as the TLAS over
//!   prisms (built on the fly from the [`BaseMesh`], never stored).
//! - [`HeightField`]: 16-bit heights with an implicit min-max pyramid (levels 0 and 1 read
//!   from the samples, the rest stored), partial updates after edits.
//! - [`DisplacedSurface`]: TLAS + the pyramid traversed by nonlinear rays (root selection,
//!   texel discard, nearest-first order, range reduction, flat-texel shortcut); where a
//!   patch of base triangles has equal displacement directions (a terrain), the ray is a
//!   straight line in texel space and the pyramid is walked along it, texels by a watertight
//!   ray-triangle test ([`DisplacedSurface::set_straight_walk`]).
//! - [`ShellSurface`]: an object in texture space ([`ShellObject`], with its own BVH)
//!   tiled over the base mesh: TLAS + implicit quadtree over tiles + the object's BVH.
//! - Crack-free uv and normal seams: [`Seams`] finds them, [`SeamRule::Closed`] (the
//!   default) welds displacement directions there and joins the two sides by a seam wall.
//! - Animated base meshes: `set_pose` on either surface moves the mesh and refits or
//!   rebuilds only the TLAS ([`TlasUpdate`]); the texture-space data stays untouched.
//!
//! ```
//! use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
//! use nlrt_poly::glam::{DVec2, DVec3};
//! use nlrt_shellmap::Ray;
//! // A unit square of two triangles, displaced along +z by up to 0.5 by a 4 x 4 map whose
//! // heights are all 1 (a flat plane at z = 0.5).
//! let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
//! let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
//! let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
//! let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Repeat).unwrap();
//! let surface = DisplacedSurface::new(mesh, field, 0.5, 1.0).unwrap();
//! let ray = Ray::new(DVec3::new(0.3, 0.6, 2.0), -DVec3::Z).unwrap();
//! let hit = surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default()).unwrap();
//! assert!((hit.hit.t - 1.5).abs() < 1e-12);
//! // A shadow ray asks only whether something is in the way (the first hit found ends it).
//! let up = Ray::new(DVec3::new(0.3, 0.6, 0.2), DVec3::Z).unwrap();
//! assert!(surface.occluded(&up, 0.0, f64::INFINITY, &mut TraversalStats::default()));
//! assert!(!surface.occluded(&up, 0.0, 0.2, &mut TraversalStats::default()));
//! ```
#![no_std]
#![warn(missing_docs)]
// `!(a <= b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("nlrt-accel needs the `std` or the `libm` feature");

extern crate alloc;

mod affine;
mod bvh;
mod cells;
mod displacement;
mod displacement_params;
mod heightfield;
mod leaving;
mod leaving_queries;
mod mesh;
mod object_edges;
mod object_hull;
mod plain_queries;
mod pose;
mod precision;
mod seam;
mod seam_walls;
mod shell;
mod stack;
mod stats;
mod surface_hit;
#[cfg(test)]
mod test_util;
mod texel_hit;
mod tlas;

/// glam 0.34 (with its `f64` types), the vector types of every query. Use this one rather
/// than a `glam` of your own: one of another version has other `Vec3` types ("expected
/// `DVec3`, found `DVec3`").
///
/// ```
/// use nlrt_accel::glam::DVec3;
/// use nlrt_accel::{Hit, Ray, Real};
/// let ray = Ray::<f64>::new(DVec3::ZERO, DVec3::new(0.0, 0.0, 2.0)).unwrap();
/// assert_eq!(ray.dir, DVec3::Z); // directions are normalised
/// fn distance<T: Real>(hit: &Hit<T>) -> f64 {
///     hit.t.to_f64()
/// }
/// # let _ = distance::<f32>;
/// ```
pub use nlrt_poly::glam;
// What a query needs from the lower crates, so that a program depending on this crate alone
// can build rays and read hits.
pub use nlrt_poly::Real;
pub use nlrt_shellmap::{Hit, Ray};

pub use bvh::{ARITY, Aabb, Bvh4, Node4, SlabRay, ray_triangle, sah_lower_bound};
pub use cells::{CellTriangle, traverse_cells, uv_in_cells};
pub use displacement::{DisplacedSurface, DisplacementError, shell_floor};
pub use displacement_params::Displacement;
pub use heightfield::{HEIGHT_ONE, HeightField, HeightMapError, MAX_SAMPLES_PER_SIDE, Wrap};
pub use mesh::{BaseMesh, MeshError, prism_bounds};
pub use pose::{PoseUpdate, TlasUpdate};
pub use seam::{EDGE_VERTICES, NO_SEAM, SeamEdge, SeamRule, SeamSide, Seams, edge_parameter};
pub use shell::{ShellError, ShellHit, ShellObject, ShellSurface};
pub use stats::TraversalStats;
pub use surface_hit::{SurfaceHit, TexelPart};
pub use tlas::{MAX_TEXEL_COORDINATE, MAX_TEXEL_RANGE, RootNodes};

/// The README's examples, run by `cargo test --doc`.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
