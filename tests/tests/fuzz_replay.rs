//! Replays every file of the fuzz corpora (`fuzz/corpus/<target>/`) and of the saved crash
//! regressions (`fuzz/regressions/<target>/`) through the same checks the fuzz targets run,
//! so CI exercises what the fuzzer found without a nightly toolchain.

use nlrt_tests::fuzz_input::{fuzz_cubic, fuzz_microtriangle, fuzz_quadratic};
use std::path::PathBuf;

fn replay(target: &str, run: fn(&[u8])) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz");
    let mut count = 0;
    for dir in ["corpus", "regressions"] {
        let Ok(entries) = std::fs::read_dir(root.join(dir).join(target)) else {
            continue;
        };
        for entry in entries {
            let path = entry.expect("readable corpus directory").path();
            let data = std::fs::read(&path).expect("readable corpus file");
            let result = std::panic::catch_unwind(|| run(&data));
            assert!(result.is_ok(), "corpus file {} fails", path.display());
            count += 1;
        }
    }
    assert!(
        count > 0,
        "no corpus files for {target}: the seed corpus must be committed"
    );
    println!("{target}: replayed {count} inputs");
}

#[test]
fn replay_cubic_f32() {
    replay("cubic_f32", fuzz_cubic::<f32>);
}

#[test]
fn replay_cubic_f64() {
    replay("cubic_f64", fuzz_cubic::<f64>);
}

#[test]
fn replay_quadratic_f32() {
    replay("quadratic_f32", fuzz_quadratic::<f32>);
}

#[test]
fn replay_quadratic_f64() {
    replay("quadratic_f64", fuzz_quadratic::<f64>);
}

#[test]
fn replay_microtriangle_f32() {
    replay("microtriangle_f32", fuzz_microtriangle::<f32>);
}

#[test]
fn replay_microtriangle_f64() {
    replay("microtriangle_f64", fuzz_microtriangle::<f64>);
}

/// Writes the seed corpus from the hard families (run once by hand:
/// `cargo test -p nlrt-tests --test fuzz_replay -- --ignored write_seed_corpus`).
#[test]
#[ignore]
fn write_seed_corpus() {
    use nlrt_oracle::families::hard_cubics;
    use nlrt_poly::Real;
    use nlrt_tests::fuzz_input::{Input, encode};
    fn write<T: Real>(kind: &str) {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../fuzz/corpus/{kind}_{}", T::NAME));
        std::fs::create_dir_all(&dir).unwrap();
        for (i, case) in hard_cubics::<T>().into_iter().enumerate() {
            let bytes = if kind == "cubic" {
                encode(&Input {
                    coeffs: case.coeffs,
                    lo: case.lo,
                    hi: case.hi,
                })
            } else {
                let c = case.coeffs;
                encode(&Input {
                    coeffs: [c[1], c[2] * T::TWO, c[3] * T::THREE],
                    lo: case.lo,
                    hi: case.hi,
                })
            };
            std::fs::write(
                dir.join(format!(
                    "seed-{i:02}-{}",
                    case.name.replace(['/', ',', '^', '(', ')', '+'], "_")
                )),
                bytes,
            )
            .unwrap();
        }
        // Bad input: NaN, infinity and an empty interval.
        let bad = [T::NAN, T::INFINITY, T::ONE, T::ONE];
        let n = if kind == "cubic" { 4 } else { 3 };
        let mut bytes = Vec::new();
        for v in bad.iter().take(n).chain([&T::ONE, &T::ZERO]) {
            bytes.extend_from_slice(&v.to_bits_u64().to_le_bytes()[..(T::BITS / 8) as usize]);
        }
        std::fs::write(dir.join("seed-bad-input"), bytes).unwrap();
    }
    write::<f32>("cubic");
    write::<f64>("cubic");
    write::<f32>("quadratic");
    write::<f64>("quadratic");
}

#[test]
fn replay_displacement_f32() {
    replay(
        "displacement_f32",
        nlrt_tests::fuzz_input::fuzz_displacement::<f32>,
    );
}

#[test]
fn replay_displacement_f64() {
    replay(
        "displacement_f64",
        nlrt_tests::fuzz_input::fuzz_displacement::<f64>,
    );
}

#[test]
fn replay_shell_f32() {
    replay("shell_f32", nlrt_tests::fuzz_input::fuzz_shell::<f32>);
}

#[test]
fn replay_shell_f64() {
    replay("shell_f64", nlrt_tests::fuzz_input::fuzz_shell::<f64>);
}
