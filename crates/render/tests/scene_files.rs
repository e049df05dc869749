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
    // An RGB PNG, a map one sample wide; maps of any other size render as they are.
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
    let dir = scratch("thin");
    write(&dir.join("bumps.png"), 1, 8, png::ColorType::Grayscale);
    expect_error(&dir, &["bumps.png", "1 x 8", "from 2"]);
    for (w, h) in [(12, 12), (16, 8), (13, 29)] {
        let dir = scratch(&format!("size-{w}x{h}"));
        write(&dir.join("bumps.png"), w, h, png::ColorType::Grayscale);
        let (code, err) = render_with(&dir, &[]);
        assert_eq!(code, Some(0), "{w} x {h}: {err}");
    }
}

/// Every built-in scene exported as a scene file loads back and renders like the built-in
/// one (the OBJ carries 9 digits and is read as f32: depths agree to f32 rounding of the
/// geometry, a few 1e-7 relative; 1e-4 leaves room for the conditioning of grazing hits).
#[test]
fn exported_builtin_scenes_render_like_the_originals() {
    use nlrt_render::lab::report::compare;
    use nlrt_render::scene::scene_file::{export, load};
    use nlrt_render::scene::scenes::{self, Size};
    use nlrt_render::trace::integrator::{RenderOptions, render};
    use nlrt_render::trace::methods::Nonlinear;
    let dir = std::env::temp_dir().join(format!("nlrt-export-{}", std::process::id()));
    let opts = RenderOptions {
        width: 48,
        height: 36,
        spp: 1,
        bounces: 0,
    };
    let seam_edges =
        |scene: &scenes::Scene| scene.seams().map(|s| (s.uv_seams(), s.normal_seams()));
    for name in [
        "fur",
        "scales",
        "cornell",
        "feathers",
        "highpoly",
        "seam-cube",
        "seam-sphere",
    ] {
        let original = scenes::builtin(name, Size::Small).unwrap();
        let loaded = load(&export(&original, &dir).unwrap()).unwrap();
        // The seams survive the round trip (a clamped map stays clamped: `wrap = "clamp"`).
        assert_eq!(seam_edges(&loaded), seam_edges(&original), "{name}");
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

/// The example's 16-bit PNG heights as a one-channel 32-bit float EXR (channel `name`).
fn write_exr_heights(path: &Path, png_path: &Path, name: &str, edit: impl Fn(&mut Vec<f32>)) {
    let mut decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(png_path).unwrap(),
    ));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let side = info.width as usize;
    let mut heights: Vec<f32> = match info.bit_depth {
        png::BitDepth::Sixteen => buf[..side * side * 2]
            .chunks_exact(2)
            .map(|c| f32::from(u16::from_be_bytes([c[0], c[1]])) / 65535.0)
            .collect(),
        _ => buf[..side * side]
            .iter()
            .map(|&c| f32::from(c) / 255.0)
            .collect(),
    };
    edit(&mut heights);
    use exr::prelude::*;
    let channels = SpecificChannels::build()
        .with_channel(name)
        .with_pixel_fn(|p: Vec2<usize>| (heights[p.y() * side + p.x()],));
    Image::from_channels((side, side), channels)
        .write()
        .to_file(path)
        .unwrap();
}

#[test]
fn exr_height_maps_render_like_the_png_they_were_made_from() {
    let dir = scratch("exr");
    write_exr_heights(&dir.join("bumps.exr"), &dir.join("bumps.png"), "Y", |_| {});
    let render_to = |name: &str| render_bytes(&dir, name);
    let from_png = render_to("png.png");
    edit(&dir, "bumps.toml", "\"bumps.png\"", "\"bumps.exr\"");
    // Heights s / 65535 in f32 round back to s exactly: the same samples, the same image.
    assert_eq!(render_to("exr.png"), from_png);
}

#[test]
fn bad_exr_height_maps_are_rejected() {
    type Case<'a> = (&'a str, &'a str, fn(&mut Vec<f32>), &'a [&'a str]);
    let cases: [Case; 4] = [
        (
            "range",
            "Y",
            |h| h[5] = 1.5,
            &["bumps.exr", "outside [0, 1]"],
        ),
        (
            "nan",
            "Y",
            |h| h[7] = f32::NAN,
            &["bumps.exr", "not a finite number", "(7, 0)"],
        ),
        ("channel", "R", |_| {}, &[]), // R is accepted
        ("broken", "Y", |_| {}, &["bumps.exr", "OpenEXR"]),
    ];
    for (name, channel, change, needles) in cases {
        let dir = scratch(&format!("exr-{name}"));
        write_exr_heights(
            &dir.join("bumps.exr"),
            &dir.join("bumps.png"),
            channel,
            change,
        );
        if name == "broken" {
            std::fs::write(dir.join("bumps.exr"), b"v/1\x01 not an exr").unwrap();
        }
        edit(&dir, "bumps.toml", "\"bumps.png\"", "\"bumps.exr\"");
        if needles.is_empty() {
            let out = nlrt(&[
                "render",
                dir.join("bumps.toml").to_str().unwrap(),
                "--size",
                "8x6",
                "-o",
                dir.join("out.png").to_str().unwrap(),
            ]);
            assert!(
                out.status.success(),
                "{}",
                String::from_utf8_lossy(&out.stderr)
            );
        } else {
            expect_error(&dir, needles);
        }
    }
    // Two channels, neither Y nor R.
    let dir = scratch("exr-two");
    use exr::prelude::*;
    let channels = SpecificChannels::build()
        .with_channel("A")
        .with_channel("B")
        .with_pixel_fn(|_: Vec2<usize>| (0.5f32, 0.5f32));
    Image::from_channels((8, 8), channels)
        .write()
        .to_file(dir.join("bumps.exr"))
        .unwrap();
    edit(&dir, "bumps.toml", "\"bumps.png\"", "\"bumps.exr\"");
    expect_error(&dir, &["bumps.exr", "no height channel", "A, B"]);
}

#[test]
fn aovs_are_written_as_exr() {
    let dir = scratch("aov");
    let aov = dir.join("aov.exr");
    let (w, h) = (40usize, 30usize);
    let out = nlrt(&[
        "render",
        "mountain",
        "--size",
        &format!("{w}x{h}"),
        "-o",
        dir.join("out.png").to_str().unwrap(),
        "--aov",
        aov.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    use exr::prelude::*;
    let image = read_all_flat_layers_from_file(&aov).unwrap();
    let layer = &image.layer_data[0];
    assert_eq!((layer.size.width(), layer.size.height()), (w, h));
    let channel = |n: &str| -> Vec<f32> {
        layer
            .channel_data
            .list
            .iter()
            .find(|c| c.name.eq(n))
            .unwrap_or_else(|| panic!("channel {n}"))
            .sample_data
            .values_as_f32()
            .collect()
    };
    let (z, nx, ny, nz, id) = (
        channel("Z"),
        channel("N.X"),
        channel("N.Y"),
        channel("N.Z"),
        channel("id"),
    );
    let mut hits = 0;
    for i in 0..w * h {
        let length = (nx[i] * nx[i] + ny[i] * ny[i] + nz[i] * nz[i]).sqrt();
        if z[i].is_nan() {
            assert_eq!((length, id[i]), (0.0, u32::MAX as f32));
        } else {
            hits += 1;
            assert!(
                z[i] > 0.0 && (length - 1.0).abs() < 1e-5,
                "{i}: {} {length}",
                z[i]
            );
            assert!(
                id[i] == 0.0 || id[i] == 1.0,
                "the mountain has two base triangles"
            );
        }
    }
    // The mountain fills about a third of this view, the sky the rest.
    assert!(hits > w * h / 5 && hits < w * h, "{hits}");
}

/// Renders the scratch scene with extra arguments; the exit code and stderr.
fn render_with(dir: &Path, extra: &[&str]) -> (Option<i32>, String) {
    let out_png = dir.join("out.png");
    let mut args = vec![
        "render",
        dir.join("bumps.toml").to_str().unwrap(),
        "--size",
        "8x6",
        "-o",
        out_png.to_str().unwrap(),
    ]
    .into_iter()
    .map(str::to_owned)
    .collect::<Vec<_>>();
    args.extend(extra.iter().map(|s| s.to_string()));
    let refs: Vec<&str> = args.iter().map(String::as_str).collect();
    let out = nlrt(&refs);
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Renders the scene file in `dir` at 48 x 36 in f64 to `dir/name`, expecting success; the
/// PNG's bytes.
fn render_bytes(dir: &Path, name: &str) -> Vec<u8> {
    let out = dir.join(name);
    let o = nlrt(&[
        "render",
        dir.join("bumps.toml").to_str().unwrap(),
        "--size",
        "48x36",
        "--precision",
        "f64",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read(out).unwrap()
}

/// Texture coordinates the tracers cannot use (NaN; beyond 2^22 texels once tiled and scaled
/// by the map's side; a base triangle spanning more than 2^16 texels), whether from the OBJ or
/// from the tiling, are one message naming the scene file and the limit, not a panic.
#[test]
fn unusable_texture_coordinates_and_tilings_are_rejected() {
    let dir = scratch("uv-nan");
    edit(&dir, "quad.obj", "vt 1 0\n", "vt nan 0\n");
    expect_error(&dir, &["bumps.toml", "NaN or infinite"]);
    let dir = scratch("uv-huge");
    edit(&dir, "quad.obj", "vt 1 0\n", "vt 3e38 0\n");
    expect_error(&dir, &["bumps.toml", "2^22 texels"]);
    let dir = scratch("tiling-huge");
    edit(&dir, "bumps.toml", "tiling = 2.0", "tiling = 1e6");
    expect_error(&dir, &["bumps.toml", "tiling", "2^22 texels"]);
    // Within 2^22 but wider than MAX_TEXEL_RANGE (2^16) texels per axis: a 64^2 map tiled
    // 2048 times puts 131,072 texels under the quad's triangles.
    let dir = scratch("tiling-wide");
    edit(&dir, "bumps.toml", "tiling = 2.0", "tiling = 2048.0");
    expect_error(&dir, &["bumps.toml", "131072 x 131072 texels", "subdivide"]);
}

/// Face indices beyond the elements an OBJ defines (relative ones counting back past the
/// first, absolute ones past the last, and 0) are one message naming the file, the line and
/// the index: checked before the OBJ reader, whose index arithmetic overflows on them.
#[test]
fn obj_face_indices_out_of_range_are_rejected() {
    for (name, face, needle) in [
        (
            "relative-vt",
            "f 1/1 4/4 3/-9",
            "texture coordinate (vt) index -9",
        ),
        ("relative-v", "f 1/1 4/4 -5/3", "vertex index -5"),
        (
            "absolute-vt",
            "f 1/1 4/4 3/9223372036854775807",
            "index 9223372036854775807",
        ),
        ("zero", "f 1/1 4/4 0/3", "vertex index 0"),
    ] {
        let dir = scratch(&format!("obj-index-{name}"));
        edit(&dir, "quad.obj", "f 1/1 4/4 3/3", face);
        expect_error(&dir, &["quad.obj", "line 11", needle, "out of range"]);
    }
}

/// A height scale finite in f64 but not in f32 is an error naming the value and the
/// precision when f32 is asked for, and renders in f64. One that makes the prisms reach beyond
/// the largest world coordinate a precision traces (`max_world_coordinate`: 2^46 in f32,
/// 2^494 in f64), where the nonlinear rays' coefficients overflow to NaN, is an error in that
/// precision (the loader checks f64 for every method).
#[test]
fn a_height_scale_beyond_a_precision_is_an_error_in_that_precision() {
    // The bumps scene with `height_scale = value`, rendered in `precision`.
    let with_scale = |value: &str| {
        let dir = scratch(&format!("scale-{value}"));
        let scale = format!("height_scale = {value}");
        edit(&dir, "bumps.toml", "height_scale = 0.2", &scale);
        move |precision: &str| render_with(&dir, &["--precision", precision])
    };

    let render = with_scale("1e39");
    let (code, err) = render("f32");
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("height_scale") && err.contains("f32"), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    let (code, err) = render("f64");
    assert_eq!(code, Some(0), "{err}");

    let render = with_scale("1e20");
    let (code, err) = render("f32");
    assert_eq!(code, Some(2), "{err}");
    assert!(
        err.contains("bumps.toml")
            && err.contains("in f32")
            && err.contains("beyond the largest this precision traces")
            && err.contains("--precision f64"),
        "{err}"
    );
    let (code, err) = render("f64");
    assert_eq!(code, Some(0), "{err}");

    let render = with_scale("1e300");
    for precision in ["f32", "f64"] {
        let (code, err) = render(precision);
        assert_eq!(code, Some(2), "{err}");
        assert!(
            err.contains("in f64") && err.contains("beyond the largest this precision traces"),
            "{err}"
        );
    }
}

/// Cameras whose view direction overflows or underflows would make every ray NaN (an
/// all-black image): rejected. A sun direction whose length overflows is still a direction.
#[test]
fn cameras_without_a_usable_view_direction_are_rejected() {
    let dir = scratch("camera-overflow");
    edit(
        &dir,
        "bumps.toml",
        "eye = [0.0, 1.6, 2.2]",
        "eye = [1e308, 1e308, 1e308]",
    );
    edit(
        &dir,
        "bumps.toml",
        "target = [0.0, 0.0, 0.0]",
        "target = [-1e308, -1e308, -1e308]",
    );
    expect_error(&dir, &["bumps.toml", "view direction"]);
    let dir = scratch("camera-underflow");
    edit(
        &dir,
        "bumps.toml",
        "eye = [0.0, 1.6, 2.2]",
        "eye = [0.0, 0.0, 0.0]",
    );
    edit(
        &dir,
        "bumps.toml",
        "target = [0.0, 0.0, 0.0]",
        "target = [5e-324, 0.0, 0.0]",
    );
    expect_error(&dir, &["bumps.toml", "view direction"]);
    let dir = scratch("sun-zero");
    edit(
        &dir,
        "bumps.toml",
        "sun = [0.4, 0.8, 0.3]",
        "sun = [0.0, 0.0, 0.0]",
    );
    expect_error(&dir, &["bumps.toml", "sun direction", "zero"]);
    let dir = scratch("sun-huge");
    edit(
        &dir,
        "bumps.toml",
        "sun = [0.4, 0.8, 0.3]",
        "sun = [1e300, 1e300, 1e300]",
    );
    let (code, err) = render_with(&dir, &[]);
    assert_eq!(code, Some(0), "{err}");
}

/// A NaN vertex normal is rejected, not silently zeroed.
#[test]
fn nan_vertex_normals_are_rejected() {
    let dir = scratch("normal-nan");
    edit(
        &dir,
        "quad.obj",
        "vt 0 0\n",
        "vn nan 1 0\nvn 0 1 0\nvt 0 0\n",
    );
    edit(
        &dir,
        "quad.obj",
        "f 1/1 3/3 2/2\nf 1/1 4/4 3/3",
        "f 1/1/1 3/3/2 2/2/2\nf 1/1/2 4/4/2 3/3/2",
    );
    expect_error(&dir, &["quad.obj", "normal", "not finite"]);
}

/// A tiny EXR whose header claims 100000 x 100000 pixels is refused from its header, before
/// 40 GB are allocated (it used to abort the process).
#[test]
fn an_exr_claiming_a_huge_size_is_refused_before_allocating() {
    let dir = scratch("exr-huge");
    write_exr_heights(&dir.join("bumps.exr"), &dir.join("bumps.png"), "Y", |_| {});
    let mut bytes = std::fs::read(dir.join("bumps.exr")).unwrap();
    // The `dataWindow` attribute: name, type `box2i`, size 16, then xMin, yMin, xMax, yMax.
    let key = b"dataWindow\0box2i\0";
    let at = bytes
        .windows(key.len())
        .position(|w| w == key)
        .expect("an EXR header has a dataWindow")
        + key.len()
        + 4;
    for (k, v) in [(8, 99_999i32), (12, 99_999)] {
        bytes[at + k..at + k + 4].copy_from_slice(&v.to_le_bytes());
    }
    std::fs::write(dir.join("bumps.exr"), &bytes).unwrap();
    edit(&dir, "bumps.toml", "\"bumps.png\"", "\"bumps.exr\"");
    expect_error(&dir, &["bumps.exr", "100000 x 100000", "largest side"]);
}

/// `nlrt watertight` judges a scene file: the example's open quad has decidable rays (those
/// through its top cap) and nonlinear tracing leaks none of them.
#[test]
fn watertight_judges_scene_files() {
    expect_judged_leak_free(&scratch("watertight"));
}

/// `nlrt watertight` on the scene file in `dir`, nonlinear tracing in both precisions: it
/// succeeds, and each precision decides some rays and leaks none.
fn expect_judged_leak_free(dir: &Path) {
    let out = nlrt(&[
        "watertight",
        dir.join("bumps.toml").to_str().unwrap(),
        "--rays",
        "4096",
        "--method",
        "nonlinear",
    ]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: Vec<&str> = text.lines().filter(|l| l.contains("nonlinear")).collect();
    assert_eq!(rows.len(), 2, "{text}");
    for row in rows {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        let (decided, leaks): (u64, u64) = (cells[4].parse().unwrap(), cells[5].parse().unwrap());
        assert!(decided > 0 && leaks == 0, "{row}");
    }
}

/// `midlevel` in `[displacement]`: 0.5 renders and is judged leak-free (the part below the
/// base included); a midlevel outside `[0, 1]` is one message naming the file and the key;
/// the projective method, which offsets its own prisms, refuses a midlevel with its reason.
#[test]
fn a_midlevel_renders_is_judged_and_is_checked() {
    let dir = scratch("midlevel");
    edit(
        &dir,
        "bumps.toml",
        "tiling = 2.0",
        "tiling = 2.0\nmidlevel = 0.5",
    );
    let (code, err) = render_with(&dir, &[]);
    assert_eq!(code, Some(0), "{err}");
    expect_judged_leak_free(&dir);
    let (code, err) = render_with(&dir, &["--method", "projective"]);
    assert_eq!(code, Some(2), "{err}");
    assert!(err.contains("midlevel 0 only"), "{err}");
    for bad in ["1.5", "-0.1", "nan"] {
        let dir = scratch(&format!("midlevel-{bad}"));
        edit(
            &dir,
            "bumps.toml",
            "tiling = 2.0",
            &format!("tiling = 2.0\nmidlevel = {bad}"),
        );
        expect_error(&dir, &["bumps.toml", "midlevel", "out of range"]);
    }
}

/// The example's 16-bit PNG samples and size.
fn png_samples(png_path: &Path) -> (Vec<u16>, u32, u32) {
    let mut decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(png_path).unwrap(),
    ));
    decoder.set_transformations(png::Transformations::IDENTITY);
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let n = (info.width * info.height) as usize;
    let samples = match info.bit_depth {
        png::BitDepth::Sixteen => buf[..2 * n]
            .chunks_exact(2)
            .map(|c| u16::from_be_bytes([c[0], c[1]]))
            .collect(),
        _ => buf[..n].iter().map(|&c| u16::from(c) * 257).collect(),
    };
    (samples, info.width, info.height)
}

/// Writes a TIFF of colour type `C` (`tiff`'s encoder).
fn write_tiff<C: tiff::encoder::colortype::ColorType>(
    path: &Path,
    w: u32,
    h: u32,
    data: &[C::Inner],
) where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let file = std::fs::File::create(path).unwrap();
    let mut encoder = tiff::encoder::TiffEncoder::new(file).unwrap();
    encoder.write_image::<C>(w, h, data).unwrap();
}

/// A 16-bit grayscale TIFF of the example's samples renders exactly like the PNG; a DEM in
/// metres (32-bit floats, 800 to 2000 m) renders with `normalize = true`, which maps its range
/// onto [0, 1], and is one message naming that range without it.
#[test]
fn tiff_height_maps_render_like_the_png_and_dems_normalise() {
    use tiff::encoder::colortype::{Gray16, Gray32Float};
    let dir = scratch("tiff");
    let (samples, w, h) = png_samples(&dir.join("bumps.png"));
    write_tiff::<Gray16>(&dir.join("bumps.tif"), w, h, &samples);
    let render_to = |name: &str| render_bytes(&dir, name);
    let from_png = render_to("png.png");
    edit(&dir, "bumps.toml", "\"bumps.png\"", "\"bumps.tif\"");
    assert_eq!(render_to("tif.png"), from_png);
    // A DEM: heights in metres, the sample range stretched to [800, 2000] exactly, so that
    // normalising gives the PNG's heights back (to f32 rounding of the metres).
    let (lo, hi) = (
        f32::from(*samples.iter().min().unwrap()),
        f32::from(*samples.iter().max().unwrap()),
    );
    let metres: Vec<f32> = samples
        .iter()
        .map(|&s| 800.0 + 1200.0 * (f32::from(s) - lo) / (hi - lo))
        .collect();
    write_tiff::<Gray32Float>(&dir.join("bumps.tif"), w, h, &metres);
    expect_error(
        &dir,
        &[
            "bumps.tif",
            "outside [0, 1]",
            "[800, 2000]",
            "normalize = true",
        ],
    );
    edit(
        &dir,
        "bumps.toml",
        "tiling = 2.0",
        "tiling = 2.0\nnormalize = true",
    );
    let _ = render_to("dem.png");
    // No-data pixels, colour, signed integers and an absurd size are one message each.
    let mut holes = metres.clone();
    holes[3] = f32::NAN;
    write_tiff::<Gray32Float>(&dir.join("bumps.tif"), w, h, &holes);
    expect_error(
        &dir,
        &["bumps.tif", "not a finite number", "(3, 0)", "no-data"],
    );
    write_tiff::<tiff::encoder::colortype::RGB8>(&dir.join("bumps.tif"), 2, 2, &[0; 12]);
    expect_error(&dir, &["bumps.tif", "grayscale"]);
    write_tiff::<tiff::encoder::colortype::GrayI16>(&dir.join("bumps.tif"), 2, 2, &[0; 4]);
    expect_error(&dir, &["bumps.tif", "signed"]);
    write_tiff::<Gray32Float>(&dir.join("bumps.tif"), 20_000, 1, &vec![0.5; 20_000]);
    expect_error(&dir, &["bumps.tif", "20000 x 1", "largest side"]);
    std::fs::write(dir.join("bumps.tif"), b"II*\0 not a tiff").unwrap();
    expect_error(&dir, &["bumps.tif", "TIFF"]);
}
