//! Secondary rays two ways, against a reference: moved off the surface along the normal
//! (the renderer's rule, `integrator::secondary_offset`) and traced with the plain query, or
//! started at the hit point with the origin's element excluded (`intersect_leaving`,
//! `occluded_leaving`); also started at the hit point with no protection at all.
//!
//! `cargo run --release --example leaving_counts -p nlrt-render -- mountain paper 320`
//!
//! Arguments: scene, `small` or `paper` map sizes, the image width (default 320; height 3/4
//! of it). Every pixel centre's camera ray is traced in `f32` and `f64`; where both hit the
//! same element, a shadow ray towards the sun (where the surface faces it) and one bounce
//! ray (cosine-distributed about the `f64` normal) leave the hit, the same directions in
//! both precisions. Each is asked whether it is blocked; the reference is `f64` leaving from
//! the `f64` hit. Printed per variant: rays blocked where the reference is open (false
//! shadows, self-intersections) and open where it is blocked (leaks: light through a
//! contact or crease the offset jumped), and the one-thread time per leaving ray (median
//! of `ROUNDS` interleaved rounds).

use nlrt_accel::{ShellHit, SurfaceHit, TraversalStats};
use nlrt_poly::glam::DVec3;
use nlrt_poly::{Real, Vector3};
use nlrt_render::scene::material::Rng;
use nlrt_render::trace::integrator::secondary_offset;
use nlrt_render::trace::methods::Nonlinear;
use nlrt_shellmap::Ray;
use std::time::Instant;

mod common;

/// The name in error messages.
const PROGRAM: &str = "leaving_counts";

/// Timed passes over the leaving rays; the median is printed.
const ROUNDS: usize = 5;

/// A primary hit in precision `T`.
#[derive(Clone, Copy)]
enum Found<T: Real> {
    Displaced(SurfaceHit<T>),
    Shell(ShellHit<T>),
}

impl<T: Real> Found<T> {
    fn t(&self) -> T {
        match self {
            Self::Displaced(h) => h.hit.t,
            Self::Shell(h) => h.hit.t,
        }
    }

    /// The element hit, comparable across precisions.
    fn element(&self) -> (u32, [i32; 2], String) {
        match self {
            Self::Displaced(h) => (h.triangle, h.texel, format!("{:?}", h.part)),
            Self::Shell(h) => (h.triangle, h.tile, h.object_triangle.to_string()),
        }
    }
}

fn vec3<T: Real>(a: DVec3) -> T::Vec3 {
    T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z))
}

/// The point at distance `t` along the ray from `origin` along `dir`, in `T` (as the
/// surface computed its hit).
fn at<T: Real>(origin: DVec3, dir: DVec3, t: T) -> T::Vec3 {
    vec3::<T>(origin) + vec3::<T>(dir) * t
}

/// The nearest hit of the ray from `origin` along `dir`, with its unit normal facing
/// against the ray (f64).
fn primary<T: Real>(nl: &Nonlinear<T>, origin: DVec3, dir: DVec3) -> Option<(Found<T>, DVec3)> {
    let ray = Ray::new(vec3::<T>(origin), vec3::<T>(dir))?;
    let stats = &mut TraversalStats::default();
    let (found, normal) = match nl {
        Nonlinear::Displaced(s) => {
            let h = s.intersect(&ray, T::ZERO, T::INFINITY, stats)?;
            (Found::Displaced(h), s.normal(&h, ray.dir)?)
        }
        Nonlinear::Shell(s) => {
            let h = s.intersect(&ray, T::ZERO, T::INFINITY, stats)?;
            (Found::Shell(h), s.normal(&h, ray.dir)?)
        }
    };
    Some((found, normal.to_dvec3()))
}

/// How a secondary ray leaves its hit.
#[derive(Clone, Copy, PartialEq)]
enum Start {
    /// From the hit point moved along the normal, the plain query.
    Offset,
    /// From the hit point, the origin's element excluded.
    Leaving,
    /// From the hit point, the plain query.
    Bare,
}

/// A secondary ray: its primary ray's hit and the direction it leaves in.
struct Secondary<T: Real> {
    from: Found<T>,
    hit_point: T::Vec3,
    offset_point: T::Vec3,
    dir: T::Vec3,
}

/// Whether `ray` is blocked, leaving `s.from` as `start` says; adds to `stats`.
fn blocked<T: Real>(
    nl: &Nonlinear<T>,
    s: &Secondary<T>,
    start: Start,
    stats: &mut TraversalStats,
) -> bool {
    let origin = if start == Start::Offset {
        s.offset_point
    } else {
        s.hit_point
    };
    let Some(ray) = Ray::new(origin, s.dir) else {
        return false;
    };
    let inf = T::INFINITY;
    match (nl, start, &s.from) {
        (Nonlinear::Displaced(d), Start::Leaving, Found::Displaced(h)) => {
            d.occluded_leaving(&ray, h, inf, stats)
        }
        (Nonlinear::Shell(d), Start::Leaving, Found::Shell(h)) => {
            d.occluded_leaving(&ray, h, inf, stats)
        }
        (Nonlinear::Displaced(d), _, _) => d.occluded(&ray, T::ZERO, inf, stats),
        (Nonlinear::Shell(d), _, _) => d.occluded(&ray, T::ZERO, inf, stats),
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let (name, scene) = common::scene_from_args(&args, PROGRAM);
    let width = common::width_from_args(&args, 3, 320, PROGRAM);
    let height = width * 3 / 4;
    let narrow = Nonlinear::<f32>::new(&scene);
    let wide = Nonlinear::<f64>::new(&scene);
    let offset = secondary_offset(&scene);
    let aspect = width as f64 / height as f64;
    let (mut narrow_rays, mut wide_rays) = (Vec::new(), Vec::new());
    let mut differing_primaries = 0;
    for y in 0..height {
        for x in 0..width {
            let dir = scene.camera.direction(
                (x as f64 + 0.5) / width as f64,
                (y as f64 + 0.5) / height as f64,
                aspect,
            );
            let eye = scene.camera.eye;
            let (Some((h32, _)), Some((h64, n64))) =
                (primary(&narrow, eye, dir), primary(&wide, eye, dir))
            else {
                continue;
            };
            if h32.element() != h64.element() {
                differing_primaries += 1;
                continue;
            }
            let mut rng = Rng::stream((y * width + x) as u64);
            // A cosine-distributed bounce about the normal (Malley's method).
            let bounce = {
                let (r, phi) = (
                    rng.next_f64().sqrt(),
                    2.0 * std::f64::consts::PI * rng.next_f64(),
                );
                let t = if n64.x.abs() < 0.9 {
                    DVec3::X
                } else {
                    DVec3::Y
                };
                let (b1, b2) = (
                    n64.cross(t).normalize(),
                    n64.cross(n64.cross(t).normalize()),
                );
                (b1 * (r * phi.cos()) + b2 * (r * phi.sin()) + n64 * (1.0 - r * r).max(0.0).sqrt())
                    .normalize()
            };
            let dirs = [
                (n64.dot(scene.sun) > 0.0).then_some(scene.sun),
                Some(bounce),
            ];
            for d in dirs.into_iter().flatten() {
                let p32 = eye + dir * h32.t().to_f64();
                let p64 = eye + dir * h64.t();
                narrow_rays.push(Secondary {
                    from: h32,
                    hit_point: at::<f32>(eye, dir, h32.t()),
                    offset_point: vec3::<f32>(p32 + n64 * offset),
                    dir: vec3::<f32>(d),
                });
                wide_rays.push(Secondary {
                    from: h64,
                    hit_point: at::<f64>(eye, dir, h64.t()),
                    offset_point: vec3::<f64>(p64 + n64 * offset),
                    dir: vec3::<f64>(d),
                });
            }
        }
    }
    let reference: Vec<bool> = wide_rays
        .iter()
        .map(|s| blocked(&wide, s, Start::Leaving, &mut TraversalStats::default()))
        .collect();
    println!(
        "{name} ({}), {width} x {height} camera rays, {} secondary rays (shadow and bounce) from hits on the same element in f32 and f64 ({differing_primaries} camera rays hit different elements, left out); offset {offset:.3e}; reference: f64 leaving, {} blocked",
        args.get(2).map_or("small", String::as_str),
        wide_rays.len(),
        reference.iter().filter(|&&b| b).count(),
    );
    println!(
        "variant | blocked where the reference is open | open where it is blocked | us per ray (one thread) | per ray: prisms | nodes | texel tests"
    );
    let starts = [
        ("offset", Start::Offset),
        ("leaving", Start::Leaving),
        ("bare", Start::Bare),
    ];
    let mut seconds = vec![Vec::new(); 2 * starts.len()];
    let mut answers = vec![Vec::new(); 2 * starts.len()];
    let mut stats = vec![TraversalStats::default(); 2 * starts.len()];
    for _ in 0..ROUNDS {
        for (i, &(_, start)) in starts.iter().enumerate() {
            let j = starts.len() + i;
            stats[i] = TraversalStats::default();
            let t = Instant::now();
            answers[i] = narrow_rays
                .iter()
                .map(|s| blocked(&narrow, s, start, &mut stats[i]))
                .collect();
            seconds[i].push(t.elapsed().as_secs_f64());
            stats[j] = TraversalStats::default();
            let t = Instant::now();
            answers[j] = wide_rays
                .iter()
                .map(|s| blocked(&wide, s, start, &mut stats[j]))
                .collect();
            seconds[j].push(t.elapsed().as_secs_f64());
        }
    }
    let n = wide_rays.len().max(1) as f64;
    for (k, precision) in ["f32", "f64"].iter().enumerate() {
        for (i, (label, _)) in starts.iter().enumerate() {
            let j = k * starts.len() + i;
            let (mut false_blocks, mut leaks) = (0, 0);
            for (&a, &r) in answers[j].iter().zip(&reference) {
                false_blocks += usize::from(a && !r);
                leaks += usize::from(!a && r);
            }
            println!(
                "{precision} {label} | {false_blocks} | {leaks} | {:.3} | {:.2} | {:.2} | {:.2}",
                common::median(seconds[j].clone()) / n * 1e6,
                f64::from(stats[j].prism_tests) / n,
                f64::from(stats[j].box_tests) / n,
                f64::from(stats[j].texel_tests) / n,
            );
        }
    }
}
