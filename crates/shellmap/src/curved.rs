//! Curved shell mapping (Jeschke, Mantler and Wimmer 2007, sec. 3.2): inside each prism a
//! family of Coons-patch surfaces, one per height, that meet the neighbouring prisms' along the
//! shared edges and bend with the vertex normals, so that a displaced surface follows a smooth
//! curved base instead of the flat base triangles.
//!
//! For texture height `w` the paper compresses the height to `w' = w / 2 + 1 / 4` (so that the
//! curved surface stays inside the prism for moderate curvature; a heuristic, it notes), takes
//! the world triangle `T(w')` of the smooth shell and moves the point of barycentrics
//! `(1 - alpha - beta, alpha, beta)` on it along the unit interpolated normal by the Coons
//! displacement of `T(w')`:
//!
//! `Phi_c(alpha, beta, w) = Phi(alpha, beta, w') + n(alpha, beta) / |n(alpha, beta)| Coons_T(w')`
//!
//! With the prism's interpolated offset vector as `n` (the vertex normals of [`Prism`]), the
//! moved point stays on the prism's fibre through `(alpha, beta)`, so it is the smooth shell
//! point at height [`Prism::curved_shell_height`]: the barycentric correspondence of the paper
//! holds exactly, and the inverse of the paper's Eq. 2 interpolates along that fibre
//! ([`Prism::curved_texture_height`]).
//!
//! The Coons displacement follows the paper's description (after Smits et al. 2000): from each
//! vertex, cubic Hermite curves along its two edges (end slopes from the unit vertex normals);
//! on both, the point at parameter `1 - b_i`; a cubic Hermite between these two points (end
//! slopes from the normals interpolated along the edges). The three vertex constructions are
//! blended with equal weights, not by the paper's Boolean sum: all three equal the edge curve on
//! every edge, so any blend meets the neighbouring prism's patch exactly there (tested); tangent
//! continuity across edges is approximate.

use nlrt_poly::{Real, Vector3};

use crate::Prism;

/// `v / |v|`, or zero for a zero or non-finite length (a vertex without a normal bends nothing).
fn unit_or_zero<T: Real>(v: T::Vec3) -> T::Vec3 {
    let len = v.length();
    if len > T::ZERO && len.is_finite() {
        v * (T::ONE / len)
    } else {
        v * T::ZERO
    }
}

/// Displacement of the cubic Hermite curve from `a` (unit normal `na`) to `b` (unit normal `nb`)
/// off the straight edge, at parameter `s` (0 at `a`): zero at both ends, end slopes those of
/// the tangent planes, `-na . (b - a)` and `-nb . (b - a)`.
fn edge_curve<T: Real>(a: T::Vec3, na: T::Vec3, b: T::Vec3, nb: T::Vec3, s: T) -> T {
    let e = b - a;
    let r = T::ONE - s;
    s * r * (s * nb.dot(e) - r * na.dot(e))
}

/// The construction from vertex `i` of the triangle `v` with unit normals `m` at barycentrics
/// `b` (indices `i, j, k` in order).
fn vertex_construction<T: Real>(v: &[T::Vec3; 3], m: &[T::Vec3; 3], b: [T; 3], i: usize) -> T {
    let (j, k) = ((i + 1) % 3, (i + 2) % 3);
    let s = T::ONE - b[i];
    if !(s > T::ZERO) {
        // At the vertex itself every curve starts at zero.
        return T::ZERO;
    }
    // The points of the two edge curves at parameter s, their displacements and normals.
    let (a, c) = (v[i] + (v[j] - v[i]) * s, v[i] + (v[k] - v[i]) * s);
    let da = edge_curve::<T>(v[i], m[i], v[j], m[j], s);
    let dc = edge_curve::<T>(v[i], m[i], v[k], m[k], s);
    let na = unit_or_zero::<T>(m[i] * (T::ONE - s) + m[j] * s);
    let nc = unit_or_zero::<T>(m[i] * (T::ONE - s) + m[k] * s);
    // Hermite from a to c at r; the end slopes are the tangent planes' along c - a.
    let f = c - a;
    let r = b[k] / s;
    let q = T::ONE - r;
    let (h00, h01) = (
        (T::ONE + T::TWO * r) * q * q,
        r * r * (T::from_i32(3) - T::TWO * r),
    );
    let (h10, h11) = (r * q * q, -(r * r * q));
    h00 * da + h01 * dc - h10 * na.dot(f) - h11 * nc.dot(f)
}

/// The Coons displacement of the triangle `v` with unit vertex normals `m` at barycentrics
/// `(1 - alpha - beta, alpha, beta)`: the equal-weight blend of the three vertex constructions
/// (see the module documentation). Positive on the side the normals point to; zero for a flat
/// triangle with equal normals, and zero on an edge whose end normals are those of a plane
/// containing it.
///
/// ```
/// use nlrt_poly::glam::DVec3;
/// use nlrt_shellmap::coons_displacement;
/// // A triangle on the unit sphere with radial normals bulges outwards by about the sagitta.
/// let v = [DVec3::X, DVec3::Y, DVec3::Z];
/// let d = coons_displacement::<f64>(&v, &v, 1.0 / 3.0, 1.0 / 3.0);
/// let sagitta = 1.0 - 1.0 / 3f64.sqrt();
/// assert!(d > 0.0 && (d - sagitta).abs() < 0.25 * sagitta);
/// ```
#[must_use]
pub fn coons_displacement<T: Real>(v: &[T::Vec3; 3], m: &[T::Vec3; 3], alpha: T, beta: T) -> T {
    let b = [T::ONE - alpha - beta, alpha, beta];
    let sum = vertex_construction::<T>(v, m, b, 0)
        + vertex_construction::<T>(v, m, b, 1)
        + vertex_construction::<T>(v, m, b, 2);
    sum / T::from_i32(3)
}

impl<T: Real> Prism<T> {
    /// The height of the smooth shell that holds the curved shell point of texture height `w`
    /// at `(alpha, beta)`: `w' + Coons_T(w') / |n|` with `w' = w / 2 + 1 / 4` and `n` the
    /// interpolated vertex normal (sec. 3.2). A zero interpolated normal gives `w'`.
    ///
    /// ```
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Prism;
    /// // Flat base, equal normals: no bending, only the height compression.
    /// let z = DVec3::Z;
    /// let prism = Prism::<f64>::new([DVec3::ZERO, DVec3::X, DVec3::Y], [z, z, z], [DVec2::ZERO, DVec2::X, DVec2::Y]);
    /// assert_eq!(prism.curved_shell_height(0.2, 0.3, 0.5), 0.5);
    /// assert_eq!(prism.curved_shell_height(0.2, 0.3, 0.0), 0.25);
    /// ```
    #[must_use]
    pub fn curved_shell_height(&self, alpha: T, beta: T, w: T) -> T {
        self.curved_shell_heights(alpha, beta, [w])[0]
    }

    /// [`Prism::curved_shell_height`] at several texture heights, sharing the unit normals.
    fn curved_shell_heights<const K: usize>(&self, alpha: T, beta: T, w: [T; K]) -> [T; K] {
        let m = self.n.map(unit_or_zero::<T>);
        let n = self.n[0] + (self.n[1] - self.n[0]) * alpha + (self.n[2] - self.n[0]) * beta;
        let len = n.length();
        let bends = len > T::ZERO && len.is_finite();
        w.map(|w| {
            let compressed = w * T::HALF + T::HALF * T::HALF;
            if !bends {
                return compressed;
            }
            let v = [0, 1, 2].map(|i| self.vertex(i, compressed));
            compressed + coons_displacement::<T>(&v, &m, alpha, beta) / len
        })
    }

    /// `Phi_c(alpha, beta, w)`: the world point of the curved shell at texture height `w`.
    #[must_use]
    pub fn curved_shell_point(&self, alpha: T, beta: T, w: T) -> T::Vec3 {
        self.shell_point(alpha, beta, self.curved_shell_height(alpha, beta, w))
    }

    /// The paper's Eq. 2 (sec. 3.2): the texture height of the world point at smooth-shell
    /// coordinates `(alpha, beta, h)`, by linear interpolation between the bounding curved
    /// surfaces `w = 0` and `w = 1` along the fibre (signed: below the `w = 0` surface it is
    /// negative). Exact on the two bounding surfaces; between them the curved surfaces are
    /// not evenly spaced, and the error is the paper's (its "1/100 of the shell thickness").
    /// NaN where the two bounding surfaces meet (a zero-thickness shell).
    #[must_use]
    pub fn curved_texture_height(&self, alpha: T, beta: T, h: T) -> T {
        let [low, high] = self.curved_shell_heights(alpha, beta, [T::ZERO, T::ONE]);
        let thickness = high - low;
        if !(thickness != T::ZERO) {
            return T::NAN;
        }
        (h - low) / thickness
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::{DVec2, DVec3};

    fn sphere_prism(a: DVec3, b: DVec3, c: DVec3, thickness: f64) -> Prism<f64> {
        let v = [a, b, c].map(|p| p.normalize());
        Prism::new(
            v,
            v.map(|p| p * thickness),
            [DVec2::ZERO, DVec2::X, DVec2::Y],
        )
    }

    #[test]
    fn flat_triangles_are_only_compressed() {
        let z = DVec3::new(0.0, 0.0, 0.5);
        let prism = Prism::<f64>::new(
            [DVec3::ZERO, DVec3::X, DVec3::new(0.3, 2.0, 0.0)],
            [z, z, z],
            [DVec2::ZERO, DVec2::X, DVec2::Y],
        );
        for k in 0..=10 {
            let (a, b, w) = (0.05 * k as f64, 0.09 * k as f64 - 0.2, 0.1 * k as f64);
            let h = prism.curved_shell_height(a, b, w);
            assert!((h - (w / 2.0 + 0.25)).abs() < 1e-15);
            assert!((prism.curved_texture_height(a, b, h) - w).abs() < 1e-14);
        }
    }

    #[test]
    fn patches_of_triangles_sharing_an_edge_meet_there() {
        // Two sphere triangles sharing the edge (x, y); the far vertices differ.
        let (x, y) = (DVec3::new(1.0, 0.2, 0.1), DVec3::new(0.1, 1.0, 0.3));
        let left = sphere_prism(x, y, DVec3::new(0.2, 0.1, 1.0), 0.3);
        let right = sphere_prism(y, x, DVec3::new(0.9, 0.8, -0.6), 0.3);
        for k in 0..=8 {
            let s = k as f64 / 8.0;
            for w in [0.0, 0.4, 1.0] {
                // Left: vertex 0 = x, 1 = y, point x + s (y - x) has alpha = s, beta = 0.
                // Right: vertex 0 = y, 1 = x, the same point has alpha = 1 - s.
                let p = left.curved_shell_point(s, 0.0, w);
                let q = right.curved_shell_point(1.0 - s, 0.0, w);
                assert!((p - q).length() < 1e-14, "s {s} w {w}: {p} vs {q}");
            }
        }
    }

    #[test]
    fn sphere_patches_bulge_like_the_sphere() {
        // An octant-sized triangle and a small one: the curved mid-height surface sits at
        // nearly constant radius, the flat one sags towards the centre.
        for (scale, limit) in [(1.0, 0.06), (0.2, 0.002)] {
            let a = DVec3::new(1.0, 0.0, 0.0);
            let b = (a + DVec3::Y * scale).normalize();
            let c = (a + DVec3::Z * scale).normalize();
            let prism = sphere_prism(a, b, c, 0.1);
            let mut worst_curved: f64 = 0.0;
            let mut worst_flat: f64 = 0.0;
            for i in 0..=10 {
                for j in 0..=10 - i {
                    let (al, be) = (i as f64 / 10.0, j as f64 / 10.0);
                    // w = 0.5: w' = 0.5, radius 1.05 on the sphere of the shell.
                    let r = prism.curved_shell_point(al, be, 0.5).length();
                    worst_curved = worst_curved.max((r - 1.05).abs());
                    let flat = prism.shell_point(al, be, 0.5).length();
                    worst_flat = worst_flat.max((flat - 1.05).abs());
                }
            }
            assert!(worst_curved < limit, "{scale}: {worst_curved}");
            assert!(
                worst_curved < 0.25 * worst_flat,
                "{worst_curved} vs {worst_flat}"
            );
        }
    }

    #[test]
    fn eq2_is_exact_on_the_bounding_surfaces_and_monotone_between() {
        let prism = sphere_prism(
            DVec3::X,
            DVec3::new(0.8, 0.6, 0.0),
            DVec3::new(0.8, 0.1, 0.6),
            0.2,
        );
        for (a, b) in [(0.1, 0.2), (0.33, 0.33), (0.0, 0.9), (0.6, 0.0)] {
            let h0 = prism.curved_shell_height(a, b, 0.0);
            let h1 = prism.curved_shell_height(a, b, 1.0);
            assert!(prism.curved_texture_height(a, b, h0).abs() < 1e-13);
            assert!((prism.curved_texture_height(a, b, h1) - 1.0).abs() < 1e-13);
            let mut last = -1.0;
            for k in 0..=10 {
                let w = k as f64 / 10.0;
                let back = prism.curved_texture_height(a, b, prism.curved_shell_height(a, b, w));
                assert!(back > last);
                // The interpolation error of Eq. 2 inside: the paper's 1/100 of the shell.
                assert!((back - w).abs() < 0.01, "{a} {b} {w}: {back}");
                last = back;
            }
        }
    }

    #[test]
    fn degenerate_prisms_give_finite_heights() {
        let prism = Prism::<f32>::new(
            [
                nlrt_poly::glam::Vec3::ZERO,
                nlrt_poly::glam::Vec3::X,
                nlrt_poly::glam::Vec3::Y,
            ],
            [nlrt_poly::glam::Vec3::ZERO; 3],
            [
                nlrt_poly::glam::Vec2::ZERO,
                nlrt_poly::glam::Vec2::X,
                nlrt_poly::glam::Vec2::Y,
            ],
        );
        assert_eq!(prism.curved_shell_height(0.2, 0.2, 1.0), 0.75);
        assert!(prism.curved_texture_height(0.2, 0.2, 0.5).is_finite());
        let flat = Prism::<f32>::new(
            [nlrt_poly::glam::Vec3::ZERO; 3],
            [nlrt_poly::glam::Vec3::Z; 3],
            [
                nlrt_poly::glam::Vec2::ZERO,
                nlrt_poly::glam::Vec2::X,
                nlrt_poly::glam::Vec2::Y,
            ],
        );
        assert!(flat.curved_shell_height(0.2, 0.2, 1.0).is_finite());
    }
}
