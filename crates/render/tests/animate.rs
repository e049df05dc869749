//! Animated base meshes: every built-in scene moves, and every primary hit of every frame
//! after a pose update equals a fresh build's (f32 and f64); `nlrt animate` writes its frames
//! and report, reads OBJ pose sequences from scene files, and rejects what it cannot animate
//! with exit code 2 and one message.

use nlrt_accel::TlasUpdate;
use nlrt_render::lab::animate::{self, AnimateOptions};
use nlrt_render::scene::scenes::{self, Size, Tag, names};
use nlrt_render::trace::integrator::RenderOptions;
use nlrt_render::trace::method::Method;
use std::path::{Path, PathBuf};
use std::process::Command;

fn nlrt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_nlrt"))
        .args(args)
        .output()
        .expect("nlrt runs")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlrt-animate-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scenes = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
    for f in ["bumps.toml", "quad.obj", "bumps.png"] {
        std::fs::copy(scenes.join(f), dir.join(f)).unwrap();
    }
    dir
}

/// 16 frames of every built-in scene's motion, every pixel's primary hit compared with a
/// fresh build of the same frame, in f32 and f64, by the automatic rule and by refitting
/// only (the rule that keeps the oldest tree).
#[test]
fn every_frame_of_every_builtin_scene_equals_a_fresh_build() {
    for name in names(Tag::Report) {
        let scene = scenes::builtin(name, Size::Small).unwrap();
        for update in [TlasUpdate::DEFAULT, TlasUpdate::Refit] {
            let opts = AnimateOptions {
                frames: 16,
                render: RenderOptions {
                    width: 40,
                    height: 30,
                    spp: 1,
                    bounces: 0,
                },
                methods: vec![Method::NONLINEAR_F32, Method::NONLINEAR_F64],
                update,
                rebuild_frames: 0,
                verify: true,
                out_dir: None,
            };
            let report = animate::run(&scene, &opts).unwrap();
            assert_eq!(report.rows.len(), 32, "{name}");
            for row in &report.rows {
                let fresh = row.fresh.expect("verified");
                assert_eq!(
                    fresh.mismatches, 0,
                    "{name} frame {} {} ({update:?})",
                    row.frame, row.method
                );
                assert!(fresh.sah_ratio.is_finite() && fresh.sah_ratio > 0.0);
                if update == TlasUpdate::Refit {
                    assert_eq!(row.update, "refit");
                }
            }
            let summary = animate::summarise(&report);
            assert_eq!(summary.len(), 2);
            assert_eq!(summary[0].mismatches, Some(0));
        }
    }
}

/// The poses move the surface: frames differ from the rest pose (so the comparison above is
/// not between identical frames).
#[test]
fn frames_show_the_motion() {
    let scene = scenes::builtin("cylinder", Size::Small).unwrap();
    let rest = scene.pose(0, 8).unwrap();
    let bent = scene.pose(2, 8).unwrap();
    let moved = rest
        .positions
        .iter()
        .zip(&bent.positions)
        .map(|(a, b)| (*a - *b).length())
        .fold(0.0, f64::max);
    assert!(moved > 0.1, "{moved}");
    assert!((rest.positions[5] - scene.positions[5]).length() < 1e-12);
}

#[test]
fn the_command_writes_numbered_frames_and_its_report() {
    let dir = scratch("cli");
    let out = dir.join("frames");
    let run = nlrt(&[
        "animate",
        "fur",
        "--frames",
        "3",
        "--size",
        "16x12",
        "--methods",
        "nonlinear-f32,tessellated-f64",
        "--rebuild-frames",
        "1",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    for k in 0..3 {
        let png = out.join(format!("fur-nonlinear-f32-{k:04}.png"));
        assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    }
    assert!(out.join("fur-tessellated-f64-0000.png").exists());
    assert!(!out.join("fur-tessellated-f64-0001.png").exists());
    let md = std::fs::read_to_string(out.join("animate.md")).unwrap();
    assert!(
        md.contains("breathe") && md.contains("| nonlinear f32 | 3 |"),
        "{md}"
    );
    assert!(
        err.contains("frame 3/3 nonlinear f32"),
        "progress per frame: {err}"
    );
}

fn expect_exit_2(args: &[&str], needles: &[&str]) {
    let run = nlrt(args);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(2), "{args:?}: {err}");
    for n in needles {
        assert!(err.contains(n), "{args:?}: message lacks '{n}': {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
}

#[test]
fn what_cannot_be_animated_is_one_message_and_exit_2() {
    let dir = scratch("bad");
    let toml = dir.join("bumps.toml");
    let out = dir.join("out");
    let (t, o) = (toml.to_str().unwrap(), out.to_str().unwrap());
    expect_exit_2(
        &["animate", t, "--size", "8x6", "-o", o],
        &["no motion", "--deformation"],
    );
    expect_exit_2(
        &["animate", t, "--deformation", "wobble", "-o", o],
        &["unknown deformation 'wobble'", "breathe"],
    );
    expect_exit_2(
        &[
            "animate",
            t,
            "--deformation",
            "bend",
            "--amplitude",
            "nan",
            "-o",
            o,
        ],
        &["--amplitude NaN is out of range"],
    );
    expect_exit_2(&["animate", "fur", "--frames", "0", "-o", o], &["frames"]);
    expect_exit_2(
        &["animate", "cornell", "--methods", "projective-f32", "-o", o],
        &["cannot render cornell"],
    );
    expect_exit_2(&["animate", "nosuch", "-o", o], &["unknown scene 'nosuch'"]);
    // A static scene file animates with a deformation from the command line.
    let run = nlrt(&[
        "animate",
        t,
        "--deformation",
        "wave",
        "--amplitude",
        "-2",
        "--frames",
        "2",
        "--size",
        "8x6",
        "--methods",
        "nonlinear-f64",
        "-o",
        o,
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}

/// Writes `quad.obj` moved by `lift` per vertex as `name`.
fn write_pose(dir: &Path, name: &str, lift: f64, drop_face: bool) {
    let text = std::fs::read_to_string(dir.join("quad.obj")).unwrap();
    let mut out = String::new();
    for line in text.lines() {
        if let Some(rest) = line.strip_prefix("v ") {
            let v: Vec<f64> = rest
                .split_whitespace()
                .map(|x| x.parse().unwrap())
                .collect();
            out.push_str(&format!(
                "v {} {} {}\n",
                v[0],
                v[1] + lift * (v[0] + 1.0),
                v[2]
            ));
        } else if drop_face && line.starts_with("f 1/1 4/4") {
            continue;
        } else {
            out.push_str(line);
            out.push('\n');
        }
    }
    std::fs::write(dir.join(name), out).unwrap();
}

#[test]
fn scene_files_animate_a_sequence_of_obj_poses() {
    let dir = scratch("frames");
    for (k, lift) in [0.0, 0.1, 0.2].iter().enumerate() {
        write_pose(&dir, &format!("pose_{k}.obj"), *lift, false);
    }
    let text = std::fs::read_to_string(dir.join("bumps.toml")).unwrap();
    std::fs::write(
        dir.join("bumps.toml"),
        format!("{text}\n[animation]\nframes = [\"pose_0.obj\", \"pose_1.obj\", \"pose_2.obj\"]\n"),
    )
    .unwrap();
    let scene = nlrt_render::scene::scene_file::load(&dir.join("bumps.toml")).unwrap();
    assert_eq!(scene.motion.describe(), "3 poses from OBJ files");
    let pose = scene.pose(2, 3).unwrap();
    assert!((pose.positions.iter().map(|p| p.y).fold(0.0, f64::max) - 0.4).abs() < 1e-6);
    let out = dir.join("out");
    let run = nlrt(&[
        "animate",
        dir.join("bumps.toml").to_str().unwrap(),
        "--frames",
        "3",
        "--size",
        "12x8",
        "--methods",
        "nonlinear-f32",
        "-o",
        out.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    assert!(err.contains("0 pixels differ"), "{err}");
    // A pose with another topology is refused, naming its file.
    write_pose(&dir, "pose_1.obj", 0.1, true);
    let e = nlrt_render::scene::scene_file::load(&dir.join("bumps.toml")).unwrap_err();
    assert!(e.contains("pose_1.obj") && e.contains("triangles"), "{e}");
    // Frames and a deformation together, or an unknown deformation, are refused too.
    std::fs::write(
        dir.join("bumps.toml"),
        format!("{text}\n[animation]\nframes = [\"pose_0.obj\"]\ndeformation = \"bend\"\n"),
    )
    .unwrap();
    let e = nlrt_render::scene::scene_file::load(&dir.join("bumps.toml")).unwrap_err();
    assert!(e.contains("exactly one of frames and deformation"), "{e}");
    std::fs::write(
        dir.join("bumps.toml"),
        format!("{text}\n[animation]\ndeformation = \"bend\"\namplitude = 1e9\n"),
    )
    .unwrap();
    let e = nlrt_render::scene::scene_file::load(&dir.join("bumps.toml")).unwrap_err();
    assert!(e.contains("amplitude = 1000000000 is out of range"), "{e}");
}

/// An exported built-in scene keeps its motion.
#[test]
fn exported_scenes_keep_their_motion() {
    let dir = std::env::temp_dir().join(format!("nlrt-animate-export-{}", std::process::id()));
    let scene = scenes::builtin("cylinder", Size::Small).unwrap();
    let loaded = nlrt_render::scene::scene_file::load(
        &nlrt_render::scene::scene_file::export(&scene, &dir).unwrap(),
    )
    .unwrap();
    assert_eq!(loaded.motion.describe(), scene.motion.describe());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `nlrt watertight` judges a frame of a moving mesh: nonlinear tracing moved there by pose
/// updates, rays decided on the posed mesh, no leak and no ghost hit in either precision.
#[test]
fn watertight_judges_a_frame_of_the_motion() {
    let run = nlrt(&[
        "watertight",
        "torus",
        "--frame",
        "5",
        "--frames",
        "16",
        "--rays",
        "4096",
        "--method",
        "nonlinear",
        "--ghost-samples",
        "64",
    ]);
    let out = String::from_utf8_lossy(&run.stdout);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let rows: Vec<&str> = out
        .lines()
        .filter(|l| l.starts_with("| torus frame 5 of 16 |"))
        .collect();
    assert_eq!(rows.len(), 2, "{out}");
    for row in rows {
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        // | scene | method | rays | decided | leaks | rate | interval | ghosts (of hits) | ...
        assert!(cells[4].parse::<u64>().unwrap() > 1000, "{row}");
        assert_eq!(cells[5], "0", "leaks: {row}");
        assert!(cells[8].starts_with("0 of "), "ghosts: {row}");
    }
    expect_exit_2(
        &["watertight", "torus", "--frame", "16", "--frames", "16"],
        &["--frame 16 is not a frame of --frames 16"],
    );
}
