//! Seams of a base mesh, and the rule that closes the cracks they open once displaced.
//!
//! A *seam edge* is an edge shared by two triangles (the same world positions at both ends,
//! bit for bit) whose attributes disagree at an end: other texture coordinates (after tiling;
//! with a repeating map, uvs that differ by the same whole number of tiles at both ends agree,
//! as the torus's `u = 0 / u = 1` wrap) or other normals. Displaced, the two sides end at
//! different heights along the edge (they sample other texels) or in different side walls
//! (other displacement directions): a crack, which the paper lists as a limitation.
//!
//! [`SeamRule::Closed`] closes it, in two parts:
//! 1. **Welded directions.** The vertices that meet at the ends of shared edges (by union
//!    over every edge shared by two triangles) get one displacement direction: the normalised
//!    sum of their distinct normals times their mean length. Both prisms then have the same
//!    side wall along the edge, bit for bit (the bilinear sheet `S(s, h)` of Eq. 1 over the
//!    edge). Vertices away from seams keep their normals.
//! 2. **Seam walls.** On that shared side wall, the region between the two sides' height
//!    curves `h_A(s)` and `h_B(s)` (each the microtriangle surface of its own texels along
//!    the edge) is surface: a ray crossing the side wall at `(s, h)` with `h` between them
//!    hits it. The wall joins the two displaced curves, so the surface is closed.
//!
//! [`SeamRule::Open`] keeps the mesh as given (cracks included), to measure them.

use alloc::collections::BTreeMap;
use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};

use crate::mesh::BaseMesh;

/// How a displaced surface treats its base mesh's seams.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SeamRule {
    /// Welded displacement directions and seam walls: no crack (see the module docs).
    #[default]
    Closed,
    /// The mesh as given: the surface cracks open along seams.
    Open,
}

/// The vertices of base edge `k` in a prism, in the order of its parameter `s` (0 at the
/// first): `k` as in `BaseEdges` (0: `alpha = 0`, `s = beta`; 1: `beta = 0`, `s = alpha`;
/// 2: `alpha + beta = 1`, `s = beta`).
pub const EDGE_VERTICES: [[usize; 2]; 3] = [[0, 2], [0, 1], [1, 2]];

/// Edge parameter `s` of the canonical point `(alpha, beta)` on base edge `k`.
#[must_use]
#[inline]
pub fn edge_parameter<T: Real>(k: usize, alpha: T, beta: T) -> T {
    if k == 1 { alpha } else { beta }
}

/// One side of a seam edge: a triangle and which of its base edges ([`EDGE_VERTICES`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeamSide {
    /// The triangle.
    pub triangle: u32,
    /// Its base edge.
    pub edge: u8,
}

/// An edge where two triangles meet in world space but disagree on uvs or normals.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SeamEdge {
    /// The two triangles and their edges.
    pub sides: [SeamSide; 2],
    /// Whether the second side runs the edge the other way (its `s` is `1 -` the first's).
    pub reversed: bool,
    /// The tiled uvs differ at an end.
    pub uv_differs: bool,
    /// The normals differ at an end.
    pub normal_differs: bool,
}

/// "No seam on this edge" in [`Seams::of_triangle`].
pub const NO_SEAM: u32 = u32::MAX;

/// The seams of a base mesh, found once: the seam edges, per triangle which of its edges
/// are seams, and the vertex groups whose displacement directions the closed rule welds.
#[derive(Clone, Debug, Default)]
pub struct Seams {
    edges: Vec<SeamEdge>,
    /// Per triangle, per base edge, the index into `edges` or [`NO_SEAM`]; empty when there
    /// is no seam (the common case costs one length test per prism).
    by_triangle: Vec<[u32; 3]>,
    /// Vertex groups (two or more vertices at one position, joined by shared edges) whose
    /// normals are not all equal.
    weld_groups: Vec<Vec<u32>>,
    /// Edges shared by more than two triangles with disagreeing attributes (not closed).
    unpaired: usize,
}

/// Bit pattern of a position, exact for f32 and f64 (`to_f64` is exact).
type PositionKey = [u64; 3];

/// The triangles using an edge: (triangle, its edge, the edge's vertices, low key first).
type EdgeUsers = Vec<(u32, u8, [u32; 2])>;

fn position_key<T: Real>(p: T::Vec3) -> PositionKey {
    [p.x(), p.y(), p.z()].map(|c| c.to_f64().to_bits())
}

fn root(parent: &mut [u32], mut i: u32) -> u32 {
    while parent[i as usize] != i {
        parent[i as usize] = parent[parent[i as usize] as usize];
        i = parent[i as usize];
    }
    i
}

/// Whether a triangle has zero world area: its edge vectors' cross product (f64, from the
/// exact f64 values of its positions) is zero, as for two equal positions or three on a
/// line up to the rounding of that product (the pole rows of a uv sphere, Fig. 9's slivers).
fn has_no_area<T: Real>(p: [T::Vec3; 3]) -> bool {
    let f = |v: T::Vec3| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()];
    let [a, b, c] = p.map(f);
    let (e, g) = (
        [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
        [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
    );
    let cross = [
        e[1] * g[2] - e[2] * g[1],
        e[2] * g[0] - e[0] * g[2],
        e[0] * g[1] - e[1] * g[0],
    ];
    cross == [0.0; 3]
}

impl Seams {
    /// Finds the seams of `mesh` under `tiling` (uv repeats of the map per unit); `repeats`
    /// says whether the map repeats (then uvs differing by whole tiles agree).
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, Seams};
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// // Two triangles of a square that share the diagonal's positions, not its uvs.
    /// let p = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let positions = vec![p[0], p[1], p[2], p[0], p[2], p[3]];
    /// let uvs = vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::splat(0.5), DVec2::ONE, DVec2::Y];
    /// let mesh = BaseMesh::<f64>::new(positions, vec![DVec3::Z; 6], uvs, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
    /// let seams = Seams::find(&mesh, 1.0, false);
    /// assert_eq!(seams.edges().len(), 1);
    /// assert!(seams.edges()[0].uv_differs && !seams.edges()[0].normal_differs);
    /// ```
    #[must_use]
    pub fn find<T: Real>(mesh: &BaseMesh<T>, tiling: f64, repeats: bool) -> Self {
        let (positions, normals, uvs) = (mesh.positions(), mesh.normals(), mesh.uvs());
        // Per edge (by positions, low key first): (triangle, edge, its vertices low-first).
        let mut shared: BTreeMap<(PositionKey, PositionKey), EdgeUsers> = BTreeMap::new();
        for t in 0..mesh.triangle_count() {
            let tri = mesh.triangle(t);
            if has_no_area::<T>(tri.map(|v| positions[v as usize])) {
                // No surface (as in the paper's Fig. 9), so it joins nothing: its neighbours'
                // edges are shared with each other, or are boundary edges.
                continue;
            }
            for (k, [i, j]) in EDGE_VERTICES.iter().enumerate() {
                let (a, b) = (tri[*i], tri[*j]);
                let (ka, kb) = (
                    position_key::<T>(positions[a as usize]),
                    position_key::<T>(positions[b as usize]),
                );
                if ka == kb {
                    continue; // a collapsed edge joins nothing
                }
                let (key, ends) = if ka < kb {
                    ((ka, kb), [a, b])
                } else {
                    ((kb, ka), [b, a])
                };
                shared
                    .entry(key)
                    .or_default()
                    .push((t as u32, k as u8, ends));
            }
        }
        let tiled = |v: u32| {
            let uv = uvs[v as usize];
            [uv.x().to_f64() * tiling, uv.y().to_f64() * tiling]
        };
        let normal_bits = |v: u32| position_key::<T>(normals[v as usize]);
        let uv_agree = |a: [u32; 2], b: [u32; 2]| {
            let (a0, a1, b0, b1) = (tiled(a[0]), tiled(a[1]), tiled(b[0]), tiled(b[1]));
            let offset = [a0[0] - b0[0], a0[1] - b0[1]];
            // Below 2^53 the round trip through i64 is exact, so it tests "a whole number".
            let whole = offset
                .iter()
                .all(|&o| o.abs() < 9.0e15 && o == (o as i64) as f64)
                && (repeats || offset == [0.0, 0.0]);
            whole && a1[0] - b1[0] == offset[0] && a1[1] - b1[1] == offset[1]
        };
        let mut parent: Vec<u32> = (0..positions.len() as u32).collect();
        let mut seams = Self::default();
        for users in shared.values() {
            if users.len() != 2 {
                let agree_all = users.windows(2).all(|w| {
                    uv_agree(w[0].2, w[1].2)
                        && normal_bits(w[0].2[0]) == normal_bits(w[1].2[0])
                        && normal_bits(w[0].2[1]) == normal_bits(w[1].2[1])
                });
                seams.unpaired += usize::from(!agree_all);
                continue;
            }
            let ((ta, ka, ea), (tb, kb, eb)) = (users[0], users[1]);
            for end in 0..2 {
                let (a, b) = (root(&mut parent, ea[end]), root(&mut parent, eb[end]));
                parent[a as usize] = b;
            }
            let uv_differs = !uv_agree(ea, eb);
            let normal_differs = (0..2).any(|e| normal_bits(ea[e]) != normal_bits(eb[e]));
            if !(uv_differs || normal_differs) {
                continue;
            }
            // The first side's s runs from its EDGE_VERTICES[k][0]; so does the second's
            // unless the two start at different ends of the edge.
            let first = |t: u32, k: u8| mesh.triangle(t as usize)[EDGE_VERTICES[k as usize][0]];
            let starts_low = |t: u32, k: u8, ends: [u32; 2]| first(t, k) == ends[0];
            seams.edges.push(SeamEdge {
                sides: [
                    SeamSide {
                        triangle: ta,
                        edge: ka,
                    },
                    SeamSide {
                        triangle: tb,
                        edge: kb,
                    },
                ],
                reversed: starts_low(ta, ka, ea) != starts_low(tb, kb, eb),
                uv_differs,
                normal_differs,
            });
        }
        if !seams.edges.is_empty() {
            seams.by_triangle = vec![[NO_SEAM; 3]; mesh.triangle_count()];
            for (index, edge) in seams.edges.iter().enumerate() {
                for side in edge.sides {
                    seams.by_triangle[side.triangle as usize][side.edge as usize] = index as u32;
                }
            }
        }
        // Groups of vertices joined at shared edges' ends whose normals are not all equal.
        let mut groups: BTreeMap<u32, Vec<u32>> = BTreeMap::new();
        for v in 0..positions.len() as u32 {
            groups.entry(root(&mut parent, v)).or_default().push(v);
        }
        for members in groups.into_values().filter(|m| m.len() > 1) {
            let n0 = normal_bits(members[0]);
            if members.iter().any(|&v| normal_bits(v) != n0) {
                seams.weld_groups.push(members);
            }
        }
        seams
    }

    /// The seam edges.
    #[must_use]
    pub fn edges(&self) -> &[SeamEdge] {
        &self.edges
    }

    /// Per base edge of triangle `t` ([`EDGE_VERTICES`]), the index of its seam edge or
    /// [`NO_SEAM`]; `None` when the mesh has no seam.
    #[must_use]
    #[inline]
    pub fn of_triangle(&self, t: usize) -> Option<&[u32; 3]> {
        self.by_triangle.get(t)
    }

    /// Seam edges whose uvs differ.
    #[must_use]
    pub fn uv_seams(&self) -> usize {
        self.edges.iter().filter(|e| e.uv_differs).count()
    }

    /// Seam edges whose normals differ.
    #[must_use]
    pub fn normal_seams(&self) -> usize {
        self.edges.iter().filter(|e| e.normal_differs).count()
    }

    /// Edges shared by more than two triangles with disagreeing attributes: not closed by
    /// the rule (a non-manifold mesh).
    #[must_use]
    pub fn unpaired(&self) -> usize {
        self.unpaired
    }

    /// Whether some vertices have normals to weld (a normal seam, or normals that differ at a
    /// uv seam's shared ends); otherwise [`Seams::welded_normals`] returns its input.
    #[must_use]
    pub fn welds_something(&self) -> bool {
        !self.weld_groups.is_empty()
    }

    /// `normals` with each weld group's vertices given one direction: the normalised sum of
    /// the group's distinct normals times their mean length. A group whose normals cancel
    /// (the sum below `1e-9` of their total length: no direction is common to them) keeps
    /// its normals. Other vertices are untouched, bit for bit.
    #[must_use]
    pub fn welded_normals<T: Real>(&self, normals: &[T::Vec3]) -> Vec<T::Vec3> {
        let mut out = normals.to_vec();
        for group in &self.weld_groups {
            let mut distinct: Vec<[f64; 3]> = Vec::new();
            for &v in group {
                let n = normals[v as usize];
                let n = [n.x().to_f64(), n.y().to_f64(), n.z().to_f64()];
                if !distinct.contains(&n) {
                    distinct.push(n);
                }
            }
            let length =
                |n: &[f64; 3]| nlrt_poly::Real::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            let sum = distinct
                .iter()
                .fold([0.0; 3], |s, n| [s[0] + n[0], s[1] + n[1], s[2] + n[2]]);
            let total: f64 = distinct.iter().map(length).sum();
            let sum_length = length(&sum);
            // Below this the normals (nearly) cancel and their sum's direction is rounding.
            if !(sum_length > 1e-9 * total) {
                continue;
            }
            let scale = total / distinct.len() as f64 / sum_length;
            let welded = T::Vec3::new(
                T::from_f64(sum[0] * scale),
                T::from_f64(sum[1] * scale),
                T::from_f64(sum[2] * scale),
            );
            for &v in group {
                out[v as usize] = welded;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::{DVec2, DVec3};

    /// A unit square's two triangles with their own vertices: `uv_b` and `n_b` for the
    /// second triangle's copies of the diagonal's ends.
    fn split_square(uv_b: [DVec2; 2], n_b: [DVec3; 2]) -> BaseMesh<f64> {
        let p = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        BaseMesh::new(
            vec![p[0], p[1], p[2], p[2], p[3], p[0]],
            vec![DVec3::Z, DVec3::Z, DVec3::Z, n_b[1], DVec3::Z, n_b[0]],
            vec![
                DVec2::ZERO,
                DVec2::X,
                DVec2::ONE,
                uv_b[1],
                DVec2::Y,
                uv_b[0],
            ],
            vec![[0, 1, 2], [3, 4, 5]],
        )
        .unwrap()
    }

    #[test]
    fn seams_are_found_with_their_orientation() {
        let same = split_square([DVec2::ZERO, DVec2::ONE], [DVec3::Z; 2]);
        assert!(Seams::find(&same, 1.0, false).edges().is_empty());
        // Whole tiles apart agree only under a repeating map.
        let shifted = split_square([DVec2::new(1.0, 0.0), DVec2::new(2.0, 1.0)], [DVec3::Z; 2]);
        assert!(Seams::find(&shifted, 1.0, true).edges().is_empty());
        assert_eq!(Seams::find(&shifted, 1.0, false).uv_seams(), 1);
        let tilted = DVec3::new(0.3, 0.0, 1.0);
        let normals = split_square([DVec2::ZERO, DVec2::ONE], [tilted, DVec3::Z]);
        let seams = Seams::find(&normals, 1.0, false);
        assert_eq!((seams.uv_seams(), seams.normal_seams()), (0, 1));
        let edge = seams.edges()[0];
        // Triangle 0's diagonal is its edge 0 (vertices 0 and 2); triangle 1 = (p2, p3, p0)
        // has it as edge 0 too (its vertices 0 and 2, i.e. p2 then p0): reversed.
        assert_eq!(edge.sides.map(|s| s.edge), [0, 0]);
        assert!(edge.reversed);
        assert_eq!(seams.of_triangle(1), Some(&[0, NO_SEAM, NO_SEAM]));
    }

    #[test]
    fn welding_gives_a_group_one_direction_and_leaves_the_rest() {
        let tilted = DVec3::new(0.6, 0.0, 0.8);
        let mesh = split_square([DVec2::ZERO, DVec2::ONE], [tilted, DVec3::Z]);
        let seams = Seams::find(&mesh, 1.0, false);
        let welded = seams.welded_normals::<f64>(mesh.normals());
        // p0's two vertices (0 and 5) share one unit direction between Z and the tilt.
        assert_eq!(welded[0], welded[5]);
        assert!((welded[0].length() - 1.0).abs() < 1e-15);
        assert!((welded[0] - (tilted + DVec3::Z).normalize()).length() < 1e-15);
        // p2's vertices agreed already; p1 and p3 are on no shared edge.
        for v in [1, 2, 3, 4] {
            assert_eq!(welded[v], mesh.normals()[v]);
        }
        // Welding is idempotent: a welded mesh has nothing left to weld.
        let again = BaseMesh::<f64>::new(
            mesh.positions().to_vec(),
            welded.clone(),
            mesh.uvs().to_vec(),
            vec![mesh.triangle(0), mesh.triangle(1)],
        )
        .unwrap();
        assert_eq!(
            Seams::find(&again, 1.0, false).welded_normals::<f64>(&welded),
            welded
        );
    }
}
