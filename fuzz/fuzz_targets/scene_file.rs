//! Fuzz target: the scene-file loader on arbitrary TOML, OBJ and PNG/EXR bytes, then a tiny
//! render of what loads (see `nlrt_tests::fuzz_input::fuzz_scene_file`).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    nlrt_tests::fuzz_input::fuzz_scene_file(data);
});
