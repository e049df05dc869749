//! `nlrt`: the command-line tool of the nlrt workspace.
//!
//! With no arguments it runs the default job: the built-in scenes at a small size through
//! every method, and the report (Markdown and images) in `nlrt-report/`.

use clap::{Parser, Subcommand, ValueEnum};
use nlrt_render::integrator::RenderOptions;
use nlrt_render::method::Method;
use nlrt_render::report::{self, ReportOptions};
use nlrt_render::scenes::{self, SCENE_NAMES, Size};
use nlrt_render::watertight;
use nlrt_render::{edit, solvers};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "nlrt",
    version,
    about = "Nonlinear ray tracing of displaced and shell-mapped surfaces: renders, benchmarks and precision reports"
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    /// Leave the base mesh's uv and normal seams open (no welded displacement directions, no
    /// seam walls), to see and measure the cracks the seam rule closes.
    #[arg(long, global = true)]
    no_seam_fix: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum Precision {
    F32,
    F64,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum MethodKind {
    /// Nonlinear ray tracing (Ogaki 2023).
    Nonlinear,
    /// Tessellation-free displacement mapping (Thonat et al. 2021); height fields only.
    TessellationFree,
    /// Geometry-image ray tracing (Carr et al. 2006); height fields on one uv chart only.
    GeometryImage,
    /// Smooth shell mapping by ray marching (Jeschke et al. 2007); instanced objects voxelised.
    Marching,
    /// Ray marching with Jeschke's 3D distance map (sec. 4.4); instanced objects voxelised.
    DistanceMap,
    /// Tetrahedral shells (piecewise-linear mapping); height fields only.
    Tetrahedra,
    /// Projective displacement mapping (parallel offset prisms); height fields only.
    Projective,
    /// Curved shell mapping (Jeschke et al. 2007, Coons patches); height fields only.
    Curved,
    /// Cone tracing with silhouettes, viewing-ray rectification (Ouazzani Chahdi et al.
    /// 2021); height fields only.
    ConeRay,
    /// Cone tracing with silhouettes, cone rectification; height fields only.
    ConeCone,
    /// The pre-tessellated microtriangles through Embree 3 (f32; the `embree` feature).
    Embree,
    /// The pre-tessellated reference (f64).
    Tessellated,
    /// The curved shell's surface pre-tessellated (f64): the curved shell's reference.
    TessellatedCurved,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum SceneSize {
    /// The paper's map sizes (4096^2; fur 256^2 tiled 8 x 8). The pre-tessellated reference
    /// then needs several GB.
    Paper,
    /// Maps of a quarter of the side: quick runs.
    Small,
}

impl From<SceneSize> for Size {
    fn from(s: SceneSize) -> Self {
        match s {
            SceneSize::Paper => Size::Paper,
            SceneSize::Small => Size::Small,
        }
    }
}

/// Image size `WxH`.
fn distance_cell(r: &watertight::LeakReport) -> String {
    r.distance_error.map_or("-".into(), |d| {
        format!(
            "{:.1e} / {:.1e} / {:.1e} ({}, {})",
            d.median, d.p99, d.max, d.samples, d.unverified
        )
    })
}

/// Ghost hits, grazing near misses and hits too far among the hits judged by the oracle, or
/// `-`.
fn ghost_cell(r: &watertight::LeakReport) -> String {
    r.ghosts.as_ref().map_or("- | - | -".into(), |g| {
        format!("{} of {} | {} | {}", g.ghosts, g.hits, g.grazing, g.too_far)
    })
}

fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_slug(s).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.slug()).collect();
        format!("unknown method '{s}' (methods: {})", names.join(", "))
    })
}

fn parse_deformation(s: &str) -> Result<nlrt_render::animation::Deformation, String> {
    nlrt_render::animation::Deformation::from_name(s)
}

/// `--tlas`: how nonlinear tracing's TLAS follows a pose.
#[derive(Clone, Copy, Debug, ValueEnum)]
enum TlasRule {
    /// Refit, rebuild when the SAH cost has grown past the default rule's factor.
    Auto,
    /// Refit every frame.
    Refit,
    /// Rebuild every frame.
    Rebuild,
}

fn parse_size(s: &str) -> Result<(usize, usize), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{s}' is not WIDTHxHEIGHT (e.g. 640x480)"))?;
    let parse = |v: &str| {
        v.parse::<usize>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("'{v}' is not a size between 1 and 16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

#[derive(clap::Args, Clone)]
struct RenderArgs {
    /// Image size.
    #[arg(long, value_parser = parse_size, default_value = "320x240")]
    size: (usize, usize),
    /// Samples per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    spp: u32,
    /// Diffuse bounces (each hit also casts a shadow ray).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=16))]
    bounces: u32,
    /// Map sizes of the built-in scenes.
    #[arg(long, value_enum, default_value = "small")]
    scene_size: SceneSize,
    /// Every height map of the built-in scenes at this side (a power of two, 512 to 16384),
    /// the rest at the paper's sizes: a scale sweep, e.g. `bench mountain --map-side 8192`.
    /// Overrides --scene-size.
    #[arg(long, value_parser = parse_map_side)]
    map_side: Option<Size>,
}

/// `--map-side N`: [`Size::map_side`].
fn parse_map_side(text: &str) -> Result<Size, String> {
    let side: usize = text
        .parse()
        .map_err(|_| format!("'{text}' is not a whole number"))?;
    Size::map_side(side)
}

impl RenderArgs {
    /// The scene size: `--map-side` where given, else `--scene-size`.
    fn scene_size(&self) -> Size {
        self.map_side.unwrap_or(self.scene_size.into())
    }

    fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.size.0,
            height: self.size.1,
            spp: self.spp as usize,
            bounces: self.bounces as usize,
        }
    }
}

#[derive(Subcommand)]
enum Command {
    /// Render a built-in scene with nonlinear ray tracing to a PNG.
    Render {
        #[arg(help = scene_help("A built-in scene"))]
        scene: String,
        /// Precision of the intersection (the pre-tessellated reference is always f64).
        #[arg(long, value_enum, default_value = "f32")]
        precision: Precision,
        /// Intersection method.
        #[arg(long, value_enum, default_value = "nonlinear")]
        method: MethodKind,
        #[command(flatten)]
        args: RenderArgs,
        /// Output PNG.
        #[arg(short, long, default_value = "nlrt.png")]
        output: PathBuf,
        /// Also write the primary hits' depth, normal and hit id (base triangle) to this
        /// OpenEXR file (32-bit float channels Z, N.X, N.Y, N.Z; unsigned integer id).
        #[arg(long)]
        aov: Option<PathBuf>,
    },
    /// Speed, init time, memory and 1-thread vs all-threads scaling per scene and method (no
    /// images written).
    Bench {
        #[arg(help = scene_help("Scenes (default: every built-in one but the variants), each a built-in scene"))]
        scenes: Vec<String>,
        #[command(flatten)]
        args: RenderArgs,
        /// Leave out the pre-tessellated references (their build dominates at paper sizes).
        #[arg(long)]
        no_reference: bool,
        /// Only these methods (comma-separated slugs, e.g. nonlinear-f32, marching-f64,
        /// curved-f32, tessellated-f64; an unknown one lists them all; default: all).
        #[arg(long, value_delimiter = ',', value_parser = parse_method)]
        methods: Vec<Method>,
        /// Leave out the replay of one recorded ray stream per scene into every method (the
        /// stream columns: the same rays for every method, timed without shading).
        #[arg(long)]
        no_ray_stream: bool,
        /// Also write every column as JSON to this file, with the machine, the build's target
        /// features and the commit (format `nlrt-bench/1`, described in `docs/measurements.md`).
        #[arg(long, value_name = "FILE")]
        json: Option<PathBuf>,
        /// Replay each scene's ray stream in this many interleaved rounds (every method in turn
        /// per round, all threads then one thread): the stream's "all" columns become the
        /// rounds' medians, and a table gives each round's ratio to the scene's first method
        /// with their median and spread (in the JSON too). Keeps every method's acceleration
        /// data alive at once. 1: one replay per method, no rounds.
        #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
        rounds: u32,
    },
    /// The full report: every scene and method, images, differences, and the solver table.
    Report {
        /// Output directory.
        #[arg(short, long, default_value = "nlrt-report")]
        output: PathBuf,
        #[command(flatten)]
        args: RenderArgs,
        /// Random cubics per precision for the solver table.
        #[arg(long, default_value_t = REPORT_SOLVER_SAMPLES)]
        solver_samples: usize,
        /// The scenes of the speed-and-error table (comma-separated built-in names or scene
        /// files `*.toml`; default: every built-in one but the variants). The watertightness
        /// section judges the built-in judged scenes whatever this says.
        #[arg(long, value_delimiter = ',')]
        scenes: Vec<String>,
    },
    /// Leaks, decided by exact arithmetic: rays that reach a base triangle from outside (so
    /// must have hit the displaced surface) but were not hit, or, on shell scenes, rays aimed
    /// at the object that pass its exact crossing; and ghost hits of nonlinear tracing: hits
    /// in front of the true surface, judged by the MPFR oracle.
    Watertight {
        /// Displacement scene: torus, fur, mountain, mountain-grazing, fig9-displaced, the
        /// ghost-hit tori torus-spikes, torus-tilted, torus-twisted, the uv-seam scenes
        /// seam-cube, seam-sphere (or cylinder, whose open ends make only part of its rays
        /// decidable); shell scene: scales, feathers, cornell, highpoly, fig9 (nonlinear
        /// tracing only); or a scene file (`*.toml`).
        scene: String,
        /// Rays: a square grid of camera rays with at least this many (on shell scenes, rays
        /// aimed at the object).
        #[arg(long, default_value_t = 65_536, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
        rays: u64,
        /// Precision (default: both).
        #[arg(long, value_enum)]
        precision: Option<Precision>,
        /// Method (default: nonlinear and tessellation-free).
        #[arg(long, value_enum)]
        method: Option<MethodKind>,
        /// Map sizes of the built-in scenes.
        #[arg(long, value_enum, default_value = "small")]
        scene_size: SceneSize,
        /// Judge about this many of nonlinear tracing's hits for ghosts, evenly spaced (default:
        /// every hit, about 0.3 ms of one core each).
        #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
        ghost_samples: Option<u64>,
        /// Judge this frame of the scene's motion (`nlrt animate`'s frame numbers, from 0):
        /// nonlinear tracing is moved there by pose updates from the rest pose.
        #[arg(long, value_parser = clap::value_parser!(u32).range(0..=100_000))]
        frame: Option<u32>,
        /// Frames of the motion's cycle, for `--frame`.
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        frames: u32,
        /// Directory for the leak images (`<scene>-leaks-<method>.png`).
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Time from a brush stroke on the mountain's height map to the next traceable frame:
    /// partial min-max update, full rebuild, re-tessellation.
    Edit {
        /// Map size (small: 1024^2, paper: 4096^2).
        #[arg(long, value_enum, default_value = "small")]
        scene_size: SceneSize,
        /// Strokes timed.
        #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u64).range(1..=100_000))]
        strokes: u64,
        /// Brush side in samples.
        #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=4096))]
        brush: u64,
        /// Skip the pre-tessellated rebuild (at paper size it needs several GB).
        #[arg(long)]
        no_reference: bool,
    },
    /// Animate a scene's base mesh: per frame, nonlinear tracing refits (or rebuilds) only its
    /// TLAS; every other method is built afresh on the posed mesh. Writes the frames and
    /// `animate.md` (update and render times, checks against fresh builds).
    Animate {
        #[arg(help = scene_help("A built-in scene (each has a motion)"))]
        scene: String,
        /// Frames (one cycle of a deformation).
        #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        frames: u32,
        #[command(flatten)]
        args: RenderArgs,
        /// Methods (comma-separated slugs; default nonlinear-f32,nonlinear-f64,tessellated-f64).
        #[arg(long, value_delimiter = ',', value_parser = parse_method)]
        methods: Vec<Method>,
        /// How nonlinear tracing's TLAS follows each pose: refit, rebuild, or auto (refit,
        /// rebuilt when its SAH cost has grown by the default rule's factor).
        #[arg(long, value_enum, default_value = "auto")]
        tlas: TlasRule,
        /// Replace the scene's motion by this deformation of its base mesh (wave, bend,
        /// twist, breathe, squash).
        #[arg(long, value_parser = parse_deformation)]
        deformation: Option<nlrt_render::animation::Deformation>,
        /// Strength of `--deformation` (1 the built-in one; |amplitude| <= 10).
        #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
        amplitude: f64,
        /// Frames rendered by the methods built afresh per frame (the pre-tessellated
        /// reference, Embree): their rebuild does not depend on the pose.
        #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=100_000))]
        rebuild_frames: u32,
        /// Do not build nonlinear tracing afresh each frame to compare hits and speed with.
        #[arg(long)]
        no_verify: bool,
        /// Output directory (frames `<scene>-<method>-<frame>.png`, `animate.md`).
        #[arg(short, long, default_value = "nlrt-animate")]
        output: PathBuf,
    },
    /// Write a built-in scene (or a scene file, rewritten with its objects placed) as a scene
    /// file (TOML + OBJ + 16-bit PNG or object OBJ, per object).
    Export {
        #[arg(help = scene_help("A built-in scene"))]
        scene: String,
        /// Map sizes.
        #[arg(long, value_enum, default_value = "small")]
        scene_size: SceneSize,
        /// Output directory.
        #[arg(short, long, default_value = "scenes/builtin")]
        output: PathBuf,
    },
    /// Speed against error of the cubic solvers (nlrt-poly, closed form, `roots` crate) for
    /// f32 and f64, judged by the MPFR oracle.
    Solvers {
        /// Random cubics per precision, split evenly over the random families.
        #[arg(long, default_value_t = solvers::Options::default().samples)]
        samples: usize,
        /// Seed of the random families.
        #[arg(long, default_value_t = solvers::Options::default().seed)]
        seed: u64,
        /// Timed passes per row; the median is reported.
        #[arg(long, default_value_t = solvers::Options::default().passes)]
        passes: usize,
        /// Also write the table (Markdown) to this file.
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
}

fn fail(command: &str, message: impl std::fmt::Display) -> ExitCode {
    eprintln!("nlrt {command}: {message}");
    ExitCode::from(2)
}

fn check_scenes(names: &[String]) -> Result<(), String> {
    for n in names {
        if !(scenes::is_builtin(n) || n.ends_with(".toml")) {
            return Err(format!(
                "unknown scene '{n}' (built-in scenes: {}; variants: {})",
                SCENE_NAMES.join(", "),
                scenes::VARIANT_NAMES.join(", ")
            ));
        }
    }
    Ok(())
}

/// The built-in scenes and variants as the help lists them (from the list the code builds,
/// so the help cannot fall behind it).
fn builtin_list() -> String {
    format!(
        "{}; variants {}",
        SCENE_NAMES.join(", "),
        scenes::VARIANT_NAMES.join(", ")
    )
}

/// The built-in displacement scenes `nlrt watertight` is meant for, each once: the judged
/// ones, the ghost-hit tori, the seam scenes, the cone fur and the cylinder.
fn judged_scene_names() -> Vec<&'static str> {
    let mut names: Vec<&'static str> = Vec::new();
    for name in scenes::WATERTIGHT_SCENES
        .iter()
        .chain(scenes::GHOST_SCENES.iter())
        .chain(scenes::SEAM_SCENES.iter())
        .chain(["fur-cones", "cylinder"].iter())
        .chain(["scales", "feathers", "cornell", "highpoly", "fig9"].iter())
    {
        if !names.contains(name) {
            names.push(name);
        }
    }
    names
}

/// Help for a scene argument: `what` (built-in scenes listed) or a scene file.
fn scene_help(what: &str) -> String {
    format!(
        "{what} ({}) or a scene file (`*.toml`, see the README)",
        builtin_list()
    )
}

/// A built-in scene by name, or a scene file (`*.toml`).
fn resolve_scene(
    name: &str,
    size: Size,
    seam_rule: nlrt_accel::SeamRule,
) -> Result<scenes::Scene, String> {
    let mut scene = nlrt_render::scene_file::builtin_or_file(name, size)?;
    scene.set_seam_rule(seam_rule);
    Ok(scene)
}

/// Hits per scene and precision the report judges for ghosts: the oracle's 0.3 ms per hit
/// keeps the default job's watertightness section within seconds (`nlrt watertight` judges
/// every hit).
const REPORT_GHOST_SAMPLES: usize = 4096;

/// Hits per scene and precision whose distance the report compares with the oracle's: at
/// `watertight::DISTANCE_SAMPLES` (1,024) they took about 4 s per scene of the torus and the
/// fur (2026-12-03, 2-core machine), a third of the watertightness section.
const REPORT_DISTANCE_SAMPLES: usize = 256;

/// Image size of the default job (`cargo run --release`): 320 x 240, the size of
/// `nlrt report`, took 129 s of its scene renders (2026-12-03, 2-core machine, the whole job
/// 176 s), too near its 3 minutes on a loaded machine; 256 x 192 has 0.64 of the pixels.
const DEFAULT_JOB_SIZE: (usize, usize) = (256, 192);

/// Side of the report's watertightness grid (16,384 rays per scene): at 256^2 the section
/// took 72 s of the default job (2026-12-03, 2-core machine), which must stay under 3
/// minutes; `nlrt watertight --rays N` judges as many as asked (the 1M-ray tables of
/// docs/watertightness.md).
const REPORT_WATERTIGHT_GRID: usize = 128;

/// Cubics per precision in the report's solver table (`nlrt report --solver-samples`,
/// `nlrt solvers --samples` for more): 50,000 took 31 s of the default job (same run).
const REPORT_SOLVER_SAMPLES: usize = 20_000;

fn report_command(
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
            SCENE_NAMES.iter().map(|s| s.to_string()).collect()
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
    for name in scenes::WATERTIGHT_SCENES {
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
            let (lo, hi) = r.wilson_95();
            leaks_md.push_str(&format!(
                "| {name} | {} | {} | {} | {} | {:.2e} | [{:.1e}, {:.1e}] | {} | {} |\n",
                r.method,
                r.rays,
                r.decided,
                r.leaks,
                r.rate(),
                lo,
                hi,
                ghost_cell(&r),
                distance_cell(&r)
            ));
            let path = output.join(format!("{name}-leaks-{}.png", r.method.slug()));
            if let Err(e) = nlrt_render::image::write_png(
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
fn seam_section(output: &std::path::Path, args: &RenderArgs) -> Result<String, String> {
    let Some(scene) = scenes::builtin("seam-cube", args.scene_size()) else {
        return Err("no seam-cube scene".into());
    };
    let opts = args.options();
    let view = nlrt_render::seam_view::compare(&scene, &opts)?;
    let path = output.join("seam-cube-seams.png");
    nlrt_render::image::write_png(&path, 2 * view.width, view.height, &view.rgb)
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

#[allow(clippy::too_many_arguments)]
fn animate_command(
    scene: &str,
    frames: usize,
    args: &RenderArgs,
    methods: Vec<Method>,
    tlas: TlasRule,
    deformation: Option<nlrt_render::animation::Deformation>,
    amplitude: f64,
    rebuild_frames: usize,
    verify: bool,
    output: PathBuf,
    seam_rule: nlrt_accel::SeamRule,
) -> ExitCode {
    use nlrt_render::animate::{self, AnimateOptions};
    use nlrt_render::animation::Motion;
    let mut built = match resolve_scene(scene, args.scene_size(), seam_rule) {
        Ok(s) => s,
        Err(e) => return fail("animate", e),
    };
    if !(amplitude.is_finite() && amplitude.abs() <= 10.0) {
        return fail(
            "animate",
            format!("--amplitude {amplitude} is out of range (|amplitude| <= 10)"),
        );
    }
    if let Some(deformation) = deformation {
        built.set_motion(Motion::Deform {
            deformation,
            amplitude,
        });
    }
    let defaults = AnimateOptions::default();
    let opts = AnimateOptions {
        frames,
        render: args.options(),
        methods: if methods.is_empty() {
            defaults.methods
        } else {
            methods
        },
        update: match tlas {
            TlasRule::Auto => nlrt_accel::TlasUpdate::DEFAULT,
            TlasRule::Refit => nlrt_accel::TlasUpdate::Refit,
            TlasRule::Rebuild => nlrt_accel::TlasUpdate::Rebuild,
        },
        rebuild_frames,
        verify,
        out_dir: Some(output.clone()),
    };
    let report = match animate::run(&built, &opts) {
        Ok(r) => r,
        Err(e) => return fail("animate", format!("{scene}: {e}")),
    };
    let md = format!("# nlrt animate {scene}\n\n{}", animate::markdown(&report));
    let path = output.join("animate.md");
    if let Err(e) = std::fs::write(&path, &md) {
        return fail("animate", format!("cannot write {}: {e}", path.display()));
    }
    print!("{md}");
    eprintln!("frames and animate.md written to {}", output.display());
    ExitCode::SUCCESS
}

/// `nlrt watertight` on one object of a scene (`built` traced alone, its `others` not looked
/// at): `scene` labels its rows and messages, `stem` names its leak images, `header` prints
/// the table's header first.
#[allow(clippy::too_many_arguments)]
fn judge_object(
    built: &scenes::Scene,
    scene: &str,
    stem: &str,
    header: bool,
    rays: u64,
    precision: Option<Precision>,
    method: Option<MethodKind>,
    ghost_samples: Option<u64>,
    frame: Option<u32>,
    frames: u32,
    output: &Option<PathBuf>,
) -> Result<(), String> {
    let side = ((rays as f64).sqrt().ceil() as usize).max(1);
    // Shell-mapped scenes are judged for nonlinear tracing only (the other judged
    // methods displace a height field); asking for another says so.
    let shell = matches!(built.content, scenes::Content::Shell(_));
    let mut methods = watertight::METHODS
        .into_iter()
        .filter(|m| {
            let precision_ok = match precision {
                Some(Precision::F32) => m.name().ends_with("f32"),
                Some(Precision::F64) => m.name().ends_with("f64"),
                None => true,
            };
            let method_ok = match method {
                Some(MethodKind::Nonlinear) => {
                    matches!(m, Method::NonlinearF32 | Method::NonlinearF64)
                }
                Some(MethodKind::TessellationFree) => {
                    matches!(m, Method::AffineF32 | Method::AffineF64)
                }
                Some(MethodKind::Marching) => {
                    matches!(m, Method::MarchingF32 | Method::MarchingF64)
                }
                Some(MethodKind::DistanceMap) => {
                    matches!(m, Method::DistanceMapF32 | Method::DistanceMapF64)
                }
                Some(MethodKind::Tetrahedra) => {
                    matches!(m, Method::TetrahedraF32 | Method::TetrahedraF64)
                }
                Some(
                    MethodKind::Tessellated
                    | MethodKind::Embree
                    | MethodKind::TessellatedCurved
                    | MethodKind::GeometryImage
                    | MethodKind::Projective
                    | MethodKind::Curved
                    | MethodKind::ConeRay
                    | MethodKind::ConeCone,
                ) => false,
                None => !shell || matches!(m, Method::NonlinearF32 | Method::NonlinearF64),
            };
            precision_ok && method_ok
        })
        .peekable();
    if methods.peek().is_none() {
        let judged: Vec<&str> = watertight::METHODS.iter().map(|m| m.slug()).collect();
        return Err(format!(
            "no method to judge: watertightness is measured for {} (the references are what it judges against; the other methods have no per-texel surface to decide leaks on)",
            judged.join(", ")
        ));
    }
    // Methods the scene's map does not suit (a cone or distance map on a map that is
    // not square with a power-of-two side) are left out, and said so; asked for alone,
    // the reason is the error.
    let (methods, unsupported): (Vec<Method>, Vec<Method>) =
        methods.partition(|m| shell || m.unsupported_reason_for_object(built).is_none());
    if let Some(first) = unsupported.first() {
        let why = first
            .unsupported_reason_for_object(built)
            .unwrap_or_default();
        if methods.is_empty() {
            return Err(format!("{scene}: {}: {why}", first.name()));
        }
        let names: Vec<&str> = unsupported.iter().map(|m| m.name()).collect();
        eprintln!("{scene}: not judged: {} ({why})", names.join(", "));
    }
    if header {
        println!(
            "| scene | method | rays | decided | leaks | rate | 95% interval | ghost hits (of hits judged) | grazing | too far | hit distance vs oracle: median / p99 / max rel. error (hits compared, unverified) | seconds |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    }
    let judged_hits = ghost_samples.map_or(watertight::JudgedHits::Every, |n| {
        watertight::JudgedHits::Spaced {
            ghosts: usize::try_from(n).unwrap_or(usize::MAX),
            distances: watertight::DISTANCE_SAMPLES,
        }
    });
    let at = frame.map(|k| (k as usize, frames as usize));
    let reports = match watertight::measure_all_at_frame(built, at, side, &methods, judged_hits) {
        Ok(r) => r,
        Err(e) => return Err(format!("{scene}: {e}")),
    };
    let label = frame.map_or(scene.to_string(), |k| {
        format!("{scene} frame {k} of {frames}")
    });
    let seams = built.describe_seams();
    if !seams.is_empty() {
        eprintln!("{scene}: {}", seams.trim_start_matches(", "));
    }
    let mut where_leaked = Vec::new();
    for r in reports {
        if !r.leak_edges.is_empty() {
            // At most this many places listed per method: enough to find them again.
            const LISTED: usize = 8;
            let places: Vec<String> = r
                .leak_edges
                .iter()
                .take(LISTED)
                .map(|e| {
                    format!(
                        "triangle {} edge {}{}: {}",
                        e.triangle,
                        e.edge,
                        if e.seam { " (seam)" } else { "" },
                        e.leaks
                    )
                })
                .collect();
            let more = r.leak_edges.len().saturating_sub(LISTED);
            where_leaked.push(format!(
                "{}: leaks by base triangle and nearest edge: {}{}",
                r.method,
                places.join(", "),
                if more > 0 {
                    format!(", and {more} more")
                } else {
                    String::new()
                }
            ));
        }
        let (lo, hi) = r.wilson_95();
        println!(
            "| {label} | {} | {} | {} | {} | {:.2e} | [{:.1e}, {:.1e}] | {} | {} | {:.1} |",
            r.method,
            r.rays,
            r.decided,
            r.leaks,
            r.rate(),
            lo,
            hi,
            ghost_cell(&r),
            distance_cell(&r),
            r.seconds
        );
        if let Some(dir) = output
            && !shell
        {
            let path = dir.join(format!("{stem}-leaks-{}.png", r.method.slug()));
            if let Err(e) = std::fs::create_dir_all(dir).and_then(|()| {
                nlrt_render::image::write_png(&path, side, side, &watertight::leak_image(&r))
            }) {
                return Err(format!("cannot write {}: {e}", path.display()));
            }
        }
    }
    for line in where_leaked {
        println!("{line}");
    }
    Ok(())
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let seam_rule = if cli.no_seam_fix {
        nlrt_accel::SeamRule::Open
    } else {
        nlrt_accel::SeamRule::Closed
    };
    let Some(command) = cli.command else {
        eprintln!("nlrt: no command given; running `nlrt report` (see `nlrt --help`)");
        let args = RenderArgs {
            size: DEFAULT_JOB_SIZE,
            spp: 1,
            bounces: 1,
            scene_size: SceneSize::Small,
            map_side: None,
        };
        return report_command(
            PathBuf::from("nlrt-report"),
            &args,
            REPORT_SOLVER_SAMPLES,
            Vec::new(),
            seam_rule,
        );
    };
    match command {
        Command::Render {
            scene,
            precision,
            method,
            args,
            output,
            aov,
        } => {
            let built = match resolve_scene(&scene, args.scene_size(), seam_rule) {
                Ok(s) => s,
                Err(e) => return fail("render", e),
            };
            let method = match (method, precision) {
                (MethodKind::Nonlinear, Precision::F32) => Method::NonlinearF32,
                (MethodKind::Nonlinear, Precision::F64) => Method::NonlinearF64,
                (MethodKind::TessellationFree, Precision::F32) => Method::AffineF32,
                (MethodKind::TessellationFree, Precision::F64) => Method::AffineF64,
                (MethodKind::GeometryImage, Precision::F32) => Method::GeometryImageF32,
                (MethodKind::GeometryImage, Precision::F64) => Method::GeometryImageF64,
                (MethodKind::Marching, Precision::F32) => Method::MarchingF32,
                (MethodKind::Marching, Precision::F64) => Method::MarchingF64,
                (MethodKind::DistanceMap, Precision::F32) => Method::DistanceMapF32,
                (MethodKind::DistanceMap, Precision::F64) => Method::DistanceMapF64,
                (MethodKind::Tetrahedra, Precision::F32) => Method::TetrahedraF32,
                (MethodKind::Tetrahedra, Precision::F64) => Method::TetrahedraF64,
                (MethodKind::Projective, Precision::F32) => Method::ProjectiveF32,
                (MethodKind::Projective, Precision::F64) => Method::ProjectiveF64,
                (MethodKind::ConeRay, Precision::F32) => Method::ConeRayF32,
                (MethodKind::ConeRay, Precision::F64) => Method::ConeRayF64,
                (MethodKind::ConeCone, Precision::F32) => Method::ConeConeF32,
                (MethodKind::ConeCone, Precision::F64) => Method::ConeConeF64,
                (MethodKind::Curved, Precision::F32) => Method::CurvedF32,
                (MethodKind::Curved, Precision::F64) => Method::CurvedF64,
                (MethodKind::Embree, _) => Method::EmbreeF32,
                (MethodKind::Tessellated, _) => Method::Tessellated,
                (MethodKind::TessellatedCurved, _) => Method::TessellatedCurved,
            };
            if let Some(why) = method.unsupported_reason(&built) {
                return fail("render", format!("{method} cannot render {scene}: {why}"));
            }
            // Scene files are checked in f64 when loaded; a value finite in f64 may not be
            // in f32.
            if method.slug().ends_with("-f32")
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
            if let Err(e) = nlrt_render::image::write_png(
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
        Command::Bench {
            scenes,
            args,
            no_reference,
            methods,
            no_ray_stream,
            json,
            rounds,
        } => {
            if rounds > 1 && no_ray_stream {
                return fail(
                    "bench",
                    "--rounds interleaves the ray stream's replays; it cannot go with --no-ray-stream",
                );
            }
            let scenes = if scenes.is_empty() {
                SCENE_NAMES.iter().map(|s| s.to_string()).collect()
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
                        let text = nlrt_render::bench_json::to_json(&opts, &rows);
                        if let Err(e) = file.write_all(text.as_bytes()) {
                            return fail("bench", format!("cannot write {}: {e}", path.display()));
                        }
                    }
                    ExitCode::SUCCESS
                }
                Err(e) => fail("bench", e),
            }
        }
        Command::Report {
            output,
            args,
            solver_samples,
            scenes,
        } => report_command(output, &args, solver_samples, scenes, seam_rule),
        Command::Edit {
            scene_size,
            strokes,
            brush,
            no_reference,
        } => {
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
        Command::Animate {
            scene,
            frames,
            args,
            methods,
            tlas,
            deformation,
            amplitude,
            rebuild_frames,
            no_verify,
            output,
        } => animate_command(
            &scene,
            frames as usize,
            &args,
            methods,
            tlas,
            deformation,
            amplitude,
            rebuild_frames as usize,
            !no_verify,
            output,
            seam_rule,
        ),
        Command::Export {
            scene,
            scene_size,
            output,
        } => {
            let built = match nlrt_render::scene_file::builtin_or_file(&scene, scene_size.into()) {
                Ok(s) => s,
                Err(e) => return fail("export", e),
            };
            // A scene file is written under its own stem (its scenes are all named "file").
            let name = std::path::Path::new(&scene)
                .file_stem()
                .and_then(|s| s.to_str())
                .filter(|_| scene.ends_with(".toml"))
                .unwrap_or(built.name);
            match nlrt_render::scene_file::export_as(&built, name, &output) {
                Ok(path) => {
                    println!("{scene} written to {}", path.display());
                    ExitCode::SUCCESS
                }
                Err(e) => fail("export", e),
            }
        }
        Command::Watertight {
            scene,
            rays,
            precision,
            method,
            scene_size,
            ghost_samples,
            frame,
            frames,
            output,
        } => {
            let built = if scene.ends_with(".toml") {
                match nlrt_render::scene_file::load(std::path::Path::new(&scene)) {
                    Ok(s) => s,
                    Err(e) => return fail("watertight", e),
                }
            } else {
                let known = scenes::is_builtin(&scene);
                match scenes::builtin(&scene, scene_size.into()).filter(|_| known) {
                    Some(s) => s,
                    None => {
                        return fail(
                            "watertight",
                            format!(
                                "unknown scene '{scene}' (scenes: {}, or a scene file *.toml)",
                                judged_scene_names().join(", ")
                            ),
                        );
                    }
                }
            };
            let mut built = built;
            built.set_seam_rule(seam_rule);
            if let Some(k) = frame
                && k >= frames
            {
                return fail(
                    "watertight",
                    format!(
                        "--frame {k} is not a frame of --frames {frames} (0 to {})",
                        frames - 1
                    ),
                );
            }
            // Scene files are checked in f64 when loaded; f32 is judged too unless excluded.
            if !matches!(precision, Some(Precision::F64))
                && let Err(e) = built.check_precision::<f32>()
            {
                return fail("watertight", format!("{scene}: {e}"));
            }
            for (k, object) in built.objects().enumerate() {
                let (label, stem) = if built.others.is_empty() {
                    (scene.clone(), scene.clone())
                } else {
                    (
                        format!("{scene} object {}", k + 1),
                        format!("{scene}-object-{}", k + 1),
                    )
                };
                if let Err(e) = judge_object(
                    object,
                    &label,
                    &stem,
                    k == 0,
                    rays,
                    precision,
                    method,
                    ghost_samples,
                    frame,
                    frames,
                    &output,
                ) {
                    return fail("watertight", e);
                }
            }
            ExitCode::SUCCESS
        }
        Command::Solvers {
            samples,
            seed,
            passes,
            output,
        } => {
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
}
