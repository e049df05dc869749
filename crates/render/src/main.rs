//! `nlrt`: the command-line tool of the nlrt workspace.
//!
//! With no arguments it runs the default job (for now the solver report; scenes come with the
//! renderer).

use clap::{Parser, Subcommand};
use nlrt_render::solvers;
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
}

#[derive(Subcommand)]
enum Command {
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let command = cli.command.unwrap_or(Command::Solvers {
        samples: solvers::Options::default().samples,
        seed: solvers::Options::default().seed,
        passes: solvers::Options::default().passes,
        output: None,
    });
    match command {
        Command::Solvers {
            samples,
            seed,
            passes,
            output,
        } => {
            if samples == 0 || passes == 0 {
                eprintln!("nlrt solvers: --samples and --passes must be at least 1");
                return ExitCode::from(2);
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
                eprintln!("nlrt solvers: cannot write {}: {e}", path.display());
                return ExitCode::from(2);
            }
            ExitCode::SUCCESS
        }
    }
}
