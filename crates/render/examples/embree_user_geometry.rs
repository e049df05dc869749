//! An nlrt displaced surface as an Embree user geometry beside Embree triangles, against the
//! same surface pre-tessellated into the same Embree scene: the hits agree, and the table says
//! what each costs (build, memory, rays per second, one thread and all).
//!
//! `cargo run --release -p nlrt-render --features embree --example embree_user_geometry --
//! [small|paper] [width]`

use std::time::Instant;

use nlrt_poly::glam::DVec3;
use nlrt_render::scene::scenes::{Size, builtin};
use nlrt_render::trace::embree_reference::{EmbreeTriangles, Isa};
use nlrt_render::trace::embree_user::{EmbreeWithSurface, SURFACE_ID};
use nlrt_render::trace::tessellate::Tessellated;
use nlrt_render::trace::tracer::Tracer;
use rayon::prelude::*;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size = if args.get(1).is_some_and(|a| a == "paper") {
        Size::Paper
    } else {
        Size::Small
    };
    let width: usize = args.get(2).and_then(|w| w.parse().ok()).unwrap_or(640);
    let height = width * 3 / 4;
    let scene = builtin("mountain", size).expect("built-in");
    // A wall of two triangles behind the terrain, which rays over the ridge meet.
    let wall = vec![
        [
            DVec3::new(-3.0, -0.5, -1.4),
            DVec3::new(3.0, -0.5, -1.4),
            DVec3::new(3.0, 3.0, -1.4),
        ],
        [
            DVec3::new(-3.0, -0.5, -1.4),
            DVec3::new(3.0, 3.0, -1.4),
            DVec3::new(-3.0, 3.0, -1.4),
        ],
    ];
    let start = Instant::now();
    let surface = scene.displaced_surface::<f32>().expect("a valid scene");
    let user = EmbreeWithSurface::new(surface, &wall, Isa::Build).expect("an Embree device");
    let user_build = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let mut triangles = Tessellated::new(&scene).triangles().to_vec();
    let surface_triangles = triangles.len() as u32;
    // The wall last: its indices follow the microtriangles'.
    triangles.extend_from_slice(&wall);
    let tessellated = EmbreeTriangles::new(&triangles, Isa::Build).expect("an Embree device");
    let tessellated_build = start.elapsed().as_secs_f64();
    drop(triangles);
    let rays: Vec<DVec3> = (0..width * height)
        .map(|k| {
            let x = ((k % width) as f64 + 0.5) / width as f64;
            let y = ((k / width) as f64 + 0.5) / height as f64;
            scene.camera.direction(x, y, width as f64 / height as f64)
        })
        .collect();
    let eye = scene.camera.eye;
    // Which hits lie on the surface: the user geometry's, or the microtriangles' (the wall's
    // indices follow them).
    let user_surface = |id: u32| id == SURFACE_ID;
    let tessellated_surface = |id: u32| id < surface_triangles;
    let trace = |t: &dyn Tracer, on_surface: &(dyn Fn(u32) -> bool + Sync), threads: bool| {
        let start = Instant::now();
        let hits: Vec<Option<(f64, bool)>> = if threads {
            rays.par_iter()
                .map(|&d| t.intersect(eye, d, 0.0, f64::INFINITY))
                .map(|h| h.map(|h| (h.t, on_surface(h.id))))
                .collect()
        } else {
            rays.iter()
                .map(|&d| t.intersect(eye, d, 0.0, f64::INFINITY))
                .map(|h| h.map(|h| (h.t, on_surface(h.id))))
                .collect()
        };
        (
            hits,
            rays.len() as f64 / start.elapsed().as_secs_f64() / 1e6,
        )
    };
    let (a, user_one) = trace(&user, &user_surface, false);
    let (b, tess_one) = trace(&tessellated, &tessellated_surface, false);
    let (_, user_all) = trace(&user, &user_surface, true);
    let (_, tess_all) = trace(&tessellated, &tessellated_surface, true);
    let (mut agree, mut on_surface, mut on_wall) = (0, 0, 0);
    for (x, y) in a.iter().zip(&b) {
        match (x, y) {
            (None, None) => agree += 1,
            (Some((s, p)), Some((t, q))) if p == q && (s - t).abs() <= 1e-4 * t => {
                agree += 1;
                if *p {
                    on_surface += 1;
                } else {
                    on_wall += 1;
                }
            }
            _ => {}
        }
    }
    println!(
        "mountain ({:?}), {width} x {height} camera rays: {agree} agree ({on_surface} on the surface, {on_wall} on the wall), {} differ",
        size,
        rays.len() - agree
    );
    println!("| scene in Embree | build s | memory MB | Mrays/s 1 thread | Mrays/s all |");
    println!("|---|---:|---:|---:|---:|");
    println!(
        "| nlrt surface as user geometry + 2 triangles | {user_build:.3} | {:.1} (Embree {:.3}) | {user_one:.3} | {user_all:.3} |",
        user.memory_bytes() as f64 / 1e6,
        user.embree_bytes() as f64 / 1e6
    );
    println!(
        "| {surface_triangles} microtriangles + 2 triangles | {tessellated_build:.3} | {:.1} | {tess_one:.3} | {tess_all:.3} |",
        tessellated.memory_bytes() as f64 / 1e6
    );
    let middle = rays[rays.len() / 2 + width / 2];
    println!(
        "the middle ray: hit {:?}, occluded (any hit) {}",
        user.intersect(eye, middle, 0.0, f64::INFINITY).map(|h| h.t),
        user.occluded(eye, middle, f64::INFINITY)
    );
}
