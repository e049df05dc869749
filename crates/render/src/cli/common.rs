//! What the commands share: the error exit, scene names and lookup, table cells, the default
//! job's sizes.

use nlrt_render::lab::watertight;
use nlrt_render::scene::scenes::{self, Size, Tag, names};
use std::process::ExitCode;
/// Image size `WxH`.
pub fn distance_cell(r: &watertight::LeakReport) -> String {
    r.distance_error.map_or("-".into(), |d| {
        format!(
            "{:.1e} / {:.1e} / {:.1e} ({}, {})",
            d.median, d.p99, d.max, d.samples, d.unverified
        )
    })
}

/// Ghost hits, grazing near misses and hits too far among the hits judged by the oracle, or
/// `-`.
pub fn ghost_cell(r: &watertight::LeakReport) -> String {
    r.ghosts.as_ref().map_or("- | - | -".into(), |g| {
        format!("{} of {} | {} | {}", g.ghosts, g.hits, g.grazing, g.too_far)
    })
}

/// A watertightness table row up to its distance cell: label, method, rays, decided, leaks,
/// rate, its 95% interval, ghost hits, grazing, too far and the distances.
pub fn leak_row(label: &str, r: &watertight::LeakReport) -> String {
    let (lo, hi) = r.wilson_95();
    format!(
        "| {label} | {} | {} | {} | {} | {:.2e} | [{:.1e}, {:.1e}] | {} | {} |",
        r.method,
        r.rays,
        r.decided,
        r.leaks,
        r.rate(),
        lo,
        hi,
        ghost_cell(r),
        distance_cell(r)
    )
}

pub fn fail(command: &str, message: impl std::fmt::Display) -> ExitCode {
    eprintln!("nlrt {command}: {message}");
    ExitCode::from(2)
}

pub fn check_scenes(asked: &[String]) -> Result<(), String> {
    for n in asked {
        if !(scenes::is_builtin(n) || n.ends_with(".toml")) {
            return Err(format!(
                "unknown scene '{n}' (built-in scenes: {}; variants: {})",
                names(Tag::Report).join(", "),
                names(Tag::Variant).join(", ")
            ));
        }
    }
    Ok(())
}

/// The built-in scenes and variants as the help lists them (from the list the code builds,
/// so the help cannot fall behind it).
pub fn builtin_list() -> String {
    format!(
        "{}; variants {}",
        names(Tag::Report).join(", "),
        names(Tag::Variant).join(", ")
    )
}

/// Help for a scene argument: `what` (built-in scenes listed) or a scene file.
pub fn scene_help(what: &str) -> String {
    format!(
        "{what} ({}) or a scene file (`*.toml`, see the README)",
        builtin_list()
    )
}

/// A built-in scene by name, or a scene file (`*.toml`).
pub fn resolve_scene(
    name: &str,
    size: Size,
    seam_rule: nlrt_accel::SeamRule,
) -> Result<scenes::Scene, String> {
    let mut scene = nlrt_render::scene::scene_file::builtin_or_file(name, size)?;
    scene.set_seam_rule(seam_rule);
    Ok(scene)
}

/// Hits per scene and precision the report judges for ghosts: the oracle's 0.3 ms per hit
/// keeps the default job's watertightness section within seconds (`nlrt watertight` judges
/// every hit).
pub const REPORT_GHOST_SAMPLES: usize = 4096;

/// Hits per scene and precision whose distance the report compares with the oracle's: at
/// `watertight::DISTANCE_SAMPLES` (1,024) they took about 4 s per scene of the torus and the
/// fur on a 2-core machine, a third of the default job's watertightness section.
pub const REPORT_DISTANCE_SAMPLES: usize = 256;

/// Image size of the default job (`cargo run --release`): at 320 x 240, the size of
/// `nlrt report`, its scene renders took 129 s of a 176 s job on a 2-core machine, too near
/// its 3 minutes on a loaded one; 256 x 192 has 0.64 of the pixels (the job's time is in
/// docs/measurements.md, "Whole renders").
pub const DEFAULT_JOB_SIZE: (usize, usize) = (256, 192);

/// Side of the report's watertightness grid (16,384 rays per scene): at 256^2 the section
/// took 72 s of the default job on a 2-core machine, which must stay under 3 minutes;
/// `nlrt watertight --rays N` judges as many as asked (the 1M-ray tables of
/// docs/watertightness.md).
pub const REPORT_WATERTIGHT_GRID: usize = 128;

/// Cubics per precision in the report's solver table (`nlrt report --solver-samples`,
/// `nlrt solvers --samples` for more): 50,000 took 31 s of the default job (same run).
pub const REPORT_SOLVER_SAMPLES: usize = 20_000;
