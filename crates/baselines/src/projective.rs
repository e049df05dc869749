//! Projective displacement mapping (Projective Displacement Mapping for Ray Traced Editable
//! Surfaces): parallel offset prisms, whose offset triangles are parallel to the base
//! triangle, so that a world point's height is its distance from the base plane (linear) and
//! its barycentric coordinates are those in the *scanning triangle* at that height (a planar
//! projection): samples along a world ray map to texture space without a cubic. The ray is
//! sampled at equal world steps between its entry and exit of the prism (the prism's sides are
//! bilinear patches, intersected exactly by [`nlrt_shellmap::intersect_prism`]), with the
//! first sample jittered (the paper's thin-feature sampling), the first sample under the
//! surface is a hit, refined by interpolating the height difference across the surface.
//! There is no bottom-level structure: an edit of the map needs no rebuild at all.
//!
//! The parallel prism of a base triangle with unit geometric normal `n_g` has offset
//! directions `N'_i = d N_i / (N_i . n_g)`, `d` the mean of `N_i . n_g` (so the offset
//! triangle lies at the mean perpendicular height of Eq. 1's top). The displaced surface is
//! Eq. 1 over that prism: the same as nonlinear tracing's where the normals are constant,
//! different on curved bases (measured by the report).

use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Prism, Ray, intersect_prism};

use nlrt_accel::{
    BaseMesh, DisplacedSurface, DisplacementError, HeightField, SurfaceHit, TraversalStats,
};

use crate::march::{MarchOptions, SampledSurface};

/// A displaced surface over parallel offset prisms (projective displacement mapping).
#[derive(Clone, Debug)]
pub struct ProjectiveSurface<T: Real> {
    surface: DisplacedSurface<T>,
    /// Per triangle: unit geometric normal (zero for a triangle of zero area) and the offset
    /// height `d`.
    planes: Vec<(T::Vec3, T)>,
}

impl<T: Real> ProjectiveSurface<T> {
    /// Builds the parallel offset prisms of `mesh` with its normals scaled by `height_scale`
    /// (each triangle gets its own three
    /// vertices, since `N'_i` depends on the triangle) and the TLAS over them. A triangle of
    /// zero area, or one where a vertex normal does not point to the side of the geometric
    /// normal the others do, gets a flat prism and is never hit.
    ///
    /// # Errors
    /// A non-finite height scale, or as [`DisplacedSurface::new`].
    pub fn new(
        mesh: &BaseMesh<T>,
        field: HeightField,
        height_scale: T,
        tiling: T,
    ) -> Result<Self, DisplacementError> {
        if !height_scale.is_finite() {
            return Err(DisplacementError::BadHeightScale(height_scale.to_f64()));
        }
        let n = mesh.triangle_count();
        let (mut positions, mut normals, mut uvs, mut triangles, mut planes) = (
            Vec::with_capacity(3 * n),
            Vec::with_capacity(3 * n),
            Vec::with_capacity(3 * n),
            Vec::with_capacity(n),
            Vec::with_capacity(n),
        );
        let zero = T::Vec3::new(T::ZERO, T::ZERO, T::ZERO);
        for i in 0..n {
            let t = mesh.triangle(i).map(|v| v as usize);
            let p = t.map(|v| mesh.positions()[v]);
            let nv = t.map(|v| mesh.normals()[v] * height_scale);
            let g = (p[1] - p[0]).cross(p[2] - p[0]);
            let len = g.length();
            let mut offsets = [zero; 3];
            let mut plane = (zero, T::ZERO);
            if len > T::ZERO && len.is_finite() {
                // Orient the geometric normal like the vertex normals.
                let sum = nv[0] + nv[1] + nv[2];
                let g = if g.dot(sum) < T::ZERO { -g } else { g } * (T::ONE / len);
                let cos = nv.map(|v| v.dot(g));
                if cos.iter().all(|c| *c > T::ZERO) {
                    let d = (cos[0] + cos[1] + cos[2]) / T::THREE;
                    let o: [T::Vec3; 3] = core::array::from_fn(|k| nv[k] * (d / cos[k]));
                    if o.iter().all(|v| v.dot(*v).is_finite()) {
                        offsets = o;
                        plane = (g, d);
                    }
                }
            }
            let base = positions.len() as u32;
            for k in 0..3 {
                positions.push(p[k]);
                normals.push(offsets[k]);
                uvs.push(mesh.uvs()[t[k]]);
            }
            triangles.push([base, base + 1, base + 2]);
            planes.push(plane);
        }
        let parallel = BaseMesh::new(positions, normals, uvs, triangles)
            .expect("the triangles of a valid mesh, with finite offsets");
        Ok(Self {
            surface: DisplacedSurface::new(parallel, field, T::ONE, tiling)?,
            planes,
        })
    }

    /// The displaced surface over the parallel prisms (for normals and the height field).
    #[must_use]
    pub fn surface(&self) -> &DisplacedSurface<T> {
        &self.surface
    }

    /// Bytes of the data the method uses: the height samples and the TLAS (it has no
    /// bottom-level structure; the pyramid that [`DisplacedSurface`] keeps is not read).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        core::mem::size_of_val(self.surface.field().samples())
            + self.surface.tlas().memory_bytes()
            + self.planes.len() * core::mem::size_of::<(T::Vec3, T)>()
    }

    /// The nearest hit of `ray` with `t` in `(t_min, t_max)`; `jitter` in `[0, 1)` shifts the
    /// first sample (thin-feature sampling: vary it per ray or per frame).
    pub fn intersect(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        jitter: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.surface
            .traverse_prisms(ray, t_min, t_max, |tri, prism, t_max| {
                stats.prism_tests += 1;
                let (g, d) = self.planes[tri];
                if d == T::ZERO {
                    return None;
                }
                let span = intersect_prism(prism, ray, t_min, t_max)?;
                let hit = self.scan(
                    tri, prism, g, ray, span.t_in, span.t_out, jitter, opts, stats,
                )?;
                (hit.hit.t > t_min && hit.hit.t < t_max).then_some((hit, hit.hit.t))
            })
    }

    /// Canonical `(alpha, beta, h)` of world point `x` in the parallel prism: `h` from the
    /// distance to the base plane, `alpha, beta` in the scanning triangle at that height.
    fn canonical(prism: &Prism<T>, g: T::Vec3, x: T::Vec3) -> Option<[T; 3]> {
        let top = prism.vertex(0, T::ONE) - prism.p[0];
        let h = (x - prism.p[0]).dot(g) / top.dot(g);
        let s0 = prism.vertex(0, h);
        let (e0, e1) = (prism.vertex(1, h) - s0, prism.vertex(2, h) - s0);
        let n = e0.cross(e1);
        let nn = n.dot(n);
        if !(nn > T::ZERO && nn.is_finite()) {
            return None;
        }
        let r = x - s0;
        Some([r.cross(e1).dot(n) / nn, e0.cross(r).dot(n) / nn, h])
    }

    #[allow(clippy::too_many_arguments)]
    fn scan(
        &self,
        tri: usize,
        prism: &Prism<T>,
        g: T::Vec3,
        ray: &Ray<T>,
        t_in: T,
        t_out: T,
        jitter: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let s = &self.surface;
        let at = |t: T| Self::canonical(prism, g, ray.origin + ray.dir * t);
        let (start, end) = (at(t_in)?, at(t_out)?);
        let uv = |c: &[T; 3]| prism.texture_uv(c[0], c[1]);
        // The sample spacing: `samples_per_texel` per texel crossed.
        let steps = s.sample_steps(uv(&start), uv(&end), opts);
        let dt = (t_out - t_in) / T::from_i32(steps as i32);
        // Height above the surface (negative: under it) at distance t.
        let above = |t: T| -> Option<(T, [T; 3])> {
            let c = at(t)?;
            let p = uv(&c);
            let (h, _, _) = s.surface_height(p.x(), p.y());
            Some((c[2] - h, c))
        };
        let mut previous: Option<(T, T)> = None;
        let mut k = 0;
        loop {
            // The first sample jittered by `jitter` of a step, then equal steps, then the exit.
            let t = if k == 0 {
                t_in
            } else {
                (t_in + dt * (T::from_i32(k - 1) + jitter)).min(t_out)
            };
            stats.texel_tests += 1;
            let (f, c) = above(t)?;
            let inside = c[0] >= T::ZERO && c[1] >= T::ZERO && c[0] + c[1] <= T::ONE;
            if inside && f <= T::ZERO {
                // Interpolate the height difference across the surface.
                let t_hit = match previous {
                    Some((tp, fp)) if fp > T::ZERO => tp + (t - tp) * (fp / (fp - f)),
                    _ => t,
                };
                let c = at(t_hit).unwrap_or(c);
                return Some(s.sampled_hit(tri, prism, c, t_hit));
            }
            previous = Some((t, f));
            if t >= t_out || k as usize > steps + 1 {
                return None;
            }
            k += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;
    use nlrt_accel::Wrap;
    use nlrt_poly::glam::{DVec2, DVec3};

    #[test]
    fn constant_normals_give_the_same_surface_as_nonlinear_tracing() {
        let mesh = crate::test_util::unit_square(DVec3::Z * 0.3, [[0, 1, 2], [0, 2, 3]]);
        let side = 32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (i, j) = (
                    (k % side) as f32 / side as f32,
                    (k / side) as f32 / side as f32,
                );
                0.5 + 0.3 * (5.0 * i).sin() * (4.0 * j).cos()
            })
            .collect();
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp).unwrap();
        let exact = DisplacedSurface::new(mesh.clone(), field.clone(), 1.0, 1.0).unwrap();
        let pdm = ProjectiveSurface::new(&mesh, field, 1.0, 1.0).unwrap();
        let opts = MarchOptions::default();
        let mut st = TraversalStats::default();
        for k in 0..400 {
            let (x, y) = (0.1 + (k % 20) as f64 * 0.04, 0.1 + (k / 20) as f64 * 0.04);
            let ray = Ray::new(DVec3::new(x, y, 1.0), DVec3::new(0.2, 0.1, -1.0)).unwrap();
            let a = exact
                .intersect(&ray, 0.0, f64::INFINITY, &mut st)
                .map(|h| h.hit.t);
            let b = pdm
                .intersect(&ray, 0.0, f64::INFINITY, 0.5, &opts, &mut st)
                .map(|h| h.hit.t);
            match (a, b) {
                // Linear interpolation of the height difference between samples half a texel
                // apart on a smooth map: within 1e-3 of the ray's length here.
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-3, "{k}: {a} vs {b}"),
                (None, None) => {}
                other => panic!("{k}: {other:?}"),
            }
        }
    }

    #[test]
    fn degenerate_triangles_get_flat_prisms() {
        let mesh = BaseMesh::<f64>::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(2.0, 0.0, 0.0)],
            vec![DVec3::Z; 3],
            vec![DVec2::ZERO, DVec2::X, DVec2::Y],
            vec![[0, 1, 2]],
        )
        .unwrap();
        let field = HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).unwrap();
        let pdm = ProjectiveSurface::new(&mesh, field, 1.0, 1.0).unwrap();
        let ray = Ray::new(DVec3::new(0.5, 0.0, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let mut st = TraversalStats::default();
        assert!(
            pdm.intersect(
                &ray,
                0.0,
                f64::INFINITY,
                0.5,
                &MarchOptions::default(),
                &mut st
            )
            .is_none()
        );
    }
}
