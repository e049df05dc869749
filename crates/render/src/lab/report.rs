//! `nlrt report` and `nlrt bench`: per scene and method, speed (Mrays/s of primary and of all
//! rays), init time, memory, and error against the f64 pre-tessellated reference (hit/miss
//! mismatches and depth error of the primary rays), with images.

use crate::scene::scenes::{Scene, Size};
use crate::trace::image::write_png;
use crate::trace::integrator::{Frame, RenderOptions, render, render_recording};
use crate::trace::method::{Kind, Method, Precision};
use crate::trace::ray_stream::{RayKind, RayStream, Replay, replay};
use crate::trace::tracer::Tracer;
use std::fmt::Write as _;
use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Error of a frame's primary rays against a reference frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ErrorStats {
    /// Pixels where one frame hits and the other misses.
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

impl ErrorStats {
    /// Mismatch rate.
    #[must_use]
    pub fn mismatch_rate(&self) -> f64 {
        self.mismatches as f64 / self.pixels.max(1) as f64
    }
}

/// Compares the primary-ray depths of `frame` with `reference`.
#[must_use]
pub fn compare(frame: &Frame, reference: &Frame) -> ErrorStats {
    let mut rel = Vec::new();
    let mut mismatches = 0;
    for (&a, &b) in frame.depth.iter().zip(&reference.depth) {
        match (a.is_nan(), b.is_nan()) {
            (true, true) => {}
            (false, false) => rel.push((a - b).abs() / b.abs().max(1e-300)),
            _ => mismatches += 1,
        }
    }
    rel.sort_by(f64::total_cmp);
    let q = |p: f64| {
        if rel.is_empty() {
            0.0
        } else {
            rel[((rel.len() - 1) as f64 * p).round() as usize]
        }
    };
    ErrorStats {
        mismatches,
        pixels: frame.depth.len(),
        depth_median: q(0.5),
        depth_p99: q(0.99),
        depth_max: q(1.0),
    }
}

/// One method on one scene.
#[derive(Clone, Debug)]
pub struct MethodRun {
    /// The method.
    pub method: Method,
    /// Seconds to build its acceleration data (time to first pixel).
    pub init_seconds: f64,
    /// Bytes of its acceleration data.
    pub memory_bytes: usize,
    /// The frame.
    pub frame: Frame,
    /// Seconds of the same render on one thread (when measured).
    pub one_thread_seconds: Option<f64>,
    /// The scene's recorded ray stream replayed into this method (when measured).
    pub stream: Option<StreamTimes>,
    /// The interleaved rounds of the stream's replay (`--rounds N`, N >= 2; empty otherwise):
    /// in each round every method traced the stream in turn.
    pub rounds: Vec<RoundTimes>,
}

/// One round of the interleaved replays ([`ReportOptions::rounds`]).
#[derive(Clone, Copy, Debug)]
pub struct RoundTimes {
    /// Every ray, all threads.
    pub all: Replay,
    /// Every ray, one thread.
    pub all_one_thread: Replay,
}

/// The ratios of one method's rates to another's, round by round, with their median and
/// spread.
#[derive(Clone, Debug, PartialEq)]
pub struct RoundRatios {
    /// This method's rate over the other's, per round.
    pub per_round: Vec<f64>,
    /// Their median (the mean of the middle two for an even count).
    pub median: f64,
    /// The smallest.
    pub min: f64,
    /// The largest.
    pub max: f64,
}

impl RoundRatios {
    /// `rate(mine[i]) / rate(theirs[i])` for each round both have; `None` without rounds.
    #[must_use]
    pub fn new(mine: &[Replay], theirs: &[Replay]) -> Option<Self> {
        let per_round: Vec<f64> = mine
            .iter()
            .zip(theirs)
            .map(|(a, b)| a.mrays() / b.mrays())
            .collect();
        let mut sorted = per_round.clone();
        sorted.sort_by(f64::total_cmp);
        let n = sorted.len();
        let median = match n {
            0 => return None,
            _ if n % 2 == 1 => sorted[n / 2],
            _ => 0.5 * (sorted[n / 2 - 1] + sorted[n / 2]),
        };
        Some(Self {
            median,
            min: sorted[0],
            max: sorted[n - 1],
            per_round,
        })
    }
}

/// The replay of median duration among `replays` (the lower middle one for an even count).
fn median_replay(replays: impl Iterator<Item = Replay>) -> Option<Replay> {
    let mut all: Vec<Replay> = replays.collect();
    all.sort_by(|a, b| a.seconds.total_cmp(&b.seconds));
    all.get(all.len().saturating_sub(1) / 2).copied()
}

/// One method's replays of a scene's recorded ray stream ([`crate::trace::ray_stream`]).
#[derive(Clone, Copy, Debug)]
pub struct StreamTimes {
    /// Every ray, all threads.
    pub all: Replay,
    /// The primary rays, all threads.
    pub primary: Replay,
    /// Every ray, one thread.
    pub all_one_thread: Replay,
}

impl MethodRun {
    /// Million primary rays per second.
    #[must_use]
    pub fn primary_mrays(&self) -> f64 {
        self.frame.primary_rays as f64 / self.frame.seconds / 1e6
    }

    /// Million rays (all kinds) per second.
    #[must_use]
    pub fn all_mrays(&self) -> f64 {
        self.frame.all_rays as f64 / self.frame.seconds / 1e6
    }
}

/// Options of a report or bench run.
#[derive(Clone, Debug)]
pub struct ReportOptions {
    /// Scene names.
    pub scenes: Vec<String>,
    /// Scene sizes.
    pub size: Size,
    /// Render settings.
    pub render: RenderOptions,
    /// Methods.
    pub methods: Vec<Method>,
    /// Where images and the report go (`None`: nowhere).
    pub out_dir: Option<PathBuf>,
    /// Also render on one thread and report the speed-up of all threads over it.
    pub scaling: bool,
    /// Also record one ray stream per scene (rendered with the scene's first method) and
    /// replay it into every method: primary rays and all rays on every thread, all rays on
    /// one thread.
    pub ray_stream: bool,
    /// How the scenes' uv and normal seams are treated (`--no-seam-fix`: left open).
    pub seam_rule: nlrt_accel::SeamRule,
    /// With the ray stream: how many interleaved rounds of replays (every method in turn per
    /// round, all threads then one thread), whose medians fill the stream's "all" columns and
    /// whose per-round ratios to the scene's first method are reported. 1: one replay per
    /// method right after its render, no rounds. Every method's acceleration data stays alive
    /// until the scene's rounds are done.
    pub rounds: usize,
}

/// A progress bar over image rows on a terminal (indicatif); nothing when stderr is not one.
fn progress_printer(label: String, rows: usize) -> impl Fn(usize) + Sync {
    let bar = if std::io::stderr().is_terminal() {
        let bar = indicatif::ProgressBar::new(rows as u64);
        if let Ok(style) = indicatif::ProgressStyle::with_template(
            "  {prefix:32} [{bar:30}] {pos}/{len} rows, {elapsed}, eta {eta}",
        ) {
            bar.set_style(style.progress_chars("=> "));
        }
        bar.set_prefix(label);
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    move |done: usize| {
        bar.set_position(done as u64);
        if done == rows {
            bar.finish();
        }
    }
}

/// Builds `method`'s tracer for `scene`, timed; `None` when the method does not support it.
fn build(scene: &Scene, method: Method) -> Option<(Box<dyn Tracer>, f64)> {
    let start = Instant::now();
    let tracer = method.build(scene)?;
    Some((tracer, start.elapsed().as_secs_f64()))
}

/// Renders `scene` with every method of `opts`.
#[must_use]
pub fn run_scene(scene: &Scene, opts: &ReportOptions) -> Vec<MethodRun> {
    run_scene_with_stream(scene, opts).0
}

/// [`run_scene`], with the ray stream the replays used (recorded with the first supported
/// method, when `opts.ray_stream`).
fn run_scene_with_stream(
    scene: &Scene,
    opts: &ReportOptions,
) -> (Vec<MethodRun>, Option<(Method, RayStream)>) {
    let recorded = opts
        .ray_stream
        .then(|| opts.methods.iter().copied().find(|m| m.supports(scene)))
        .flatten()
        .and_then(|method| {
            eprintln!("  {}: recording the ray stream with {method}", scene.name);
            let (tracer, _) = build(scene, method)?;
            Some((
                method,
                render_recording(scene, tracer.as_ref(), &opts.render).1,
            ))
        });
    // One single-thread pool for every 1-thread measurement of the scene (renders, replays).
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().ok();
    let interleaved = opts.rounds >= 2 && recorded.is_some();
    let no_replay = Replay {
        rays: 0,
        hits: 0,
        seconds: f64::NAN,
    };
    let replay_one_thread = |tracer: &dyn Tracer, stream: &RayStream| {
        one_thread.as_ref().map_or(no_replay, |pool| {
            pool.install(|| replay(tracer, stream, None))
        })
    };
    // The tracers kept for the interleaved rounds.
    let mut kept: Vec<Box<dyn Tracer>> = Vec::new();
    let mut runs: Vec<MethodRun> = opts
        .methods
        .iter()
        .filter_map(|&method| {
            if let Some(why) = method.unsupported_reason(scene) {
                // Said when the methods were chosen; with every method asked for (the report),
                // those a scene cannot take are expected, and the table shows which ran.
                if opts.methods.len() < Method::ALL.len() {
                    eprintln!("  {}: {method} left out: {why}", scene.name);
                }
                return None;
            }
            eprintln!("  {}: building {method}", scene.name);
            let Some((tracer, init_seconds)) = build(scene, method) else {
                eprintln!(
                    "  {}: {method} left out: its acceleration data could not be built (memory)",
                    scene.name
                );
                return None;
            };
            let label = format!("{} {method}", scene.name);
            let frame = render(
                scene,
                tracer.as_ref(),
                &opts.render,
                &progress_printer(label, opts.render.height),
            );
            let one_thread_seconds = opts.scaling.then(|| {
                one_thread.as_ref().map_or(f64::NAN, |pool| {
                    pool.install(|| render(scene, tracer.as_ref(), &opts.render, &|_| {}).seconds)
                })
            });
            // With rounds, "all" and "all, 1 thread" come from the rounds below.
            let stream = recorded.as_ref().map(|(_, stream)| {
                let tracer = tracer.as_ref();
                StreamTimes {
                    all: if interleaved {
                        no_replay
                    } else {
                        replay(tracer, stream, None)
                    },
                    primary: replay(tracer, stream, Some(RayKind::Primary)),
                    all_one_thread: if interleaved {
                        no_replay
                    } else {
                        replay_one_thread(tracer, stream)
                    },
                }
            });
            let run = MethodRun {
                method,
                init_seconds,
                memory_bytes: tracer.memory_bytes(),
                frame,
                one_thread_seconds,
                stream,
                rounds: Vec::new(),
            };
            if interleaved {
                kept.push(tracer);
            }
            Some(run)
        })
        .collect();
    if let (true, Some((_, stream))) = (interleaved, &recorded) {
        for round in 0..opts.rounds {
            eprintln!(
                "  {}: round {} of {} of the stream's replays",
                scene.name,
                round + 1,
                opts.rounds
            );
            for (run, tracer) in runs.iter_mut().zip(&kept) {
                let all = replay(tracer.as_ref(), stream, None);
                let all_one_thread = replay_one_thread(tracer.as_ref(), stream);
                run.rounds.push(RoundTimes {
                    all,
                    all_one_thread,
                });
            }
        }
        for run in &mut runs {
            if let Some(st) = run.stream.as_mut() {
                st.all = median_replay(run.rounds.iter().map(|r| r.all)).unwrap_or(no_replay);
                st.all_one_thread =
                    median_replay(run.rounds.iter().map(|r| r.all_one_thread)).unwrap_or(no_replay);
            }
        }
    }
    (runs, recorded)
}

/// A method's interleaved rounds against another's (the scene's first method): the ratios of
/// their rates on every thread and on one thread.
#[must_use]
pub fn round_ratios(mine: &MethodRun, first: &MethodRun) -> Option<(RoundRatios, RoundRatios)> {
    let all = |r: &MethodRun| r.rounds.iter().map(|t| t.all).collect::<Vec<_>>();
    let one = |r: &MethodRun| {
        r.rounds
            .iter()
            .map(|t| t.all_one_thread)
            .collect::<Vec<_>>()
    };
    Some((
        RoundRatios::new(&all(mine), &all(first))?,
        RoundRatios::new(&one(mine), &one(first))?,
    ))
}

/// The interleaved rounds as a Markdown section: per scene and method, the rates (medians of
/// the rounds) and the ratios to the scene's first method, round by round, with their median
/// and spread.
fn rounds_table(rows: &[TableRow], threads: usize) -> String {
    let mut md = String::new();
    let rounds = rows.iter().map(|r| r.run.rounds.len()).max().unwrap_or(0);
    let _ = writeln!(
        md,
        "\n### Interleaved rounds of the stream\n\n{rounds} rounds; in each, every method traced \
         the stream in turn ({threads} threads, then 1 thread). Ratios are each round's rate over \
         the scene's first method's in the same round; the median and the spread (smallest - \
         largest) over the rounds.\n\n\
         | scene | method | against | Mrays/s all (median) | ratio per round | ratio median (spread) | \
         Mrays/s all, 1 thread (median) | 1-thread ratio per round | 1-thread ratio median (spread) |\n\
         |---|---|---|---|---|---|---|---|---|"
    );
    let fmt_list = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    for row in rows {
        let Some(first) = rows
            .iter()
            .find(|r| r.scene == row.scene && !r.run.rounds.is_empty())
        else {
            continue;
        };
        let (Some((all, one)), Some(st)) = (round_ratios(&row.run, &first.run), row.run.stream)
        else {
            continue;
        };
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.3} | {} | {:.3} ({:.3} - {:.3}) | {:.3} | {} | {:.3} ({:.3} - {:.3}) |",
            row.scene,
            row.run.method,
            first.run.method,
            st.all.mrays(),
            fmt_list(&all.per_round),
            all.median,
            all.min,
            all.max,
            st.all_one_thread.mrays(),
            fmt_list(&one.per_round),
            one.median,
            one.min,
            one.max,
        );
    }
    md
}

fn mib(bytes: usize) -> f64 {
    bytes as f64 / (1024.0 * 1024.0)
}

/// A difference image: `4 |a - b|` per channel; pixels where one hits and the other misses
/// in magenta.
fn difference_image(a: &Frame, b: &Frame) -> Vec<u8> {
    let mut out = Vec::with_capacity(a.color.len() * 3);
    for i in 0..a.color.len() {
        if a.depth[i].is_nan() != b.depth[i].is_nan() {
            out.extend([255, 0, 255]);
            continue;
        }
        for c in 0..3 {
            let d = (a.color[i][c] - b.color[i][c]).abs() * 4.0;
            out.push((d.clamp(0.0, 1.0) * 255.0 + 0.5) as u8);
        }
    }
    out
}

/// The speed-against-error figure: small multiples, one panel per scene (depth error p99
/// against Mrays/s), a colour per kind of method, a circle for f32 and a square for f64, the
/// Pareto front of the methods that are not references joined.
fn speed_against_error_svg(points: &[(Method, String, f64, ErrorStats)]) -> String {
    use crate::lab::plot::{LegendEntry, Marker, Panel, Point, Series};
    let color = |m: Method| {
        // Per kind a dark colour for f32 and a light one for f64.
        let [f32_colour, f64_colour] = match m.kind() {
            Kind::Nonlinear => ["#d62728", "#ff9896"],
            Kind::TessellationFree => ["#1f77b4", "#aec7e8"],
            Kind::GeometryImage => ["#9467bd", "#c5b0d5"],
            Kind::Marching => ["#ff7f0e", "#ffbb78"],
            Kind::DistanceMap => ["#7f7f7f", "#c7c7c7"],
            Kind::Tetrahedra => ["#8c564b", "#c49c94"],
            Kind::Projective => ["#e377c2", "#f7b6d2"],
            Kind::ConeRay => ["#393b79", "#6b6ecf"],
            Kind::ConeCone => ["#637939", "#b5cf6b"],
            Kind::Curved => ["#17becf", "#9edae5"],
            Kind::Embree => ["#000000"; 2],
            Kind::EmbreeNative => ["#555555"; 2],
            Kind::EmbreeGrid => ["#999999"; 2],
            Kind::Tessellated => ["#2ca02c"; 2],
            Kind::TessellatedCurved => ["#bcbd22"; 2],
        };
        match m.precision() {
            Precision::F32 => f32_colour,
            Precision::F64 => f64_colour,
        }
    };
    let methods: Vec<Method> = Method::ALL
        .into_iter()
        .filter(|m| points.iter().any(|p| p.0 == *m))
        .collect();
    let marker = |m: Method| match m.precision() {
        Precision::F32 => Marker::Circle,
        Precision::F64 => Marker::Square,
    };
    // One panel per scene, in the order the scenes ran.
    let mut scenes: Vec<&str> = Vec::new();
    for p in points {
        if !scenes.contains(&p.1.as_str()) {
            scenes.push(&p.1);
        }
    }
    let panels: Vec<Panel> = scenes
        .iter()
        .map(|&scene| Panel {
            title: scene.to_string(),
            x_label: "Mrays/s (all rays)".into(),
            y_label: "depth error, p99".into(),
            y_floor: 1e-17,
            pareto: true,
            series: methods
                .iter()
                .map(|&m| Series {
                    name: m.name().to_string(),
                    color: color(m),
                    marker: marker(m),
                    on_front: !m.is_reference(),
                    points: points
                        .iter()
                        .filter(|p| p.0 == m && p.1 == scene)
                        .map(|p| Point {
                            x: p.2,
                            y: p.3.depth_p99,
                            label: String::new(),
                        })
                        .collect(),
                })
                .collect(),
        })
        .collect();
    // The legend: one colour per kind (f32's), then the two markers.
    let mut legend: Vec<LegendEntry> = Vec::new();
    for &m in &methods {
        let name = m.name().trim_end_matches(" f32").trim_end_matches(" f64");
        if !legend.iter().any(|e| e.name == name) {
            legend.push(LegendEntry {
                name: name.to_string(),
                color: color(Method::in_precision_or_only(m.kind(), Precision::F32)),
                marker: Marker::Circle,
            });
        }
    }
    for (name, marker) in [
        ("f32: circle (dark)", Marker::Circle),
        ("f64: square (light)", Marker::Square),
    ] {
        legend.push(LegendEntry {
            name: name.into(),
            color: "#444444",
            marker,
        });
    }
    crate::lab::plot::svg(&panels, 3, &legend)
}

/// Runs every scene and writes images (when `out_dir` is set); returns the Markdown tables.
///
/// # Errors
/// An unknown scene name, or an image that cannot be written.
pub fn run(opts: &ReportOptions) -> Result<String, String> {
    run_with_rows(opts).map(|(md, _)| md)
}

/// One row of the table as data: a method's run on a scene with its errors against the
/// reference and against its f64 partner (where they ran).
#[derive(Clone, Debug)]
pub struct TableRow {
    /// Scene name.
    pub scene: String,
    /// The method's run.
    pub run: MethodRun,
    /// Against the f64 pre-tessellated reference.
    pub vs_reference: Option<ErrorStats>,
    /// Against the method's f64 partner.
    pub vs_f64: Option<ErrorStats>,
}

/// [`run`], with every row of the table as data (for `nlrt bench --json`).
///
/// # Errors
/// As [`run`].
pub fn run_with_rows(opts: &ReportOptions) -> Result<(String, Vec<TableRow>), String> {
    let mut md = String::new();
    let mut rows = Vec::new();
    let r = &opts.render;
    let _ = writeln!(
        md,
        "## Scenes\n\n{}x{} pixels, {} spp, {} bounce(s) with a shadow ray per hit; {} threads; target features: {}. \
         Scene size: {:?}. Error columns compare primary-ray depths with the f64 pre-tessellated reference \
         (a different surface by design: flat world triangles through mapped vertices) and with nonlinear f64 \
         (the precision error alone); the curved shell's with its own surface pre-tessellated and with \
         curved shell f64.\n",
        r.width,
        r.height,
        r.spp,
        r.bounces,
        rayon::current_num_threads(),
        crate::lab::solvers::target_features(),
        opts.size
    );
    let _ = writeln!(
        md,
        "| scene | method | init s | accel MiB | Mrays/s primary | Mrays/s all | {}{}miss/hit mismatch vs ref | depth err vs ref median / p99 | mismatch vs f64 | depth err vs f64 p99 / max |",
        if opts.scaling {
            format!("speed-up {} threads / 1 | ", rayon::current_num_threads())
        } else {
            String::new()
        },
        if opts.ray_stream {
            "stream Mrays/s primary | stream Mrays/s all | stream Mrays/s all, 1 thread | "
        } else {
            ""
        }
    );
    let _ = writeln!(
        md,
        "|---|---|---|---|---|---|---|{}{}---|---|---|",
        if opts.scaling { "---|" } else { "" },
        if opts.ray_stream { "---|---|---|" } else { "" }
    );
    let mut stream_notes = Vec::new();
    let mut ran = Vec::new();
    let mut points = Vec::new();
    for name in &opts.scenes {
        let mut scene = crate::scene::scene_file::builtin_or_file(name, opts.size)?;
        scene.set_seam_rule(opts.seam_rule);
        let stem = image_stem(name);
        eprintln!(
            "scene {name}: {} base triangles, {}{}",
            scene.triangle_count(),
            scene.describe_content(),
            scene.describe_seams()
        );
        let (runs, recorded) = run_scene_with_stream(&scene, opts);
        if let Some((method, stream)) = &recorded {
            stream_notes.push(format!(
                "{name}: {} rays ({} primary, {} shadow, {} bounce), recorded with {method}",
                stream.len(),
                stream.count(RayKind::Primary),
                stream.count(RayKind::Shadow),
                stream.count(RayKind::Bounce)
            ));
        }
        ran.push((
            name.clone(),
            runs.iter().map(|m| m.method).collect::<Vec<_>>(),
        ));
        let run_of = |method: Method| runs.iter().find(|r| r.method == method);
        for m in &runs {
            let reference = run_of(m.method.reference());
            let vs = |other: Option<&MethodRun>| other.map(|o| compare(&m.frame, &o.frame));
            let (e_ref, e_64) = (vs(reference), vs(run_of(m.method.f64_partner())));
            rows.push(TableRow {
                scene: name.clone(),
                run: m.clone(),
                vs_reference: e_ref,
                vs_f64: e_64,
            });
            if let Some(e) = e_ref {
                points.push((m.method, name.clone(), m.all_mrays(), e));
            }
            let fmt_rate = |e: Option<ErrorStats>| {
                e.map_or("-".into(), |e| {
                    format!("{:.4}% ({})", 100.0 * e.mismatch_rate(), e.mismatches)
                })
            };
            let _ = writeln!(
                md,
                "| {name} | {} | {:.3} | {:.1} | {:.3} | {:.3} | {}{}{} | {} | {} | {} |",
                m.method,
                m.init_seconds,
                mib(m.memory_bytes),
                m.primary_mrays(),
                m.all_mrays(),
                m.one_thread_seconds.map_or(String::new(), |one| format!(
                    "{:.2} | ",
                    one / m.frame.seconds
                )),
                m.stream.map_or(String::new(), |st| format!(
                    "{:.3} | {:.3} | {:.3} | ",
                    st.primary.mrays(),
                    st.all.mrays(),
                    st.all_one_thread.mrays()
                )),
                fmt_rate(e_ref),
                e_ref.map_or("-".into(), |e| format!(
                    "{:.1e} / {:.1e}",
                    e.depth_median, e.depth_p99
                )),
                fmt_rate(e_64),
                e_64.map_or("-".into(), |e| format!(
                    "{:.1e} / {:.1e}",
                    e.depth_p99, e.depth_max
                )),
            );
            if let Some(dir) = &opts.out_dir {
                let path = dir.join(format!("{stem}-{}.png", m.method.slug()));
                write_png(&path, m.frame.width, m.frame.height, &m.frame.rgb8())
                    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                if let Some(reference) = reference.filter(|_| !m.method.is_reference()) {
                    let path = dir.join(format!("{stem}-{}-diff.png", m.method.slug()));
                    write_png(
                        &path,
                        m.frame.width,
                        m.frame.height,
                        &difference_image(&m.frame, &reference.frame),
                    )
                    .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
                }
            }
        }
    }
    if !stream_notes.is_empty() {
        let _ = writeln!(
            md,
            "\nStream columns: every method traced the same recorded rays (the render's primary, \
             shadow and bounce rays of one method, replayed in render order in chunks of \
             consecutive rays), timed without shading. Ray streams:\n"
        );
        for note in &stream_notes {
            let _ = writeln!(md, "- {note}");
        }
    }
    if rows.iter().any(|r| !r.run.rounds.is_empty()) {
        md.push_str(&rounds_table(&rows, rayon::current_num_threads()));
    }
    if let Some(dir) = &opts.out_dir
        && !points.is_empty()
    {
        let path = dir.join("speed-vs-error.svg");
        std::fs::write(&path, speed_against_error_svg(&points))
            .map_err(|e| format!("cannot write {}: {e}", path.display()))?;
        let _ = writeln!(
            md,
            "\n### Speed against error\n\nEvery scene and method: all rays per second (log) against the \
             error of the primary rays versus the f64 pre-tessellated reference (left: 99th percentile \
             of the relative depth difference; right: hit/miss mismatch rate; zeros on the floor \
             line).\n\n![speed against error](speed-vs-error.svg)\n"
        );
    }
    if let Some(dir) = &opts.out_dir {
        let _ = writeln!(md, "\n### Images\n");
        for (name, methods) in &ran {
            let cells: Vec<String> = methods
                .iter()
                .map(|m| format!("![{name} {m}]({}-{}.png)", image_stem(name), m.slug()))
                .collect();
            let _ = writeln!(md, "{name}: {}\n", cells.join(" "));
            let diffs: Vec<String> = methods
                .iter()
                .filter(|&&m| !m.is_reference() && methods.contains(&m.reference()))
                .map(|m| {
                    format!(
                        "![{name} {m} minus reference]({}-{}-diff.png)",
                        image_stem(name),
                        m.slug()
                    )
                })
                .collect();
            if !diffs.is_empty() {
                let _ = writeln!(
                    md,
                    "{name} differences from the reference (x4; magenta: hit/miss mismatch): {}\n",
                    diffs.join(" ")
                );
            }
        }
        let _ = Path::new(dir);
    }
    Ok((md, rows))
}

/// The start of a scene's image names: its name, or a scene file's stem (a path is no file
/// name).
fn image_stem(name: &str) -> String {
    match std::path::Path::new(name)
        .file_stem()
        .and_then(|s| s.to_str())
    {
        Some(stem) if name.ends_with(".toml") => stem.to_string(),
        _ => name.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::{Replay, RoundRatios, median_replay};

    fn replay(rays: u64, seconds: f64) -> Replay {
        Replay {
            rays,
            hits: 0,
            seconds,
        }
    }

    /// Ratios per round are rate over rate; the median of an odd count is its middle value,
    /// of an even count the mean of the middle two; the spread is the extremes.
    #[test]
    fn round_ratios_are_per_round_with_median_and_spread() {
        let mine = [replay(100, 1.0), replay(100, 2.0), replay(100, 4.0)];
        let theirs = [replay(100, 2.0), replay(100, 2.0), replay(100, 2.0)];
        let r = RoundRatios::new(&mine, &theirs).unwrap();
        assert_eq!(r.per_round, vec![2.0, 1.0, 0.5]);
        assert_eq!((r.median, r.min, r.max), (1.0, 0.5, 2.0));
        let r = RoundRatios::new(&mine[..2], &theirs[..2]).unwrap();
        assert_eq!((r.median, r.min, r.max), (1.5, 1.0, 2.0));
        assert_eq!(RoundRatios::new(&[], &[]), None);
    }

    /// The median replay is the one of median duration (the faster middle one of an even
    /// count).
    #[test]
    fn the_median_replay_is_the_middle_duration() {
        let rounds = [
            replay(1, 3.0),
            replay(2, 1.0),
            replay(3, 2.0),
            replay(4, 5.0),
        ];
        assert_eq!(median_replay(rounds.into_iter()).map(|r| r.rays), Some(3));
        assert_eq!(
            median_replay(rounds[..3].iter().copied()).map(|r| r.rays),
            Some(3)
        );
        assert_eq!(median_replay(core::iter::empty()), None);
    }
}
