//! Traversal counters of nonlinear tracing per primary ray of a built-in scene, one thread:
//! prism (TLAS leaf) visits, node visits of the BLAS walk, texel tests and walks that fell
//! back to box tests, with a checksum of the hits (triangle, texel and the bits of the
//! distance) that tells whether a change to the traversal altered any answer.
//!
//! `cargo run --release --example traversal_counts -p nlrt-render -- fur paper f32 160`
//!
//! Arguments: scene, `small` or `paper` map sizes, `f32` or `f64`, pixels per row (rows:
//! 3/4 of it), and optionally `open` (seams left open, as `--no-seam-fix`). Instruction counts of the trace alone, which do not depend on the load of a
//! shared machine: `valgrind --tool=callgrind --toggle-collect='*trace_all*'` on the built
//! example.

use nlrt_accel::TraversalStats;
use nlrt_poly::{Real, Vector3};
use nlrt_render::scene::scenes::Scene;
use nlrt_render::trace::methods::Nonlinear;
use nlrt_shellmap::Ray;

mod common;

/// The name in error messages.
const PROGRAM: &str = "traversal_counts";

/// The camera ray through the centre of pixel `(x, y)` of `w x h`, in `T`.
fn camera_ray<T: Real>(scene: &Scene, x: usize, y: usize, w: usize, h: usize) -> Option<Ray<T>> {
    let v = |a: nlrt_poly::glam::DVec3| {
        T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z))
    };
    let d = scene.camera.direction(
        (x as f64 + 0.5) / w as f64,
        (y as f64 + 0.5) / h as f64,
        w as f64 / h as f64,
    );
    Ray::new(v(scene.camera.eye), v(d))
}

/// Hits, counters and the hits' checksum of `w x h` pixel-centre camera rays.
#[inline(never)]
fn trace_all<T: Real>(
    scene: &Scene,
    nl: &Nonlinear<T>,
    w: usize,
    h: usize,
) -> (u32, TraversalStats, u64) {
    let mut st = TraversalStats::default();
    let (mut hits, mut checksum) = (0, 0u64);
    for y in 0..h {
        for x in 0..w {
            let Some(ray) = camera_ray::<T>(scene, x, y, w, h) else {
                continue;
            };
            let hit = match nl {
                Nonlinear::Displaced(s) => s
                    .intersect(&ray, T::ZERO, T::INFINITY, &mut st)
                    .map(|h| (h.triangle, h.texel, h.hit.t)),
                Nonlinear::Shell(s) => s
                    .intersect(&ray, T::ZERO, T::INFINITY, &mut st)
                    .map(|h| (h.triangle, [0, 0], h.hit.t)),
            };
            if let Some((triangle, texel, t)) = hit {
                hits += 1;
                let key = u64::from(triangle)
                    ^ (u64::from(texel[0] as u32) << 20)
                    ^ (u64::from(texel[1] as u32) << 40)
                    ^ t.to_f64().to_bits();
                checksum = checksum.rotate_left(5) ^ key;
            }
        }
    }
    (hits, st, checksum)
}

/// Which BLAS walk affine prisms take.
#[derive(Clone, Copy, PartialEq)]
enum Walk {
    Straight,
    Curved,
    Compare,
}

/// Hits of both walks on the same rays: rays where one hits and the other does not, and the
/// largest relative difference of their distances where both hit.
fn compare<T: Real>(scene: &Scene, w: usize, h: usize) {
    let mut straight = Nonlinear::<T>::new(scene);
    let mut curved = Nonlinear::<T>::new(scene);
    let Nonlinear::Displaced(c) = &mut curved else {
        common::fail(PROGRAM, "compare needs a displacement scene");
    };
    c.set_straight_walk(false);
    let (Nonlinear::Displaced(c), Nonlinear::Displaced(s)) = (&curved, &mut straight) else {
        unreachable!("both built from one displacement scene");
    };
    s.set_straight_walk(true);
    let wide = Nonlinear::<f64>::new(scene);
    let Nonlinear::Displaced(w64) = &wide else {
        unreachable!("a displacement scene");
    };
    let (mut against_f64, mut curved_against_f64) = (0, 0);
    let (mut disagree, mut both, mut worst, mut same_texel) = (0, 0, 0.0f64, 0);
    for y in 0..h {
        for x in 0..w {
            let Some(ray) = camera_ray::<T>(scene, x, y, w, h) else {
                continue;
            };
            let mut st = TraversalStats::default();
            let a = s.intersect(&ray, T::ZERO, T::INFINITY, &mut st);
            let b = c.intersect(&ray, T::ZERO, T::INFINITY, &mut st);
            let wide_ray = Ray::new(ray.origin.to_dvec3(), ray.dir.to_dvec3());
            let truth = wide_ray.and_then(|r| w64.intersect(&r, 0.0, f64::INFINITY, &mut st));
            if a.is_some() != truth.is_some() {
                against_f64 += 1;
                if std::env::var_os("NLRT_SHOW").is_some() {
                    println!("{ray:?}: straight {a:?}, f64 {truth:?}");
                }
            }
            curved_against_f64 += usize::from(b.is_some() != truth.is_some());
            match (a, b) {
                (Some(a), Some(b)) => {
                    both += 1;
                    let (ta, tb) = (a.hit.t.to_f64(), b.hit.t.to_f64());
                    worst = worst.max((ta - tb).abs() / tb.abs());
                    same_texel += usize::from(a.texel == b.texel && a.part == b.part);
                }
                (None, None) => {}
                _ => disagree += 1,
            }
        }
    }
    println!(
        "{} straight vs curved: {disagree} hit/miss disagreements of {} rays, both hit {both} (same microtriangle {same_texel}), largest relative difference in t {worst:.3e}; hit/miss against f64 (the same ray widened): straight {against_f64}, curved {curved_against_f64}",
        T::NAME,
        w * h
    );
}

fn run<T: Real>(name: &str, scene: &Scene, w: usize, walk: Walk) {
    let h = w * 3 / 4;
    if walk == Walk::Compare {
        compare::<T>(scene, w, h);
        return;
    }
    let mut nl = Nonlinear::<T>::new(scene);
    nl.set_straight_walk(walk == Walk::Straight);
    println!(
        "{name}: {} of {} base triangles walked straight",
        nl.straight_triangles(),
        scene.triangles.len()
    );
    let t0 = std::time::Instant::now();
    let (hits, st, checksum) = trace_all(scene, &nl, w, h);
    let n = (w * h) as f64;
    println!(
        "{name} {}: {:.3} s, hits {hits}, checksum {checksum:016x}, per ray: prisms {:.2} nodes {:.2} texels {:.2} fallbacks {}, prisms traced in f64 {}",
        T::NAME,
        t0.elapsed().as_secs_f64(),
        f64::from(st.prism_tests) / n,
        f64::from(st.box_tests) / n,
        f64::from(st.texel_tests) / n,
        st.fallbacks,
        st.f64_prisms
    );
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (name, mut scene) = common::scene_from_args(&args, PROGRAM);
    let w = common::width_from_args(&args, 4, 160, PROGRAM);
    let mut walk = Walk::Straight;
    match args.get(5).map(String::as_str) {
        None => {}
        Some("open") => scene.seam_rule = nlrt_accel::SeamRule::Open,
        Some("curved") => walk = Walk::Curved,
        Some("compare") => walk = Walk::Compare,
        Some(other) => common::fail(
            PROGRAM,
            &format!("unknown option {other} (open, curved or compare)"),
        ),
    }
    match args.get(3).map(String::as_str) {
        None | Some("f32") => run::<f32>(name, &scene, w, walk),
        Some("f64") => run::<f64>(name, &scene, w, walk),
        Some(other) => common::fail(PROGRAM, &format!("unknown precision {other} (f32 or f64)")),
    }
}
