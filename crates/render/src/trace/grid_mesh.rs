//! The pre-tessellated displaced surface as vertex grids: what a memory-conscious Embree user
//! builds for a height field (`RTC_GEOMETRY_TYPE_GRID`, the `embree-grid-f32` method). One
//! grid per pair of base triangles that together cover a square of whole texels, split along
//! the square's diagonal from its `(0, 0)` to its `(n, n)` corner (the mountain's quad): the
//! grid's quads are then the texels and its triangles the microtriangles of
//! [`Tessellated`](crate::trace::tessellate::Tessellated), one vertex per texel corner
//! instead of three per microtriangle. Other base meshes (a texel cut by a base edge, a seam
//! wall) have no grid and are refused with the reason.

use std::collections::HashMap;

use nlrt_accel::{HEIGHT_ONE, HeightField};
use nlrt_poly::glam::{DVec2, DVec3};

use crate::scene::scenes::{Content, Scene};
use crate::trace::tessellate::{displaced_floor, flat_world};

/// The most vertices per grid side Embree accepts (`RTCGrid`'s `width` and `height`; its
/// documentation: "The maximum allowed width and height is 32767").
pub const MAX_GRID_VERTICES: u32 = 32767;

/// One grid: a window of [`GridMesh::vertices`] (`width x height` vertices, rows `stride`
/// apart from `start`) and the base triangles whose texels it holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Grid {
    /// Index of the grid's first vertex.
    pub start: u32,
    /// Vertices from one row to the next.
    pub stride: u32,
    /// Vertices per row.
    pub width: u16,
    /// Rows.
    pub height: u16,
    /// The base triangle below the square's diagonal (texel-space `x - x0 > y - y0`) and
    /// the one above it.
    pub base: [u32; 2],
    /// The texel-space corner `(x0, y0)` of the grid's square and its side `n` in texels.
    pub square: [i64; 3],
    /// The texel-space `x` of the grid's first vertex column (columns run towards smaller
    /// `x`, see [`GridMesh`]) and `y` of its first row.
    pub first: [i64; 2],
}

/// Vertex grids of a displacement scene. Rows run along texel-space `y`; within a row the
/// vertices run towards *smaller* `x`, so that Embree's split of a grid quad `v0 v1 v2 v3`
/// into `(v0, v1, v3)` and `(v2, v3, v1)` cuts each texel along the diagonal from its
/// `(0, 0)` to its `(1, 1)` corner, as the microtriangles do.
#[derive(Clone, Debug, Default)]
pub struct GridMesh {
    /// Vertices in world space, single precision (Embree's).
    pub vertices: Vec<[f32; 3]>,
    /// The grids.
    pub grids: Vec<Grid>,
}

/// The windows `[column, row, width, height]` (in vertices) that cover a square of `n x n`
/// quads with grids of at most [`MAX_GRID_VERTICES`] per side, neighbours sharing their
/// border vertices.
fn windows(n: i64) -> Vec<[i64; 4]> {
    let step = i64::from(MAX_GRID_VERTICES) - 1;
    let starts = || (0..n).step_by(step as usize);
    starts()
        .flat_map(|row| {
            starts().map(move |col| [col, row, (n - col).min(step) + 1, (n - row).min(step) + 1])
        })
        .collect()
}

/// Why an instanced object has no grid.
const NOT_A_HEIGHT_FIELD: &str = "grid geometry holds height fields, not instanced objects";

/// A base triangle's uvs in texel units.
fn texel_uvs<'a>(scene: &'a Scene, field: &HeightField) -> impl Fn(usize) -> [DVec2; 3] + 'a {
    let scale = DVec2::new(field.width() as f64, field.height() as f64) * scene.tiling;
    move |b: usize| scene.triangles[b].map(|v| scene.uvs[v as usize] * scale)
}

/// A square of whole texels that two base triangles cover.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Square {
    /// Its texel-space corner `(x0, y0)` and side `n`: `[x0, y0, n]`.
    pub square: [i64; 3],
    /// The base triangle below its diagonal (`x - x0 > y - y0`) and the one above.
    pub base: [u32; 2],
}

/// The squares of whole texels that pairs of base triangles cover, or why the scene has none:
/// what [`GridMesh::new`] checks before it allocates.
///
/// # Errors
/// As [`GridMesh::new`], but for memory.
pub fn squares(scene: &Scene) -> Result<Vec<Square>, &'static str> {
    let Content::Displacement(field) = &scene.content else {
        return Err(NOT_A_HEIGHT_FIELD);
    };
    let (seams, _, _) = displaced_floor(scene);
    if seams.is_some_and(|s| !s.edges().is_empty()) {
        return Err("grid geometry holds no seam walls: the base mesh has uv seams");
    }
    let texel_uvs = texel_uvs(scene, field);
    // Each base triangle's partner across an edge: the two make a square of whole texels
    // whose diagonal `(x0, y0)-(x0 + n, y0 + n)` is their shared edge.
    let mut by_edge: HashMap<[u32; 2], Vec<usize>> = HashMap::new();
    for (b, tri) in scene.triangles.iter().enumerate() {
        for k in 0..3 {
            let (i, j) = (tri[k], tri[(k + 1) % 3]);
            by_edge.entry([i.min(j), i.max(j)]).or_default().push(b);
        }
    }
    let square_of = |a: usize, b: usize| -> Option<Square> {
        let corners: Vec<[i64; 2]> = texel_uvs(a)
            .iter()
            .chain(texel_uvs(b).iter())
            .map(|p| Some([integer(p.x)?, integer(p.y)?]))
            .collect::<Option<_>>()?;
        let x0 = corners.iter().map(|c| c[0]).min()?;
        let y0 = corners.iter().map(|c| c[1]).min()?;
        let n = corners.iter().map(|c| c[0]).max()? - x0;
        let below = |t: &[[i64; 2]]| t.contains(&[x0 + n, y0]);
        let (ta, tb) = (&corners[..3], &corners[3..]);
        let diagonal = [[x0, y0], [x0 + n, y0 + n]];
        let square = n > 0
            && corners.iter().map(|c| c[1]).max()? - y0 == n
            && [ta, tb]
                .iter()
                .all(|t| diagonal.iter().all(|d| t.contains(d)))
            && below(ta) != below(tb)
            && [ta, tb].iter().any(|t| t.contains(&[x0, y0 + n]));
        let base = if below(ta) { [a, b] } else { [b, a] };
        square.then_some(Square {
            square: [x0, y0, n],
            base: base.map(|t| t as u32),
        })
    };
    let mut squares = Vec::new();
    let mut paired = vec![false; scene.triangles.len()];
    for (a, tri) in scene.triangles.iter().enumerate() {
        if paired[a] {
            continue;
        }
        let partner = (0..3).find_map(|k| {
            let (i, j) = (tri[k], tri[(k + 1) % 3]);
            let others = by_edge.get(&[i.min(j), i.max(j)])?;
            others
                .iter()
                .filter(|&&b| b != a && !paired[b])
                .find_map(|&b| Some((b, square_of(a, b)?)))
        });
        let Some((b, square)) = partner else {
            return Err(
                "grid geometry needs the base mesh in pairs of triangles covering squares of whole texels, split along their (0, 0)-(n, n) diagonal",
            );
        };
        paired[a] = true;
        paired[b] = true;
        squares.push(square);
    }
    let vertices: u64 = squares
        .iter()
        .map(|q| (q.square[2] as u64 + 1).pow(2))
        .sum();
    if vertices > u64::from(u32::MAX) {
        return Err("grid geometry of more vertices than 32-bit indices address");
    }
    Ok(squares)
}

/// A texel-space coordinate that is an integer (exactly) of magnitude below `2^31`.
fn integer(v: f64) -> Option<i64> {
    (v == v.round() && v.abs() < 2f64.powi(31)).then_some(v as i64)
}

impl GridMesh {
    /// The grids of `scene`, or why it has none.
    ///
    /// # Errors
    /// Instanced objects; seam walls; a base triangle without a partner forming a square of
    /// whole texels split along its `(0, 0)`-`(n, n)` diagonal; more vertices than 32-bit
    /// indices address or than memory holds.
    pub fn new(scene: &Scene) -> Result<Self, &'static str> {
        let squares = squares(scene)?;
        let Content::Displacement(field) = &scene.content else {
            return Err(NOT_A_HEIGHT_FIELD);
        };
        let (_, normals, floor) = displaced_floor(scene);
        let texel_uvs = texel_uvs(scene, field);
        let total: u64 = squares
            .iter()
            .map(|q| (q.square[2] as u64 + 1).pow(2))
            .sum();
        let mut vertices = Vec::new();
        if vertices.try_reserve_exact(total as usize).is_err() {
            return Err("grid geometry's vertices do not fit in memory");
        }
        let mut grids = Vec::new();
        for Square {
            square: [x0, y0, n],
            base,
        } in squares
        {
            let maps = base.map(|b| {
                let b = b as usize;
                let tri = scene.triangles[b];
                let t = texel_uvs(b);
                let det = (t[1] - t[0]).perp_dot(t[2] - t[0]);
                let p = tri.map(|v| floor[v as usize]);
                let d = tri.map(|v| normals[v as usize] * scene.height_scale);
                (t, det, p, d)
            });
            let start = vertices.len() as u64;
            for j in 0..=n {
                for i in (0..=n).rev() {
                    // Texels on the diagonal belong to both triangles: the one below takes it.
                    let (t, det, p, d) = &maps[usize::from(i < j)];
                    let (x, y) = (x0 + i, y0 + j);
                    let h = f64::from(field.sample(x, y)) / f64::from(HEIGHT_ONE);
                    let w: DVec3 = flat_world(t, *det, p, d, [x as f64, y as f64, h]);
                    vertices.push([w.x as f32, w.y as f32, w.z as f32]);
                }
            }
            for [col, row, w, h] in windows(n) {
                grids.push(Grid {
                    start: (start + (row * (n + 1) + col) as u64) as u32,
                    stride: (n + 1) as u32,
                    width: w as u16,
                    height: h as u16,
                    base,
                    square: [x0, y0, n],
                    first: [x0 + n - col, y0 + row],
                });
            }
        }
        Ok(Self { vertices, grids })
    }

    /// The base triangle of the point at grid coordinates `(u, v)` in `[0, 1]^2` of grid `g`
    /// (Embree's hit coordinates, over the whole grid): the one of the square's side of the
    /// diagonal the point lies on.
    #[must_use]
    pub fn base_triangle(&self, g: usize, u: f32, v: f32) -> Option<u32> {
        let grid = self.grids.get(g)?;
        let x = grid.first[0] as f64 - f64::from(u) * f64::from(grid.width - 1);
        let y = grid.first[1] as f64 + f64::from(v) * f64::from(grid.height - 1);
        let [x0, y0, _] = grid.square;
        Some(grid.base[usize::from(x - x0 as f64 <= y - y0 as f64)])
    }

    /// The grids' triangles in world space, two per texel, in Embree's split of each quad:
    /// `(v0, v1, v3)` and `(v2, v3, v1)` with `v0 = (c, r)`, `v1 = (c + 1, r)`,
    /// `v2 = (c + 1, r + 1)`, `v3 = (c, r + 1)` in (column, row).
    #[must_use]
    pub fn triangles(&self) -> Vec<[[f32; 3]; 3]> {
        let mut out = Vec::new();
        for g in &self.grids {
            let at = |c: u32, r: u32| self.vertices[(g.start + r * g.stride + c) as usize];
            for r in 0..u32::from(g.height) - 1 {
                for c in 0..u32::from(g.width) - 1 {
                    let v = [at(c, r), at(c + 1, r), at(c + 1, r + 1), at(c, r + 1)];
                    out.push([v[0], v[1], v[3]]);
                    out.push([v[2], v[3], v[1]]);
                }
            }
        }
        out
    }

    /// Bytes of the vertices and grid records (Embree's copies and its BVH are counted by
    /// Embree).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.vertices.len() * std::mem::size_of::<[f32; 3]>()
            + self.grids.len() * std::mem::size_of::<Grid>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::scenes::{Size, builtin};
    use crate::trace::tessellate::Tessellated;

    /// A triangle's corners, each coordinate rounded to a multiple of `quantum` (vertices on
    /// a square's diagonal are mapped by either base triangle, which may differ by a
    /// rounding), sorted (the grid's triangles wind the other way round).
    fn key(t: [[f32; 3]; 3], quantum: f32) -> [[i64; 3]; 3] {
        let mut q = t.map(|p| p.map(|c| (c / quantum).round() as i64));
        q.sort_unstable();
        q
    }

    /// Whether a triangle has an area (the clipping of the tessellation leaves slivers of
    /// none along a base edge that runs on texel diagonals).
    fn has_area(t: &[DVec3; 3]) -> bool {
        let e = (t[1] - t[0]).cross(t[2] - t[0]).length();
        e > 1e-9
            * (t[1] - t[0])
                .length_squared()
                .max((t[2] - t[0]).length_squared())
    }

    /// The grids hold exactly the tessellation's microtriangles (those with an area), split
    /// along the same diagonals (the other split would make every non-planar texel's
    /// triangles differ), on the mountain (one square) and the torus (a quad mesh of 8 x 8
    /// texel squares), and a hit coordinate maps back to the base triangle of its texel.
    #[test]
    fn the_grids_are_the_microtriangles() {
        for (name, squares) in [("mountain", 1), ("torus", 4096)] {
            let scene = builtin(name, Size::Small).unwrap();
            let grids = GridMesh::new(&scene).unwrap();
            let tessellated = Tessellated::new(&scene);
            assert_eq!(grids.grids.len(), squares, "{name}");
            let quantum = 1e-5;
            let mut expected: HashMap<[[i64; 3]; 3], usize> = HashMap::new();
            let mut with_area = 0;
            for t in tessellated.triangles().iter().filter(|t| has_area(t)) {
                with_area += 1;
                let t = t.map(|p| [p.x as f32, p.y as f32, p.z as f32]);
                *expected.entry(key(t, quantum)).or_default() += 1;
            }
            let triangles = grids.triangles();
            assert_eq!(triangles.len(), with_area, "{name}");
            let mut missing = 0;
            for t in triangles {
                match expected.get_mut(&key(t, quantum)) {
                    Some(n) if *n > 0 => *n -= 1,
                    _ => missing += 1,
                }
            }
            // A corner within a rounding of a quantum's boundary may round to the other key.
            assert!(
                missing * 1000 <= with_area,
                "{name}: {missing} of {with_area}"
            );
            let g = &grids.grids[0];
            let n = g.square[2] as f32;
            // Grid (u, v) = (0, 0) is the square's corner (x0 + n, y0), below the diagonal;
            // (1, 1) is (x0, y0 + n), above it.
            assert_eq!(
                grids.base_triangle(0, 0.1 / n, 0.0),
                Some(g.base[0]),
                "{name}"
            );
            assert_eq!(grids.base_triangle(0, 1.0, 0.9), Some(g.base[1]), "{name}");
            assert_ne!(g.base[0], g.base[1]);
        }
    }

    /// Scenes without squares of whole texels are refused with the reason: instanced
    /// objects, rectangles of texels that are not squares, a triangle without its partner.
    #[test]
    fn other_base_meshes_have_no_grid() {
        let cornell = builtin("cornell", Size::Small).unwrap();
        let mut stretched = builtin("mountain", Size::Small).unwrap();
        for uv in &mut stretched.uvs {
            uv.y *= 0.5;
        }
        let mut alone = builtin("mountain", Size::Small).unwrap();
        alone.triangles.truncate(1);
        for scene in [cornell, stretched, alone] {
            let e = GridMesh::new(&scene).unwrap_err();
            assert!(e.contains("grid geometry"), "{e}");
        }
    }

    /// Squares wider than Embree's limit are covered by several grids within it, each quad
    /// by exactly one, neighbours sharing their border vertices.
    #[test]
    fn large_squares_split_into_grids_within_the_limit() {
        for n in [1, 4096, 32766, 32767, 65536] {
            let w = windows(n);
            let mut quads = 0;
            for &[col, row, width, height] in &w {
                assert!(
                    width <= i64::from(MAX_GRID_VERTICES) && height <= i64::from(MAX_GRID_VERTICES)
                );
                assert!(col + width - 1 <= n && row + height - 1 <= n, "{n}");
                quads += (width - 1) * (height - 1);
            }
            assert_eq!(quads, n * n, "{n}");
            let expected = if n <= 32766 {
                1
            } else {
                (n as usize).div_ceil(32766).pow(2)
            };
            assert_eq!(w.len(), expected, "{n}");
        }
    }
}
