//! Geometry the unit tests of the methods share.

use alloc::vec;
use nlrt_poly::glam::{DVec2, DVec3};

use nlrt_accel::{BaseMesh, DisplacedSurface, HEIGHT_ONE, HeightField, Wrap};

/// The unit square `[0, 1]^2` at `z = 0` as two triangles, uvs equal to `(x, y)`, every vertex
/// normal `normal`.
pub(crate) fn unit_square(normal: DVec3, triangles: [[u32; 3]; 2]) -> BaseMesh<f64> {
    BaseMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
        vec![normal; 4],
        vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
        triangles.to_vec(),
    )
    .expect("a valid square")
}

/// The triangle `(0, 0, 0), (1, 0, 0), (0, 1, 0)` with normals `+z` and its uvs on a line
/// (`(0, 0), (0.5, 0.5), (1, 1)`): degenerate in uv, not in world.
pub(crate) fn uv_line_triangle() -> BaseMesh<f64> {
    BaseMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::Y],
        vec![DVec3::Z; 3],
        vec![DVec2::ZERO, DVec2::splat(0.5), DVec2::ONE],
        vec![[0, 1, 2]],
    )
    .expect("a valid triangle")
}

/// The triangle `(0, 0, 0), (1, 0, 0), (2, 0, 0)` with normals `+z` and regular uvs:
/// degenerate in world (a line), not in uv.
pub(crate) fn world_line_triangle() -> BaseMesh<f64> {
    BaseMesh::new(
        vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)],
        vec![DVec3::Z; 3],
        vec![DVec2::ZERO, DVec2::X, DVec2::Y],
        vec![[0, 1, 2]],
    )
    .expect("a valid triangle")
}

/// The unit square with normals `+z`, height scale 1, under a constant map at `height`; with
/// the height as stored (16-bit).
pub(crate) fn flat_map_square(height: f32) -> (DisplacedSurface<f64>, f64) {
    let mesh = unit_square(DVec3::Z, [[0, 1, 2], [0, 2, 3]]);
    let field =
        HeightField::from_unit_heights(16, 16, &[height; 256], Wrap::Clamp).expect("a valid map");
    let stored = f64::from(field.sample(0, 0)) / f64::from(HEIGHT_ONE);
    let surface = DisplacedSurface::new(mesh, field, 1.0, 1.0).expect("a valid surface");
    (surface, stored)
}

/// 100 slanted rays down onto [`flat_map_square`]: `trace(ray)` must return a hit distance
/// whose point lies at world height `z` within 1e-3 (the sampling methods' binary search
/// reaches 2^-10 of a sample step).
pub(crate) fn assert_slanted_rays_meet_height(
    z: f64,
    mut trace: impl FnMut(&nlrt_shellmap::Ray<f64>) -> Option<f64>,
) {
    for i in 0..100 {
        let (x, y) = (0.05 + 0.007 * i as f64, 0.9 - 0.008 * i as f64);
        let ray = nlrt_shellmap::Ray::new(DVec3::new(x, y, 2.0), DVec3::new(0.1, 0.05, -1.0))
            .expect("a valid ray");
        let t = trace(&ray).unwrap_or_else(|| panic!("ray {i} misses"));
        let p = ray.origin + ray.dir * t;
        assert!((p.z - z).abs() < 1e-3, "ray {i}: {p:?}");
    }
}
