//! The `nlrt` command line: its arguments ([`args`]) and one module per group of commands,
//! each turning its arguments into a call of the library and an exit code.

pub mod animate;
pub mod args;
pub mod common;
pub mod render;
pub mod report;
pub mod watertight;
