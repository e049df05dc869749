//! Fuzz target: seam walls and welded directions in f32 on arbitrary inputs (see
//! `nlrt_tests::fuzz_input::fuzz_seam`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_seam::<f32>(data));
