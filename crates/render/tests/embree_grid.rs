//! The displaced surface as Embree grid geometry hits where the same microtriangles as an
//! Embree triangle mesh do, with the base triangle of the hit texel as its id, on the mountain
//! (one square of texels) and the torus (a quad mesh of texel squares). Only with the `embree`
//! feature (Debian's libembree-dev).
#![cfg(feature = "embree")]

use nlrt_render::scene::scenes::{Size, builtin};
use nlrt_render::trace::embree_grid::EmbreeGrids;
use nlrt_render::trace::embree_reference::{EmbreeTessellated, Isa};
use nlrt_render::trace::method::Method;
use nlrt_render::trace::tracer::Tracer;

#[test]
fn grids_hit_where_the_triangle_mesh_does() {
    for name in ["mountain", "torus"] {
        let scene = builtin(name, Size::Small).expect("built-in");
        let grids = EmbreeGrids::new(&scene, Isa::Build).expect("grids and an Embree device");
        let triangles = EmbreeTessellated::new(&scene, Isa::Build).expect("an Embree device");
        let n = 96;
        let (mut hits, mut other_id) = (0, 0);
        for k in 0..n * n {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let dir = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
            let eye = scene.camera.eye;
            let a = grids.intersect(eye, dir, 0.0, f64::INFINITY);
            let b = triangles.intersect(eye, dir, 0.0, f64::INFINITY);
            assert_eq!(a.is_some(), b.is_some(), "{name} ray {k}");
            // Embree's any-hit query (`rtcOccluded1`) agrees on both.
            assert_eq!(grids.occluded(eye, dir, 0.0, f64::INFINITY), a.is_some());
            assert_eq!(
                triangles.occluded(eye, dir, 0.0, f64::INFINITY),
                b.is_some()
            );
            if let (Some(a), Some(b)) = (a, b) {
                hits += 1;
                assert!(
                    (a.t - b.t).abs() <= 1e-5 * b.t,
                    "{name} ray {k}: {} vs {}",
                    a.t,
                    b.t
                );
                assert!(a.normal.dot(b.normal) > 0.999, "{name} ray {k}");
                // A hit on the square's diagonal may take either base triangle.
                if a.id != b.id {
                    other_id += 1;
                }
            }
        }
        assert!(hits > n * n / 4, "{name}: {hits}");
        assert!(other_id * 100 <= hits, "{name}: {other_id} of {hits}");
        assert!(
            grids.memory_bytes() * 2 < triangles.memory_bytes(),
            "{name}"
        );
    }
    let cornell = builtin("cornell", Size::Small).expect("built-in");
    assert!(!Method::EMBREE_GRID_F32.supports(&cornell));
}
