//! # nlrt-render
//!
//! Scenes, reports and the `nlrt` command-line tool. So far: the solver report
//! ([`solvers`]); scenes and the renderer follow.

pub mod solvers;
