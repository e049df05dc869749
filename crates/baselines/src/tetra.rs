//! Tetrahedral shells (Porumbescu et al. 2005, Hirche et al. 2004), the baseline whose
//! "buckling" Jeschke et al. 2007 show: each prism is split into three tetrahedra, with the
//! diagonals of its side quads chosen from the global vertex order so that neighbouring
//! prisms split a shared side the same way, and inside each tetrahedron the world-to-texture
//! map is the affine map of its four corners. A ray is then a straight segment in texture space
//! per tetrahedron, sampled like the marching method (the same samples per texel, the first
//! sample under the height field a hit, refined by binary search). The mapping is piecewise
//! linear instead of Eq. 1's, so the displaced surface bends at the tetrahedra's faces; the
//! report measures how far that is from the others.

use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Prism, Ray};

use nlrt_accel::{DisplacedSurface, SurfaceHit, TraversalStats};

use crate::march::{MarchOptions, SampledSurface};

/// Binary-search steps refining a hit between two samples.
const REFINE_STEPS: usize = 10;

/// The three tetrahedra of a prism as corner ids: `k` for the base corner `S_k(0)`, `k + 3`
/// for the top corner `S_k(1)`. With the corners sorted by global vertex index `a < b < c`,
/// every side quad's diagonal runs from its smallest corner's base vertex (`a0-b1`, `a0-c1`,
/// `b0-c1`), which the neighbour sharing that side chooses too.
fn tetrahedra(global: [u32; 3]) -> [[usize; 4]; 3] {
    let mut order = [0usize, 1, 2];
    order.sort_by_key(|&k| global[k]);
    let [a, b, c] = order;
    [
        [a, b, c, c + 3],
        [a, b, b + 3, c + 3],
        [a, a + 3, b + 3, c + 3],
    ]
}

/// Tetrahedral shells (Porumbescu et al. 2005) on the paper's [`DisplacedSurface`]: each prism split into three affinely mapped tetrahedra.
pub trait TetrahedralShells<T: Real> {
    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` on the tetrahedral shell (see
    /// the module documentation); `opts` sets the sampling as for
    /// [`Marching::intersect_marching`](crate::Marching::intersect_marching) (its angle limit is unused: the map is
    /// affine per tetrahedron, so the texture-space segment is exact).
    fn intersect_tetrahedra(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;
}

impl<T: Real> TetrahedralShells<T> for DisplacedSurface<T> {
    fn intersect_tetrahedra(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.traverse_prisms(ray, t_min, t_max, |tri, prism, t_max| {
            stats.prism_tests += 1;
            let global = self.mesh().triangle(tri);
            let mut best: Option<SurfaceHit<T>> = None;
            for tet in tetrahedra(global) {
                let limit = best.map_or(t_max, |b| b.hit.t);
                if let Some(hit) =
                    self.march_tetrahedron(tri, prism, &tet, ray, t_min, limit, opts, stats)
                {
                    best = Some(hit);
                }
            }
            best.map(|b| (b, b.hit.t))
        })
    }
}

/// The steps of [`TetrahedralShells`].
pub(crate) trait TetraParts<T: Real> {
    #[allow(clippy::too_many_arguments)]
    fn march_tetrahedron(
        &self,
        tri: usize,
        prism: &Prism<T>,
        tet: &[usize; 4],
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;
}

impl<T: Real> TetraParts<T> for DisplacedSurface<T> {
    #[allow(clippy::too_many_arguments)]
    fn march_tetrahedron(
        &self,
        tri: usize,
        prism: &Prism<T>,
        tet: &[usize; 4],
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let corner_canonical = |k: usize| -> [T; 3] {
            let h = if k >= 3 { T::ONE } else { T::ZERO };
            match k % 3 {
                0 => [T::ZERO, T::ZERO, h],
                1 => [T::ONE, T::ZERO, h],
                _ => [T::ZERO, T::ONE, h],
            }
        };
        let world = tet.map(|k| prism.vertex(k % 3, if k >= 3 { T::ONE } else { T::ZERO }));
        let canonical = tet.map(corner_canonical);
        // Cyrus-Beck clipping of the ray against the four faces.
        let (mut t_in, mut t_out) = (t_min, t_max);
        let (mut in_face, mut out_face) = (None, None);
        for skip in 0..4 {
            let f: [usize; 3] = match skip {
                0 => [1, 2, 3],
                1 => [0, 2, 3],
                2 => [0, 1, 3],
                _ => [0, 1, 2],
            };
            let (p, q, r) = (world[f[0]], world[f[1]], world[f[2]]);
            let mut n = (q - p).cross(r - p);
            let opposite = n.dot(world[skip] - p);
            if !(opposite != T::ZERO && opposite.is_finite()) {
                return None; // a flat tetrahedron (a degenerate prism): no volume
            }
            if opposite > T::ZERO {
                n = -n; // outward
            }
            let num = n.dot(p - ray.origin);
            let den = n.dot(ray.dir);
            if den == T::ZERO {
                if num < T::ZERO {
                    return None; // parallel and outside this face
                }
                continue;
            }
            let t = num / den;
            if den < T::ZERO {
                if t > t_in {
                    t_in = t;
                    in_face = Some(skip);
                }
            } else if t < t_out {
                t_out = t;
                out_face = Some(skip);
            }
        }
        if !(t_in < t_out) {
            return None;
        }
        // The affine map world -> canonical of this tetrahedron (barycentric coordinates by
        // triple products).
        let (e1, e2, e3) = (
            world[1] - world[0],
            world[2] - world[0],
            world[3] - world[0],
        );
        let volume = e1.dot(e2.cross(e3));
        let to_canonical = |x: T::Vec3| -> [T; 3] {
            let d = x - world[0];
            let l1 = d.dot(e2.cross(e3)) / volume;
            let l2 = e1.dot(d.cross(e3)) / volume;
            let l3 = e1.dot(e2.cross(d)) / volume;
            core::array::from_fn(|i| {
                canonical[0][i]
                    + (canonical[1][i] - canonical[0][i]) * l1
                    + (canonical[2][i] - canonical[0][i]) * l2
                    + (canonical[3][i] - canonical[0][i]) * l3
            })
        };
        // A segment end on the base or top face lies at height exactly 0 or 1: set it, so
        // that rounding cannot lift an exit through the base above a zero-height surface.
        let cap_height = |face: Option<usize>| {
            let corners = (0..4).filter(|&i| Some(i) != face).map(|i| tet[i]);
            let heights: [bool; 2] = [
                corners.clone().all(|k| k < 3),
                corners.clone().all(|k| k >= 3),
            ];
            match (face, heights) {
                (Some(_), [true, _]) => Some(T::ZERO),
                (Some(_), [_, true]) => Some(T::ONE),
                _ => None,
            }
        };
        let mut start = to_canonical(ray.origin + ray.dir * t_in);
        let mut end = to_canonical(ray.origin + ray.dir * t_out);
        if let Some(h) = cap_height(in_face) {
            start[2] = h;
        }
        if let Some(h) = cap_height(out_face) {
            end[2] = h;
        }
        let uv = |c: &[T; 3]| prism.texture_uv(c[0], c[1]);
        let count = self.sample_steps(uv(&start), uv(&end), opts) + 1;
        let below = |c: &[T; 3]| {
            let p = uv(c);
            let (h, texel, part) = self.surface_height(p.x(), p.y());
            (c[2] <= h, texel, part)
        };
        let at = |s: T| -> [T; 3] { core::array::from_fn(|i| start[i] + (end[i] - start[i]) * s) };
        let step = T::ONE / T::from_i32((count - 1) as i32);
        let mut previous = T::ZERO;
        for k in 0..count {
            stats.texel_tests += 1;
            let s = T::from_i32(k as i32) * step;
            if !below(&at(s)).0 {
                previous = s;
                continue;
            }
            // First sample under the surface (the entry itself when k = 0): refine.
            let (mut lo, mut hi) = (previous, s);
            for _ in 0..REFINE_STEPS {
                let mid = (lo + hi) * T::HALF;
                if below(&at(mid)).0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let t = t_in + (t_out - t_in) * hi;
            return Some(self.sampled_hit(tri, prism, at(hi), t));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    #[test]
    fn neighbours_split_their_shared_side_alike() {
        // Two triangles sharing vertices 1 and 2, listed in different orders: the faces of
        // their tetrahedra on the shared side quad (corners 1, 2 at both heights) match.
        let side_faces = |global: [u32; 3]| {
            let mut faces = vec![];
            for tet in tetrahedra(global) {
                for skip in 0..4 {
                    let face: vec::Vec<(u32, bool)> = (0..4)
                        .filter(|&i| i != skip)
                        .map(|i| (global[tet[i] % 3], tet[i] >= 3))
                        .collect();
                    if face.iter().all(|(g, _)| *g == 1 || *g == 2) {
                        let mut f = face;
                        f.sort();
                        faces.push(f);
                    }
                }
            }
            faces.sort();
            faces
        };
        assert_eq!(side_faces([0, 1, 2]), side_faces([2, 3, 1]));
        assert_eq!(side_faces([0, 1, 2]).len(), 2);
    }

    #[test]
    fn constant_normal_prisms_are_linear_so_a_flat_map_is_exact() {
        let (surface, stored) = crate::test_util::flat_map_square(0.4);
        let opts = MarchOptions::default();
        crate::test_util::assert_slanted_rays_meet_height(stored, |ray| {
            let mut stats = TraversalStats::default();
            let hit = surface.intersect_tetrahedra(ray, 0.0, f64::INFINITY, &opts, &mut stats)?;
            Some(hit.hit.t)
        });
    }
}

#[cfg(test)]
mod degenerate {
    use super::*;
    use crate::Marching;
    use nlrt_accel::{HeightField, Wrap};
    use nlrt_poly::glam::DVec3;

    /// A base triangle of zero world area (a line) has flat tetrahedra and flat prisms: the
    /// sampling methods report no hit and do not panic, for rays across it from any side;
    /// a uv-degenerate one (a line in uv) is still a volume and is hit.
    #[test]
    fn world_degenerate_triangles_are_not_hit_uv_degenerate_ones_are() {
        let field = HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).unwrap();
        let line = crate::test_util::world_line_triangle();
        let flat = DisplacedSurface::new(line, field.clone(), 1.0, 1.0).unwrap();
        let uv_line = crate::test_util::uv_line_triangle();
        let degenerate_uv = DisplacedSurface::new(uv_line, field, 1.0, 1.0).unwrap();
        let opts = MarchOptions::default();
        let mut st = TraversalStats::default();
        for dir in [
            DVec3::new(0.0, 0.0, -1.0),
            DVec3::new(0.0, 1.0, -1.0),
            DVec3::new(0.0, 1.0, 0.0),
        ] {
            // Aimed at a point of the sheet the line's shell would be (x = 0.5, y = 0, z = 0.25).
            let ray = Ray::new(DVec3::new(0.5, 0.0, 0.25) - dir, dir).unwrap();
            assert!(
                flat.intersect_tetrahedra(&ray, 0.0, f64::INFINITY, &opts, &mut st)
                    .is_none()
            );
            assert!(
                flat.intersect_marching(&ray, 0.0, f64::INFINITY, &opts, &mut st)
                    .is_none()
            );
            assert!(
                flat.intersect_curved_marching(&ray, 0.0, f64::INFINITY, &opts, &mut st)
                    .is_none()
            );
        }
        let down = Ray::new(DVec3::new(0.2, 0.2, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let hit = degenerate_uv
            .intersect_tetrahedra(&down, 0.0, f64::INFINITY, &opts, &mut st)
            .expect("a uv-degenerate prism still has volume");
        assert!((hit.hit.t - 1.5).abs() < 1e-3, "{hit:?}");
        // Curved: flat base, equal normals, so the surface is at 0.5 / 2 + 1 / 4; the normal
        // is the shell triangle's (no uv inverse for the microtriangle's corners).
        let hit = degenerate_uv
            .intersect_curved_marching(&down, 0.0, f64::INFINITY, &opts, &mut st)
            .expect("a uv-degenerate prism still has volume");
        assert!((hit.hit.t - 1.5).abs() < 1e-3, "{hit:?}");
        let n = degenerate_uv.curved_normal(&hit, down.dir).unwrap();
        assert!((n - DVec3::Z).length() < 1e-12, "{n}");
    }
}
