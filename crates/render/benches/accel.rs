//! Build times and BLAS/TLAS traversal speed of nlrt-accel on the paper's map sizes.
//!
//! `cargo bench -p nlrt-render --bench accel`
//!
//! - `build/mipmap-4096`: the min-max pyramid of a 4096^2 map (goal <= 60 ms, one thread).
//! - `build/tlas-175k`: TLAS over 175,232 prisms (the paper's dress size; goal <= 150 ms).
//! - `trace/<scene>/<type>`: primary camera rays through the whole structure (TLAS, BLAS
//!   walk, texel or object tests) of the mountain (2 triangles, 4096^2 fBm), the fur (8,192
//!   triangles, 256^2 spikes tiled 8 x 8) and two shell-mapped scenes, the Cornell box
//!   (2,780 object triangles, 16 x 16 tiles) and the high-polygon blob (145,260), f32 and
//!   f64, one thread.

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
use nlrt_poly::glam::{DVec2, DVec3};
use nlrt_poly::{Real, Vector3};
use nlrt_render::scene::scenes::{self, Scene, Size};
use nlrt_render::trace::methods::Nonlinear;
use nlrt_shellmap::Ray;
use std::hint::black_box;

/// Camera rays through a jittered grid of `n x n` pixels.
fn camera_rays(scene: &Scene, n: usize) -> Vec<(DVec3, DVec3)> {
    (0..n * n)
        .map(|k| {
            let (x, y) = ((k % n) as f64 + 0.37, (k / n) as f64 + 0.61);
            (
                scene.camera.eye,
                scene
                    .camera
                    .direction(x / n as f64, y / n as f64, 4.0 / 3.0),
            )
        })
        .collect()
}

fn trace<T: Real>(c: &mut Criterion, scene: &Scene) {
    let surface = Nonlinear::<T>::new(scene);
    let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
    let rays: Vec<Ray<T>> = camera_rays(scene, 64)
        .into_iter()
        .map(|(o, d)| Ray::new(v(o), v(d)).unwrap())
        .collect();
    let mut g = c.benchmark_group(format!("trace/{}", scene.name));
    g.throughput(Throughput::Elements(rays.len() as u64));
    g.bench_function(BenchmarkId::from_parameter(T::NAME), |b| {
        b.iter(|| {
            let mut stats = TraversalStats::default();
            rays.iter()
                .filter(|r| match &surface {
                    Nonlinear::Displaced(s) => s
                        .intersect(black_box(r), T::ZERO, T::INFINITY, &mut stats)
                        .is_some(),
                    Nonlinear::Shell(s) => s
                        .intersect(black_box(r), T::ZERO, T::INFINITY, &mut stats)
                        .is_some(),
                })
                .count()
        })
    });
    g.finish();
}

/// A torus of `n x n` quads (2 n^2 triangles).
fn torus_mesh(n: usize) -> BaseMesh<f32> {
    let (mut p, mut nn, mut uv, mut t) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for j in 0..=n {
        for i in 0..=n {
            let (a, b) = (
                std::f64::consts::TAU * i as f64 / n as f64,
                std::f64::consts::TAU * j as f64 / n as f64,
            );
            let normal = DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
            let pos = DVec3::new(a.cos(), 0.0, a.sin()) + normal * 0.3;
            p.push(pos.as_vec3());
            nn.push(normal.as_vec3());
            uv.push(DVec2::new(i as f64 / n as f64, j as f64 / n as f64).as_vec2());
        }
    }
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    BaseMesh::new(p, nn, uv, t).unwrap()
}

fn builds(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    let heights = scenes::fbm_map(4096, 4, 8, 11);
    let field = HeightField::from_unit_heights(4096, 4096, &heights, Wrap::Repeat).unwrap();
    eprintln!(
        "4096^2 map: samples + pyramid = {:.2} MB ({:.2} MiB)",
        field.memory_bytes() as f64 / 1e6,
        field.memory_bytes() as f64 / (1024.0 * 1024.0)
    );
    g.bench_function("mipmap-4096", |b| {
        let mut f = field.clone();
        b.iter(|| {
            f.rebuild();
            black_box(f.range())
        })
    });
    let mut edit = field.clone();
    g.bench_function("mipmap-4096-edit-64", |b| {
        b.iter(|| {
            for j in 1000..1064 {
                for i in 2000..2064 {
                    edit.samples_mut()[j * 4096 + i] ^= 0x55;
                }
            }
            edit.update_region(2000, 1000, 2064, 1064);
            black_box(edit.range())
        })
    });
    let mesh = torus_mesh(296);
    assert_eq!(mesh.triangle_count(), 175_232);
    let small = HeightField::new(2, 2, vec![0; 4], Wrap::Repeat).unwrap();
    g.bench_function("tlas-175k", |b| {
        b.iter(|| {
            DisplacedSurface::new(mesh.clone(), small.clone(), 0.01f32, 1.0)
                .unwrap()
                .tlas()
                .node_count()
        })
    });
    let boxes: Vec<_> = (0..mesh.triangle_count())
        .map(|i| nlrt_accel::prism_bounds(&mesh.prism(i, 0.01, [1.0; 2])))
        .collect();
    g.bench_function("bvh-only-175k", |b| {
        b.iter(|| nlrt_accel::Bvh4::build(black_box(&boxes), 1).node_count())
    });
    g.finish();
}

fn traversal(c: &mut Criterion) {
    for name in ["mountain", "fur", "cornell", "highpoly"] {
        let scene = scenes::builtin(name, Size::Paper).unwrap();
        trace::<f32>(c, &scene);
        trace::<f64>(c, &scene);
    }
}

criterion_group! {
    name = accel;
    config = Criterion::default().sample_size(10).warm_up_time(std::time::Duration::from_millis(500)).measurement_time(std::time::Duration::from_secs(3));
    targets = builds, traversal
}
criterion_main!(accel);
