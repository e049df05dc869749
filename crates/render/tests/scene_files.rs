//! Scene files: the example in `scenes/` renders; every kind of bad input is one clear message
//! naming the file (and line), exit code 2, and no output written.

use std::path::{Path, PathBuf};
use std::process::Command;

fn nlrt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_nlrt"))
        .args(args)
        .output()
        .expect("nlrt runs")
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// A scratch directory holding a copy of the example scene, unique per test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlrt-scene-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for f in ["bumps.toml", "quad.obj", "bumps.png"] {
        std::fs::copy(repo().join("scenes").join(f), dir.join(f)).unwrap();
    }
    dir
}

/// Renders `toml` (in `dir`) and expects failure with exit code 2, a message containing all of
/// `needles`, and no output image.
fn expect_error(dir: &Path, needles: &[&str]) {
    let out_png = dir.join("out.png");
    let out = nlrt(&[
        "render",
        dir.join("bumps.toml").to_str().unwrap(),
        "--size",
        "8x6",
        "-o",
        out_png.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    for n in needles {
        assert!(err.contains(n), "message lacks '{n}': {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    assert!(!out_png.exists(), "no output on error");
}

fn edit(dir: &Path, file: &str, from: &str, to: &str) {
    let path = dir.join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from}");
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
}

#[test]
fn the_example_scene_renders() {
    let dir = scratch("ok");
    let out_png = dir.join("out.png");
    let out = nlrt(&[
        "render",
        dir.join("bumps.toml").to_str().unwrap(),
        "--size",
        "16x12",
        "-o",
        out_png.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(&std::fs::read(&out_png).unwrap()[1..4], b"PNG");
}

#[test]
fn missing_files_are_named() {
    let dir = scratch("missing");
    std::fs::remove_file(dir.join("quad.obj")).unwrap();
    expect_error(&dir, &["quad.obj"]);
    let out = nlrt(&["render", "/nonexistent/scene.toml"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("/nonexistent/scene.toml"));
}

#[test]
fn bad_toml_keys_and_values_name_the_line() {
    let dir = scratch("key");
    edit(&dir, "bumps.toml", "tiling = 2.0", "tilling = 2.0");
    expect_error(&dir, &["bumps.toml line 10", "tilling"]);
    let dir = scratch("value");
    edit(
        &dir,
        "bumps.toml",
        "height_scale = 0.2",
        "height_scale = \"high\"",
    );
    expect_error(&dir, &["bumps.toml line 9"]);
    let dir = scratch("range");
    edit(
        &dir,
        "bumps.toml",
        "height_scale = 0.2",
        "height_scale = -1.0",
    );
    expect_error(&dir, &["bumps.toml", "height_scale"]);
    let dir = scratch("syntax");
    edit(&dir, "bumps.toml", "[camera]", "[camera");
    expect_error(&dir, &["bumps.toml line"]);
}

#[test]
fn broken_meshes_are_rejected() {
    let dir = scratch("nouv");
    edit(
        &dir,
        "quad.obj",
        "f 1/1 3/3 2/2\nf 1/1 4/4 3/3",
        "f 1 3 2\nf 1 4 3",
    );
    expect_error(&dir, &["quad.obj", "texture coordinates"]);
    let dir = scratch("nan");
    edit(&dir, "quad.obj", "v 1 0 -1", "v nan 0 -1");
    expect_error(&dir, &["quad.obj", "NaN"]);
    let dir = scratch("degenerate");
    edit(&dir, "quad.obj", "f 1/1 3/3 2/2", "f 1/1 1/1 2/2");
    expect_error(&dir, &["quad.obj", "zero area"]);
    let dir = scratch("garbage");
    edit(&dir, "quad.obj", "f 1/1 3/3 2/2", "f 1/1 9/9 2/2");
    expect_error(&dir, &["quad.obj"]);
}

#[test]
fn unsupported_height_maps_are_rejected() {
    let dir = scratch("notpng");
    std::fs::write(dir.join("bumps.png"), b"this is not a png").unwrap();
    expect_error(&dir, &["bumps.png", "PNG"]);
    // An RGB PNG and a non-power-of-two side.
    let write = |path: &Path, w: u32, h: u32, color: png::ColorType| {
        let file = std::fs::File::create(path).unwrap();
        let mut e = png::Encoder::new(file, w, h);
        e.set_color(color);
        e.set_depth(png::BitDepth::Eight);
        let channels = if color == png::ColorType::Rgb { 3 } else { 1 };
        e.write_header()
            .unwrap()
            .write_image_data(&vec![128; (w * h) as usize * channels])
            .unwrap();
    };
    let dir = scratch("rgb");
    write(&dir.join("bumps.png"), 8, 8, png::ColorType::Rgb);
    expect_error(&dir, &["bumps.png", "grayscale"]);
    let dir = scratch("side");
    write(&dir.join("bumps.png"), 12, 12, png::ColorType::Grayscale);
    expect_error(&dir, &["bumps.png", "power of two"]);
    let dir = scratch("square");
    write(&dir.join("bumps.png"), 16, 8, png::ColorType::Grayscale);
    expect_error(&dir, &["bumps.png", "square"]);
}

/// Every built-in scene exported as a scene file loads back and renders like the built-in
/// one (the OBJ carries 9 digits and is read as f32: depths agree to f32 rounding of the
/// geometry, a few 1e-7 relative; 1e-4 leaves room for the conditioning of grazing hits).
#[test]
fn exported_builtin_scenes_render_like_the_originals() {
    use nlrt_render::report::compare;
    use nlrt_render::scene_file::{export, load};
    use nlrt_render::scenes::{self, Size};
    use nlrt_render::trace::{Nonlinear, RenderOptions, render};
    let dir = std::env::temp_dir().join(format!("nlrt-export-{}", std::process::id()));
    let opts = RenderOptions {
        width: 48,
        height: 36,
        spp: 1,
        bounces: 0,
    };
    for name in ["fur", "scales", "cornell"] {
        let original = scenes::builtin(name, Size::Small).unwrap();
        let loaded = load(&export(&original, &dir).unwrap()).unwrap();
        let a = render(&original, &Nonlinear::<f64>::new(&original), &opts, &|_| {});
        let b = render(&loaded, &Nonlinear::<f64>::new(&loaded), &opts, &|_| {});
        let e = compare(&b, &a);
        assert!(
            a.depth.iter().filter(|d| !d.is_nan()).count() > 100,
            "{name}"
        );
        assert!(
            e.mismatch_rate() < 0.01 && e.depth_p99 < 1e-4,
            "{name}: {e:?}"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
