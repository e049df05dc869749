//! Geometry the unit tests of the methods share.

use alloc::vec;
use nlrt_poly::glam::{DVec2, DVec3};

use crate::mesh::BaseMesh;

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
