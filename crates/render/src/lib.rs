//! # nlrt-render
//!
//! Scenes, the renderer, reports and the `nlrt` command-line tool.
//!
//! Where a ray goes, in reading order:
//!
//! 1. [`integrator::render`] shoots camera, shadow and bounce rays (f64) through a
//!    [`tracer::Tracer`], the one interface every method is traced through;
//! 2. [`method::Method`] names the methods and builds their tracers: [`tracers`] for
//!    nonlinear ray tracing and the compared methods of `nlrt-baselines`, [`tessellate`] for
//!    the pre-tessellated reference, [`resample`] for geometry images;
//! 3. nonlinear ray tracing ([`tracers::Nonlinear`]) hands the ray to `nlrt-accel`: the TLAS
//!    over the base mesh's prisms, then per prism the nonlinear ray of `nlrt-shellmap`;
//! 4. the BLAS walk of `nlrt-accel` (the implicit min-max mipmap, or the quadtree over an
//!    instanced object's tiles) follows the ray's texture-space curve;
//! 5. the texel (or object triangle) test of `nlrt-shellmap` solves the cubic of `nlrt-poly`
//!    and returns the hit, which [`material::Material`] shades.
//!
//! Around them: the built-in scenes ([`scenes`]) and scene files ([`scene_file`]), the
//! speed-against-error report ([`report`], plots in [`plot`]), watertightness against the
//! MPFR oracle ([`watertight`]), what the seam rule closes ([`seam_view`]), height-map edits ([`edit`]), animated base meshes
//! ([`animation`], [`animate`]), the solver report
//! ([`solvers`]) and image output ([`image`]).

// `!(a > b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod animate;
pub mod animation;
pub mod bench_json;
pub mod edit;
#[cfg(feature = "embree")]
pub mod embree_reference;
#[cfg(feature = "embree")]
pub mod embree_user;
pub mod image;
pub mod integrator;
pub mod material;
pub mod method;
pub mod objects;
pub mod plot;
pub mod ray_stream;
pub mod report;
pub mod resample;
pub mod scene_file;
pub mod scenes;
pub mod seam_view;
pub mod solvers;
pub mod tessellate;
pub mod tracer;
pub mod tracers;
pub mod watertight;
