//! # nlrt-render
//!
//! Scenes, the renderer, reports and the `nlrt` command-line tool: the built-in scenes
//! ([`scenes`]), the pre-tessellated reference ([`tessellate`]), the methods and the path
//! tracer ([`trace`]), the speed-against-error report ([`report`]) and the solver report
//! ([`solvers`]).

// `!(a > b)` is deliberate: it is true when either side is NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod edit;
#[cfg(feature = "embree")]
pub mod embree_reference;
pub mod plot;
pub mod report;
pub mod resample;
pub mod scene_file;
pub mod scenes;
pub mod solvers;
pub mod tessellate;
pub mod trace;
pub mod watertight;
