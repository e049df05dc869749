//! Per-operation cost of the shell-mapping kernels, f32 and f64, each next to one cubic solve
//! measured in the same run (the unit the issue asks for).
//!
//! `cargo bench -p nlrt-shellmap --bench shellmap`

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nlrt_oracle::families::SplitMix64;
use nlrt_poly::{Real, Vector2, Vector3, solve_cubic_in};
use nlrt_shellmap::{
    NonlinearRay, Prism, Ray, intersect_box, intersect_microtriangle, intersect_prism,
};
use std::hint::black_box;

const N: usize = 4096;

struct Setup<T: Real> {
    prisms: Vec<Prism<T>>,
    rays: Vec<Ray<T>>,
    tris: Vec<[T::Vec3; 3]>,
}

fn setup<T: Real>() -> Setup<T> {
    let mut rng = SplitMix64::new(7);
    let mut r = |scale: f64| T::from_f64(scale * (rng.unit() - 0.5));
    let mut prisms = Vec::new();
    let mut rays = Vec::new();
    let mut tris = Vec::new();
    for _ in 0..N {
        let v = |x: T, y: T, z: T| T::Vec3::new(x, y, z);
        let one = T::ONE;
        let p = [
            v(r(0.2), r(0.2), r(0.2)),
            v(one + r(0.2), r(0.2), r(0.2)),
            v(r(0.2), one + r(0.2), r(0.2)),
        ];
        let n = [
            v(r(0.4), r(0.4), one),
            v(r(0.4), r(0.4), one),
            v(r(0.4), r(0.4), one),
        ];
        let uv = [
            T::Vec2::new(T::ZERO, T::ZERO),
            T::Vec2::new(one, T::ZERO),
            T::Vec2::new(T::ZERO, one),
        ];
        prisms.push(Prism::new(p, n, uv));
        let origin = v(
            r(1.0) + T::HALF * T::HALF,
            r(1.0) + T::HALF * T::HALF,
            T::from_f64(3.0),
        );
        let target = v(
            T::from_f64(0.3) + r(0.2),
            T::from_f64(0.3) + r(0.2),
            T::HALF,
        );
        rays.push(Ray::new(origin, target - origin).unwrap());
        // A microtriangle of a 64 x 64 texel grid under the ray, heights in [0.3, 0.7].
        let texel = T::from_f64(1.0 / 64.0);
        let (u0, v0) = (T::from_f64(0.3), T::from_f64(0.3));
        let mut h = || T::from_f64(0.5) + r(0.4);
        tris.push([
            v(u0, v0, h()),
            v(u0 + texel, v0, h()),
            v(u0, v0 + texel, h()),
        ]);
    }
    Setup { prisms, rays, tris }
}

fn bench_type<T: Real>(c: &mut Criterion) {
    let s = setup::<T>();
    let rays: Vec<NonlinearRay<T>> = s
        .prisms
        .iter()
        .zip(&s.rays)
        .map(|(p, r)| NonlinearRay::new(p, r))
        .collect();
    let cubics: Vec<[T; 4]> = s
        .tris
        .iter()
        .zip(&rays)
        .map(|(t, r)| {
            nlrt_shellmap::TexturePlane::through(t)
                .unwrap()
                .ray_cubic(r)
        })
        .collect();
    let mut g = c.benchmark_group(format!("shellmap/{}", T::NAME));
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function(BenchmarkId::from_parameter("cubic_solve_reference"), |b| {
        b.iter(|| {
            cubics
                .iter()
                .map(|&c| solve_cubic_in(black_box(c), T::ZERO, T::ONE).len())
                .sum::<usize>()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("nonlinear_ray_setup"), |b| {
        b.iter(|| {
            s.prisms
                .iter()
                .zip(&s.rays)
                .map(|(p, r)| NonlinearRay::new(black_box(p), black_box(r)).d[0])
                .fold(T::ZERO, |a, x| a + x)
        })
    });
    g.bench_function(BenchmarkId::from_parameter("microtriangle"), |b| {
        b.iter(|| {
            s.prisms
                .iter()
                .zip(&rays)
                .zip(&s.tris)
                .filter(|((p, r), t)| {
                    intersect_microtriangle(
                        p,
                        r,
                        black_box(t),
                        T::ZERO,
                        T::ONE,
                        T::ZERO,
                        T::INFINITY,
                    )
                    .is_some()
                })
                .count()
        })
    });
    // A texel-sized box (64 x 64 grid) around the microtriangle, heights [0.3, 0.7].
    let boxes: Vec<([T; 3], [T; 3])> = s
        .tris
        .iter()
        .map(|t| {
            let texel = T::from_f64(1.0 / 64.0);
            (
                [t[0].x(), t[0].y(), T::from_f64(0.3)],
                [t[0].x() + texel, t[0].y() + texel, T::from_f64(0.7)],
            )
        })
        .collect();
    g.bench_function(BenchmarkId::from_parameter("texture_aabb"), |b| {
        b.iter(|| {
            s.prisms
                .iter()
                .zip(&rays)
                .zip(&boxes)
                .filter(|((p, r), (lo, hi))| {
                    intersect_box(p, r, black_box(*lo), *hi, T::ZERO, T::INFINITY).is_some()
                })
                .count()
        })
    });
    g.bench_function(BenchmarkId::from_parameter("ray_vs_prism"), |b| {
        b.iter(|| {
            s.prisms
                .iter()
                .zip(&s.rays)
                .filter(|(p, r)| intersect_prism(black_box(p), r, T::ZERO, T::INFINITY).is_some())
                .count()
        })
    });
    g.finish();
}

fn benches(c: &mut Criterion) {
    bench_type::<f64>(c);
    bench_type::<f32>(c);
}

criterion_group! {
    name = shellmap;
    config = Criterion::default().sample_size(20).warm_up_time(std::time::Duration::from_millis(300)).measurement_time(std::time::Duration::from_secs(1));
    targets = benches
}
criterion_main!(shellmap);
