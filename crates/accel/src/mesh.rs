//! The base mesh of a shell: triangles with per-vertex positions, normals and texture
//! coordinates. Prisms are built from it on the fly (sec. 5.2: the TLAS stores no prisms).

use alloc::vec::Vec;
use core::fmt;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::Prism;

use crate::bvh::Aabb;

/// Why a base mesh was rejected. Like every error of this crate it implements
/// [`core::error::Error`], so `?` carries it into a `Box<dyn Error>`:
///
/// ```
/// use nlrt_accel::BaseMesh;
/// use nlrt_accel::glam::{DVec2, DVec3};
/// fn mesh() -> Result<BaseMesh<f64>, Box<dyn std::error::Error>> {
///     Ok(BaseMesh::new(vec![DVec3::ZERO], vec![], vec![DVec2::ZERO], vec![])?)
/// }
/// let message = mesh().unwrap_err().to_string();
/// assert_eq!(message, "vertex attribute counts differ: 1 positions, 0 normals, 1 uvs");
/// ```
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum MeshError {
    /// The position, normal and uv arrays differ in length.
    AttributeCountMismatch {
        /// Positions.
        positions: usize,
        /// Normals.
        normals: usize,
        /// Texture coordinates.
        uvs: usize,
    },
    /// A triangle names a vertex that does not exist.
    IndexOutOfRange {
        /// Triangle.
        triangle: usize,
        /// The bad index.
        index: u32,
    },
    /// A vertex attribute is NaN or infinite.
    NotFinite {
        /// Vertex.
        vertex: usize,
        /// `"position"`, `"normal"` or `"uv"`.
        attribute: &'static str,
    },
    /// No triangles.
    Empty,
    /// A pose's position, or normal times the surface's height scale, has a coordinate
    /// beyond `nlrt_shellmap::max_world_coordinate` of the precision.
    BeyondWorldRange {
        /// Vertex.
        vertex: usize,
        /// `"position"` or `"normal"` (times the height scale).
        attribute: &'static str,
    },
    /// A new pose ([`BaseMesh::set_pose`]) has another vertex count than the mesh.
    PoseVertexCount {
        /// Vertices of the mesh.
        vertices: usize,
        /// Positions in the pose.
        positions: usize,
        /// Normals in the pose.
        normals: usize,
    },
}

impl fmt::Display for MeshError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::AttributeCountMismatch {
                positions,
                normals,
                uvs,
            } => write!(
                f,
                "vertex attribute counts differ: {positions} positions, {normals} normals, {uvs} uvs"
            ),
            Self::IndexOutOfRange { triangle, index } => {
                write!(
                    f,
                    "triangle {triangle} names vertex {index}, which does not exist"
                )
            }
            Self::NotFinite { vertex, attribute } => {
                write!(f, "vertex {vertex} has a NaN or infinite {attribute}")
            }
            Self::Empty => write!(f, "the mesh has no triangles"),
            Self::BeyondWorldRange { vertex, attribute } => write!(
                f,
                "vertex {vertex}: a coordinate of its {attribute} is beyond the largest this precision traces (2^46 in f32, 2^494 in f64: see max_world_coordinate)"
            ),
            Self::PoseVertexCount {
                vertices,
                positions,
                normals,
            } => write!(
                f,
                "a pose of this mesh needs {vertices} positions and normals, not {positions} and {normals}"
            ),
        }
    }
}

/// A plain error (no source): `?` carries it into `Box<dyn core::error::Error>`.
impl core::error::Error for MeshError {}

/// A triangle mesh with positions, normals and texture coordinates per vertex. Degenerate
/// triangles (zero area in world space or in uv space) are allowed: the shell math handles
/// them (Fig. 9 of the paper).
#[derive(Clone, Debug)]
pub struct BaseMesh<T: Real> {
    positions: Vec<T::Vec3>,
    normals: Vec<T::Vec3>,
    uvs: Vec<T::Vec2>,
    triangles: Vec<[u32; 3]>,
}

impl<T: Real> BaseMesh<T> {
    /// A mesh, validated.
    ///
    /// # Errors
    /// Mismatched attribute counts, out-of-range indices, non-finite attributes, no triangles.
    pub fn new(
        positions: Vec<T::Vec3>,
        normals: Vec<T::Vec3>,
        uvs: Vec<T::Vec2>,
        triangles: Vec<[u32; 3]>,
    ) -> Result<Self, MeshError> {
        if positions.len() != normals.len() || positions.len() != uvs.len() {
            return Err(MeshError::AttributeCountMismatch {
                positions: positions.len(),
                normals: normals.len(),
                uvs: uvs.len(),
            });
        }
        if triangles.is_empty() {
            return Err(MeshError::Empty);
        }
        for (t, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(MeshError::IndexOutOfRange { triangle: t, index });
            }
        }
        check_finite::<T>(&positions, &normals)?;
        if let Some(vertex) = uvs
            .iter()
            .position(|uv| !(uv.x().is_finite() && uv.y().is_finite()))
        {
            return Err(MeshError::NotFinite {
                vertex,
                attribute: "uv",
            });
        }
        Ok(Self {
            positions,
            normals,
            uvs,
            triangles,
        })
    }

    /// Moves the vertices to a new pose (an animation frame): new positions and normals, the
    /// same triangles and texture coordinates. The mesh is unchanged when the pose is
    /// rejected. Degenerate poses (collapsed or inverted triangles, zero normals) are
    /// accepted, as in [`BaseMesh::new`].
    ///
    /// # Errors
    /// Another vertex count than the mesh's, or a NaN or infinite value.
    pub fn set_pose(
        &mut self,
        positions: &[T::Vec3],
        normals: &[T::Vec3],
    ) -> Result<(), MeshError> {
        if positions.len() != self.positions.len() || normals.len() != self.positions.len() {
            return Err(MeshError::PoseVertexCount {
                vertices: self.positions.len(),
                positions: positions.len(),
                normals: normals.len(),
            });
        }
        check_finite::<T>(positions, normals)?;
        self.positions.copy_from_slice(positions);
        self.normals.copy_from_slice(normals);
        Ok(())
    }

    /// Triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Vertex indices of triangle `i`.
    #[must_use]
    pub fn triangle(&self, i: usize) -> [u32; 3] {
        self.triangles[i]
    }

    /// Vertex positions.
    #[must_use]
    pub fn positions(&self) -> &[T::Vec3] {
        &self.positions
    }

    /// Vertex normals (not necessarily unit).
    #[must_use]
    pub fn normals(&self) -> &[T::Vec3] {
        &self.normals
    }

    /// Vertex texture coordinates.
    #[must_use]
    pub fn uvs(&self) -> &[T::Vec2] {
        &self.uvs
    }

    /// The prism of triangle `i` with normals scaled by `height_scale` and uvs by `uv_scale`
    /// (per axis: the tiling, times the map's [`crate::HeightField::grid_scale`] for a map that
    /// is not square or not a power of two).
    #[must_use]
    #[inline]
    pub fn prism(&self, i: usize, height_scale: T, uv_scale: [T; 2]) -> Prism<T> {
        let scaled = |uv: T::Vec2| T::Vec2::new(uv.x() * uv_scale[0], uv.y() * uv_scale[1]);
        let [a, b, c] = self.triangles[i].map(|v| v as usize);
        Prism::new(
            [self.positions[a], self.positions[b], self.positions[c]],
            [
                self.normals[a] * height_scale,
                self.normals[b] * height_scale,
                self.normals[c] * height_scale,
            ],
            [
                scaled(self.uvs[a]),
                scaled(self.uvs[b]),
                scaled(self.uvs[c]),
            ],
        )
    }

    /// Bytes of the mesh arrays.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.positions.len()
            * (2 * core::mem::size_of::<T::Vec3>() + core::mem::size_of::<T::Vec2>())
            + self.triangles.len() * 12
    }
}

/// The first vertex whose position or normal is NaN or infinite, as an error.
fn check_finite<T: Real>(positions: &[T::Vec3], normals: &[T::Vec3]) -> Result<(), MeshError> {
    let finite3 = |v: &T::Vec3| v.x().is_finite() && v.y().is_finite() && v.z().is_finite();
    for (vertex, (p, n)) in positions.iter().zip(normals).enumerate() {
        let attribute = if !finite3(p) {
            "position"
        } else if !finite3(n) {
            "normal"
        } else {
            continue;
        };
        return Err(MeshError::NotFinite { vertex, attribute });
    }
    Ok(())
}

/// The box of a prism: its six corners `P_i` and `P_i + N_i` (every side is a bilinear patch
/// between them, inside their convex hull, and the caps are triangles on them).
#[must_use]
pub fn prism_bounds<T: Real>(prism: &Prism<T>) -> Aabb<T> {
    Aabb::of_points((0..3).flat_map(|i| [prism.p[i], prism.p[i] + prism.n[i]]))
}
