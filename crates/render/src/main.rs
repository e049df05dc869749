//! `nlrt`: the command-line tool of the nlrt workspace.
//!
//! With no arguments it runs the default job: the built-in scenes at a small size through
//! every method, and the report (Markdown and images) in `nlrt-report/`.

mod cli;

use clap::Parser;
use cli::args::{Cli, Command, RenderArgs, SceneSize};
use cli::common::{DEFAULT_JOB_SIZE, REPORT_SOLVER_SAMPLES};
use cli::report::report_command;
use std::path::PathBuf;
use std::process::ExitCode;

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
        Command::Render(c) => c.run(seam_rule),
        Command::Bench(c) => c.run(seam_rule),
        Command::Report(c) => c.run(seam_rule),
        Command::Watertight(c) => c.run(seam_rule),
        Command::Edit(c) => c.run(),
        Command::Animate(c) => c.run(seam_rule),
        Command::Export(c) => c.run(),
        Command::Solvers(c) => c.run(),
    }
}
