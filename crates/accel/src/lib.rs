//! nlrt-accel: not yet implemented; see the project's issues.
#![no_std]

#[cfg(not(any(feature = "std", feature = "libm")))]
compile_error!("nlrt-accel needs the `std` or the `libm` feature");
