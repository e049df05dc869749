//! What is measured: reports, benchmarks' JSON, watertightness against the oracle, the solver
//! table, edits, animation runs, the seam view and plots. Built on [`crate::scene`] and
//! [`crate::trace`].

pub mod animate;
pub mod bench_json;
pub mod edit;
mod median;
pub mod plot;
pub mod report;
pub mod seam_view;
pub mod solvers;
pub mod watertight;

pub use median::median;
