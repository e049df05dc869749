//! Scene files of several `[[object]]` tables: the example (a displaced terrain beside a
//! shell-mapped brick wall) renders, is judged object by object and animates; the objects
//! traced as one answer as each object alone; placement and every kind of bad table is one
//! clear message.

use nlrt_render::scene::scene_file::{self, MAX_OBJECTS, Source};
use nlrt_render::scene::scenes::{Content, Scene};
use nlrt_render::trace::method::Method;
use nlrt_render::trace::tracer::Tracer;
use std::path::{Path, PathBuf};
use std::process::Command;

const EXAMPLE: &str = "terrain-and-wall.toml";
const FILES: [&str; 5] = [EXAMPLE, "quad.obj", "bumps.png", "wall.obj", "brick.obj"];

fn nlrt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_nlrt"))
        .args(args)
        .output()
        .expect("nlrt runs")
}

fn scenes_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// A scratch directory holding a copy of the example, unique per test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("nlrt-objects-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for f in FILES {
        std::fs::copy(scenes_dir().join(f), dir.join(f)).unwrap();
    }
    dir
}

fn edit(dir: &Path, from: &str, to: &str) {
    let path = dir.join(EXAMPLE);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from}");
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
}

/// Loads the example in `dir`, or its message.
fn load(dir: &Path) -> Result<Scene, String> {
    scene_file::load(&dir.join(EXAMPLE))
}

fn stdout_of(out: &std::process::Output) -> String {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The example loads as two objects with their own content and material; `translate` and
/// `scale` place the whole object, its height scale included.
#[test]
fn the_example_loads_as_two_placed_objects() {
    let dir = scratch("load");
    let scene = load(&dir).unwrap();
    assert_eq!(scene.object_count(), 2);
    assert!(matches!(scene.content, Content::Displacement(_)));
    assert!(matches!(scene.others[0].content, Content::Shell(_)));
    let wall = &scene.others[0];
    assert!(wall.positions.iter().all(|p| p.z == -1.0), "translated");
    assert_eq!(scene.triangle_count(), 4);
    edit(
        &dir,
        "translate = [0.0, 0.0, -1.0]",
        "translate = [0.5, 0.0, -1.0]\nscale = 2.0",
    );
    let scaled = load(&dir).unwrap();
    let moved = &scaled.others[0];
    for (p, q) in moved.positions.iter().zip(&wall.positions) {
        let expected = (*q - nlrt_poly::glam::DVec3::new(0.0, 0.0, -1.0)) * 2.0
            + nlrt_poly::glam::DVec3::new(0.5, 0.0, -1.0);
        assert_eq!(*p, expected);
    }
    assert_eq!(moved.height_scale, 2.0 * wall.height_scale);
    assert_eq!(scaled.height_scale, scene.height_scale, "the terrain stays");
}

/// The objects traced as one: every camera ray's hit is the nearer of the objects' own hits
/// (each object built alone), with the object's ids shifted past the first one's
/// triangles, and shading takes the hit object's material.
#[test]
fn the_objects_traced_as_one_answer_as_each_alone() {
    let scene = scene_file::load(&scenes_dir().join(EXAMPLE)).unwrap();
    let first_alone = Scene {
        others: Vec::new(),
        ..scene.clone()
    };
    let second_alone = scene.others[0].clone();
    let first_triangles = scene.triangles.len() as u32;
    for method in [
        Method::NONLINEAR_F32,
        Method::NONLINEAR_F64,
        Method::TESSELLATED_F64,
    ] {
        let union = method.build(&scene).unwrap();
        let (a, b) = (
            method.build(&first_alone).unwrap(),
            method.build(&second_alone).unwrap(),
        );
        assert_eq!(
            union.memory_bytes(),
            a.memory_bytes() + b.memory_bytes(),
            "{method}"
        );
        let n = 64;
        let mut hits = [0usize; 2];
        for k in 0..n * n {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let dir = scene
                .camera
                .direction(x / n as f64, y / n as f64, 4.0 / 3.0);
            let eye = scene.camera.eye;
            let hit = union.intersect(eye, dir, 0.0, f64::INFINITY);
            let on_a = a.intersect(eye, dir, 0.0, f64::INFINITY);
            let on_b = b.intersect(eye, dir, 0.0, f64::INFINITY).map(|h| {
                nlrt_render::trace::tracer::TraceHit {
                    id: h.id + first_triangles,
                    ..h
                }
            });
            let expected = match (on_a, on_b) {
                (Some(p), Some(q)) => Some(if q.t < p.t { q } else { p }),
                (p, q) => p.or(q),
            };
            assert_eq!(hit, expected, "{method}, ray {k}");
            if let Some(h) = hit {
                let (object, id) = scene.object_of(h.id).unwrap();
                let second = h.id >= first_triangles;
                hits[usize::from(second)] += 1;
                assert_eq!(id, h.id - if second { first_triangles } else { 0 });
                assert!(std::ptr::eq(
                    object,
                    if second { &scene.others[0] } else { &scene }
                ));
            }
        }
        assert!(hits[0] > 100 && hits[1] > 100, "{method}: {hits:?}");
    }
}

/// `render` (f32, f64 and the reference), `bench` and `watertight` take the file; the
/// watertightness table judges each object, and nonlinear tracing leaks none of either.
#[test]
fn the_example_renders_benches_and_is_judged_object_by_object() {
    let dir = scratch("cli");
    let file = dir.join(EXAMPLE);
    let file = file.to_str().unwrap();
    for (precision, method) in [
        ("f32", "nonlinear"),
        ("f64", "nonlinear"),
        ("f64", "tessellated"),
    ] {
        let png = dir.join(format!("{precision}-{method}.png"));
        stdout_of(&nlrt(&[
            "render",
            file,
            "--precision",
            precision,
            "--method",
            method,
            "--size",
            "32x24",
            "-o",
            png.to_str().unwrap(),
        ]));
        assert_eq!(&std::fs::read(&png).unwrap()[1..4], b"PNG");
    }
    let bench = stdout_of(&nlrt(&[
        "bench",
        file,
        "--methods",
        "nonlinear-f32,nonlinear-f64",
        "--no-reference",
        "--size",
        "32x24",
    ]));
    assert!(bench.contains("nonlinear f32"), "{bench}");
    let text = stdout_of(&nlrt(&[
        "watertight",
        file,
        "--rays",
        "16384",
        "--method",
        "nonlinear",
        "--ghost-samples",
        "500",
    ]));
    for object in ["object 1", "object 2"] {
        let rows: Vec<&str> = text
            .lines()
            .filter(|l| l.contains(object) && l.contains("nonlinear"))
            .collect();
        assert_eq!(rows.len(), 2, "{object}: {text}");
        for row in rows {
            let cells: Vec<&str> = row.split('|').map(str::trim).collect();
            let (decided, leaks): (u64, u64) =
                (cells[4].parse().unwrap(), cells[5].parse().unwrap());
            assert!(decided > 0 && leaks == 0, "{row}");
            assert!(cells[8].starts_with("0 of "), "ghosts: {row}");
        }
    }
}

/// `animate` moves every object by the file's deformation; each frame's pose updates give
/// the hits of a fresh build.
#[test]
fn a_deformation_moves_every_object() {
    let dir = scratch("animate");
    edit(
        &dir,
        "[camera]",
        "[animation]\ndeformation = \"wave\"\namplitude = 0.5\n\n[camera]",
    );
    let scene = load(&dir).unwrap();
    let rest = scene.posed_at(0, 4).unwrap();
    let moved = scene.posed_at(1, 4).unwrap();
    for (r, m) in rest.objects().zip(moved.objects()) {
        assert_ne!(r.positions, m.positions, "every object moves");
    }
    let out_dir = dir.join("frames");
    let text = stdout_of(&nlrt(&[
        "animate",
        dir.join(EXAMPLE).to_str().unwrap(),
        "--frames",
        "3",
        "--methods",
        "nonlinear-f32",
        "--size",
        "32x24",
        "-o",
        out_dir.to_str().unwrap(),
    ]));
    let report = nlrt_render::lab::animate::run(
        &scene,
        &nlrt_render::lab::animate::AnimateOptions {
            frames: 3,
            methods: vec![Method::NONLINEAR_F32, Method::NONLINEAR_F64],
            render: nlrt_render::trace::integrator::RenderOptions {
                width: 32,
                height: 24,
                ..Default::default()
            },
            out_dir: None,
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(report.rows.len(), 6, "{text}");
    for row in &report.rows {
        let fresh = row.fresh.expect("verified");
        assert_eq!(fresh.mismatches, 0, "frame {} {}", row.frame, row.method);
    }
}

/// Each malformed layout or value is one message naming the file (and the object).
#[test]
fn bad_object_tables_are_one_message() {
    let cases: [(&str, &str, &[&str]); 8] = [
        (
            "# A scene file of two objects",
            "[mesh]\nobj = \"quad.obj\"\n# A scene file of two objects",
            &["either one [mesh] or [[object]]"],
        ),
        (
            "[camera]",
            "[displacement]\nheight_map = \"bumps.png\"\nheight_scale = 0.1\n[camera]",
            &["[object.displacement]"],
        ),
        (
            "translate = [0.0, 0.0, -1.0]",
            "translate = [0.0, 0.0, -1.0]\nscale = 0.0",
            &["object 2", "scale = 0"],
        ),
        (
            "translate = [0.0, 0.0, -1.0]",
            "translate = [0.0, 0.0, -1.0]\nscale = -2.0",
            &["object 2", "scale = -2"],
        ),
        (
            "translate = [0.0, 0.0, -1.0]",
            "translate = [0.0, nan, -1.0]",
            &["object 2", "translate"],
        ),
        (
            "translate = [0.0, 0.0, -1.0]",
            "translate = [0.0, 0.0, -1.0]\nscale = 1e308",
            &["object 2"],
        ),
        (
            "[object.shell]\nobject",
            "[object.displacement]\nheight_map = \"bumps.png\"\nheight_scale = 0.1\n[object.shell]\nobject",
            &["object 2", "exactly one of [displacement] and [shell]"],
        ),
        (
            "[camera]",
            "[animation]\nframes = [\"quad.obj\"]\n[camera]",
            &["several objects", "deformation"],
        ),
    ];
    for (k, (from, to, needles)) in cases.into_iter().enumerate() {
        let dir = scratch(&format!("bad-{k}"));
        edit(&dir, from, to);
        let e = load(&dir).expect_err(to);
        for n in needles {
            assert!(e.contains(n), "case {k}: message lacks '{n}': {e}");
        }
        assert!(e.contains(EXAMPLE), "case {k}: {e}");
        // The CLI: the same message, exit code 2, no image.
        let png = dir.join("out.png");
        let out = nlrt(&[
            "render",
            dir.join(EXAMPLE).to_str().unwrap(),
            "--size",
            "8x6",
            "-o",
            png.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {k}: {err}");
        assert!(
            !err.contains("panicked") && !png.exists(),
            "case {k}: {err}"
        );
    }
}

/// Too few or too many objects, and maps that together exceed one largest map's samples.
#[test]
fn object_counts_and_total_map_samples_are_bounded() {
    let dir = scratch("counts");
    let text = std::fs::read_to_string(dir.join(EXAMPLE)).unwrap();
    let camera = &text[text.find("[camera]").unwrap()..];
    let write = |body: String| {
        let path = dir.join("count.toml");
        std::fs::write(&path, body).unwrap();
        path
    };
    let e = scene_file::load(&write(format!("object = []\n{camera}"))).unwrap_err();
    assert!(e.contains("0 [[object]] tables"), "{e}");
    let table = "[[object]]\nobj = \"quad.obj\"\n[object.shell]\nobject = \"brick.obj\"\nheight_scale = 0.1\n";
    let many = table.repeat(MAX_OBJECTS + 1);
    let e = scene_file::load(&write(format!("{many}{camera}"))).unwrap_err();
    assert!(
        e.contains(&format!("{} [[object]] tables", MAX_OBJECTS + 1)),
        "{e}"
    );
    let most = table.repeat(MAX_OBJECTS);
    let scene = scene_file::load(&write(format!("{most}{camera}"))).unwrap();
    assert_eq!(scene.object_count(), MAX_OBJECTS);
    // Two 64 x 64 maps where the largest side is 64: the second exceeds the file's samples.
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    let source = |side| Source {
        read: &read,
        max_map_side: side,
    };
    let two_maps = write(format!(
        "[[object]]\nobj = \"quad.obj\"\n[object.displacement]\nheight_map = \"bumps.png\"\nheight_scale = 0.1\n{}{camera}",
        "[[object]]\nobj = \"wall.obj\"\n[object.displacement]\nheight_map = \"bumps.png\"\nheight_scale = 0.1\n"
    ));
    let e = scene_file::load_from(&two_maps, &source(64)).unwrap_err();
    assert!(
        e.contains("object 2") && e.contains("together") && e.contains("4096 samples"),
        "{e}"
    );
    assert!(scene_file::load_from(&two_maps, &source(128)).is_ok());
}

/// `export` rewrites the file with its objects placed, as `[[object]]` tables, and the copy
/// renders the same image; the report's table takes the file, its images named after the
/// file's stem.
#[test]
fn the_example_exports_and_reports() {
    let dir = scratch("export");
    let file = dir.join(EXAMPLE);
    let out_dir = dir.join("exported");
    let text = stdout_of(&nlrt(&[
        "export",
        file.to_str().unwrap(),
        "-o",
        out_dir.to_str().unwrap(),
    ]));
    let copy = out_dir.join(EXAMPLE);
    assert!(text.contains(copy.to_str().unwrap()), "{text}");
    let toml = std::fs::read_to_string(&copy).unwrap();
    assert_eq!(toml.matches("[[object]]").count(), 2, "{toml}");
    assert!(!toml.contains("translate"), "placement applied: {toml}");
    let render = |path: &Path, png: &str| {
        let png = dir.join(png);
        stdout_of(&nlrt(&[
            "render",
            path.to_str().unwrap(),
            "--size",
            "48x36",
            "-o",
            png.to_str().unwrap(),
        ]));
        std::fs::read(png).unwrap()
    };
    assert_eq!(render(&file, "original.png"), render(&copy, "copy.png"));

    let report_dir = dir.join("report");
    std::fs::create_dir_all(&report_dir).unwrap();
    let opts = nlrt_render::lab::report::ReportOptions {
        scenes: vec![file.to_str().unwrap().to_string()],
        size: nlrt_render::scene::scenes::Size::Small,
        render: nlrt_render::trace::integrator::RenderOptions {
            width: 32,
            height: 24,
            ..Default::default()
        },
        methods: vec![Method::NONLINEAR_F32, Method::TESSELLATED_F64],
        out_dir: Some(report_dir.clone()),
        scaling: false,
        ray_stream: false,
        seam_rule: nlrt_accel::SeamRule::Closed,
        rounds: 1,
    };
    let md = nlrt_render::lab::report::run(&opts).unwrap();
    assert!(md.contains("terrain-and-wall-nonlinear-f32.png"), "{md}");
    assert!(
        report_dir
            .join("terrain-and-wall-nonlinear-f32.png")
            .exists()
    );
}
