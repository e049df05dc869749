//! `nlrt render`, `nlrt bench` and `nlrt export`.

use super::args::*;
use super::common::*;
use nlrt_render::lab::report::{self, ReportOptions};
use nlrt_render::scene::scenes::{Tag, names};
use nlrt_render::trace::method::{Method, Precision};
use std::process::ExitCode;

impl RenderCommand {
    /// Runs `nlrt render`.
    pub fn run(self, seam_rule: nlrt_accel::SeamRule) -> ExitCode {
        let Self {
            scene,
            precision,
            method,
            args,
            output,
            aov,
        } = self;
        let built = match resolve_scene(&scene, args.scene_size(), seam_rule) {
            Ok(s) => s,
            Err(e) => return fail("render", e),
        };
        // Embree runs in f32 and the references in f64, whatever `--precision` says.
        let method = Method::in_precision_or_only(method, precision);
        if let Some(why) = method.unsupported_reason(&built) {
            return fail("render", format!("{method} cannot render {scene}: {why}"));
        }
        // Scene files are checked in f64 when loaded; a value finite in f64 may not be
        // in f32.
        if method.precision() == Precision::F32
            && let Err(e) = built.check_precision::<f32>()
        {
            return fail("render", format!("{scene}: {e}"));
        }
        let opts = ReportOptions {
            scenes: vec![scene.clone()],
            size: args.scene_size(),
            render: args.options(),
            methods: vec![method],
            out_dir: None,
            scaling: false,
            ray_stream: false,
            seam_rule,
            rounds: 1,
        };
        let seams = built.describe_seams();
        if !seams.is_empty() {
            eprintln!("{scene}: {}", seams.trim_start_matches(", "));
        }
        let runs = report::run_scene(&built, &opts);
        let run = &runs[0];
        if let Err(e) = nlrt_render::trace::image::write_png(
            &output,
            run.frame.width,
            run.frame.height,
            &run.frame.rgb8(),
        ) {
            return fail("render", format!("cannot write {}: {e}", output.display()));
        }
        if let Some(path) = &aov
            && let Err(e) = run.frame.write_aovs_exr(path)
        {
            return fail("render", e);
        }
        println!(
            "{scene} ({method}): init {:.3} s, {:.3} Mrays/s ({} rays), written to {}",
            run.init_seconds,
            run.all_mrays(),
            run.frame.all_rays,
            output.display()
        );
        ExitCode::SUCCESS
    }
}

impl BenchCommand {
    /// Runs `nlrt bench`.
    pub fn run(self, seam_rule: nlrt_accel::SeamRule) -> ExitCode {
        let Self {
            scenes,
            args,
            no_reference,
            methods,
            no_ray_stream,
            json,
            rounds,
        } = self;
        if rounds > 1 && no_ray_stream {
            return fail(
                "bench",
                "--rounds interleaves the ray stream's replays; it cannot go with --no-ray-stream",
            );
        }
        let scenes = if scenes.is_empty() {
            names(Tag::Report).iter().map(|s| s.to_string()).collect()
        } else {
            scenes
        };
        if let Err(e) = check_scenes(&scenes) {
            return fail("bench", e);
        }
        // Opened before the run, so that an unwritable path fails at once, not after it.
        let json_file = json.as_deref().map(|path| {
            std::fs::File::create(path)
                .map(|file| (path, file))
                .map_err(|e| format!("cannot write {}: {e}", path.display()))
        });
        let json_file = match json_file.transpose() {
            Ok(f) => f,
            Err(e) => return fail("bench", e),
        };
        let methods = Method::ALL
            .into_iter()
            .filter(|m| methods.is_empty() || methods.contains(m))
            .filter(|&m| !(no_reference && m.is_reference()))
            .collect();
        let opts = ReportOptions {
            scenes,
            size: args.scene_size(),
            render: args.options(),
            methods,
            out_dir: None,
            scaling: true,
            ray_stream: !no_ray_stream,
            seam_rule,
            rounds: rounds as usize,
        };
        match report::run_with_rows(&opts) {
            Ok((md, rows)) => {
                print!("{md}");
                if let Some((path, mut file)) = json_file {
                    use std::io::Write as _;
                    let text = nlrt_render::lab::bench_json::to_json(&opts, &rows);
                    if let Err(e) = file.write_all(text.as_bytes()) {
                        return fail("bench", format!("cannot write {}: {e}", path.display()));
                    }
                }
                ExitCode::SUCCESS
            }
            Err(e) => fail("bench", e),
        }
    }
}

impl ExportCommand {
    /// Runs `nlrt export`.
    pub fn run(self) -> ExitCode {
        let Self {
            scene,
            scene_size,
            output,
        } = self;
        let built = match nlrt_render::scene::scene_file::builtin_or_file(&scene, scene_size.into())
        {
            Ok(s) => s,
            Err(e) => return fail("export", e),
        };
        // A scene file is written under its own stem (its scenes are all named "file").
        let name = std::path::Path::new(&scene)
            .file_stem()
            .and_then(|s| s.to_str())
            .filter(|_| scene.ends_with(".toml"))
            .unwrap_or(built.name);
        match nlrt_render::scene::scene_file::export_as(&built, name, &output) {
            Ok(path) => {
                println!("{scene} written to {}", path.display());
                ExitCode::SUCCESS
            }
            Err(e) => fail("export", e),
        }
    }
}
