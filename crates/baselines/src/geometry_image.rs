//! Geometry-image ray tracing (Carr, Hoberock, Crane and Hart 2006): the displaced surface
//! re-sampled on a regular grid (a *geometry image*: one world position per texel corner), a
//! min-max pyramid of world-space boxes built like a mipmap over it, traversed without a stack
//! by following *hit* links (to the first child) and *miss* links (to the next sibling or
//! uncle), and each grid quad's two triangles intersected as a pair: the side of their shared
//! diagonal the ray passes decides which one is tested.
//!
//! The links are implicit in the quadtree (children in a fixed order), as the paper notes one
//! of them can be. The traversal order is fixed, not nearest first, which is the method's
//! documented cost ("nodes are always traversed in the same order").

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;

use nlrt_accel::{Aabb, SlabRay, ray_triangle};

/// Why a geometry image was rejected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GeometryImageError {
    /// The grid side (in quads) is not a power of two >= 1.
    Side(usize),
    /// The number of positions is not `(side + 1)^2`.
    Positions {
        /// Expected.
        expected: usize,
        /// Given.
        given: usize,
    },
}

impl core::fmt::Display for GeometryImageError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Side(s) => write!(f, "geometry image side {s} is not a power of two"),
            Self::Positions { expected, given } => {
                write!(f, "geometry image needs {expected} positions, got {given}")
            }
        }
    }
}

/// A plain error (no source): `?` carries it into `Box<dyn core::error::Error>`.
impl core::error::Error for GeometryImageError {}

/// A hit on a geometry image.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeometryImageHit<T: Real> {
    /// Ray parameter.
    pub t: T,
    /// Geometric normal (not normalised, either orientation).
    pub normal: T::Vec3,
    /// Quad `(x, y)` of the grid.
    pub quad: [u32; 2],
}

/// A geometry image with its min-max pyramid of world boxes.
#[derive(Clone, Debug)]
pub struct GeometryImage<T: Real> {
    side: usize,
    /// `(side + 1)^2` corner positions, row-major; a non-finite position marks a corner the
    /// surface does not cover (its quads are empty).
    positions: Vec<T::Vec3>,
    /// Level `l` holds `(side >> l)^2` boxes; level 0 bounds single quads.
    levels: Vec<Vec<Aabb<T>>>,
}

impl<T: Real> GeometryImage<T> {
    /// Builds the pyramid over a `side x side` grid of quads with `(side + 1)^2` corner
    /// positions (row-major).
    ///
    /// # Errors
    /// A side that is not a power of two, or a wrong number of positions.
    pub fn new(side: usize, positions: Vec<T::Vec3>) -> Result<Self, GeometryImageError> {
        if !side.is_power_of_two() {
            return Err(GeometryImageError::Side(side));
        }
        let expected = (side + 1) * (side + 1);
        if positions.len() != expected {
            return Err(GeometryImageError::Positions {
                expected,
                given: positions.len(),
            });
        }
        let mut image = Self {
            side,
            positions,
            levels: Vec::new(),
        };
        image.rebuild();
        Ok(image)
    }

    /// Rebuilds the pyramid from the positions (after a change of the geometry image).
    pub fn rebuild(&mut self) {
        let n = self.side;
        let mut level0 = Vec::with_capacity(n * n);
        for y in 0..n {
            for x in 0..n {
                let corners = self.quad_corners(x, y);
                let finite = corners
                    .iter()
                    .all(|p| p.x().is_finite() && p.y().is_finite() && p.z().is_finite());
                level0.push(if finite {
                    Aabb::of_points(corners)
                } else {
                    Aabb::EMPTY
                });
            }
        }
        self.levels.clear();
        self.levels.push(level0);
        while self.levels.last().map_or(0, Vec::len) > 1 {
            let below = self.levels.last().expect("a level");
            let m = (n >> self.levels.len()).max(1);
            let mut level = Vec::with_capacity(m * m);
            for y in 0..m {
                for x in 0..m {
                    let at = |cx: usize, cy: usize| &below[(2 * y + cy) * 2 * m + 2 * x + cx];
                    level.push(at(0, 0).union(at(1, 0)).union(at(0, 1)).union(at(1, 1)));
                }
            }
            self.levels.push(level);
        }
    }

    /// Quads per side.
    #[must_use]
    pub fn side(&self) -> usize {
        self.side
    }

    /// Bytes of positions and boxes.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.positions.len() * core::mem::size_of::<T::Vec3>()
            + self
                .levels
                .iter()
                .map(|l| l.len() * core::mem::size_of::<Aabb<T>>())
                .sum::<usize>()
    }

    /// The corners of quad `(x, y)`: `(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)`.
    fn quad_corners(&self, x: usize, y: usize) -> [T::Vec3; 4] {
        let w = self.side + 1;
        let p = |i: usize, j: usize| self.positions[j * w + i];
        [p(x, y), p(x + 1, y), p(x + 1, y + 1), p(x, y + 1)]
    }

    /// The nearest hit with `t` in `(t_min, t_max)`: stackless walk of the pyramid (hit link
    /// to the first child, miss link to the next sibling or uncle), quads as triangle pairs.
    pub fn intersect(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<GeometryImageHit<T>> {
        let slab = SlabRay::new(ray.origin, ray.dir);
        let top = self.levels.len() as u32 - 1;
        let mut best: Option<GeometryImageHit<T>> = None;
        let mut t_max = t_max;
        // The current node: level and position; `None` when the walk is over.
        let mut node = Some((top, 0usize, 0usize));
        while let Some((level, x, y)) = node {
            let m = self.side >> level;
            let b = &self.levels[level as usize][y * m + x];
            let hit = slab.entry(b.lo, b.hi, t_min, t_max).is_some();
            if hit && level > 0 {
                node = Some((level - 1, 2 * x, 2 * y)); // hit link: first child
                continue;
            }
            if hit && let Some(h) = self.intersect_quad(ray, x, y, t_min, t_max) {
                t_max = h.t;
                best = Some(h);
            }
            node = Self::miss_link(top, level, x, y);
        }
        best
    }

    /// The next sibling (children in the order (0,0), (1,0), (0,1), (1,1)) or, after the
    /// last, the parent's miss link; `None` past the root.
    fn miss_link(top: u32, level: u32, x: usize, y: usize) -> Option<(u32, usize, usize)> {
        let (mut level, mut x, mut y) = (level, x, y);
        loop {
            if level == top {
                return None;
            }
            match (x & 1, y & 1) {
                (0, 0) => return Some((level, x + 1, y)),
                (1, 0) => return Some((level, x - 1, y + 1)),
                (0, 1) => return Some((level, x + 1, y)),
                _ => {
                    level += 1;
                    x /= 2;
                    y /= 2;
                }
            }
        }
    }

    /// The quad's two triangles `(c0, c1, c2)` and `(c0, c2, c3)` as a pair: the side of the
    /// shared diagonal `c0 c2` the ray passes picks the one to test (Möller-Trumbore).
    fn intersect_quad(
        &self,
        ray: &Ray<T>,
        x: usize,
        y: usize,
        t_min: T,
        t_max: T,
    ) -> Option<GeometryImageHit<T>> {
        let c = self.quad_corners(x, y);
        // Sign of the ray's passage relative to the plane through the diagonal containing the
        // ray direction: c1 and c3 lie on opposite sides of it for a non-folded quad.
        let diagonal = c[2] - c[0];
        let side_normal = ray.dir.cross(diagonal);
        let s_ray = side_normal.dot(ray.origin - c[0]);
        let s_c1 = side_normal.dot(c[1] - c[0]);
        let first = if s_ray * s_c1 >= T::ZERO {
            [c[0], c[1], c[2]]
        } else {
            [c[0], c[2], c[3]]
        };
        let second = if s_ray * s_c1 >= T::ZERO {
            [c[0], c[2], c[3]]
        } else {
            [c[0], c[1], c[2]]
        };
        // The pair test: the picked triangle; the other only where the quad folds (both
        // off-diagonal corners on one side), where one side no longer decides.
        let folded = s_c1 * side_normal.dot(c[3] - c[0]) > T::ZERO;
        let tris: &[[T::Vec3; 3]] = if folded {
            &[first, second]
        } else {
            core::slice::from_ref(&first)
        };
        let mut best: Option<GeometryImageHit<T>> = None;
        for tri in tris {
            if let Some(t) = ray_triangle(tri, ray.origin, ray.dir).map(|h| h.0)
                && t > t_min
                && t < best.map_or(t_max, |b| b.t)
            {
                best = Some(GeometryImageHit {
                    t,
                    normal: (tri[1] - tri[0]).cross(tri[2] - tri[0]),
                    quad: [x as u32, y as u32],
                });
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;
    use nlrt_poly::glam::DVec3;

    /// A `side x side` grid over the unit square at heights `f(x, y)`.
    fn grid(side: usize, f: impl Fn(f64, f64) -> f64) -> GeometryImage<f64> {
        let mut p = Vec::new();
        for j in 0..=side {
            for i in 0..=side {
                let (x, y) = (i as f64 / side as f64, j as f64 / side as f64);
                p.push(DVec3::new(x, y, f(x, y)));
            }
        }
        GeometryImage::new(side, p).unwrap()
    }

    #[test]
    fn miss_links_visit_every_node_once_in_order() {
        // Walking only miss links from the first node of a level visits each node of that
        // level once (within the root), then ends.
        let top = 3u32;
        for level in 0..top {
            let mut seen = vec![false; 1 << (2 * (top - level))];
            let m = 1usize << (top - level);
            let mut node = Some((level, 0usize, 0usize));
            let mut count = 0;
            while let Some((l, x, y)) = node {
                if l != level {
                    // Climbed: continue from the first child down to `level` again.
                    let k = 1usize << (l - level);
                    node = Some((level, x * k, y * k));
                    continue;
                }
                assert!(!seen[y * m + x]);
                seen[y * m + x] = true;
                count += 1;
                node = GeometryImage::<f64>::miss_link(top, level, x, y);
            }
            assert_eq!(count, m * m);
        }
    }

    #[test]
    fn finds_the_nearest_hit_like_brute_force() {
        let image = grid(16, |x, y| 0.2 * (7.0 * x).sin() * (5.0 * y).cos());
        let mut state = 1u64;
        let mut next = || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..2000 {
            let o = DVec3::new(next() * 1.4 - 0.2, next() * 1.4 - 0.2, 1.0 + next());
            let target = DVec3::new(next(), next(), -0.2 + 0.4 * next());
            let ray = Ray::new(o, target - o).unwrap();
            let fast = image.intersect(&ray, 0.0, f64::INFINITY).map(|h| h.t);
            let mut slow: Option<f64> = None;
            for y in 0..16 {
                for x in 0..16 {
                    let c = image.quad_corners(x, y);
                    for tri in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
                        if let Some(t) = ray_triangle(&tri, ray.origin, ray.dir).map(|h| h.0)
                            && t > 0.0
                            && slow.is_none_or(|s| t < s)
                        {
                            slow = Some(t);
                        }
                    }
                }
            }
            match (fast, slow) {
                (Some(a), Some(b)) => assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}"),
                (None, None) => {}
                // The pair test may differ from testing both triangles only on the diagonal
                // itself, where both give the same point.
                other => panic!("{other:?} for {ray:?}"),
            }
        }
    }

    #[test]
    fn bad_input_is_an_error_and_uncovered_corners_are_holes() {
        assert_eq!(
            GeometryImage::<f64>::new(3, vec![DVec3::ZERO; 16]).unwrap_err(),
            GeometryImageError::Side(3)
        );
        assert!(GeometryImage::<f64>::new(2, vec![DVec3::ZERO; 8]).is_err());
        let mut image = grid(2, |_, _| 0.0);
        image.positions[0] = DVec3::splat(f64::NAN);
        image.rebuild();
        let down =
            |x: f64, y: f64| Ray::new(DVec3::new(x, y, 1.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        assert!(
            image
                .intersect(&down(0.2, 0.2), 0.0, f64::INFINITY)
                .is_none()
        );
        assert!(
            image
                .intersect(&down(0.7, 0.7), 0.0, f64::INFINITY)
                .is_some()
        );
    }
}
