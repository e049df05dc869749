//! Traversal counters and one-thread time of nonlinear tracing per kind of ray (primary,
//! shadow, bounce) on the recorded ray stream that `nlrt bench` replays: where a scene's
//! rays spend their work, beyond the primary rays that `traversal_counts` measures.
//!
//! `cargo run --release --example stream_counts -p nlrt-render -- mountain paper`
//!
//! Arguments: scene, `small` or `paper` map sizes, optionally the image width (default 320,
//! the bench's; height 3/4 of it) and `f32` or `f64` to trace in that precision alone (for a
//! profile; default both). The stream is recorded by a render with nonlinear
//! `f32` (1 spp, one bounce, as the bench), then traced one ray at a time on this thread by
//! the `f32` and the `f64` surface, each kind of ray in turn, interleaved over `ROUNDS`
//! rounds; the time printed is each kind's median over the rounds.

use nlrt_accel::TraversalStats;
use nlrt_poly::{Real, Vector3};
use nlrt_render::integrator::{RenderOptions, render_recording};
use nlrt_render::ray_stream::{RayKind, StreamRay};
use nlrt_render::tracers::Nonlinear;
use nlrt_shellmap::Ray;
use std::time::Instant;

/// Timed passes over each kind's rays; the median is printed.
const ROUNDS: usize = 5;

mod common;

/// The name in error messages.
const PROGRAM: &str = "stream_counts";

/// Traces `rays` one at a time; returns the hits and the counters.
#[inline(never)]
fn trace_stream<T: Real>(nl: &Nonlinear<T>, rays: &[StreamRay]) -> (u64, TraversalStats) {
    let mut stats = TraversalStats::default();
    let v = |a: nlrt_poly::glam::DVec3| {
        T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z))
    };
    let mut hits = 0;
    for r in rays {
        let Some(ray) = Ray::new(v(r.origin), v(r.dir)) else {
            continue;
        };
        let hit = match nl {
            Nonlinear::Displaced(s) => s
                .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                .is_some(),
            Nonlinear::Shell(s) => s
                .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                .is_some(),
        };
        hits += u64::from(hit);
    }
    (hits, stats)
}

/// Median of `xs` (NaN when empty: a precision left out).
fn median(mut xs: Vec<f64>) -> f64 {
    xs.sort_by(f64::total_cmp);
    xs.get(xs.len() / 2).copied().unwrap_or(f64::NAN)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (name, scene) = common::scene_from_args(&args, PROGRAM);
    let width = common::width_from_args(&args, 3, 320, PROGRAM);
    let only = match args.get(4).map(String::as_str) {
        None => None,
        Some("f32") => Some(0),
        Some("f64") => Some(1),
        Some(other) => common::fail(PROGRAM, &format!("unknown precision {other} (f32 or f64)")),
    };
    let opts = RenderOptions {
        width,
        height: width * 3 / 4,
        spp: 1,
        bounces: 1,
    };
    let narrow = Nonlinear::<f32>::new(&scene);
    let wide = Nonlinear::<f64>::new(&scene);
    let (_, stream) = render_recording(&scene, &narrow, &opts);
    let kinds = [
        ("primary", RayKind::Primary),
        ("shadow", RayKind::Shadow),
        ("bounce", RayKind::Bounce),
    ];
    let rays_of = |kind| -> Vec<StreamRay> {
        stream
            .rays()
            .iter()
            .copied()
            .filter(|r| r.kind == kind)
            .collect()
    };
    println!(
        "{name} ({}), stream of {} rays, one thread, medians of {ROUNDS} rounds",
        args.get(2).map_or("small", String::as_str),
        stream.len()
    );
    println!(
        "kind | rays | hits | us per ray f32 | f64 | f32 / f64 speed | per ray: prisms | nodes | texel tests | prisms in f64"
    );
    let mut total = [0.0; 2];
    for (label, kind) in kinds {
        let rays = rays_of(kind);
        if rays.is_empty() {
            continue;
        }
        let mut seconds = [Vec::new(), Vec::new()];
        let mut result = None;
        for _ in 0..ROUNDS {
            if only != Some(1) {
                let t = Instant::now();
                result = Some(trace_stream(&narrow, &rays));
                seconds[0].push(t.elapsed().as_secs_f64());
            }
            if only != Some(0) {
                let t = Instant::now();
                let wide_result = trace_stream(&wide, &rays);
                seconds[1].push(t.elapsed().as_secs_f64());
                result = result.or(Some(wide_result));
            }
        }
        let Some((hits, st)) = result else {
            continue;
        };
        let [s32, s64] = seconds.map(median);
        total[0] += s32;
        total[1] += s64;
        let n = rays.len() as f64;
        println!(
            "{label} | {} | {hits} | {:.3} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4}",
            rays.len(),
            s32 / n * 1e6,
            s64 / n * 1e6,
            s64 / s32,
            f64::from(st.prism_tests) / n,
            f64::from(st.box_tests) / n,
            f64::from(st.texel_tests) / n,
            f64::from(st.f64_prisms) / n,
        );
    }
    let n = stream.len() as f64;
    println!(
        "all | {} | | {:.3} | {:.3} | {:.2} | Mrays/s f32 {:.3}, f64 {:.3}",
        stream.len(),
        total[0] / n * 1e6,
        total[1] / n * 1e6,
        total[1] / total[0],
        n / total[0] / 1e6,
        n / total[1] / 1e6
    );
}
