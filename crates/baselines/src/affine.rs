//! Tessellation-free displacement mapping (Thonat et al. 2021), the state of the art that
//! nonlinear ray tracing improves on, on the same acceleration data as
//! [`DisplacedSurface`]: the TLAS over prisms and the implicit min-max pyramid. The difference
//! is where the work happens: every pyramid node gets a world-space box, computed on the fly by
//! affine arithmetic over the node's uv square and height range, and each texel's two
//! microtriangles are mapped to world space (Eq. 1 at their corners) and intersected there as
//! flat triangles. So the surface is the pre-tessellated one (flat world triangles), with no
//! memory beyond the pyramid.
//!
//! It needs the inverse of Eq. 2-3 (uv to barycentric) to place a uv square in world space:
//! a base triangle whose uvs are degenerate (a line or a point) has none, and is not rendered
//! ([`AffineTracing::intersect_affine`] documents the outcome; the report measures it).

use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::{Prism, Ray};

use nlrt_accel::{
    CellTriangle, DisplacedSurface, SlabRay, TexelPart, TraversalStats, ray_triangle,
    traverse_cells, uv_in_cells,
};
use nlrt_shellmap::facing_unit;

/// A hit of [`AffineTracing::intersect_affine`]: a flat world-space microtriangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AffineHit<T: Real> {
    /// Ray parameter.
    pub t: T,
    /// Geometric normal of the microtriangle (not normalised, either orientation).
    pub normal: T::Vec3,
    /// Base triangle.
    pub triangle: u32,
    /// Texel (in the infinite, tiled grid).
    pub texel: [i32; 2],
    /// Which microtriangle of the texel ([`TexelPart::Lower`] or [`TexelPart::Upper`]).
    pub part: TexelPart,
}

impl<T: Real> AffineHit<T> {
    /// The unit normal of the hit microtriangle facing against `dir` (`None` for a
    /// microtriangle of zero area).
    #[must_use]
    pub fn facing_normal(&self, dir: T::Vec3) -> Option<T::Vec3> {
        facing_unit::<T>(self.normal, dir)
    }
}

/// The world-space shell of one base triangle as an affine function of texel coordinates:
/// `P(u, v) + h N(u, v)` with `P`, `N` affine in `(u, v)` (Eq. 1 composed with the inverse of
/// Eq. 2-3).
pub(crate) struct AffineShell<T: Real> {
    prism: Prism<T>,
    /// uv of vertex 0 in texel units.
    origin: [T; 2],
    /// `d alpha / du`, `d alpha / dv`, `d beta / du`, `d beta / dv`.
    grad: [T; 4],
    /// The triangle's uv bounding box in texel units, `[u0, v0, u1, v1]`.
    uv_box: [T; 4],
}

/// `gamma(n) = n u / (1 - n u)`: the relative error bound of `n` rounded operations.
fn gamma<T: Real>(n: i32) -> T {
    let nu = T::from_i32(n) * T::UNIT_ROUNDOFF;
    nu / (T::ONE - nu)
}

impl<T: Real> AffineShell<T> {
    /// `None` when the uvs are degenerate: no inverse of Eq. 2-3.
    fn new(prism: &Prism<T>, uv: [[T; 2]; 3]) -> Option<Self> {
        let (e0, e1) = (
            [uv[1][0] - uv[0][0], uv[1][1] - uv[0][1]],
            [uv[2][0] - uv[0][0], uv[2][1] - uv[0][1]],
        );
        let det = e0[0] * e1[1] - e0[1] * e1[0];
        if !(det.abs() > T::ZERO && det.is_finite()) {
            return None;
        }
        let inv = T::ONE / det;
        let grad = [e1[1] * inv, -e1[0] * inv, -e0[1] * inv, e0[0] * inv];
        if !grad.iter().all(|g| g.is_finite()) {
            return None;
        }
        let (mut lo, mut hi) = (uv[0], uv[0]);
        for c in &uv[1..] {
            for a in 0..2 {
                lo[a] = lo[a].min(c[a]);
                hi[a] = hi[a].max(c[a]);
            }
        }
        Some(Self {
            prism: *prism,
            origin: uv[0],
            grad,
            uv_box: [lo[0], lo[1], hi[0], hi[1]],
        })
    }

    /// Barycentric `(alpha, beta)` of texel coordinates `(u, v)`.
    #[inline]
    fn barycentric(&self, u: T, v: T) -> (T, T) {
        let (du, dv) = (u - self.origin[0], v - self.origin[1]);
        let [au, av, bu, bv] = self.grad;
        (au * du + av * dv, bu * du + bv * dv)
    }

    /// The world box of the shell over texel square `[u0, u1] x [v0, v1]` (clipped to the
    /// triangle's uv box) and heights `[h0, h1]`, by affine arithmetic: with `u = uc + ur e1`,
    /// `v = vc + vr e2`, `h = hc + hr e3` (`e_i` in `[-1, 1]`), `P + h N` is affine in the
    /// `e_i` except for the products `hr e3 (N_u ur e1 + N_v vr e2)`, bounded by their
    /// magnitude. Widened by a bound on the rounding of the computation (`gamma(16)` of the
    /// magnitudes involved: each term passes through at most 16 roundings), so the box holds
    /// the exact shell.
    fn node_box(&self, u: [T; 2], v: [T; 2], h: [T; 2]) -> Option<([T; 3], [T; 3])> {
        let [bu0, bv0, bu1, bv1] = self.uv_box;
        let (u0, u1) = (u[0].max(bu0), u[1].min(bu1));
        let (v0, v1) = (v[0].max(bv0), v[1].min(bv1));
        if !(u0 <= u1 && v0 <= v1) {
            return None;
        }
        let (uc, ur) = ((u0 + u1) * T::HALF, (u1 - u0) * T::HALF);
        let (vc, vr) = ((v0 + v1) * T::HALF, (v1 - v0) * T::HALF);
        let (hc, hr) = ((h[0] + h[1]) * T::HALF, (h[1] - h[0]) * T::HALF);
        let p = &self.prism;
        let (ep, en) = (
            [p.p[1] - p.p[0], p.p[2] - p.p[0]],
            [p.n[1] - p.n[0], p.n[2] - p.n[0]],
        );
        let (alpha, beta) = self.barycentric(uc, vc);
        let pc = p.p[0] + ep[0] * alpha + ep[1] * beta;
        let nc = p.n[0] + en[0] * alpha + en[1] * beta;
        let [au, av, bu, bv] = self.grad;
        // Partial derivatives of P and N along u and v, times the radii.
        let (pu, pv) = (
            (ep[0] * au + ep[1] * bu) * ur,
            (ep[0] * av + ep[1] * bv) * vr,
        );
        let (nu, nv) = (
            (en[0] * au + en[1] * bu) * ur,
            (en[0] * av + en[1] * bv) * vr,
        );
        let centre = pc + nc * hc;
        let (mut lo, mut hi) = ([T::ZERO; 3], [T::ZERO; 3]);
        let slack = gamma::<T>(16);
        for i in 0..3 {
            let radius = (pu.get(i) + nu.get(i) * hc).abs()
                + (pv.get(i) + nv.get(i) * hc).abs()
                + (nc.get(i) * hr).abs()
                + hr * (nu.get(i).abs() + nv.get(i).abs());
            let magnitude = pc.get(i).abs()
                + (nc.get(i) * hc).abs()
                + radius
                + (pu.get(i).abs() + pv.get(i).abs())
                + (nu.get(i).abs() + nv.get(i).abs()) * hc.abs();
            let widen = radius + slack * magnitude;
            lo[i] = centre.get(i) - widen;
            hi[i] = centre.get(i) + widen;
        }
        Some((lo, hi))
    }

    /// The world point of texel coordinates `(u, v)` at height `h` (Eq. 1).
    #[inline]
    fn world(&self, u: T, v: T, h: T) -> T::Vec3 {
        let (alpha, beta) = self.barycentric(u, v);
        self.prism.shell_point(alpha, beta, h)
    }

    /// Whether texel coordinates `(u, v)` lie in the base triangle (edges included).
    #[inline]
    fn contains(&self, u: T, v: T) -> bool {
        let (alpha, beta) = self.barycentric(u, v);
        alpha >= T::ZERO && beta >= T::ZERO && alpha + beta <= T::ONE
    }
}

/// Tessellation-free displacement mapping (Thonat et al. 2021) on the paper's [`DisplacedSurface`]: world-space node boxes by affine arithmetic, flat world microtriangles.
pub trait AffineTracing<T: Real> {
    /// The nearest hit of `ray` with `t` in `[t_min, t_max]` by tessellation-free
    /// displacement mapping (Thonat et al. 2021): TLAS, then per base triangle the implicit
    /// min-max pyramid with world-space node boxes from affine arithmetic (no prism gate, no
    /// nonlinear ray), then per texel its two microtriangles as flat world triangles, a hit
    /// kept where its uv lies in the base triangle.
    ///
    /// Base triangles with degenerate uvs (a line or a point in texture space) are never hit:
    /// the method has no world position for a uv square there. Microtriangles are tested
    /// independently (Möller-Trumbore), so rays can slip between neighbours in finite
    /// precision, as in the original.
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
    /// use nlrt_baselines::AffineTracing;
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Ray;
    /// // A unit square lifted by a constant height of 0.5 (scale 1).
    /// let mesh = BaseMesh::<f64>::new(
    ///     vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
    ///     vec![DVec3::Z; 4],
    ///     vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
    ///     vec![[0, 1, 2], [0, 2, 3]],
    /// ).unwrap();
    /// let field = HeightField::from_unit_heights(8, 8, &[0.5f32; 64], Wrap::Clamp).unwrap();
    /// let surface = DisplacedSurface::new(mesh, field, 1.0, 1.0).unwrap();
    /// let ray = Ray::new(DVec3::new(0.3, 0.6, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
    /// let hit = surface.intersect_affine(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default()).unwrap();
    /// assert!((hit.t - 1.5).abs() < 1e-3);
    /// ```
    fn intersect_affine(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<AffineHit<T>>;
}

impl<T: Real> AffineTracing<T> for DisplacedSurface<T> {
    fn intersect_affine(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<AffineHit<T>> {
        let slab = SlabRay::new(ray.origin, ray.dir);
        self.traverse_prisms(ray, t_min, t_max, |tri, prism, t_max| {
            let uv = uv_in_cells(prism, self.texel_size());
            let shell = AffineShell::new(prism, uv)?;
            let mut best = None;
            traverse_cells(
                self.roots(tri),
                &CellTriangle::new(uv),
                t_max,
                stats,
                |level, x, y, t_max| {
                    let k = 1i64 << level;
                    let (cx, cy) = (i64::from(x) * k, i64::from(y) * k);
                    let c = |i: i64| T::from_f64(i as f64);
                    let [lo, hi] = self.field().texel_bounds(level, i64::from(x), i64::from(y));
                    let (lo, hi) = shell.node_box(
                        [c(cx), c(cx + k)],
                        [c(cy), c(cy + k)],
                        [Self::height(lo), Self::height(hi)],
                    )?;
                    slab.entry(lo, hi, t_min, t_max)
                },
                |x, y, t_max, stats| {
                    stats.texel_tests += 1;
                    let hit = self.affine_texel(&shell, ray, x, y, t_min, t_max)?;
                    let t = hit.t;
                    best = Some(AffineHit {
                        triangle: tri as u32,
                        ..hit
                    });
                    Some(t)
                },
            );
            best.map(|h: AffineHit<T>| (h, h.t))
        })
    }
}

/// The steps of [`AffineTracing`].
pub(crate) trait AffineParts<T: Real> {
    fn affine_texel(
        &self,
        shell: &AffineShell<T>,
        ray: &Ray<T>,
        x: i32,
        y: i32,
        t_min: T,
        t_max: T,
    ) -> Option<AffineHit<T>>;
}

impl<T: Real> AffineParts<T> for DisplacedSurface<T> {
    fn affine_texel(
        &self,
        shell: &AffineShell<T>,
        ray: &Ray<T>,
        x: i32,
        y: i32,
        t_min: T,
        t_max: T,
    ) -> Option<AffineHit<T>> {
        let [h00, h10, h01, h11] = self
            .field()
            .texel_corners(i64::from(x), i64::from(y))
            .map(Self::height);
        let (u0, v0) = (T::from_i32(x), T::from_i32(y));
        let (u1, v1) = (u0 + T::ONE, v0 + T::ONE);
        let corners = [
            ([u0, v0], shell.world(u0, v0, h00)),
            ([u1, v0], shell.world(u1, v0, h10)),
            ([u1, v1], shell.world(u1, v1, h11)),
            ([u0, v1], shell.world(u0, v1, h01)),
        ];
        let mut best: Option<AffineHit<T>> = None;
        for (part, [a, b, c]) in [(TexelPart::Lower, [0, 1, 2]), (TexelPart::Upper, [0, 2, 3])] {
            let tri = [corners[a].1, corners[b].1, corners[c].1];
            let Some((t, b1, b2)) = ray_triangle(&tri, ray.origin, ray.dir) else {
                continue;
            };
            let limit = best.map_or(t_max, |h| h.t);
            if !(t > t_min && t < limit) {
                continue;
            }
            let b0 = T::ONE - b1 - b2;
            let (ua, ub, uc) = (corners[a].0, corners[b].0, corners[c].0);
            let u = ua[0] * b0 + ub[0] * b1 + uc[0] * b2;
            let v = ua[1] * b0 + ub[1] * b1 + uc[1] * b2;
            if !shell.contains(u, v) {
                continue;
            }
            best = Some(AffineHit {
                t,
                normal: (tri[1] - tri[0]).cross(tri[2] - tri[0]),
                triangle: 0,
                texel: [x, y],
                part,
            });
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;
    use nlrt_accel::{HeightField, Wrap};
    use nlrt_poly::glam::{DVec2, DVec3};

    fn plane(heights: &[f32], side: usize) -> DisplacedSurface<f64> {
        let mesh = crate::test_util::unit_square(DVec3::Z, [[0, 1, 2], [0, 2, 3]]);
        let field = HeightField::from_unit_heights(side, side, heights, Wrap::Clamp).unwrap();
        DisplacedSurface::new(mesh, field, 1.0, 1.0).unwrap()
    }

    #[test]
    fn node_boxes_hold_every_texel_corner() {
        // Random heights on a curved prism: every node box of the pyramid holds the world
        // points of its texels' corners.
        let side = 16;
        let heights: Vec<f32> = (0..side * side)
            .map(|i| ((i * 7919) % 101) as f32 / 100.0)
            .collect();
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp).unwrap();
        let prism = Prism::<f64>::new(
            [
                DVec3::ZERO,
                DVec3::new(1.0, 0.2, 0.0),
                DVec3::new(0.1, 1.0, 0.3),
            ],
            [
                DVec3::new(0.0, 0.0, 0.3),
                DVec3::new(0.2, 0.1, 0.25),
                DVec3::new(-0.1, 0.2, 0.35),
            ],
            [DVec2::ZERO, DVec2::X, DVec2::Y],
        );
        let uv = uv_in_cells(&prism, 1.0 / side as f64);
        let shell = AffineShell::new(&prism, uv).unwrap();
        for level in 0..=4u32 {
            let n = side as i64 >> level;
            for y in 0..n {
                for x in 0..n {
                    let k = 1i64 << level;
                    let [lo, hi] = field.texel_bounds(level, x, y);
                    let h = |s: u16| f64::from(s) / f64::from(nlrt_accel::HEIGHT_ONE);
                    let (u, v) = (
                        [(x * k) as f64, ((x + 1) * k) as f64],
                        [(y * k) as f64, ((y + 1) * k) as f64],
                    );
                    let Some((blo, bhi)) = shell.node_box(u, v, [h(lo), h(hi)]) else {
                        continue;
                    };
                    for ty in y * k..=(y + 1) * k {
                        for tx in x * k..=(x + 1) * k {
                            let (uf, vf) = (tx as f64, ty as f64);
                            if !(uf <= 16.0 && vf <= 16.0 && shell.contains(uf, vf)) {
                                continue;
                            }
                            let p = shell.world(uf, vf, h(field.sample(tx, ty)));
                            for i in 0..3 {
                                assert!(blo[i] <= p.get(i) && p.get(i) <= bhi[i]);
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn flat_maps_are_hit_at_their_height_everywhere() {
        for height in [0.0f32, 0.25, 1.0] {
            let surface = plane(&[height; 64], 8);
            for i in 0..400 {
                let (x, y) = ((i % 20) as f64 / 19.0, (i / 20) as f64 / 19.0);
                let ray: Ray<f64> =
                    Ray::new(DVec3::new(x, y, 3.0), DVec3::new(0.01, -0.02, -1.0)).unwrap();
                let stored =
                    f64::from(surface.field().sample(0, 0)) / f64::from(nlrt_accel::HEIGHT_ONE);
                // Where the ray crosses the plane z = stored: inside the square, a hit there.
                let expected = ray.origin + ray.dir * ((ray.origin.z - stored) / -ray.dir.z);
                let inside = (0.0..=1.0).contains(&expected.x) && (0.0..=1.0).contains(&expected.y);
                let hit = surface.intersect_affine(
                    &ray,
                    0.0,
                    f64::INFINITY,
                    &mut TraversalStats::default(),
                );
                match hit {
                    Some(hit) => {
                        let p = ray.origin + ray.dir * hit.t;
                        assert!((p - expected).length() < 1e-12, "{p:?} vs {expected:?}");
                    }
                    None => assert!(!inside, "{expected:?} missed"),
                }
            }
        }
    }

    #[test]
    fn uv_degenerate_triangles_are_never_hit() {
        let mesh = crate::test_util::uv_line_triangle();
        let field = HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).unwrap();
        let surface = DisplacedSurface::new(mesh, field, 1.0, 1.0).unwrap();
        let ray = Ray::new(DVec3::new(0.2, 0.2, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let mut stats = TraversalStats::default();
        assert!(
            surface
                .intersect(&ray, 0.0, f64::INFINITY, &mut stats)
                .is_some()
        );
        assert!(
            surface
                .intersect_affine(&ray, 0.0, f64::INFINITY, &mut stats)
                .is_none()
        );
    }
}
