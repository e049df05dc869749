//! # nlrt-render
//!
//! Scenes, the renderer, reports and the `nlrt` command-line tool, in three groups with one
//! direction between them (`scene <- trace <- lab`):
//!
//! - [`scene`]: what is traced: the built-in scenes and the [`scene::scenes::Scene`] type
//!   ([`scene::scenes`]), scene files ([`scene::scene_file`]), base-mesh motion
//!   ([`scene::motion`]) and materials ([`scene::material`]);
//! - [`trace`]: how rays meet it: the one interface every method is traced through
//!   ([`trace::tracer::Tracer`]), the methods by name ([`trace::method::Method`]) and their
//!   tracers ([`trace::methods`], [`trace::tessellate`], [`trace::geometry_image`], Embree
//!   behind the `embree` feature), several objects as one ([`trace::objects`]), the path
//!   tracer ([`trace::integrator`]), recorded ray streams and image files;
//! - [`lab`]: what is measured: the speed-against-error report and `nlrt bench`'s JSON,
//!   watertightness against the MPFR oracle, the solver table, height-map edits, animation
//!   runs, the seam view and the plots.
//!
//! Where a ray goes, in reading order:
//!
//! 1. [`trace::integrator::render`] shoots camera, shadow and bounce rays (f64) through a
//!    [`trace::tracer::Tracer`];
//! 2. [`trace::method::Method`] builds the tracer of a method: [`trace::methods`] for
//!    nonlinear ray tracing and the compared methods of `nlrt-baselines`,
//!    [`trace::tessellate`] for the pre-tessellated reference, [`trace::geometry_image`] for
//!    geometry images;
//! 3. nonlinear ray tracing ([`trace::methods::Nonlinear`]) hands the ray to `nlrt-accel`:
//!    the TLAS over the base mesh's prisms, then per prism the nonlinear ray of
//!    `nlrt-shellmap`;
//! 4. the BLAS walk of `nlrt-accel` (the implicit min-max mipmap, or the quadtree over an
//!    instanced object's tiles) follows the ray's texture-space curve;
//! 5. the texel (or object triangle) test of `nlrt-shellmap` solves the cubic of `nlrt-poly`
//!    and returns the hit, which [`scene::material::Material`] shades.
//!
//! `docs/architecture.md` draws the same with the crates below.

// `!(a > b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod lab;
pub mod scene;
pub mod trace;
