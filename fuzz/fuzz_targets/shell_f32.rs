//! Fuzz target: the shell traversal in f32 on arbitrary inputs (see
//! `nlrt_tests::fuzz_input::fuzz_shell`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| nlrt_tests::fuzz_input::fuzz_shell::<f32>(data));
