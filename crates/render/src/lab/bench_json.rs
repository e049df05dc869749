//! `nlrt bench --json FILE`: every column of the bench table with the machine, the build's
//! target features and the commit, so that runs can be compared by scripts.
//!
//! The file is one JSON object:
//!
//! ```json
//! { "format": "nlrt-bench/1", "date_utc": "2026-12-02T19:00:00Z",
//!   "nlrt": { "version": "0.1.0", "commit": "4a18df6...", "dirty": false },
//!   "machine": { "cpu": "...", "logical_cores": 2, "os": "linux", "arch": "x86_64" },
//!   "build": { "target_features": ["fma", "avx2"] },
//!   "settings": { "width": 320, "height": 240, "spp": 1, "bounces": 1, "threads": 2,
//!                 "scene_size": "paper" },
//!   "rows": [ { "scene": "mountain", "method": "nonlinear-f32", ... } ] }
//! ```
//!
//! A row holds the seconds and ray counts the rates come from; the error fields are `null`
//! where the table shows `-`. With `--rounds N` (N >= 2) a row's `rounds` holds every round's
//! replays and the ratios to the scene's first method (per round, median, smallest, largest).

use crate::lab::report::{
    ErrorStats, MethodRun, ReportOptions, RoundRatios, TableRow, round_ratios,
};
use crate::trace::ray_stream::Replay;
use serde::Serialize;

/// The commit the binary was built from (`build.rs`; `unknown` outside a git checkout).
const COMMIT: &str = env!("NLRT_COMMIT");
/// Whether the checkout had uncommitted changes to tracked files when built.
const DIRTY: &str = env!("NLRT_DIRTY");

/// Error of a row's primary rays against another method ([`ErrorStats`]).
#[derive(Clone, Debug, Serialize)]
pub struct ErrorFields {
    /// Against which method (its slug).
    pub against: String,
    /// Pixels where one hits and the other misses.
    pub mismatches: usize,
    /// Pixels compared.
    pub pixels: usize,
    /// Median relative depth difference over pixels both hit.
    pub depth_median: f64,
    /// 99th percentile of the relative depth difference.
    pub depth_p99: f64,
    /// Largest relative depth difference.
    pub depth_max: f64,
}

impl ErrorFields {
    fn new(against: &str, e: &ErrorStats) -> Self {
        Self {
            against: against.to_string(),
            mismatches: e.mismatches,
            pixels: e.pixels,
            depth_median: e.depth_median,
            depth_p99: e.depth_p99,
            depth_max: e.depth_max,
        }
    }
}

/// One replay of a ray stream ([`Replay`]).
#[derive(Clone, Debug, Serialize)]
pub struct ReplayFields {
    /// Rays traced.
    pub rays: u64,
    /// Rays that hit.
    pub hits: u64,
    /// Seconds.
    pub seconds: f64,
    /// Million rays per second.
    pub mrays_per_s: f64,
}

impl ReplayFields {
    fn new(r: &Replay) -> Self {
        Self {
            rays: r.rays,
            hits: r.hits,
            seconds: r.seconds,
            mrays_per_s: r.mrays(),
        }
    }
}

/// A method's replays of the scene's ray stream ([`crate::lab::report::StreamTimes`]).
#[derive(Clone, Debug, Serialize)]
pub struct StreamFields {
    /// The primary rays, every thread.
    pub primary: ReplayFields,
    /// Every ray, every thread.
    pub all: ReplayFields,
    /// Every ray, one thread.
    pub all_one_thread: ReplayFields,
}

/// Ratios of a method's rates to another's over the rounds ([`RoundRatios`]).
#[derive(Clone, Debug, Serialize)]
pub struct RatioFields {
    /// Per round.
    pub per_round: Vec<f64>,
    /// Their median.
    pub median: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
}

impl RatioFields {
    fn new(r: RoundRatios) -> Self {
        Self {
            per_round: r.per_round,
            median: r.median,
            min: r.min,
            max: r.max,
        }
    }
}

/// A method's interleaved rounds of the scene's stream ([`crate::lab::report::RoundTimes`]).
#[derive(Clone, Debug, Serialize)]
pub struct RoundsFields {
    /// The method the ratios are against (the scene's first; its slug).
    pub against: String,
    /// Every ray, all threads, per round.
    pub all: Vec<ReplayFields>,
    /// Every ray, one thread, per round.
    pub all_one_thread: Vec<ReplayFields>,
    /// All threads: this method's rate over the first method's.
    pub ratio_all: RatioFields,
    /// One thread: the same.
    pub ratio_all_one_thread: RatioFields,
}

/// One scene and method: a row of the bench table.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    /// Scene name.
    pub scene: String,
    /// Method slug (as `--methods` takes it).
    pub method: String,
    /// Method name (as the table shows it).
    pub method_name: String,
    /// Seconds to build the acceleration data.
    pub init_seconds: f64,
    /// Bytes of the acceleration data.
    pub memory_bytes: usize,
    /// Primary rays traced.
    pub primary_rays: u64,
    /// Rays of every kind traced.
    pub all_rays: u64,
    /// Seconds of the render on every thread.
    pub seconds: f64,
    /// Million primary rays per second.
    pub primary_mrays_per_s: f64,
    /// Million rays (all kinds) per second.
    pub all_mrays_per_s: f64,
    /// Seconds of the same render on one thread (`null` when not measured).
    pub one_thread_seconds: Option<f64>,
    /// The scene's recorded ray stream replayed into this method (`null` without it).
    pub stream: Option<StreamFields>,
    /// The interleaved rounds (`--rounds N`, N >= 2; `null` otherwise).
    pub rounds: Option<RoundsFields>,
    /// Against the f64 pre-tessellated reference (`null` when it did not run).
    pub vs_reference: Option<ErrorFields>,
    /// Against the method's f64 partner (`null` when it did not run).
    pub vs_f64: Option<ErrorFields>,
}

impl BenchRow {
    /// The row of `run` on `scene`, with its errors against the reference and the f64
    /// partner where they ran.
    #[must_use]
    pub fn new(
        scene: &str,
        run: &MethodRun,
        first: Option<&MethodRun>,
        vs_reference: Option<ErrorStats>,
        vs_f64: Option<ErrorStats>,
    ) -> Self {
        let m = run.method;
        let rounds = first.and_then(|first| {
            let (all, one) = round_ratios(run, first)?;
            Some(RoundsFields {
                against: first.method.slug().to_string(),
                all: run
                    .rounds
                    .iter()
                    .map(|r| ReplayFields::new(&r.all))
                    .collect(),
                all_one_thread: run
                    .rounds
                    .iter()
                    .map(|r| ReplayFields::new(&r.all_one_thread))
                    .collect(),
                ratio_all: RatioFields::new(all),
                ratio_all_one_thread: RatioFields::new(one),
            })
        });
        Self {
            scene: scene.to_string(),
            method: m.slug().to_string(),
            method_name: m.to_string(),
            init_seconds: run.init_seconds,
            memory_bytes: run.memory_bytes,
            primary_rays: run.frame.primary_rays,
            all_rays: run.frame.all_rays,
            seconds: run.frame.seconds,
            primary_mrays_per_s: run.primary_mrays(),
            all_mrays_per_s: run.all_mrays(),
            one_thread_seconds: run.one_thread_seconds,
            stream: run.stream.map(|st| StreamFields {
                primary: ReplayFields::new(&st.primary),
                all: ReplayFields::new(&st.all),
                all_one_thread: ReplayFields::new(&st.all_one_thread),
            }),
            rounds,
            vs_reference: vs_reference.map(|e| ErrorFields::new(m.reference().slug(), &e)),
            vs_f64: vs_f64.map(|e| ErrorFields::new(m.f64_partner().slug(), &e)),
        }
    }
}

#[derive(Serialize)]
struct Version {
    version: &'static str,
    commit: &'static str,
    dirty: bool,
}

#[derive(Serialize)]
struct Machine {
    cpu: String,
    logical_cores: usize,
    os: &'static str,
    arch: &'static str,
}

#[derive(Serialize)]
struct Build {
    target_features: Vec<&'static str>,
}

#[derive(Serialize)]
struct Settings {
    width: usize,
    height: usize,
    spp: usize,
    bounces: usize,
    threads: usize,
    scene_size: String,
}

#[derive(Serialize)]
struct BenchFile<'a> {
    format: &'static str,
    date_utc: String,
    nlrt: Version,
    machine: Machine,
    build: Build,
    settings: Settings,
    rows: &'a [BenchRow],
}

/// The CPU's model name (`/proc/cpuinfo` on Linux), else `unknown`.
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// `YYYY-MM-DDTHH:MM:SSZ` of a Unix time (the proleptic Gregorian calendar; H. Hinnant's
/// days-to-civil algorithm).
#[must_use]
pub fn utc_timestamp(unix_seconds: u64) -> String {
    let days = (unix_seconds / 86_400) as i64;
    let secs = unix_seconds % 86_400;
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = doy - (153 * mp + 2) / 5 + 1;
    let month = if mp < 10 { mp + 3 } else { mp - 9 };
    let year = yoe + era * 400 + i64::from(month <= 2);
    format!(
        "{year:04}-{month:02}-{day:02}T{:02}:{:02}:{:02}Z",
        secs / 3600,
        secs / 60 % 60,
        secs % 60
    )
}

/// The bench file's text for the table `rows` measured with `opts`.
#[must_use]
pub fn to_json(opts: &ReportOptions, rows: &[TableRow]) -> String {
    let rows: Vec<BenchRow> = rows
        .iter()
        .map(|r| {
            let first = rows
                .iter()
                .find(|f| f.scene == r.scene && !f.run.rounds.is_empty());
            BenchRow::new(
                &r.scene,
                &r.run,
                first.map(|f| &f.run),
                r.vs_reference,
                r.vs_f64,
            )
        })
        .collect();
    let now = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs());
    let file = BenchFile {
        format: "nlrt-bench/1",
        date_utc: utc_timestamp(now),
        nlrt: Version {
            version: env!("CARGO_PKG_VERSION"),
            commit: COMMIT,
            dirty: DIRTY == "true",
        },
        machine: Machine {
            cpu: cpu_model(),
            logical_cores: std::thread::available_parallelism().map_or(0, usize::from),
            os: std::env::consts::OS,
            arch: std::env::consts::ARCH,
        },
        build: Build {
            target_features: crate::lab::solvers::target_feature_list(),
        },
        settings: Settings {
            width: opts.render.width,
            height: opts.render.height,
            spp: opts.render.spp,
            bounces: opts.render.bounces,
            threads: rayon::current_num_threads(),
            scene_size: format!("{:?}", opts.size).to_lowercase(),
        },
        rows: &rows,
    };
    // Serializing plain numbers, strings and options cannot fail; NaN (a failed one-thread
    // pool) becomes null.
    serde_json::to_string_pretty(&file).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}

#[cfg(test)]
mod tests {
    use super::utc_timestamp;

    /// Known instants, leap days and the end of a century included.
    #[test]
    fn timestamps_are_the_calendar_dates() {
        assert_eq!(utc_timestamp(0), "1970-01-01T00:00:00Z");
        assert_eq!(utc_timestamp(951_782_400), "2000-02-29T00:00:00Z");
        assert_eq!(utc_timestamp(1_798_229_096), "2026-12-25T20:04:56Z");
        assert_eq!(utc_timestamp(4_107_542_399), "2100-02-28T23:59:59Z");
        assert_eq!(utc_timestamp(4_107_542_400), "2100-03-01T00:00:00Z");
    }
}
