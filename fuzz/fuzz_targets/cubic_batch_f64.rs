//! Fuzz target: the batch cubic solvers in f64 against the scalar ones, bit for bit, on eight
//! arbitrary bit-pattern inputs (see `nlrt_tests::fuzz_input::fuzz_cubic_batch`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_cubic_batch::<f64>(data));
