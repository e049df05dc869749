//! Replays every file of the fuzz corpora (`fuzz/corpus/<target>/`) and of the saved crash
//! regressions (`fuzz/regressions/<target>/`) through the same checks the fuzz targets run,
//! so CI exercises what the fuzzer found without a nightly toolchain.

use nlrt_tests::fuzz_input::{fuzz_cubic, fuzz_cubic_batch, fuzz_microtriangle, fuzz_quadratic};
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
fn replay_cubic_batch_f32() {
    replay("cubic_batch_f32", fuzz_cubic_batch::<f32>);
}

#[test]
fn replay_cubic_batch_f64() {
    replay("cubic_batch_f64", fuzz_cubic_batch::<f64>);
}

/// Packs the cubic corpora eight inputs to a file for the batch targets (run once by hand:
/// `cargo test -p nlrt-tests --test fuzz_replay -- --ignored write_batch_seed_corpus`). The
/// files are taken in name order; each input is zero-padded or cut to its full length, so a
/// short scalar input (solved on the whole line) becomes one on `[0, 0]` or on its bytes'
/// interval.
#[test]
#[ignore]
fn write_batch_seed_corpus() {
    use nlrt_poly::{CUBIC_BATCH, Real};
    use nlrt_tests::fuzz_input::cubic_input_bytes;
    fn write<T: Real>() {
        let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus");
        let mut files: Vec<PathBuf> = std::fs::read_dir(root.join(format!("cubic_{}", T::NAME)))
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect();
        files.sort();
        let dir = root.join(format!("cubic_batch_{}", T::NAME));
        std::fs::create_dir_all(&dir).unwrap();
        let width = cubic_input_bytes::<T>();
        for (k, group) in files.chunks(CUBIC_BATCH).enumerate() {
            let mut bytes = Vec::new();
            for path in group {
                let mut one = std::fs::read(path).unwrap();
                one.resize(width, 0);
                bytes.extend_from_slice(&one);
            }
            std::fs::write(dir.join(format!("packed-{k:03}")), bytes).unwrap();
        }
    }
    write::<f32>();
    write::<f64>();
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

#[test]
fn replay_scene_file() {
    replay("scene_file", |data| {
        nlrt_tests::fuzz_input::fuzz_scene_file(data);
    });
}

/// The seeds are valid scenes (so the fuzzer starts from inputs that reach the renderer).
#[test]
fn scene_file_seeds_load() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/scene_file");
    for name in [
        "seed-png16",
        "seed-exr",
        "seed-png8",
        "seed-shell",
        "seed-object-displacement",
        "seed-object-shell",
    ] {
        let data = std::fs::read(dir.join(name)).expect("committed seed");
        assert!(nlrt_tests::fuzz_input::fuzz_scene_file(&data), "{name}");
    }
}

/// Writes the scene-file target's seeds (run once by hand:
/// `cargo test -p nlrt-tests --test fuzz_replay -- --ignored write_scene_file_seeds`): the
/// example scene with its PNG map, with the map as an 8 x 8 EXR, with an 8-bit 4 x 4 PNG,
/// a shell-mapped quad, and each of the two as an `[[object]]` table (placed; the shell with a
/// deformation); each as TOML, 0, base OBJ, 0, third file.
#[test]
#[ignore]
fn write_scene_file_seeds() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..");
    let dir = root.join("fuzz/corpus/scene_file");
    std::fs::create_dir_all(&dir).unwrap();
    let toml = std::fs::read_to_string(root.join("scenes/bumps.toml")).unwrap();
    let obj = std::fs::read(root.join("scenes/quad.obj")).unwrap();
    let seed = |name: &str, toml: &str, third: &[u8]| {
        let mut bytes = toml.as_bytes().to_vec();
        bytes.push(0);
        bytes.extend_from_slice(&obj);
        bytes.push(0);
        bytes.extend_from_slice(third);
        std::fs::write(dir.join(name), bytes).unwrap();
    };
    seed(
        "seed-png16",
        &toml,
        &std::fs::read(root.join("scenes/bumps.png")).unwrap(),
    );
    // An 8 x 8 EXR of heights, channel Y.
    let exr_path = std::env::temp_dir().join("nlrt-seed.exr");
    {
        use exr::prelude::*;
        let channels = SpecificChannels::build()
            .with_channel("Y")
            .with_pixel_fn(|p: Vec2<usize>| (((p.x() * 7 + p.y() * 3) % 8) as f32 / 8.0,));
        Image::from_channels((8, 8), channels)
            .write()
            .to_file(&exr_path)
            .unwrap();
    }
    seed(
        "seed-exr",
        &toml.replace("\"bumps.png\"", "\"bumps.exr\""),
        &std::fs::read(&exr_path).unwrap(),
    );
    // A 4 x 4 8-bit grayscale PNG.
    let mut png_bytes = Vec::new();
    {
        let mut encoder = png::Encoder::new(&mut png_bytes, 4, 4);
        encoder.set_color(png::ColorType::Grayscale);
        encoder.set_depth(png::BitDepth::Eight);
        let mut writer = encoder.write_header().unwrap();
        let data: Vec<u8> = (0..16).map(|i| (i * 16) as u8).collect();
        writer.write_image_data(&data).unwrap();
    }
    seed("seed-png8", &toml, &png_bytes);
    let shell = "[mesh]\nobj = \"quad.obj\"\n[shell]\nobject = \"tile.obj\"\nheight_scale = 0.3\ntiling = 2.0\n[camera]\neye = [0.0, 1.6, 2.2]\ntarget = [0.0, 0.0, 0.0]\n";
    seed(
        "seed-shell",
        shell,
        b"v 0.1 0.1 0.2\nv 0.9 0.1 0.5\nv 0.5 0.9 0.9\nf 1 2 3\n",
    );
    let camera = "[camera]\neye = [0.0, 1.4, 2.4]\ntarget = [0.0, 0.3, -0.5]\n";
    seed(
        "seed-object-displacement",
        &format!(
            "[[object]]\nobj = \"quad.obj\"\ntranslate = [0.5, 0.0, -1.0]\nscale = 2.0\n[object.displacement]\nheight_map = \"bumps.png\"\nheight_scale = 0.2\nmidlevel = 0.5\n{camera}"
        ),
        &std::fs::read(root.join("scenes/bumps.png")).unwrap(),
    );
    seed(
        "seed-object-shell",
        &format!(
            "[[object]]\nobj = \"quad.obj\"\nmaterial = \"glossy\"\n[object.shell]\nobject = \"brick.obj\"\nheight_scale = 0.08\ntiling = 3.0\n[animation]\ndeformation = \"wave\"\n{camera}"
        ),
        &std::fs::read(root.join("scenes/brick.obj")).unwrap(),
    );
}

#[test]
fn replay_seam_f32() {
    replay("seam_f32", nlrt_tests::fuzz_input::fuzz_seam::<f32>);
}

#[test]
fn replay_seam_f64() {
    replay("seam_f64", nlrt_tests::fuzz_input::fuzz_seam::<f64>);
}

/// The seam target's checks on 2,000 structured inputs per precision (uv seams, normal seams,
/// both and neither, rays from steep to grazing): more than the committed seeds, still quick;
/// 1,000,000 with `NLRT_EXTENSIVE=1`.
#[test]
fn seam_target_holds_on_structured_inputs() {
    use nlrt_tests::fuzz_input::{fuzz_seam, seam_case, seam_seed};
    let cases = if std::env::var_os("NLRT_EXTENSIVE").is_some() {
        1_000_000
    } else {
        2000
    };
    let mut with_seam = 0;
    for k in 0..cases {
        fuzz_seam::<f32>(&seam_seed::<f32>(k));
        let bytes = seam_seed::<f64>(k);
        fuzz_seam::<f64>(&bytes);
        if let Some((closed, _, _)) = seam_case::<f64>(&bytes) {
            with_seam += usize::from(!closed.seams().edges().is_empty());
        }
    }
    assert!(
        with_seam as u64 > cases / 2,
        "{with_seam} of {cases} inputs have a seam"
    );
}

/// Writes the seam targets' seed corpus (run once by hand:
/// `cargo test -p nlrt-tests --test fuzz_replay -- --ignored write_seam_seed_corpus`).
#[test]
#[ignore]
fn write_seam_seed_corpus() {
    use nlrt_poly::Real;
    fn write<T: Real>() {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join(format!("../fuzz/corpus/seam_{}", T::NAME));
        std::fs::create_dir_all(&dir).unwrap();
        for k in 0..32 {
            let bytes = nlrt_tests::fuzz_input::seam_seed::<T>(10_000 + k);
            std::fs::write(dir.join(format!("seed-{k:02}")), bytes).unwrap();
        }
    }
    write::<f32>();
    write::<f64>();
}
