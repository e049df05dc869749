//! `nlrt watertight`: leaks of the floating-point tracer, decided by exact arithmetic.
//!
//! A ray leaks when, in exact arithmetic, it reaches a base triangle from the side its
//! normals point to, having entered the shell from outside, yet the tracer reports no hit
//! before that point. Heights are `>= 0`, so the displaced surface (or, for shell mapping, a
//! closed object layer... see below) lies on or above the base: a ray from outside that
//! reaches the base must have crossed it. The base crossing is computed with GMP rationals
//! ([`nlrt_oracle::crossing`]) on exactly the values the tracer sees (its precision's mesh and
//! ray), so the verdict does not depend on floating point. For open meshes (the mountain) the
//! ray must also cross the top cap from outside before the base (the shell is then a convex
//! slab, so the ray stays inside it); closed meshes (tori) have no other way in.
//!
//! This finds misses and hits beyond the base; a hit that is too far but still above the base
//! is not detected (a lower bound on leaks). `NLRT_SHOW_LEAKS=1` prints each leak. Displacement scenes only: a shell-mapped object
//! need not cover the base.

use crate::scenes::{Content, Scene};
use crate::trace::{Method, Nonlinear};
use nlrt_accel::{Aabb, Bvh4, SlabRay, TraversalStats};
use nlrt_oracle::crossing::ray_triangle;
use nlrt_poly::glam::DVec3;
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;
use rayon::prelude::*;

/// A hit farther than the exact base crossing by more than this relative amount counts as a
/// leak. Distances of a correct hit carry a relative error of a few ulps times the hit's
/// conditioning (measured p99 ~ 4e-7 for f32 in the report); at the base (height 0) the true
/// hit is the crossing itself. 1e-4 is 250x that, and below the smallest displacement
/// feature relative to the viewing distance (a texel of the maps here is ~ 1e-3 of it).
pub const LEAK_TOLERANCE: f64 = 1e-4;

/// The methods whose leaks are measured, in report order.
pub const METHODS: [Method; 4] = [
    Method::NonlinearF32,
    Method::NonlinearF64,
    Method::AffineF32,
    Method::AffineF64,
];

/// The outcome for one ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The ray does not reach a base triangle from outside: no claim.
    NotDecided,
    /// Reaches the base and the tracer hit no farther than the crossing.
    Hit,
    /// Reaches the base and the tracer missed or hit beyond the crossing.
    Leak,
}

/// Leak counts of one precision on one scene.
#[derive(Clone, Debug)]
pub struct LeakReport {
    /// The tracing method measured.
    pub method: Method,
    /// Rays cast.
    pub rays: usize,
    /// Rays that reach a base triangle from outside (decided by the oracle).
    pub decided: usize,
    /// Leaks among them.
    pub leaks: usize,
    /// Verdict per pixel (row-major), for the leak image.
    pub verdicts: Vec<Verdict>,
    /// Seconds.
    pub seconds: f64,
}

impl LeakReport {
    /// Leak rate among decided rays.
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.leaks as f64 / self.decided.max(1) as f64
    }

    /// 95% Wilson score interval of the leak rate (sound also at 0 leaks).
    #[must_use]
    pub fn wilson_95(&self) -> (f64, f64) {
        let n = self.decided.max(1) as f64;
        let p = self.rate();
        let z = 1.959_963_984_540_054f64;
        let den = 1.0 + z * z / n;
        let centre = (p + z * z / (2.0 * n)) / den;
        let half = z * ((p * (1.0 - p) / n) + z * z / (4.0 * n * n)).sqrt() / den;
        let lo = if self.leaks == 0 {
            0.0
        } else {
            (centre - half).max(0.0)
        };
        (lo, (centre + half).min(1.0))
    }
}

/// Whether every edge of the mesh has two triangles (no boundary).
fn is_closed(scene: &Scene) -> bool {
    use std::collections::HashMap;
    let key = |p: DVec3| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
    let mut edges: HashMap<_, u32> = HashMap::new();
    for t in &scene.triangles {
        for k in 0..3 {
            let (a, b) = (
                key(scene.positions[t[k] as usize]),
                key(scene.positions[t[(k + 1) % 3] as usize]),
            );
            *edges
                .entry(if a < b { (a, b) } else { (b, a) })
                .or_default() += 1;
        }
    }
    edges.values().all(|&c| c == 2)
}

/// A float pre-filter for the exact test: `false` only when the f64 barycentric coordinates
/// are clearly outside (by 1e-6, some 10^9 ulps of the well-conditioned f64 computation) or
/// the crossing is clearly behind; near-parallel rays go to the exact test.
fn may_cross(o: [f64; 3], d: [f64; 3], tri: &[[f64; 3]; 3]) -> bool {
    let (o, d) = (DVec3::from(o), DVec3::from(d));
    let [a, b, c] = tri.map(DVec3::from);
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 * e1.length() * e2.length() {
        return true;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    const SLACK: f64 = 1e-6;
    u >= -SLACK && v >= -SLACK && u + v <= 1.0 + SLACK && t > -SLACK * (1.0 + t.abs())
}

/// A prism's base and top triangles (f64, exactly the tracer's values) and the sign that
/// orients the base's geometric normal like the vertex normals.
type Caps = ([[f64; 3]; 3], [[f64; 3]; 3], f64);

fn to_f64<T: Real>(v: T::Vec3) -> [f64; 3] {
    [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()]
}

/// Runs `rays_side x rays_side` camera rays (pixel centres) through `scene` with `method`
/// (nonlinear tracing or tessellation-free mapping, in either precision).
///
/// # Errors
/// A scene that is not a displacement scene, or the pre-tessellated reference (its f64
/// triangles are not the surface the oracle's criterion is stated for).
pub fn measure(scene: &Scene, rays_side: usize, method: Method) -> Result<LeakReport, String> {
    match method {
        Method::NonlinearF32 => measure_in::<f32>(scene, rays_side, method),
        Method::NonlinearF64 => measure_in::<f64>(scene, rays_side, method),
        Method::AffineF32 => measure_in::<f32>(scene, rays_side, method),
        Method::AffineF64 => measure_in::<f64>(scene, rays_side, method),
        Method::Tessellated => Err(format!(
            "{method}: watertightness is measured for nonlinear and tessellation-free tracing"
        )),
    }
}

fn measure_in<T: Real>(
    scene: &Scene,
    rays_side: usize,
    method: Method,
) -> Result<LeakReport, String> {
    if !matches!(scene.content, Content::Displacement(_)) {
        return Err(format!(
            "scene '{}' is shell-mapped; watertightness is measured on displacement scenes",
            scene.name
        ));
    }
    let start = std::time::Instant::now();
    let affine = matches!(method, Method::AffineF32 | Method::AffineF64);
    let tracer = Nonlinear::<T>::new(scene);
    let Nonlinear::Displaced(surface) = &tracer else {
        unreachable!("displacement scene")
    };
    let closed = is_closed(scene);
    // Base and top-cap triangles exactly as the tracer's prisms have them.
    let mesh = surface.mesh();
    let caps: Vec<Caps> = (0..mesh.triangle_count())
        .map(|i| {
            let prism = surface.prism(i);
            let base = prism.p.map(to_f64::<T>);
            let top = [0, 1, 2].map(|k| to_f64::<T>(prism.p[k] + prism.n[k]));
            // Orientation: the side the (scaled) normals point to.
            let (a, b, c) = (
                DVec3::from(base[0]),
                DVec3::from(base[1]),
                DVec3::from(base[2]),
            );
            let normal_sum = prism
                .n
                .iter()
                .fold(DVec3::ZERO, |s, &n| s + DVec3::from(to_f64::<T>(n)));
            let orient = (b - a).cross(c - a).dot(normal_sum).signum();
            (base, top, orient)
        })
        .collect();
    let boxes: Vec<Aabb<f64>> = caps
        .iter()
        .map(|(b, t, _)| Aabb::of_points(b.iter().chain(t.iter()).map(|&p| DVec3::from(p))))
        .collect();
    let bvh = Bvh4::build(&boxes, 1);
    let n = rays_side;
    let verdicts: Vec<Verdict> = (0..n * n)
        .into_par_iter()
        .map(|k| {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let d = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
            let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
            let Some(ray) = Ray::new(v(scene.camera.eye), v(d)) else {
                return Verdict::NotDecided;
            };
            let (o, dir) = (to_f64::<T>(ray.origin), to_f64::<T>(ray.dir));
            // Nearest exact base crossing, and the nearest front top-cap crossing.
            let slab = SlabRay::new(DVec3::from(o), DVec3::from(dir));
            let mut base: Option<(f64, bool)> = None;
            let mut top: Option<f64> = None;
            bvh.traverse(&slab, 0.0, f64::INFINITY, |i, _| {
                let (b, t, orient) = &caps[i as usize];
                if may_cross(o, dir, b)
                    && let Some(c) = ray_triangle(o, dir, *b)
                {
                    let front = c.from_front == (*orient > 0.0);
                    if base.is_none_or(|(bt, _)| c.t < bt) {
                        base = Some((c.t, front));
                    }
                }
                if may_cross(o, dir, t)
                    && let Some(c) = ray_triangle(o, dir, *t)
                    && c.from_front == (*orient > 0.0)
                    && top.is_none_or(|tt| c.t < tt)
                {
                    top = Some(c.t);
                }
                None // visit every candidate
            });
            let Some((t_base, true)) = base else {
                return Verdict::NotDecided;
            };
            if !closed && !top.is_some_and(|t| t <= t_base) {
                return Verdict::NotDecided;
            }
            let mut stats = TraversalStats::default();
            let hit = if affine {
                surface
                    .intersect_affine(&ray, T::ZERO, T::INFINITY, &mut stats)
                    .map(|h| (h.t, h.triangle, h.texel, h.part, T::NAN))
            } else {
                surface
                    .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                    .map(|h| (h.hit.t, h.triangle, h.texel, h.part, h.hit.h))
            };
            match hit {
                Some(h) if h.0.to_f64() <= t_base * (1.0 + LEAK_TOLERANCE) => Verdict::Hit,
                _ => {
                    if std::env::var_os("NLRT_SHOW_LEAKS").is_some() {
                        eprintln!(
                            "{method} leak at pixel ({x}, {y}): base crossing t = {t_base}, tracer {:?}",
                            hit.map(|h| (h.0.to_f64(), h.1, h.2, h.3, h.4.to_f64()))
                        );
                    }
                    Verdict::Leak
                }
            }
        })
        .collect();
    let decided = verdicts
        .iter()
        .filter(|v| **v != Verdict::NotDecided)
        .count();
    let leaks = verdicts.iter().filter(|v| **v == Verdict::Leak).count();
    Ok(LeakReport {
        method,
        rays: n * n,
        decided,
        leaks,
        verdicts,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// A leak image like the paper's Fig. 8: decided rays grey, leaks red, undecided black.
#[must_use]
pub fn leak_image(report: &LeakReport) -> Vec<u8> {
    report
        .verdicts
        .iter()
        .flat_map(|v| match v {
            Verdict::NotDecided => [0, 0, 0],
            Verdict::Hit => [150, 150, 150],
            Verdict::Leak => [255, 0, 0],
        })
        .collect()
}
