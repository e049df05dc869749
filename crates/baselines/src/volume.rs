//! Volumetric content for ray marching (Jeschke, Mantler and Wimmer 2007, sec. 4.4: "height
//! fields as well as 3D textures"): an instanced object voxelised in its unit tile, a 3D
//! texture of occupancy with its distance map, sampled by the same canonical-space marcher as
//! height fields ([`VoxelMarching::intersect_marching`]).
//!
//! The voxels are the object's surface (every voxel a triangle passes through, found by
//! sampling each triangle at half-voxel spacing), not its interior: thin open objects (the
//! feathers' barbs) have no inside. So the surface is thickened to a voxel, and a hit lies up
//! to a voxel (and the binary search's resolution) in front of the object's surface; where a
//! ray slips between two voxels that touch at an edge or corner it misses. The report measures
//! both against the reference.

use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Hit, Prism, Ray, intersect_prism};

use nlrt_accel::{ShellHit, ShellObject, ShellSurface, TraversalStats};

use crate::march::{MarchOptions, Medium, march_segment, sample_count};

/// Largest empty radius stored (voxels).
const MAX_RADIUS: u8 = 15;

/// An object voxelised in its unit tile, with per voxel the empty radius (see the module
/// documentation).
#[derive(Clone, Debug)]
pub struct VoxelObject {
    /// Voxels per axis.
    res: usize,
    /// Occupancy bits, `x + res (y + res z)`.
    occupied: Vec<u64>,
    /// `(voxel, object triangle)` for every occupied voxel, sorted: the triangle that
    /// marked it first (its normal is the hit's).
    triangle_of: Vec<(u32, u32)>,
    /// Chebyshev radius of the empty box around each voxel (tiles repeat in `u` and `v`;
    /// outside `[0, 1]` in height nothing is solid); 0 for occupied voxels.
    radius: Vec<u8>,
}

impl VoxelObject {
    /// Voxelises `object` at `res` voxels per axis (at least 1, at most 1024).
    ///
    /// ```
    /// use nlrt_accel::ShellObject;
    /// use nlrt_baselines::VoxelObject;
    /// use nlrt_poly::glam::DVec3;
    /// // A horizontal square at height 0.5 in the tile.
    /// let (a, b, c, d) = (
    ///     DVec3::new(0.0, 0.0, 0.5),
    ///     DVec3::new(1.0, 0.0, 0.5),
    ///     DVec3::new(1.0, 1.0, 0.5),
    ///     DVec3::new(0.0, 1.0, 0.5),
    /// );
    /// let object = ShellObject::<f64>::new(vec![[a, b, c], [a, c, d]]).unwrap();
    /// let voxels = VoxelObject::new(&object, 16);
    /// assert!(voxels.occupied(3, 7, 8));
    /// assert!(!voxels.occupied(3, 7, 2));
    /// // Six voxels below the square: an empty box of radius 5 around it.
    /// assert_eq!(voxels.radius_at(3, 7, 2), 5);
    /// ```
    #[must_use]
    pub fn new<T: Real>(object: &ShellObject<T>, res: usize) -> Self {
        let res = res.clamp(1, 1024);
        let cells = res * res * res;
        let mut occupied = vec![0u64; cells.div_ceil(64)];
        let mut triangle_of = Vec::new();
        let voxel = |x: f64| ((x * res as f64) as usize).min(res - 1);
        for (k, tri) in object.triangles().iter().enumerate() {
            let p = tri.map(|v| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()]);
            let edge = |a: usize, b: usize| {
                (0..3)
                    .map(|i| (p[a][i] - p[b][i]).abs())
                    .fold(0.0, f64::max)
            };
            let longest = edge(0, 1).max(edge(1, 2)).max(edge(0, 2));
            // Half-voxel spacing along both edge directions.
            let n = ((2.0 * res as f64 * longest) as usize + 1).min(4 * res);
            for i in 0..=n {
                for j in 0..=n - i {
                    let (s, t) = (i as f64 / n as f64, j as f64 / n as f64);
                    let at = |c: usize| p[0][c] + (p[1][c] - p[0][c]) * s + (p[2][c] - p[0][c]) * t;
                    let index = voxel(at(0)) + res * (voxel(at(1)) + res * voxel(at(2)));
                    let (word, bit) = (index / 64, 1u64 << (index % 64));
                    if occupied[word] & bit == 0 {
                        occupied[word] |= bit;
                        triangle_of.push((index as u32, k as u32));
                    }
                }
            }
        }
        triangle_of.sort_unstable();
        let mut this = Self {
            res,
            occupied,
            triangle_of,
            radius: Vec::new(),
        };
        this.radius = this.radii();
        this
    }

    /// Radii from the Chebyshev distance to the nearest occupied voxel (capped at
    /// `MAX_RADIUS + 1`), separable: along `u` (wrapping) by two sweeps per row, then along `v`
    /// (wrapping) and height (not wrapping) as `min over d of max(|d|, previous)`; the empty
    /// box of radius `r` around a voxel exists while `r` is below that distance.
    fn radii(&self) -> Vec<u8> {
        let res = self.res;
        let cap = MAX_RADIUS + 1;
        let index = |x: usize, y: usize, z: usize| x + res * (y + res * z);
        let mut dist = vec![cap; res * res * res];
        for z in 0..res {
            for y in 0..res {
                // Two laps of the row in each direction carry distances across the wrap.
                let row = index(0, y, z);
                for backwards in [false, true] {
                    let mut d = cap;
                    for k in 0..2 * res {
                        let x = if backwards { 2 * res - 1 - k } else { k } % res;
                        d = if self.bit(row + x) {
                            0
                        } else {
                            (d + 1).min(cap)
                        };
                        dist[row + x] = dist[row + x].min(d);
                    }
                }
            }
        }
        // Along v (wrapping) and then height (outside the shell: nothing solid), line by line.
        let mut line = vec![0u8; res];
        for (axis, stride) in [(1usize, res), (2, res * res)] {
            for a in 0..res {
                for b in 0..res {
                    // The line's first voxel: the other two coordinates fixed.
                    let first = if axis == 1 {
                        index(a, 0, b)
                    } else {
                        index(a, b, 0)
                    };
                    for (k, v) in line.iter_mut().enumerate() {
                        *v = dist[first + k * stride];
                    }
                    for p in 0..res {
                        let mut best = line[p];
                        let mut d = 1usize;
                        // max(d, .) >= d: nothing at distance >= best can lower it.
                        while d < usize::from(best) && d < res {
                            for q in [p as i64 - d as i64, (p + d) as i64] {
                                let q = if axis == 1 {
                                    q.rem_euclid(res as i64)
                                } else if (0..res as i64).contains(&q) {
                                    q
                                } else {
                                    continue;
                                };
                                best = best.min((d as u8).max(line[q as usize]));
                            }
                            d += 1;
                        }
                        dist[first + p * stride] = best;
                    }
                }
            }
        }
        dist.iter()
            .map(|&d| d.saturating_sub(1).min(MAX_RADIUS))
            .collect()
    }

    fn bit(&self, i: usize) -> bool {
        self.occupied[i / 64] & (1u64 << (i % 64)) != 0
    }

    /// The voxel index of `(x, y, z)` (wrapping in `x` and `y`), or `None` outside the
    /// shell's height.
    fn index(&self, x: i64, y: i64, z: i64) -> Option<usize> {
        let n = self.res as i64;
        (0..n)
            .contains(&z)
            .then(|| (x.rem_euclid(n) + n * (y.rem_euclid(n) + n * z)) as usize)
    }

    /// Voxels per axis.
    #[must_use]
    pub fn resolution(&self) -> usize {
        self.res
    }

    /// Whether voxel `(x, y, z)` holds object surface (tiles repeat in `x` and `y`).
    #[must_use]
    pub fn occupied(&self, x: i64, y: i64, z: i64) -> bool {
        self.index(x, y, z).is_some_and(|i| self.bit(i))
    }

    /// The empty radius of voxel `(x, y, z)` in voxels (`MAX_RADIUS` = 15 at most; 0 for
    /// occupied voxels; outside the shell's height, 0).
    #[must_use]
    pub fn radius_at(&self, x: i64, y: i64, z: i64) -> u8 {
        self.index(x, y, z).map_or(0, |i| self.radius[i])
    }

    /// The object triangle that marked voxel `(x, y, z)`.
    #[must_use]
    pub fn triangle_at(&self, x: i64, y: i64, z: i64) -> Option<u32> {
        let i = self.index(x, y, z)? as u32;
        let k = self.triangle_of.binary_search_by_key(&i, |e| e.0).ok()?;
        Some(self.triangle_of[k].1)
    }

    /// Bytes of occupancy, triangle ids and radii.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.occupied.len() * 8 + self.triangle_of.len() * 8 + self.radius.len()
    }
}

/// The voxels as a marcher sees them.
pub(crate) struct VoxelMedium<'a> {
    voxels: &'a VoxelObject,
    jumps: bool,
}

impl VoxelMedium<'_> {
    /// The voxel (global, tiles unwrapped) of canonical point `c`.
    fn voxel<T: Real>(&self, prism: &Prism<T>, c: &[T; 3]) -> [i64; 3] {
        let uv = prism.texture_uv(c[0], c[1]);
        let res = self.voxels.res as f64;
        let floor = |x: f64| {
            let i = x as i64;
            if (i as f64) > x {
                i.saturating_sub(1)
            } else {
                i
            }
        };
        [
            floor(uv.x().to_f64() * res),
            floor(uv.y().to_f64() * res),
            floor(c[2].to_f64() * res),
        ]
    }

    /// The segment's extent in voxels (the longest axis).
    fn extent<T: Real>(&self, prism: &Prism<T>, a: &[T; 3], b: &[T; 3]) -> f64 {
        let (p, q) = (prism.texture_uv(a[0], a[1]), prism.texture_uv(b[0], b[1]));
        let res = self.voxels.res as f64;
        ((q.x() - p.x()).abs().to_f64() * res)
            .max((q.y() - p.y()).abs().to_f64() * res)
            .max((b[2] - a[2]).abs().to_f64() * res)
    }
}

impl<T: Real> Medium<T> for VoxelMedium<'_> {
    fn solid(&self, prism: &Prism<T>, c: &[T; 3]) -> bool {
        let [x, y, z] = self.voxel(prism, c);
        self.voxels.occupied(x, y, z)
    }

    fn steps(&self, prism: &Prism<T>, start: &[T; 3], end: &[T; 3], opts: &MarchOptions) -> usize {
        sample_count(self.extent(prism, start, end), opts)
    }

    fn empty_fraction(&self, prism: &Prism<T>, current: &[T; 3], end: &[T; 3]) -> T {
        if !self.jumps {
            return T::ZERO;
        }
        let [x, y, z] = self.voxel(prism, current);
        let r = self.voxels.radius_at(x, y, z);
        if r == 0 {
            return T::ZERO;
        }
        T::from_f64(f64::from(r) / self.extent(prism, current, end))
    }
}

/// Ray marching of a voxelised object (Jeschke et al. 2007, sec. 4.2-4.4) on the paper's [`ShellSurface`].
pub trait VoxelMarching<T: Real> {
    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` by ray marching through the
    /// voxelised object (Jeschke et al. 2007 sec. 4.2-4.3 for volumetric content);
    /// `opts.samples_per_texel` counts per voxel. The hit's object triangle is the one that
    /// marked the hit voxel.
    fn intersect_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        voxels: &VoxelObject,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>>;

    /// [`VoxelMarching::intersect_marching`] with jumps by the voxels' distance map (sec. 4.4).
    fn intersect_sphere_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        voxels: &VoxelObject,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>>;
}

impl<T: Real> VoxelMarching<T> for ShellSurface<T> {
    fn intersect_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        voxels: &VoxelObject,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        let medium = VoxelMedium {
            voxels,
            jumps: false,
        };
        self.march_voxels(ray, t_min, t_max, &medium, opts, stats)
    }

    fn intersect_sphere_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        voxels: &VoxelObject,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        let medium = VoxelMedium {
            voxels,
            jumps: true,
        };
        self.march_voxels(ray, t_min, t_max, &medium, opts, stats)
    }
}

/// The steps of [`VoxelMarching`].
pub(crate) trait VoxelParts<T: Real> {
    fn march_voxels(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        medium: &VoxelMedium<'_>,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>>;
}

impl<T: Real> VoxelParts<T> for ShellSurface<T> {
    fn march_voxels(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        medium: &VoxelMedium<'_>,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        let voxels = medium.voxels;
        self.traverse_prisms(ray, t_min, t_max, |tri, prism, t_max| {
            stats.prism_tests += 1;
            let span = intersect_prism(prism, ray, t_min, t_max)?;
            let (c, t) = march_segment(prism, ray, &span, opts, medium, stats)?;
            if !(t > t_min && t < t_max) {
                return None;
            }
            let [x, y, z] = medium.voxel(prism, &c);
            let res = voxels.res as i64;
            let hit = ShellHit {
                hit: Hit::at(prism, t, c[0], c[1], c[2]),
                triangle: tri as u32,
                tile: [x.div_euclid(res) as i32, y.div_euclid(res) as i32],
                object_triangle: voxels.triangle_at(x, y, z)?,
            };
            Some((hit, t))
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use nlrt_poly::glam::DVec3;

    /// An axis-aligned box `[lo, hi]` in the tile as 12 triangles.
    fn cube(lo: DVec3, hi: DVec3) -> Vec<[DVec3; 3]> {
        let c = |x: usize, y: usize, z: usize| {
            DVec3::new(
                if x == 0 { lo.x } else { hi.x },
                if y == 0 { lo.y } else { hi.y },
                if z == 0 { lo.z } else { hi.z },
            )
        };
        let quads = [
            [c(0, 0, 0), c(1, 0, 0), c(1, 1, 0), c(0, 1, 0)],
            [c(0, 0, 1), c(1, 0, 1), c(1, 1, 1), c(0, 1, 1)],
            [c(0, 0, 0), c(1, 0, 0), c(1, 0, 1), c(0, 0, 1)],
            [c(0, 1, 0), c(1, 1, 0), c(1, 1, 1), c(0, 1, 1)],
            [c(0, 0, 0), c(0, 1, 0), c(0, 1, 1), c(0, 0, 1)],
            [c(1, 0, 0), c(1, 1, 0), c(1, 1, 1), c(1, 0, 1)],
        ];
        quads
            .iter()
            .flat_map(|q| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect()
    }

    /// A base triangle of zero world area has no shell: no hit from any side; one degenerate
    /// in uv (a line) still holds a volume, marched through the voxels of that line.
    #[test]
    fn degenerate_base_triangles_give_a_defined_outcome() {
        let object = ShellObject::<f64>::new(cube(DVec3::splat(0.0), DVec3::splat(1.0))).unwrap();
        let voxels = VoxelObject::new(&object, 16);
        let opts = MarchOptions::default();
        let mut st = TraversalStats::default();
        let flat = ShellSurface::new(
            crate::test_util::world_line_triangle(),
            object.clone(),
            1.0,
            1.0,
        )
        .unwrap();
        for dir in [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.0, 1.0, -1.0),
            DVec3::Y,
        ] {
            let ray = Ray::new(DVec3::new(0.5, 0.0, 0.25) - dir, dir).unwrap();
            let far = f64::INFINITY;
            assert!(
                flat.intersect_marching(&ray, 0.0, far, &voxels, &opts, &mut st)
                    .is_none()
            );
            assert!(
                flat.intersect_sphere_traced(&ray, 0.0, far, &voxels, &opts, &mut st)
                    .is_none()
            );
        }
        // uvs on the tile's diagonal: the cube's voxels there are its faces' only at the tile
        // corners, and the top face (h = 1) lies along the whole line.
        let uv_line =
            ShellSurface::new(crate::test_util::uv_line_triangle(), object, 1.0, 1.0).unwrap();
        let down = Ray::new(DVec3::new(0.2, 0.2, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let hit = uv_line
            .intersect_marching(&down, 0.0, f64::INFINITY, &voxels, &opts, &mut st)
            .expect("the top face's voxels along the line");
        assert!((hit.hit.t - 1.0).abs() <= 1.0 / 16.0 + 1e-3, "{hit:?}");
    }

    #[test]
    fn radii_are_empty_boxes_by_brute_force() {
        let object =
            ShellObject::<f64>::new(cube(DVec3::new(0.3, 0.2, 0.1), DVec3::new(0.6, 0.5, 0.4)))
                .unwrap();
        let v = VoxelObject::new(&object, 12);
        let n = 12i64;
        for z in 0..n {
            for y in 0..n {
                for x in 0..n {
                    let r = i64::from(v.radius_at(x, y, z));
                    if v.occupied(x, y, z) {
                        assert_eq!(r, 0);
                        continue;
                    }
                    let empty = |r: i64| {
                        (-r..=r).all(|dz| {
                            (-r..=r)
                                .all(|dy| (-r..=r).all(|dx| !v.occupied(x + dx, y + dy, z + dz)))
                        })
                    };
                    assert!(empty(r), "({x}, {y}, {z}) radius {r}");
                    if r < i64::from(MAX_RADIUS) {
                        assert!(!empty(r + 1), "({x}, {y}, {z}) radius {r} could be larger");
                    }
                }
            }
        }
    }

    /// A cube on a flat unit-square base with constant normals (affine prisms, texture space
    /// = world space): marched hits lie within a voxel's diagonal of the cube's surface and
    /// never behind the exact hit; the distance map's jumps need fewer samples.
    #[test]
    fn a_cube_is_found_on_its_faces_with_and_without_jumps() {
        let (lo, hi) = (DVec3::new(0.25, 0.3, 0.2), DVec3::new(0.7, 0.65, 0.6));
        let object = ShellObject::<f64>::new(cube(lo, hi)).unwrap();
        let voxels = VoxelObject::new(&object, 32);
        let mesh = crate::test_util::unit_square(DVec3::Z, [[0, 1, 2], [0, 2, 3]]);
        let surface = ShellSurface::new(mesh, object, 1.0, 1.0).unwrap();
        let opts = MarchOptions::default();
        let (mut fixed, mut jumped, mut hits) = (0, 0, 0);
        for k in 0..400 {
            let (x, y) = ((k % 20) as f64 / 20.0, (k / 20) as f64 / 20.0);
            let ray = Ray::new(DVec3::new(x - 0.2, y, 1.5), DVec3::new(0.3, 0.1, -1.0)).unwrap();
            let (mut a_st, mut b_st) = (TraversalStats::default(), TraversalStats::default());
            let far = f64::INFINITY;
            let a = surface.intersect_marching(&ray, 0.0, far, &voxels, &opts, &mut a_st);
            let b = surface.intersect_sphere_traced(&ray, 0.0, far, &voxels, &opts, &mut b_st);
            fixed += a_st.texel_tests;
            jumped += b_st.texel_tests;
            let exact = surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default());
            // Distance from texture point q to the cube's surface.
            let to_surface = |q: DVec3| {
                let outside = (lo - q).max(q - hi).max(DVec3::ZERO).length();
                let inside = (q - lo).min(hi - q).min_element();
                if outside > 0.0 {
                    outside
                } else {
                    inside.max(0.0)
                }
            };
            let voxel_diagonal = 3f64.sqrt() / 32.0;
            for m in [a, b].into_iter().flatten() {
                hits += 1;
                let q = DVec3::new(m.hit.u, m.hit.v, m.hit.h);
                assert!(to_surface(q) < voxel_diagonal + 1e-3, "{k}: {m:?}");
                if let Some(e) = exact {
                    assert!(m.hit.t <= e.hit.t + 1e-3, "{k}: {m:?} behind {e:?}");
                }
            }
            if exact.is_some() {
                assert!(
                    a.is_some() && b.is_some(),
                    "{k}: the voxels cover the surface"
                );
            }
        }
        assert!(hits > 100, "{hits}");
        assert!(2 * jumped < fixed, "{jumped} vs {fixed}");
    }
}
