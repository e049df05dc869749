//! `nlrt animate`.

use super::args::*;
use super::common::*;
use nlrt_render::trace::method::Method;
use std::path::PathBuf;
use std::process::ExitCode;

impl AnimateCommand {
    /// Runs `nlrt animate`.
    pub fn run(self, seam_rule: nlrt_accel::SeamRule) -> ExitCode {
        let Self {
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
        } = self;
        animate_command(
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
        )
    }
}

#[allow(clippy::too_many_arguments)]
pub fn animate_command(
    scene: &str,
    frames: usize,
    args: &RenderArgs,
    methods: Vec<Method>,
    tlas: TlasRule,
    deformation: Option<nlrt_render::scene::motion::Deformation>,
    amplitude: f64,
    rebuild_frames: usize,
    verify: bool,
    output: PathBuf,
    seam_rule: nlrt_accel::SeamRule,
) -> ExitCode {
    use nlrt_render::lab::animate::{self, AnimateOptions};
    use nlrt_render::scene::motion::Motion;
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
