//! The command line: `nlrt`'s arguments, one struct per command.

use super::common::{REPORT_SOLVER_SAMPLES, scene_help};
use clap::{Parser, Subcommand, ValueEnum};
use nlrt_render::lab::solvers;
use nlrt_render::scene::scenes::Size;
use nlrt_render::trace::integrator::RenderOptions;
use nlrt_render::trace::method::{Kind, Method, Precision};
use std::path::PathBuf;
#[derive(Parser)]
#[command(
    name = "nlrt",
    version,
    about = "Nonlinear ray tracing of displaced and shell-mapped surfaces: renders, benchmarks and precision reports"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Leave the base mesh's uv and normal seams open (no welded displacement directions, no
    /// seam walls), to see and measure the cracks the seam rule closes.
    #[arg(long, global = true)]
    pub no_seam_fix: bool,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SceneSize {
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

pub fn parse_method(s: &str) -> Result<Method, String> {
    Method::from_slug(s).ok_or_else(|| {
        let names: Vec<&str> = Method::ALL.iter().map(|m| m.slug()).collect();
        format!("unknown method '{s}' (methods: {})", names.join(", "))
    })
}

pub fn parse_deformation(s: &str) -> Result<nlrt_render::scene::motion::Deformation, String> {
    nlrt_render::scene::motion::Deformation::from_name(s)
}

/// `--tlas`: how nonlinear tracing's TLAS follows a pose.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum TlasRule {
    /// Refit, rebuild when the SAH cost has grown past the default rule's factor.
    Auto,
    /// Refit every frame.
    Refit,
    /// Rebuild every frame.
    Rebuild,
}

pub fn parse_size(s: &str) -> Result<(usize, usize), String> {
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
pub struct RenderArgs {
    /// Image size.
    #[arg(long, value_parser = parse_size, default_value = "320x240")]
    pub size: (usize, usize),
    /// Samples per pixel.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    pub spp: u32,
    /// Diffuse bounces (each hit also casts a shadow ray).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(0..=16))]
    pub bounces: u32,
    /// Map sizes of the built-in scenes.
    #[arg(long, value_enum, default_value = "small")]
    pub scene_size: SceneSize,
    /// Every height map of the built-in scenes at this side (a power of two, 512 to 16384),
    /// the rest at the paper's sizes: a scale sweep, e.g. `bench mountain --map-side 8192`.
    /// Overrides --scene-size.
    #[arg(long, value_parser = parse_map_side)]
    pub map_side: Option<Size>,
}

/// `--map-side N`: [`Size::map_side`].
pub fn parse_map_side(text: &str) -> Result<Size, String> {
    let side: usize = text
        .parse()
        .map_err(|_| format!("'{text}' is not a whole number"))?;
    Size::map_side(side)
}

impl RenderArgs {
    /// The scene size: `--map-side` where given, else `--scene-size`.
    pub fn scene_size(&self) -> Size {
        self.map_side.unwrap_or(self.scene_size.into())
    }

    pub fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.size.0,
            height: self.size.1,
            spp: self.spp as usize,
            bounces: self.bounces as usize,
        }
    }
}

#[derive(Subcommand)]
pub enum Command {
    /// Render a built-in scene or a scene file to a PNG (nonlinear ray tracing unless
    /// `--method` says otherwise).
    Render(RenderCommand),
    /// Speed, init time, memory and 1-thread vs all-threads scaling per scene and method (no
    /// images written).
    Bench(BenchCommand),
    /// The full report: every scene and method, images, differences, and the solver table.
    Report(ReportCommand),
    /// Leaks, decided by exact arithmetic: rays that reach a base triangle from outside (so
    /// must have hit the displaced surface) but were not hit, or, on shell scenes, rays aimed
    /// at the object that pass its exact crossing; and ghost hits of nonlinear tracing: hits
    /// in front of the true surface, judged by the MPFR oracle.
    Watertight(WatertightCommand),
    /// Time from a brush stroke on the mountain's height map to the next traceable frame:
    /// partial min-max update, full rebuild, re-tessellation.
    Edit(EditCommand),
    /// Animate a scene's base mesh: per frame, nonlinear tracing refits (or rebuilds) only its
    /// TLAS; every other method is built afresh on the posed mesh. Writes the frames and
    /// `animate.md` (update and render times, checks against fresh builds).
    Animate(AnimateCommand),
    /// Write a built-in scene (or a scene file, rewritten with its objects placed) as a scene
    /// file (TOML + OBJ + 16-bit PNG or object OBJ, per object).
    Export(ExportCommand),
    /// Speed against error of the cubic solvers (nlrt-poly, closed form, `roots` crate) for
    /// f32 and f64, judged by the MPFR oracle.
    Solvers(SolversCommand),
}

/// The arguments of `nlrt render`.
#[derive(clap::Args)]
pub struct RenderCommand {
    #[arg(help = scene_help("A built-in scene"))]
    pub scene: String,
    /// Precision of the intersection (the pre-tessellated reference is always f64).
    #[arg(long, value_enum, default_value = "f32")]
    pub precision: Precision,
    /// Intersection method.
    #[arg(long, value_enum, default_value = "nonlinear")]
    pub method: Kind,
    #[command(flatten)]
    pub args: RenderArgs,
    /// Output PNG.
    #[arg(short, long, default_value = "nlrt.png")]
    pub output: PathBuf,
    /// Also write the primary hits' depth, normal and hit id (base triangle) to this
    /// OpenEXR file (32-bit float channels Z, N.X, N.Y, N.Z; unsigned integer id).
    #[arg(long)]
    pub aov: Option<PathBuf>,
}

/// The arguments of `nlrt bench`.
#[derive(clap::Args)]
pub struct BenchCommand {
    #[arg(help = scene_help("Scenes (default: every built-in one but the variants), each a built-in scene"))]
    pub scenes: Vec<String>,
    #[command(flatten)]
    pub args: RenderArgs,
    /// Leave out the pre-tessellated references (their build dominates at paper sizes).
    #[arg(long)]
    pub no_reference: bool,
    /// Only these methods (comma-separated slugs, e.g. nonlinear-f32, marching-f64,
    /// curved-f32, tessellated-f64; an unknown one lists them all; default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_method)]
    pub methods: Vec<Method>,
    /// Leave out the replay of one recorded ray stream per scene into every method (the
    /// stream columns: the same rays for every method, timed without shading).
    #[arg(long)]
    pub no_ray_stream: bool,
    /// Also write every column as JSON to this file, with the machine, the build's target
    /// features and the commit (format `nlrt-bench/1`, described in `docs/measurements.md`).
    #[arg(long, value_name = "FILE")]
    pub json: Option<PathBuf>,
    /// Replay each scene's ray stream in this many interleaved rounds (every method in turn
    /// per round, all threads then one thread): the stream's "all" columns become the
    /// rounds' medians, and a table gives each round's ratio to the scene's first method
    /// with their median and spread (in the JSON too). Keeps every method's acceleration
    /// data alive at once. 1: one replay per method, no rounds.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1000))]
    pub rounds: u32,
}

/// The arguments of `nlrt report`.
#[derive(clap::Args)]
pub struct ReportCommand {
    /// Output directory.
    #[arg(short, long, default_value = "nlrt-report")]
    pub output: PathBuf,
    #[command(flatten)]
    pub args: RenderArgs,
    /// Random cubics per precision for the solver table.
    #[arg(long, default_value_t = REPORT_SOLVER_SAMPLES)]
    pub solver_samples: usize,
    /// The scenes of the speed-and-error table (comma-separated built-in names or scene
    /// files `*.toml`; default: every built-in one but the variants). The watertightness
    /// section judges the built-in judged scenes whatever this says.
    #[arg(long, value_delimiter = ',')]
    pub scenes: Vec<String>,
}

/// The arguments of `nlrt watertight`.
#[derive(clap::Args)]
pub struct WatertightCommand {
    /// Displacement scene: torus, fur, mountain, mountain-grazing, fig9-displaced, plateau,
    /// plateau-grazing, the ghost-hit tori torus-spikes, torus-tilted, torus-twisted, the
    /// uv-seam scenes
    /// seam-cube, seam-sphere (or cylinder, whose open ends make only part of its rays
    /// decidable); shell scene: scales, feathers, cornell, highpoly, fig9 (nonlinear
    /// tracing only); or a scene file (`*.toml`).
    pub scene: String,
    /// Rays: a square grid of camera rays with at least this many (on shell scenes, rays
    /// aimed at the object).
    #[arg(long, default_value_t = 65_536, value_parser = clap::value_parser!(u64).range(1..=100_000_000))]
    pub rays: u64,
    /// Precision (default: both).
    #[arg(long, value_enum)]
    pub precision: Option<Precision>,
    /// Method (default: nonlinear and tessellation-free).
    #[arg(long, value_enum)]
    pub method: Option<Kind>,
    /// Map sizes of the built-in scenes.
    #[arg(long, value_enum, default_value = "small")]
    pub scene_size: SceneSize,
    /// Judge about this many of nonlinear tracing's hits for ghosts, evenly spaced (default:
    /// every hit, about 0.3 ms of one core each).
    #[arg(long, value_parser = clap::value_parser!(u64).range(1..))]
    pub ghost_samples: Option<u64>,
    /// Judge this frame of the scene's motion (`nlrt animate`'s frame numbers, from 0):
    /// nonlinear tracing is moved there by pose updates from the rest pose.
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    pub frame: Option<u32>,
    /// Frames of the motion's cycle, for `--frame`.
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    /// Directory for the leak images (`<scene>-leaks-<method>.png`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}

/// The arguments of `nlrt edit`.
#[derive(clap::Args)]
pub struct EditCommand {
    /// Map size (small: 1024^2, paper: 4096^2).
    #[arg(long, value_enum, default_value = "small")]
    pub scene_size: SceneSize,
    /// Strokes timed.
    #[arg(long, default_value_t = 200, value_parser = clap::value_parser!(u64).range(1..=100_000))]
    pub strokes: u64,
    /// Brush side in samples.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=4096))]
    pub brush: u64,
    /// Skip the pre-tessellated rebuild (at paper size it needs several GB).
    #[arg(long)]
    pub no_reference: bool,
}

/// The arguments of `nlrt animate`.
#[derive(clap::Args)]
pub struct AnimateCommand {
    #[arg(help = scene_help("A built-in scene (each has a motion)"))]
    pub scene: String,
    /// Frames (one cycle of a deformation).
    #[arg(long, default_value_t = 16, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub frames: u32,
    #[command(flatten)]
    pub args: RenderArgs,
    /// Methods (comma-separated slugs; default nonlinear-f32,nonlinear-f64,tessellated-f64).
    #[arg(long, value_delimiter = ',', value_parser = parse_method)]
    pub methods: Vec<Method>,
    /// How nonlinear tracing's TLAS follows each pose: refit, rebuild, or auto (refit,
    /// rebuilt when its SAH cost has grown by the default rule's factor).
    #[arg(long, value_enum, default_value = "auto")]
    pub tlas: TlasRule,
    /// Replace the scene's motion by this deformation of its base mesh (wave, bend,
    /// twist, breathe, squash).
    #[arg(long, value_parser = parse_deformation)]
    pub deformation: Option<nlrt_render::scene::motion::Deformation>,
    /// Strength of `--deformation` (1 the built-in one; |amplitude| <= 10).
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub amplitude: f64,
    /// Frames rendered by the methods built afresh per frame (the pre-tessellated
    /// reference, Embree): their rebuild does not depend on the pose.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=100_000))]
    pub rebuild_frames: u32,
    /// Do not build nonlinear tracing afresh each frame to compare hits and speed with.
    #[arg(long)]
    pub no_verify: bool,
    /// Output directory (frames `<scene>-<method>-<frame>.png`, `animate.md`).
    #[arg(short, long, default_value = "nlrt-animate")]
    pub output: PathBuf,
}

/// The arguments of `nlrt export`.
#[derive(clap::Args)]
pub struct ExportCommand {
    #[arg(help = scene_help("A built-in scene"))]
    pub scene: String,
    /// Map sizes.
    #[arg(long, value_enum, default_value = "small")]
    pub scene_size: SceneSize,
    /// Output directory.
    #[arg(short, long, default_value = "scenes/builtin")]
    pub output: PathBuf,
}

/// The arguments of `nlrt solvers`.
#[derive(clap::Args)]
pub struct SolversCommand {
    /// Random cubics per precision, split evenly over the random families.
    #[arg(long, default_value_t = solvers::Options::default().samples)]
    pub samples: usize,
    /// Seed of the random families.
    #[arg(long, default_value_t = solvers::Options::default().seed)]
    pub seed: u64,
    /// Timed passes per row; the median is reported.
    #[arg(long, default_value_t = solvers::Options::default().passes)]
    pub passes: usize,
    /// Also write the table (Markdown) to this file.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
}
