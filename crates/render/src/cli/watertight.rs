//! `nlrt watertight`: each object of a scene judged against the oracle.

use super::args::*;
use super::common::*;
use nlrt_render::lab::watertight;
use nlrt_render::scene::scenes::{self};
use nlrt_render::trace::method::{Kind, Method, Precision};
use std::path::PathBuf;
use std::process::ExitCode;

impl WatertightCommand {
    /// Runs `nlrt watertight`.
    pub fn run(self, seam_rule: nlrt_accel::SeamRule) -> ExitCode {
        let Self {
            scene,
            rays,
            precision,
            method,
            scene_size,
            ghost_samples,
            frame,
            frames,
            output,
        } = self;
        let built = match resolve_scene(&scene, scene_size.into(), seam_rule) {
            Ok(built) => built,
            Err(e) => return fail("watertight", e),
        };
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
            // Leak images are named after the scene, or a scene file's stem (a path is no
            // file name).
            let file_stem = std::path::Path::new(&scene)
                .file_stem()
                .and_then(|s| s.to_str())
                .filter(|_| scene.ends_with(".toml"))
                .unwrap_or(&scene);
            let (label, stem) = if built.others.is_empty() {
                (scene.clone(), file_stem.to_string())
            } else {
                (
                    format!("{scene} object {}", k + 1),
                    format!("{file_stem}-object-{}", k + 1),
                )
            };
            let judging = Judging {
                rays,
                precision,
                method,
                ghost_samples,
                frame,
                frames,
                output: &output,
            };
            if let Err(e) = judge_object(object, &label, &stem, k == 0, judging) {
                return fail("watertight", e);
            }
        }
        ExitCode::SUCCESS
    }
}

/// How `nlrt watertight` judges each object: its arguments.
#[derive(Clone, Copy)]
pub struct Judging<'a> {
    /// Rays (at least; a square grid).
    pub rays: u64,
    /// Only this precision.
    pub precision: Option<Precision>,
    /// Only this kind of method.
    pub method: Option<Kind>,
    /// Hits judged for ghosts (`None`: every hit).
    pub ghost_samples: Option<u64>,
    /// The frame of the motion judged.
    pub frame: Option<u32>,
    /// Frames of the motion's cycle.
    pub frames: u32,
    /// Directory of the leak images.
    pub output: &'a Option<PathBuf>,
}

/// `nlrt watertight` on one object of a scene (`built` traced alone, its `others` not looked
/// at): `scene` labels its rows and messages, `stem` names its leak images, `header` prints
/// the table's header first.
pub fn judge_object(
    built: &scenes::Scene,
    scene: &str,
    stem: &str,
    header: bool,
    judging: Judging<'_>,
) -> Result<(), String> {
    let Judging {
        rays,
        precision,
        method,
        ghost_samples,
        frame,
        frames,
        output,
    } = judging;
    let side = ((rays as f64).sqrt().ceil() as usize).max(1);
    // Shell-mapped scenes are judged for nonlinear tracing only (the other judged
    // methods displace a height field); asking for another says so.
    let shell = matches!(built.content, scenes::Content::Shell(_));
    let mut methods = watertight::METHODS
        .into_iter()
        .filter(|m| {
            let precision_ok = precision.is_none_or(|p| m.precision() == p);
            let method_ok = match method {
                Some(kind) => m.kind() == kind,
                None => !shell || m.kind() == Kind::Nonlinear,
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
        println!("{} {:.1} |", leak_row(&label, &r), r.seconds);
        if let Some(dir) = output
            && !shell
        {
            let path = dir.join(format!("{stem}-leaks-{}.png", r.method.slug()));
            if let Err(e) = std::fs::create_dir_all(dir).and_then(|()| {
                nlrt_render::trace::image::write_png(&path, side, side, &watertight::leak_image(&r))
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
