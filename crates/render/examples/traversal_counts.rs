//! Traversal counters of nonlinear tracing (f32) per primary ray of a built-in scene at its
//! small size (or, with a second argument `paper`, at the paper's), 160 x 120 pixel-centre
//! rays, one thread: prism (TLAS leaf) visits, node visits of the BLAS walk, texel tests and
//! walks that fell back to box tests.
//!
//! `cargo run --release --example traversal_counts -p nlrt-render -- fur paper`

use nlrt_accel::TraversalStats;
use nlrt_poly::glam::Vec3;
use nlrt_render::scenes::{Size, builtin};
use nlrt_render::tracers::Nonlinear;
use nlrt_shellmap::Ray;
fn main() {
    let name = std::env::args().nth(1).unwrap_or("mountain".into());
    let size = match std::env::args().nth(2).as_deref() {
        None | Some("small") => Size::Small,
        Some("paper") => Size::Paper,
        Some(other) => {
            eprintln!("unknown size {other} (small or paper)");
            std::process::exit(2);
        }
    };
    let Some(scene) = builtin(&name, size) else {
        eprintln!("unknown scene {name}");
        std::process::exit(2);
    };
    let nl = Nonlinear::<f32>::new(&scene);
    let (w, h) = (160, 120);
    let mut st = TraversalStats::default();
    let mut hits = 0;
    let t0 = std::time::Instant::now();
    for y in 0..h {
        for x in 0..w {
            let d = scene.camera.direction(
                (x as f64 + 0.5) / w as f64,
                (y as f64 + 0.5) / h as f64,
                w as f64 / h as f64,
            );
            let o = scene.camera.eye;
            let ray = Ray::new(
                Vec3::new(o.x as f32, o.y as f32, o.z as f32),
                Vec3::new(d.x as f32, d.y as f32, d.z as f32),
            )
            .unwrap();
            let hit = match &nl {
                Nonlinear::Displaced(s) => s.intersect(&ray, 0.0, f32::INFINITY, &mut st).is_some(),
                Nonlinear::Shell(s) => s.intersect(&ray, 0.0, f32::INFINITY, &mut st).is_some(),
            };
            hits += hit as u32;
        }
    }
    let n = (w * h) as f64;
    println!(
        "{name}: {:.3} s, hits {hits}, per ray: prisms {:.2} nodes {:.2} texels {:.2} fallbacks {}",
        t0.elapsed().as_secs_f64(),
        st.prism_tests as f64 / n,
        st.box_tests as f64 / n,
        st.texel_tests as f64 / n,
        st.fallbacks
    );
}
