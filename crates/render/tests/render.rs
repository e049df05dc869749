//! The renderer and the report on reduced scenes: methods agree where they must, and the
//! CLI fails cleanly.

use nlrt_render::lab::report::compare;
use nlrt_render::scene::scenes;
use nlrt_render::trace::integrator::{RenderOptions, render};
use nlrt_render::trace::method::Method;
use nlrt_render::trace::methods::Nonlinear;
use nlrt_render::trace::tessellate::Tessellated;
use std::process::Command;

fn small() -> RenderOptions {
    RenderOptions {
        width: 48,
        height: 36,
        spp: 1,
        bounces: 1,
    }
}

/// The mountain's base is flat with one normal, so every prism is an affine map and the
/// nonlinear surface is exactly the pre-tessellated one: f64 depths agree to rounding
/// (distances ~3, relative error of a few ulps amplified by the conditioning of a grazing
/// hit; 1e-9 leaves room for that and would catch any real difference, which is >= 1e-4).
#[test]
fn nonlinear_equals_tessellation_where_the_map_is_affine() {
    let scene = scenes::mountain(64);
    let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
    let nl64 = render(&scene, &Nonlinear::<f64>::new(&scene), &small(), &|_| {});
    let e = compare(&nl64, &reference);
    assert!(e.pixels == 48 * 36 && reference.depth.iter().filter(|d| !d.is_nan()).count() > 200);
    assert_eq!(e.mismatches, 0, "{e:?}");
    assert!(e.depth_max < 1e-9, "{e:?}");
    // f32 on the same scene: the same pixels hit; depths within f32 rounding amplified as
    // above (2^-24 ~ 6e-8, times conditioning; 1e-4 is the finest detail's relative size).
    let nl32 = render(&scene, &Nonlinear::<f32>::new(&scene), &small(), &|_| {});
    let e32 = compare(&nl32, &nl64);
    assert!(
        e32.mismatch_rate() < 0.01 && e32.depth_p99 < 1e-4,
        "{e32:?}"
    );
}

/// The cornell scene's base is a sphere with radial normals: every prism is a cone from the
/// centre, so a texture-space plane maps to a world-space plane and the shell-mapped object
/// equals its tessellation (same bound as the affine case).
#[test]
fn shell_mapping_equals_tessellation_where_planes_map_to_planes() {
    let scene = scenes::cornell(4);
    let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
    let nl64 = render(&scene, &Nonlinear::<f64>::new(&scene), &small(), &|_| {});
    let e = compare(&nl64, &reference);
    assert!(reference.depth.iter().filter(|d| !d.is_nan()).count() > 200);
    assert_eq!(e.mismatches, 0, "{e:?}");
    assert!(e.depth_max < 1e-9, "{e:?}");
}

/// On curved bases (cylinder, fur torus) the two surfaces differ by design; they still agree
/// on nearly every pixel.
#[test]
fn curved_scenes_agree_with_the_reference_on_most_pixels() {
    for scene in [
        scenes::cylinder(64),
        scenes::fur(32),
        scenes::fur_cones(32),
        scenes::scales(),
        scenes::feathers(),
        scenes::highpoly(16),
    ] {
        let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
        let nl = render(&scene, &Nonlinear::<f64>::new(&scene), &small(), &|_| {});
        let e = compare(&nl, &reference);
        assert!(e.mismatch_rate() < 0.02, "{}: {e:?}", scene.name);
        assert!(e.depth_median < 1e-2, "{}: {e:?}", scene.name);
        assert!(
            nl.all_rays > nl.primary_rays,
            "secondary rays are cast and counted"
        );
    }
}

/// Runs `nlrt` with `args`, requires success (printing its stderr otherwise) and returns its
/// standard output.
fn nlrt_stdout(args: &[&str]) -> String {
    let out = nlrt(args);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn nlrt(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_nlrt"))
        .args(args)
        .output()
        .expect("nlrt runs")
}

/// The help of every command that takes a scene lists exactly the built-in scenes and
/// variants the code knows (the list is built from them, so a new scene cannot be missed).
#[test]
fn help_lists_every_built_in_scene() {
    use nlrt_render::scene::scenes::{Tag, names};
    for command in ["render", "bench", "export"] {
        let out = nlrt(&[command, "--help"]);
        assert!(out.status.success(), "{command} --help");
        let help = String::from_utf8_lossy(&out.stdout);
        for name in names(Tag::Report).iter().chain(names(Tag::Variant).iter()) {
            assert!(
                help.contains(name),
                "{command} --help lacks {name}:\n{help}"
            );
        }
    }
}

#[test]
fn unknown_scene_is_a_clear_error_with_exit_code_2() {
    let out = nlrt(&["render", "teapot", "-o", "/dev/null"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("unknown scene 'teapot'") && err.contains("mountain"),
        "{err}"
    );
    let out = nlrt(&["bench", "mountain", "teapot"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn absurd_parameters_are_rejected_with_exit_code_2() {
    for args in [
        &["render", "fur", "--size", "0x10"][..],
        &["render", "fur", "--size", "64"][..],
        &["render", "fur", "--spp", "0"][..],
        &["render", "fur", "--bounces", "1000"][..],
        &["solvers", "--samples", "0"][..],
    ] {
        let out = nlrt(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!out.stderr.is_empty(), "{args:?}");
    }
}

#[test]
fn unwritable_output_is_an_error_not_a_panic() {
    let out = nlrt(&[
        "render",
        "fur",
        "--size",
        "8x6",
        "-o",
        "/nonexistent-dir/x.png",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot write"));
}

#[test]
fn render_writes_a_png() {
    let dir = std::env::temp_dir().join(format!("nlrt-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("fur.png");
    let out = nlrt(&[
        "render",
        "fur",
        "--size",
        "16x12",
        "-o",
        path.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let bytes = std::fs::read(&path).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Watertightness on Fig. 8's torus at reduced map size, 65,536 camera rays: zero leaks in
/// f64 and in f32, decided by exact arithmetic (the rays are fixed, so this is repeatable).
#[test]
fn torus_is_watertight() {
    use nlrt_render::lab::watertight::measure;
    let scene = scenes::torus_scene(64);
    for report in [
        measure(&scene, 256, Method::NONLINEAR_F64).unwrap(),
        measure(&scene, 256, Method::NONLINEAR_F32).unwrap(),
    ] {
        assert!(
            report.decided > 20_000,
            "most rays should be decided: {}",
            report.decided
        );
        assert_eq!(report.leaks, 0, "{} leaks on the torus", report.method);
        // Hit distances against the oracle: the tracer solves each plane's cubic to a few
        // ulps of its root, times the conditioning of the hit (Eq. 4-11), which is below 100
        // at these viewing angles: 2^-24 * 100 ~ 6e-6 for f32, 2^-53 * 100 ~ 1e-14 for f64;
        // the 99th percentile must be within that. The largest may be more: a hit in the
        // window by which a prism's search reaches past its base edge (a rounding bound, so
        // that neighbours overlap and no ray slips between) lies on this prism's surface
        // continued past the edge, not on the neighbour's (measured: 3.9e-5 in f32); it must
        // stay within the leak tolerance, which is what a hit "at the surface" means here.
        let d = report.distance_error.expect("nonlinear reports distances");
        let bound = if report.method == Method::NONLINEAR_F32 {
            6e-6
        } else {
            1e-14
        };
        assert!(d.samples > 500 && d.unverified == 0, "{d:?}");
        assert!(d.p99 < bound, "{}: {d:?}", report.method);
        assert!(
            d.max < nlrt_render::lab::watertight::LEAK_TOLERANCE,
            "{}: {d:?}",
            report.method
        );
    }
}

/// The mountain at grazing angles: the camera just above the shell's top, over the map's
/// edge, looking across it about 4 degrees down, 65,536 rays: zero leaks in both precisions.
#[test]
fn mountain_at_grazing_angles_is_watertight() {
    use nlrt_poly::glam::DVec3;
    use nlrt_render::lab::watertight::measure;
    let mut scene = scenes::mountain(128);
    scene.camera.eye = DVec3::new(0.0, 0.4, 0.95);
    scene.camera.target = DVec3::new(0.0, 0.25, -1.0);
    for report in [
        measure(&scene, 256, Method::NONLINEAR_F64).unwrap(),
        measure(&scene, 256, Method::NONLINEAR_F32).unwrap(),
    ] {
        assert!(
            report.decided > 5_000,
            "rays should reach the base: {}",
            report.decided
        );
        assert_eq!(report.leaks, 0, "{} leaks on the mountain", report.method);
    }
}

/// Shell scenes are judged by aimed rays, for nonlinear tracing only: another method is
/// refused with the reason.
#[test]
fn watertight_judges_shell_scenes_by_nonlinear_tracing() {
    let out = nlrt(&["watertight", "scales", "--rays", "64"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let table = String::from_utf8_lossy(&out.stdout);
    assert!(table.contains("| scales | nonlinear f32 | 64 |"), "{table}");
    assert!(table.contains("| scales | nonlinear f64 | 64 |"), "{table}");
    assert!(!table.contains("tessellation-free"), "{table}");
    let out = nlrt(&[
        "watertight",
        "scales",
        "--rays",
        "16",
        "--method",
        "tessellation-free",
    ]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("shell-mapped"));
}

/// Fig. 9's degenerate configurations (uv-degenerate to a line and a point, prisms pinching
/// to a line and a point, a triangle degenerate in world and uv, one in world only): no
/// panic, no NaN, and single and double precision agree on hit/miss for all but a handful of
/// pixels (the paper: "rendered without artifacts with both single and double precision").
/// The columns' uv-degenerate prisms decide some of their shell-mapped object's hits within
/// rounding of their degenerate edges, so a few pixels may still differ between precisions.
#[test]
fn fig9_degenerate_columns_render_alike_in_both_precisions() {
    let scene = scenes::fig9();
    let opts = RenderOptions {
        width: 140,
        height: 50,
        spp: 1,
        bounces: 0,
    };
    let f32_frame = render(&scene, &Nonlinear::<f32>::new(&scene), &opts, &|_| {});
    let f64_frame = render(&scene, &Nonlinear::<f64>::new(&scene), &opts, &|_| {});
    let hits = f64_frame.depth.iter().filter(|d| !d.is_nan()).count();
    assert!(hits > 500, "the columns should be visible: {hits}");
    assert!(f32_frame.color.iter().flatten().all(|c| c.is_finite()));
    let e = compare(&f32_frame, &f64_frame);
    eprintln!("fig9 f32 vs f64: {e:?}");
    assert!(e.mismatches <= 3, "{e:?}");
}

#[test]
fn partial_pyramid_updates_after_brush_strokes_trace_like_a_fresh_build() {
    use nlrt_render::lab::edit::{EditOptions, run};
    let report = run(&EditOptions {
        strokes: 60,
        brush: 96,
        reference: false,
        ..EditOptions::default()
    })
    .unwrap();
    assert_eq!(report.verified_rays, 128 * 128);
    assert_eq!(report.verify_mismatches, 0);
    assert!(
        run(&EditOptions {
            strokes: 0,
            ..EditOptions::default()
        })
        .is_err()
    );
}

/// The seam scenes (every edge of the cube a uv and a normal seam; the sphere's meridian and
/// poles uv seams), 16,384 rays: with the seam rule, zero leaks and every hit confirmed by the
/// oracle (f32: under 0.1% ghosts, the base-edge window class of the ghost tori); without it,
/// the cracks leak, and the leaks lie at seam edges. The pre-tessellated reference closes
/// seams by the same rule: it agrees with nonlinear tracing on nearly every pixel, and far
/// less when only one of them has the rule.
#[test]
fn seams_are_closed_by_the_rule_and_leak_without_it() {
    use nlrt_accel::SeamRule;
    use nlrt_render::lab::watertight::measure;
    for name in scenes::names(scenes::Tag::Seam) {
        let mut scene = scenes::builtin(name, scenes::Size::Small).unwrap();
        for method in [Method::NONLINEAR_F32, Method::NONLINEAR_F64] {
            let report = measure(&scene, 128, method).unwrap();
            assert!(report.decided > 5000, "{name} {method}: {}", report.decided);
            assert_eq!(report.leaks, 0, "{name} {method}: {:?}", report.leak_edges);
            let g = report.ghosts.expect("nonlinear hits are judged");
            let allowed = if method == Method::NONLINEAR_F32 {
                g.hits / 1000
            } else {
                0
            };
            assert!(
                g.hits > 5000 && g.ghosts <= allowed && g.too_far == 0,
                "{name} {method}: {g:?}"
            );
        }
        let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
        let closed = render(&scene, &Nonlinear::<f64>::new(&scene), &small(), &|_| {});
        let agree = compare(&closed, &reference);
        scene.seam_rule = SeamRule::Open;
        let open = render(&scene, &Nonlinear::<f64>::new(&scene), &small(), &|_| {});
        let open_reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
        let differ = compare(&open, &reference);
        let agree_open = compare(&open, &open_reference);
        assert!(
            agree.mismatch_rate() < 0.01 && agree.depth_median < 1e-3,
            "{name}: {agree:?}"
        );
        assert!(agree_open.mismatch_rate() < 0.01, "{name}: {agree_open:?}");
        assert!(
            differ.mismatches > agree.mismatches,
            "{name}: {differ:?} against {agree:?}"
        );
        if name != "seam-cube" {
            // The sphere's open seams are steps, not gaps (its normals agree): a ray leaks only
            // by passing a step's face at a grazing angle, 67 of 1M rays; too few for this grid.
            continue;
        }
        let report = measure(&scene, 128, Method::NONLINEAR_F64).unwrap();
        let at_seams: usize = report
            .leak_edges
            .iter()
            .filter(|e| e.seam)
            .map(|e| e.leaks)
            .sum();
        assert!(
            report.leaks > 0 && 2 * at_seams > report.leaks,
            "{name}: {:?}",
            report.leak_edges
        );
    }
}

/// A ray of `fur` (pixel (948.5, 657.5) of `watertight`'s 1000 x 1000 grid) that, in
/// f32, descends onto a texel edge whose two corners are at height 0 and reaches it exactly at
/// the base: the surface touches the base there, and the cubic's value at the piece's end is 0
/// up to the rounding of its coefficients, so no sign change shows. It must hit at the base
/// crossing (the oracle's base distance 2.35694066), not pass on to the torus's far side
/// (t = 3.2056, the leak this test was written for).
#[test]
fn a_ray_touching_the_base_at_a_zero_texel_edge_hits_there() {
    use nlrt_accel::TraversalStats;
    use nlrt_poly::glam::Vec3;
    let scene = scenes::builtin("fur", scenes::Size::Small).unwrap();
    let surface = scene.displaced_surface::<f32>().unwrap();
    let d = scene.camera.direction(948.5 / 1000.0, 657.5 / 1000.0, 1.0);
    let v = |a: nlrt_poly::glam::DVec3| Vec3::new(a.x as f32, a.y as f32, a.z as f32);
    let ray = nlrt_shellmap::Ray::<f32>::new(v(scene.camera.eye), v(d)).unwrap();
    let hit = surface
        .intersect(&ray, 0.0, f32::INFINITY, &mut TraversalStats::default())
        .expect("the ray meets the surface");
    let t_base = 2.356_940_664_401_393_7;
    assert!(
        (f64::from(hit.hit.t) - t_base).abs()
            < nlrt_render::lab::watertight::LEAK_TOLERANCE * t_base,
        "{hit:?}"
    );
    assert_eq!(hit.triangle, 1168, "{hit:?}");
}

#[test]
fn fig9_displaced_columns_nonlinear_is_watertight_tessellation_free_leaks_where_uvs_degenerate() {
    // Fig. 9's degenerate columns, displaced, 65,536 rays. Triangles: column c has 2c and
    // 2c + 1; column 1's second triangle is a line in uv; column 2's second triangle is a
    // point in uv on its own vertices (a uv seam, closed by a seam wall for nonlinear
    // tracing); column 6's second triangle is a line in world, which
    // has no surface (as in the paper), so its neighbour's edge with it is open.
    use nlrt_render::lab::watertight::measure;
    let scene = scenes::builtin("fig9-displaced", scenes::Size::Small).unwrap();
    for method in [Method::NONLINEAR_F32, Method::NONLINEAR_F64] {
        let report = measure(&scene, 256, method).unwrap();
        assert!(
            report.decided > 1000,
            "{method}: {} decided",
            report.decided
        );
        assert_eq!(
            report.leaks,
            0,
            "{method}: {:?}",
            report.leaks_by_triangle()
        );
    }
    for method in [Method::TESSELLATION_FREE_F32, Method::TESSELLATION_FREE_F64] {
        let report = measure(&scene, 256, method).unwrap();
        // Tessellation-free mapping has no world position for a uv-degenerate triangle's
        // texels, and no seam wall: its leaks are in columns 1 and 2 (and, in f32, possibly
        // between microtriangles).
        let leaks = report.leaks_by_triangle();
        let degenerate: usize = leaks
            .iter()
            .filter(|(t, _)| (2..=5).contains(t))
            .map(|(_, c)| c)
            .sum();
        assert!(degenerate > 0, "{method}: {leaks:?}");
        if method == Method::TESSELLATION_FREE_F64 {
            assert_eq!(degenerate, report.leaks, "{method}: {leaks:?}");
        }
    }
}

#[test]
fn other_methods_agree_with_the_reference_where_the_surfaces_coincide() {
    // The mountain's prisms are affine, and its texel grid's diagonals run along the base
    // triangles' shared edge: tessellation-free mapping and the geometry image build exactly
    // the reference's flat triangles, so f64 agrees to rounding (1e-12 relative, some 10^4
    // ulps of slack for the different orders of operations) and f32 to f32 rounding times
    // the conditioning of the hits (1e-5).
    let scene = scenes::mountain(128);
    let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
    for method in [
        Method::TESSELLATION_FREE_F32,
        Method::TESSELLATION_FREE_F64,
        Method::GEOMETRY_IMAGE_F32,
        Method::GEOMETRY_IMAGE_F64,
    ] {
        let tracer = method.build(&scene).expect("supported");
        let frame = render(&scene, tracer.as_ref(), &small(), &|_| {});
        let e = compare(&frame, &reference);
        let bound = if method.precision() == nlrt_render::trace::method::Precision::F32 {
            1e-5
        } else {
            1e-12
        };
        assert!(e.mismatches <= 1, "{method}: {e:?}");
        assert!(e.depth_max < bound, "{method}: {e:?}");
    }
}

#[test]
fn methods_refuse_scenes_they_cannot_represent() {
    let out = nlrt(&["render", "fig9-displaced", "--method", "geometry-image"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("overlap"), "{err}");
    for method in [
        "tessellation-free",
        "curved",
        "cone-ray",
        "cone-cone",
        "geometry-image",
    ] {
        let out = nlrt(&["render", "scales", "--method", method]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("height fields"), "{method}: {err}");
    }
    // Every method builds for every built-in scene it says it supports, and for no other.
    for name in scenes::names(scenes::Tag::Report) {
        let scene = scenes::builtin(name, scenes::Size::Small).unwrap();
        for method in Method::ALL {
            if method.is_reference() {
                continue; // slow; supports everything it draws
            }
            assert_eq!(
                method.build(&scene).is_some(),
                method.supports(&scene),
                "{method} on {name}"
            );
        }
    }
}

/// Curved shell mapping renders the surface of its Coons patches (the curved reference, to
/// the sampling's resolution), and on curved bases that surface differs from the smooth
/// shell's (so the comparison is not trivially of the same surface).
///
/// Measured (48 x 36): median relative depth error against the curved reference 1.7e-4
/// (cylinder) / 7.6e-5 (torus), against the flat reference 3.2e-3 / 6.0e-3; p99 5e-3 / 1.4e-2
/// (marching at 2 samples per texel cuts thin peaks). The bounds leave a factor ~3.
#[test]
fn curved_shell_mapping_agrees_with_its_own_reference() {
    for scene in [scenes::cylinder(128), scenes::torus_scene(128)] {
        let flat = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
        let curved = render(&scene, &Tessellated::curved(&scene), &small(), &|_| {});
        let bent = compare(&curved, &flat);
        assert!(bent.depth_median > 2e-3, "{}: {bent:?}", scene.name);
        for method in [Method::CURVED_F32, Method::CURVED_F64] {
            let tracer = method.build(&scene).expect("height field");
            let frame = render(&scene, tracer.as_ref(), &small(), &|_| {});
            let e = compare(&frame, &curved);
            let name = scene.name;
            assert!(e.mismatch_rate() < 0.005, "{name} {method}: {e:?}");
            assert!(
                e.depth_median < 0.1 * bent.depth_median,
                "{name} {method}: {e:?} vs {bent:?}"
            );
            assert!(e.depth_p99 < 0.04, "{name} {method}: {e:?}");
        }
    }
}

/// Cone tracing's silhouette correction (the per-vertex quadrics) is what keeps it near the
/// reference on a coarse curved base: with flat quadrics (the original cone tracing) the
/// cylinder's 16 x 16 grid shows in the silhouettes.
///
/// Measured (160 x 120, cylinder with a 128^2 map, primary rays): with quadrics 37 of 19,200
/// pixels hit/miss differently from the reference (0.19%), flat 167 (0.87%); both
/// rectifications alike.
#[test]
fn cone_tracing_silhouette_correction_cuts_the_mismatches_on_the_cylinder() {
    use nlrt_baselines::Rectification;
    use nlrt_render::trace::methods::ConeTracer;
    let scene = scenes::cylinder(128);
    let opts = RenderOptions {
        width: 160,
        height: 120,
        spp: 1,
        bounces: 0,
    };
    let reference = render(&scene, &Tessellated::new(&scene), &opts, &|_| {});
    for rectification in [Rectification::Ray, Rectification::Cone] {
        let rate = |silhouettes: bool| {
            let tracer = ConeTracer::<f32>::with_quadrics(&scene, rectification, silhouettes)
                .expect("height field");
            compare(&render(&scene, &tracer, &opts, &|_| {}), &reference)
        };
        let (corrected, flat) = (rate(true), rate(false));
        assert!(
            corrected.mismatch_rate() < 0.5 * flat.mismatch_rate(),
            "{rectification:?}: {corrected:?} vs flat {flat:?}"
        );
        assert!(corrected.mismatch_rate() < 0.01, "{corrected:?}");
        assert!(corrected.depth_median < 2e-3, "{corrected:?}");
    }
}

/// With the `embree` feature: Embree 3 traces the reference's own triangles, so its hits are
/// the f64 reference's to f32 rounding (1e-5 relative, as for the other f32 methods on these
/// triangles), on a height field and on a shell-mapped object, with its kernels pinned to
/// this build's instruction set and with its native choice.
#[cfg(feature = "embree")]
#[test]
fn embree_traces_the_reference_triangles() {
    use nlrt_render::trace::embree_reference::{EmbreeTessellated, Isa};
    for scene in [scenes::mountain(128), scenes::cornell(4)] {
        let reference = render(&scene, &Tessellated::new(&scene), &small(), &|_| {});
        for isa in [Isa::Build, Isa::Native] {
            let embree = EmbreeTessellated::new(&scene, isa).expect("an Embree device");
            let frame = render(&scene, &embree, &small(), &|_| {});
            let e = compare(&frame, &reference);
            assert!(e.mismatches <= 1, "{} {isa:?}: {e:?}", scene.name);
            assert!(e.depth_max < 1e-5, "{} {isa:?}: {e:?}", scene.name);
        }
    }
}

/// A method watertightness cannot judge is an exit-2 message saying which it judges, not an
/// empty table.
#[test]
fn watertight_with_an_unjudged_method_says_why() {
    let out = nlrt(&[
        "watertight",
        "torus",
        "--method",
        "geometry-image",
        "--rays",
        "16",
    ]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("no method to judge") && err.contains("nonlinear-f32"),
        "{err}"
    );
}

/// Measuring several methods at once (the judged rays decided once per precision) gives each
/// method the report it gets alone, in the order asked for.
#[test]
fn measuring_methods_together_equals_measuring_them_alone() {
    use nlrt_render::lab::watertight::{JudgedHits, measure, measure_all};
    let scene = scenes::torus_scene(64);
    let methods = [
        Method::NONLINEAR_F32,
        Method::TESSELLATION_FREE_F64,
        Method::MARCHING_F32,
        Method::NONLINEAR_F64,
    ];
    let together = measure_all(&scene, 48, &methods, JudgedHits::Every).unwrap();
    assert_eq!(together.len(), methods.len());
    for (report, &method) in together.iter().zip(&methods) {
        let alone = measure(&scene, 48, method).unwrap();
        assert_eq!(report.method, method);
        assert!(report.decided > 0);
        assert_eq!(
            (
                report.decided,
                report.leaks,
                &report.verdicts,
                &report.ghosts
            ),
            (alone.decided, alone.leaks, &alone.verdicts, &alone.ghosts),
            "{method}"
        );
    }
    assert!(
        measure_all(
            &scene,
            48,
            &[Method::NONLINEAR_F32, Method::TESSELLATED_F64],
            JudgedHits::Every
        )
        .is_err()
    );
}

/// The ghost-hit tori (self-intersecting prisms under single-texel spikes, tilted normals
/// under a checkerboard, twisted uvs with a tall shell), 64 x 64 rays: no leaks in either
/// precision, in f64 every hit confirmed by the oracle, and in f32 no ghost hit. Without the
/// f64 decision on roots in a base edge's error window (`decidedly_outside_in_f64`), f32
/// reports 2 ghosts on the twisted torus here: this prism's plane continued across the edge,
/// in front of the neighbour's true surface. Larger runs still find a few f32 ghosts of
/// other kinds (docs/watertightness.md: at most 9 of 231,488 hits at 262,144 rays).
#[test]
fn ghost_tori_hits_are_judged_by_the_oracle() {
    use nlrt_render::lab::watertight::measure;
    for name in scenes::names(scenes::Tag::Ghost) {
        let scene = scenes::builtin(name, scenes::Size::Small).unwrap();
        for method in [Method::NONLINEAR_F64, Method::NONLINEAR_F32] {
            let report = measure(&scene, 64, method).unwrap();
            let g = report.ghosts.clone().expect("nonlinear hits are judged");
            assert!(
                report.decided > 1000 && g.hits > 2000,
                "{name} {method}: {g:?}"
            );
            assert_eq!(report.leaks, 0, "{name} {method}");
            if method == Method::NONLINEAR_F64 {
                assert_eq!(
                    (g.ghosts, g.grazing, g.too_far),
                    (0, 0, 0),
                    "{name} {method}"
                );
            } else {
                assert_eq!(g.ghosts, 0, "{name} {method}: {g:?}");
            }
        }
    }
}

/// `nlrt bench --json` writes every row of the table with the machine, target features and
/// commit; the rates are the ray counts over the seconds, and an unwritable path is an exit-2
/// error before anything runs.
#[test]
fn bench_json_holds_every_row() {
    let dir = std::env::temp_dir().join(format!("nlrt-bench-json-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bench.json");
    let p = path.to_str().unwrap();
    let args = [
        "bench",
        "torus",
        "--methods",
        "nonlinear-f32,nonlinear-f64",
        "--size",
        "24x18",
        "--json",
        p,
    ];
    let table = nlrt_stdout(&args);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    assert_eq!(json["format"], "nlrt-bench/1");
    assert_eq!(json["settings"]["width"], 24);
    assert!(
        json["nlrt"]["commit"]
            .as_str()
            .is_some_and(|c| !c.is_empty())
    );
    assert!(json["build"]["target_features"].is_array());
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for (row, slug) in rows.iter().zip(["nonlinear-f32", "nonlinear-f64"]) {
        assert_eq!(row["scene"], "torus");
        assert_eq!(row["method"], slug);
        assert_eq!(row["primary_rays"], 24 * 18);
        let (rays, seconds) = (
            row["all_rays"].as_f64().unwrap(),
            row["seconds"].as_f64().unwrap(),
        );
        let rate = row["all_mrays_per_s"].as_f64().unwrap();
        assert!((rate - rays / seconds / 1e6).abs() <= 1e-9 * rate, "{row}");
        // The table's row shows the same rate.
        let line = table
            .lines()
            .find(|l| {
                l.starts_with(&format!(
                    "| torus | {} |",
                    row["method_name"].as_str().unwrap()
                ))
            })
            .unwrap();
        assert!(line.contains(&format!("{:.3}", rate)), "{line} vs {rate}");
        assert_eq!(row["vs_f64"]["against"], "nonlinear-f64");
        assert!(row["vs_reference"].is_null());
        // Both methods replayed the one stream recorded with the first.
        let stream = &row["stream"];
        assert_eq!(stream["primary"]["rays"], 24 * 18);
        assert_eq!(stream["all"]["rays"], rows[0]["all_rays"], "{row}");
        assert_eq!(stream["all_one_thread"]["rays"], stream["all"]["rays"]);
        assert_eq!(stream["all_one_thread"]["hits"], stream["all"]["hits"]);
    }
    assert!(table.contains("recorded with nonlinear f32"), "{table}");
    let bad = dir.join("missing").join("bench.json");
    let out = nlrt(&["bench", "torus", "--json", bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("cannot write"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `nlrt bench --rounds 3`: every method replays the stream once per round; the JSON holds
/// the rounds and their ratios to the scene's first method (exactly 1 for it), whose median
/// and spread follow from the per-round values; the stream's "all" columns are the rounds'
/// median; the table lists the rounds. `--rounds` without the stream is an exit-2 error.
#[test]
fn bench_rounds_interleave_the_stream_replays() {
    let dir = std::env::temp_dir().join(format!("nlrt-bench-rounds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("rounds.json");
    let args = [
        "bench",
        "torus",
        "--methods",
        "nonlinear-f32,nonlinear-f64",
        "--no-reference",
        "--size",
        "16x12",
        "--rounds",
        "3",
        "--json",
        path.to_str().unwrap(),
    ];
    let table = nlrt_stdout(&args);
    assert!(
        table.contains("### Interleaved rounds of the stream"),
        "{table}"
    );
    assert!(
        table.contains("| torus | nonlinear f64 | nonlinear f32 |"),
        "{table}"
    );
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let rows = json["rows"].as_array().unwrap();
    assert_eq!(rows.len(), 2);
    for row in rows {
        let rounds = &row["rounds"];
        assert_eq!(rounds["against"], "nonlinear-f32", "{row}");
        let all = rounds["all"].as_array().unwrap();
        assert_eq!(all.len(), 3);
        let rates: Vec<f64> = all
            .iter()
            .map(|r| {
                assert_eq!(r["rays"], row["stream"]["all"]["rays"]);
                r["mrays_per_s"].as_f64().unwrap()
            })
            .collect();
        // The stream's "all" column is one of the rounds: the median one.
        let median_rate = row["stream"]["all"]["mrays_per_s"].as_f64().unwrap();
        let mut sorted = rates.clone();
        sorted.sort_by(f64::total_cmp);
        assert_eq!(median_rate, sorted[1], "{row}");
        let ratios: Vec<f64> = rounds["ratio_all"]["per_round"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| r.as_f64().unwrap())
            .collect();
        let first = rows[0]["rounds"]["all"].as_array().unwrap();
        for ((ratio, rate), f) in ratios.iter().zip(&rates).zip(first) {
            let expected = rate / f["mrays_per_s"].as_f64().unwrap();
            assert!((ratio - expected).abs() <= 1e-12 * expected, "{row}");
        }
        let mut r = ratios.clone();
        r.sort_by(f64::total_cmp);
        assert_eq!(rounds["ratio_all"]["median"].as_f64().unwrap(), r[1]);
        assert_eq!(rounds["ratio_all"]["min"].as_f64().unwrap(), r[0]);
        assert_eq!(rounds["ratio_all"]["max"].as_f64().unwrap(), r[2]);
        assert_eq!(rounds["all_one_thread"].as_array().unwrap().len(), 3);
    }
    for r in rows[0]["rounds"]["ratio_all"]["per_round"]
        .as_array()
        .unwrap()
    {
        assert_eq!(r.as_f64(), Some(1.0));
    }
    let out = nlrt(&["bench", "torus", "--rounds", "2", "--no-ray-stream"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--no-ray-stream"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A recorded ray stream holds every ray the render cast, in its kinds; replayed into the
/// tracer that recorded it, its primary rays hit exactly where the frame has a depth, and
/// every ray hits as often on one thread as on all.
#[test]
fn a_replayed_ray_stream_gives_the_recording_renders_hits() {
    use nlrt_render::trace::integrator::render_recording;
    use nlrt_render::trace::ray_stream::{RayKind, replay};
    let scene = scenes::builtin("torus", scenes::Size::Small).unwrap();
    let tracer = Nonlinear::<f64>::new(&scene);
    let opts = RenderOptions {
        width: 40,
        height: 30,
        spp: 1,
        bounces: 2,
    };
    let (frame, stream) = render_recording(&scene, &tracer, &opts);
    assert_eq!(stream.len() as u64, frame.all_rays);
    assert_eq!(stream.count(RayKind::Primary), frame.primary_rays);
    assert!(stream.count(RayKind::Shadow) > 0 && stream.count(RayKind::Bounce) > 0);
    let primary = replay(&tracer, &stream, Some(RayKind::Primary));
    let depths = frame.depth.iter().filter(|d| !d.is_nan()).count() as u64;
    assert_eq!(primary.hits, depths);
    let all = replay(&tracer, &stream, None);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let one = pool.install(|| replay(&tracer, &stream, None));
    assert_eq!((all.rays, all.hits), (one.rays, one.hits));
    // Every bounce ray starts from a hit: it was cast only after one.
    assert!(all.hits >= stream.count(RayKind::Bounce));
}

/// The scales close: rays from the default camera beside the plane of the tile boundary at
/// the front of the torus (`x = 0`, where the view looks along the boundary between two
/// columns of scales), aimed across the tube's upper side, all hit, in nonlinear f32 and f64
/// and in the pre-tessellated reference; in the plane itself the reference hits them all.
/// With a margin between the tiles' scales, these rays passed through the gaps on the torus's
/// near and far sides (a see-through line in the default render's centre column). Rays
/// exactly in the plane run along the crease where two tiles' scales meet, an edge that no
/// object triangle shares within its tile: nonlinear tracing misses 9 (f32) and 6 (f64) of
/// these 64 there (docs/watertightness.md, "Tile boundaries").
#[test]
fn the_scales_close_along_a_tile_boundary() {
    use nlrt_poly::glam::DVec3;
    use nlrt_render::trace::tracer::Tracer;
    let scene = scenes::builtin("scales", scenes::Size::Small).unwrap();
    let tracers: [(&str, Box<dyn Tracer>, &[f64]); 3] = [
        (
            "nonlinear f32",
            Box::new(Nonlinear::<f32>::new(&scene)),
            &[-4e-3, -1e-4, 1e-4, 4e-3],
        ),
        (
            "nonlinear f64",
            Box::new(Nonlinear::<f64>::new(&scene)),
            &[-4e-3, -1e-4, 1e-4, 4e-3],
        ),
        (
            "tessellated",
            Box::new(Tessellated::new(&scene)),
            &[-4e-3, -1e-4, 0.0, 1e-4, 4e-3],
        ),
    ];
    let eye = scene.camera.eye;
    for (name, tracer, offsets) in &tracers {
        let mut misses = Vec::new();
        for &offset in *offsets {
            for k in 0..64 {
                // The tube's upper side at the front: tube angle -30 to 90 degrees.
                let phi = (-30.0 + 120.0 * f64::from(k) / 63.0_f64).to_radians();
                let target = DVec3::new(offset, 0.4 * phi.sin(), 1.0 + 0.4 * phi.cos());
                if tracer
                    .intersect(eye, target - eye, 0.0, f64::INFINITY)
                    .is_none()
                {
                    misses.push((offset, k));
                }
            }
        }
        assert!(misses.is_empty(), "{name}: {misses:?}");
    }
}

/// A method that cannot render a scene is left out of the bench with its reason (and the
/// methods that can still run); Embree's grids need a height field, and without the `embree`
/// feature the feature is named.
#[test]
fn bench_names_the_methods_it_leaves_out_and_why() {
    let out = nlrt(&[
        "bench",
        "cornell",
        "--methods",
        "cone-ray-f32,embree-grid-f32,nonlinear-f32",
        "--no-reference",
        "--no-ray-stream",
        "--size",
        "16x12",
    ]);
    assert!(out.status.success(), "{out:?}");
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stderr
            .contains("cone tracing (ray rect.) f32 left out: cone tracing renders height fields"),
        "{stderr}"
    );
    let grid_reason = if cfg!(feature = "embree") {
        "grid geometry holds height fields"
    } else {
        "built without the `embree` feature"
    };
    assert!(
        stderr.contains(&format!("Embree 3 grids f32 left out: {grid_reason}")),
        "{stderr}"
    );
    assert!(stdout.contains("| cornell | nonlinear f32 |"), "{stdout}");
    assert!(
        !stdout.contains("| cornell | Embree 3 grids f32 |"),
        "{stdout}"
    );
}
