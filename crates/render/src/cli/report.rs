//! `nlrt report` (the default job), `nlrt edit` and `nlrt solvers`.

use super::args::*;
use super::common::*;
use nlrt_render::lab::report::{self, ReportOptions};
use nlrt_render::lab::watertight;
use nlrt_render::lab::{edit, solvers};
use nlrt_render::scene::scenes::{self, Tag, names};
use nlrt_render::trace::method::Method;
use std::path::PathBuf;
use std::process::ExitCode;

impl ReportCommand {
    /// Runs `nlrt report`.
    pub fn run(self, seam_rule: nlrt_accel::SeamRule) -> ExitCode {
        let Self {
            output,
            args,
            solver_samples,
            scenes,
        } = self;
        report_command(output, &args, solver_samples, scenes, seam_rule)
    }
}

impl EditCommand {
    /// Runs `nlrt edit`.
    pub fn run(self) -> ExitCode {
        let Self {
            scene_size,
            strokes,
            brush,
            no_reference,
        } = self;
        let opts = edit::EditOptions {
            size: scene_size.into(),
            strokes: strokes as usize,
            brush: brush as usize,
            reference: !no_reference,
        };
        match edit::run(&opts) {
            Ok(r) => {
                print!("{}", edit::markdown(&r));
                ExitCode::SUCCESS
            }
            Err(e) => fail("edit", e),
        }
    }
}

impl SolversCommand {
    /// Runs `nlrt solvers`.
    pub fn run(self) -> ExitCode {
        let Self {
            samples,
            seed,
            passes,
            output,
        } = self;
        if samples == 0 || passes == 0 {
            return fail("solvers", "--samples and --passes must be at least 1");
        }
        let opts = solvers::Options {
            samples,
            seed,
            passes,
        };
        let table = solvers::markdown(&solvers::run(&opts), &opts);
        print!("{table}");
        if let Some(path) = output
            && let Err(e) = std::fs::write(&path, &table)
        {
            return fail("solvers", format!("cannot write {}: {e}", path.display()));
        }
        ExitCode::SUCCESS
    }
}

pub fn report_command(
    output: PathBuf,
    args: &RenderArgs,
    solver_samples: usize,
    scenes: Vec<String>,
    seam_rule: nlrt_accel::SeamRule,
) -> ExitCode {
    if let Err(e) = check_scenes(&scenes) {
        return fail("report", e);
    }
    if let Err(e) = std::fs::create_dir_all(&output) {
        return fail("report", format!("cannot create {}: {e}", output.display()));
    }
    let opts = ReportOptions {
        scenes: if scenes.is_empty() {
            names(Tag::Report).iter().map(|s| s.to_string()).collect()
        } else {
            scenes
        },
        size: args.scene_size(),
        render: args.options(),
        methods: Method::ALL.to_vec(),
        out_dir: Some(output.clone()),
        scaling: false,
        ray_stream: false,
        seam_rule,
        rounds: 1,
    };
    let start = std::time::Instant::now();
    let scenes_md = match report::run(&opts) {
        Ok(md) => md,
        Err(e) => return fail("report", e),
    };
    eprintln!("watertightness...");
    let mut leaks_md = String::from(
        "| scene | method | rays | decided | leaks | rate | 95% interval | ghost hits (of hits judged) | grazing | too far | hit distance vs oracle: median / p99 / max rel. error (hits compared, unverified) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for name in names(Tag::ReportJudged) {
        let Some(scene) = scenes::builtin(name, args.scene_size()) else {
            continue;
        };
        let judged_hits = watertight::JudgedHits::Spaced {
            ghosts: REPORT_GHOST_SAMPLES,
            distances: REPORT_DISTANCE_SAMPLES,
        };
        let reports = match watertight::measure_all(
            &scene,
            REPORT_WATERTIGHT_GRID,
            &watertight::METHODS,
            judged_hits,
        ) {
            Ok(r) => r,
            Err(e) => return fail("report", e),
        };
        for r in reports {
            leaks_md.push_str(&leak_row(name, &r));
            leaks_md.push('\n');
            let path = output.join(format!("{name}-leaks-{}.png", r.method.slug()));
            if let Err(e) = nlrt_render::trace::image::write_png(
                &path,
                REPORT_WATERTIGHT_GRID,
                REPORT_WATERTIGHT_GRID,
                &watertight::leak_image(&r),
            ) {
                return fail("report", format!("cannot write {}: {e}", path.display()));
            }
        }
    }
    eprintln!("uv seams...");
    let seam_md = match seam_section(&output, args) {
        Ok(md) => md,
        Err(e) => return fail("report", e),
    };
    eprintln!("editing...");
    let edit_md = match edit::run(&edit::EditOptions {
        size: args.scene_size(),
        ..edit::EditOptions::default()
    }) {
        Ok(r) => edit::markdown(&r),
        Err(e) => return fail("report", e),
    };
    eprintln!("solver table ({solver_samples} cubics per precision)...");
    let solver_opts = solvers::Options {
        samples: solver_samples.max(1),
        ..solvers::Options::default()
    };
    let solver_md = solvers::markdown(&solvers::run(&solver_opts), &solver_opts);
    let md = format!(
        "# nlrt report\n\nWritten by `nlrt report` in {:.0} s.\n\n{scenes_md}\n## Watertightness\n\n\
         Camera rays that reach a base triangle from outside, decided exactly (GMP rationals), \
         and whether the tracer hit the surface before; ghost hits: of {REPORT_GHOST_SAMPLES} \
         evenly spaced hits of nonlinear tracing, those in front of the true surface (MPFR \
         oracle on the microtriangles around the hit), and hits too far (`nlrt watertight`; \
         leak images `<scene>-leaks-<method>.png`: grey hit, red leak, yellow ghost, black \
         undecided).\n\n{leaks_md}\n{seam_md}\n## Editing (`nlrt edit`)\n\n{edit_md}\n## Cubic solvers\n\n{solver_md}",
        start.elapsed().as_secs_f64()
    );
    let path = output.join("report.md");
    if let Err(e) = std::fs::write(&path, &md) {
        return fail("report", format!("cannot write {}: {e}", path.display()));
    }
    print!("{md}");
    eprintln!("report written to {}", path.display());
    ExitCode::SUCCESS
}

/// The report's seam section: `seam-cube` rendered by nonlinear tracing in f32 with and
/// without the seam rule, side by side (`seam-cube-seams.png`), crack pixels in red.
pub fn seam_section(output: &std::path::Path, args: &RenderArgs) -> Result<String, String> {
    let Some(scene) = scenes::builtin("seam-cube", args.scene_size()) else {
        return Err("no seam-cube scene".into());
    };
    let opts = args.options();
    let view = nlrt_render::lab::seam_view::compare(&scene, &opts)?;
    let path = output.join("seam-cube-seams.png");
    nlrt_render::trace::image::write_png(&path, 2 * view.width, view.height, &view.rgb)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
    Ok(format!(
        "## uv and normal seams\n\n`seam-cube` (every cube edge a uv and a normal seam{}), \
         nonlinear f32, with the seam rule (left: welded displacement directions and seam \
         walls) and without it (right, `--no-seam-fix`), crack pixels in red: {} of {} pixels \
         that hit the surface see through a crack without the rule \
         (`seam-cube-seams.png`).\n\n![seams](seam-cube-seams.png)\n",
        scene.describe_seams(),
        view.crack_pixels,
        view.hit_pixels
    ))
}
