//! An nlrt displaced surface as an Embree user geometry beside Embree triangles hits where the
//! same surface pre-tessellated into Embree does (the flat-based mountain's microtriangles are
//! the surface itself), wall and terrain alike, and answers Embree's any-hit query. Only with
//! the `embree` feature (Debian's libembree-dev).
#![cfg(feature = "embree")]

use nlrt_poly::glam::DVec3;
use nlrt_render::scene::scenes::{Size, builtin};
use nlrt_render::trace::embree_reference::{EmbreeTriangles, Isa};
use nlrt_render::trace::embree_user::{EmbreeWithSurface, SURFACE_ID};
use nlrt_render::trace::tessellate::Tessellated;
use nlrt_render::trace::tracer::Tracer;

#[test]
fn a_user_geometry_surface_hits_where_its_tessellation_does() {
    let scene = builtin("mountain", Size::Small).expect("built-in");
    let wall = [
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
    let surface = scene.displaced_surface::<f32>().expect("a valid scene");
    let user = EmbreeWithSurface::new(surface, &wall, Isa::Build).expect("an Embree device");
    let mut triangles = Tessellated::new(&scene).triangles().to_vec();
    let microtriangles = triangles.len() as u32;
    triangles.extend_from_slice(&wall);
    let tessellated = EmbreeTriangles::new(&triangles, Isa::Build).expect("an Embree device");
    let n = 64;
    let (mut on_surface, mut on_wall) = (0, 0);
    for k in 0..n * n {
        let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
        let dir = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
        let eye = scene.camera.eye;
        let a = user.intersect(eye, dir, 0.0, f64::INFINITY);
        let b = tessellated.intersect(eye, dir, 0.0, f64::INFINITY);
        match (a, b) {
            (None, None) => {}
            (Some(a), Some(b)) => {
                assert!(
                    (a.t - b.t).abs() <= 1e-4 * b.t,
                    "ray {k}: {} vs {}",
                    a.t,
                    b.t
                );
                assert_eq!(a.id == SURFACE_ID, b.id < microtriangles, "ray {k}");
                if a.id == SURFACE_ID {
                    on_surface += 1;
                    assert!(user.occluded(eye, dir, f64::INFINITY), "ray {k}");
                    assert!(
                        !user.occluded(eye, dir, a.t * 0.99),
                        "ray {k}: before the hit"
                    );
                } else {
                    on_wall += 1;
                }
            }
            other => panic!("ray {k}: {other:?}"),
        }
    }
    assert!(
        on_surface > n * n / 5 && on_wall > n * n / 5,
        "{on_surface} {on_wall}"
    );
    assert!(user.memory_bytes() * 20 < tessellated.memory_bytes());
}
