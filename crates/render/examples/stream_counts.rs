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
//! the `f32` and the `f64` surface (and, where the scene has affine patches, both again with
//! the curved walk on every prism), each kind of ray in turn, interleaved over `ROUNDS`
//! rounds; the time printed is each kind's median over the rounds. Shadow rays are traced
//! twice: for their nearest hit and, as the renderer asks them, as occlusion queries (the
//! totals count the latter).

use nlrt_accel::TraversalStats;
use nlrt_poly::{Real, Vector3};
use nlrt_render::trace::integrator::{RenderOptions, render_recording};
use nlrt_render::trace::methods::Nonlinear;
use nlrt_render::trace::ray_stream::{RayKind, StreamRay};
use nlrt_shellmap::Ray;
use std::time::Instant;

/// Timed passes over each kind's rays; the median is printed.
const ROUNDS: usize = 5;

mod common;

/// The name in error messages.
const PROGRAM: &str = "stream_counts";

/// Traces `rays` one at a time (the nearest hit, or with `any` the occlusion query a
/// renderer asks of a shadow ray); returns the hits and the counters.
#[inline(never)]
fn trace_stream<T: Real>(
    nl: &Nonlinear<T>,
    rays: &[StreamRay],
    any: bool,
) -> (u64, TraversalStats) {
    let mut stats = TraversalStats::default();
    let v = |a: nlrt_poly::glam::DVec3| {
        T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z))
    };
    let mut hits = 0;
    for r in rays {
        let Some(ray) = Ray::new(v(r.origin), v(r.dir)) else {
            continue;
        };
        let hit = match (nl, any) {
            (Nonlinear::Displaced(s), false) => s
                .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                .is_some(),
            (Nonlinear::Shell(s), false) => s
                .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                .is_some(),
            (Nonlinear::Displaced(s), true) => s.occluded(&ray, T::ZERO, T::INFINITY, &mut stats),
            (Nonlinear::Shell(s), true) => s.occluded(&ray, T::ZERO, T::INFINITY, &mut stats),
        };
        hits += u64::from(hit);
    }
    (hits, stats)
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
    let (_, stream) = render_recording(&scene, &narrow, &opts);
    // The curved walk on every prism beside the default (the straight walk on affine
    // patches), where the scene has affine patches.
    let straight = narrow.straight_triangles();
    let curved = |mut nl: Nonlinear<f32>| {
        nl.set_straight_walk(false);
        nl
    };
    let curved_wide = |mut nl: Nonlinear<f64>| {
        nl.set_straight_walk(false);
        nl
    };
    let variants: Vec<(&str, Variant)> = [
        (only != Some(1)).then_some(("f32", Variant::Narrow(narrow))),
        (only != Some(0)).then(|| ("f64", Variant::Wide(Nonlinear::<f64>::new(&scene)))),
        (straight > 0 && only != Some(1)).then(|| {
            (
                "f32 curved",
                Variant::Narrow(curved(Nonlinear::<f32>::new(&scene))),
            )
        }),
        (straight > 0 && only != Some(0)).then(|| {
            (
                "f64 curved",
                Variant::Wide(curved_wide(Nonlinear::<f64>::new(&scene))),
            )
        }),
    ]
    .into_iter()
    .flatten()
    .collect();
    // Shadow rays twice: for the nearest hit, and as the renderer asks them (any hit); the
    // totals count them once, as asked.
    let kinds = [
        ("primary", RayKind::Primary, false),
        ("shadow (nearest)", RayKind::Shadow, false),
        ("shadow", RayKind::Shadow, true),
        ("bounce", RayKind::Bounce, false),
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
        "{name} ({}), stream of {} rays, one thread, medians of {ROUNDS} rounds, {straight} base triangles walked straight",
        args.get(2).map_or("small", String::as_str),
        stream.len()
    );
    println!(
        "kind | variant | rays | hits | us per ray | speed against the first | per ray: prisms | nodes | texel tests | prisms in f64"
    );
    let mut total = vec![0.0; variants.len()];
    for (label, kind, any) in kinds {
        let rays = rays_of(kind);
        if rays.is_empty() {
            continue;
        }
        let mut seconds = vec![Vec::new(); variants.len()];
        let mut results = vec![None; variants.len()];
        for _ in 0..ROUNDS {
            for (i, (_, variant)) in variants.iter().enumerate() {
                let t = Instant::now();
                results[i] = Some(variant.trace(&rays, any));
                seconds[i].push(t.elapsed().as_secs_f64());
            }
        }
        let medians: Vec<f64> = seconds.into_iter().map(common::median).collect();
        let n = rays.len() as f64;
        for (i, (variant, _)) in variants.iter().enumerate() {
            let Some((hits, st)) = results[i] else {
                continue;
            };
            // Shadow rays count once, as the occlusion queries the renderer asks.
            if kind != RayKind::Shadow || any {
                total[i] += medians[i];
            }
            println!(
                "{label} | {variant} | {} | {hits} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4}",
                rays.len(),
                medians[i] / n * 1e6,
                medians[0] / medians[i],
                f64::from(st.prism_tests) / n,
                f64::from(st.box_tests) / n,
                f64::from(st.texel_tests) / n,
                f64::from(st.f64_prisms) / n,
            );
        }
    }
    let n = stream.len() as f64;
    for (i, (variant, _)) in variants.iter().enumerate() {
        println!(
            "all | {variant} | {} | | {:.3} | {:.2} | Mrays/s {:.3}",
            stream.len(),
            total[i] / n * 1e6,
            total[0] / total[i],
            n / total[i] / 1e6,
        );
    }
}

/// A surface in one of the two precisions.
enum Variant {
    Narrow(Nonlinear<f32>),
    Wide(Nonlinear<f64>),
}

impl Variant {
    fn trace(&self, rays: &[StreamRay], any: bool) -> (u64, TraversalStats) {
        match self {
            Variant::Narrow(nl) => trace_stream(nl, rays, any),
            Variant::Wide(nl) => trace_stream(nl, rays, any),
        }
    }
}
