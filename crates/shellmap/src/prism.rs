//! A prism of the shell: a base triangle extruded along its vertex normals (Ogaki 2023, sec. 3),
//! and the maps between world, canonical `(alpha, beta, h)` and texture `(u, v, h)` space.

use nlrt_poly::{Real, Vector3, solve_cubic_in};

/// Canonical coordinates of a point in a prism: barycentric `(alpha, beta)` on the base triangle
/// and height `h`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Canonical<T> {
    /// Weight of vertex 1.
    pub alpha: T,
    /// Weight of vertex 2.
    pub beta: T,
    /// Height parameter.
    pub h: T,
}

/// One prism of a shell: base triangle `P_i`, vertex normals `N_i` (not necessarily unit: their
/// length scales the height), and texture coordinates `T_i = (U_i, V_i)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prism<T: Real> {
    /// Base triangle vertices `P_0, P_1, P_2`.
    pub p: [T::Vec3; 3],
    /// Vertex normals `N_0, N_1, N_2`.
    pub n: [T::Vec3; 3],
    /// Texture coordinates `T_0, T_1, T_2`.
    pub uv: [T::Vec2; 3],
}

/// `(alpha, beta)` moved onto the base triangle (`alpha, beta >= 0`, `alpha + beta <= 1`):
/// negative coordinates to 0, a sum above 1 scaled back to 1. For canonical coordinates that
/// rounding put just outside the triangle; a point inside is returned unchanged.
///
/// ```
/// use nlrt_shellmap::onto_base_triangle;
/// assert_eq!(onto_base_triangle(0.25f64, 0.5), (0.25, 0.5));
/// assert_eq!(onto_base_triangle(-1e-17f64, 0.5), (0.0, 0.5));
/// let (a, b) = onto_base_triangle(0.75f32, 0.5);
/// assert!(a + b <= 1.0 && (a - 0.6).abs() < 1e-6);
/// ```
#[must_use]
pub fn onto_base_triangle<T: Real>(alpha: T, beta: T) -> (T, T) {
    let (alpha, beta) = (alpha.max(T::ZERO), beta.max(T::ZERO));
    let sum = alpha + beta;
    if sum > T::ONE {
        // The quotients may still sum to 1 + 1 ulp; `1 - alpha` then makes the sum round to
        // at most 1 (it is within half an ulp of `beta` of 1).
        let (alpha, beta) = (alpha / sum, beta / sum);
        if alpha + beta > T::ONE {
            (alpha, T::ONE - alpha)
        } else {
            (alpha, beta)
        }
    } else {
        (alpha, beta)
    }
}

impl<T: Real> Prism<T> {
    /// A prism from its base triangle, vertex normals and texture coordinates.
    #[must_use]
    pub fn new(p: [T::Vec3; 3], n: [T::Vec3; 3], uv: [T::Vec2; 3]) -> Self {
        Self { p, n, uv }
    }

    /// `S_i(h) = P_i + h N_i`.
    #[must_use]
    #[inline]
    pub fn vertex(&self, i: usize, h: T) -> T::Vec3 {
        self.p[i] + self.n[i] * h
    }

    /// `E_0(h) = S_1(h) - S_0(h)` and `E_1(h) = S_2(h) - S_0(h)` as `(constant, slope)` in `h`.
    #[must_use]
    #[inline]
    pub(crate) fn edges(&self) -> [(T::Vec3, T::Vec3); 2] {
        [
            (self.p[1] - self.p[0], self.n[1] - self.n[0]),
            (self.p[2] - self.p[0], self.n[2] - self.n[0]),
        ]
    }

    /// The shell point `S(alpha, beta, h)` of Eq. 1.
    ///
    /// ```
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Prism;
    /// let z = DVec3::Z;
    /// let prism = Prism::<f64>::new([DVec3::ZERO, DVec3::X, DVec3::Y], [z, z, z], [DVec2::ZERO, DVec2::X, DVec2::Y]);
    /// assert_eq!(prism.shell_point(0.25, 0.5, 2.0), DVec3::new(0.25, 0.5, 2.0));
    /// ```
    #[must_use]
    #[inline]
    pub fn shell_point(&self, alpha: T, beta: T, h: T) -> T::Vec3 {
        let s0 = self.vertex(0, h);
        s0 + (self.vertex(1, h) - s0) * alpha + (self.vertex(2, h) - s0) * beta
    }

    /// Texture coordinates `(u, v)` of barycentric `(alpha, beta)` (Eq. 2-3).
    #[must_use]
    #[inline]
    pub fn texture_uv(&self, alpha: T, beta: T) -> T::Vec2 {
        let t0 = self.uv[0];
        t0 + (self.uv[1] - t0) * alpha + (self.uv[2] - t0) * beta
    }

    /// Canonical coordinates of a world point with `h` in `[h_lo, h_hi]` (the inverse of
    /// Eq. 1, through the cubic of Eq. 4; also Jeschke 2007's inverse smooth mapping). Where the
    /// cubic has several roots in the range (a folded shell), the one inside the base triangle
    /// (then the one reproducing `x` best) is returned. `None` if no height in the range fits or the prism is
    /// degenerate there.
    #[must_use]
    pub fn world_to_canonical(&self, x: T::Vec3, h_lo: T, h_hi: T) -> Option<Canonical<T>> {
        let [(a0, a1), (b0, b1)] = self.edges();
        // N(h) = E0(h) x E1(h) = c0 + c1 h + c2 h^2; I - S0(h) = d0 + d1 h.
        let c0 = a0.cross(b0);
        let c1 = a0.cross(b1) + a1.cross(b0);
        let c2 = a1.cross(b1);
        let d0 = x - self.p[0];
        let d1 = -self.n[0];
        let cubic = [
            d0.dot(c0),
            d0.dot(c1) + d1.dot(c0),
            d0.dot(c2) + d1.dot(c1),
            d1.dot(c2),
        ];
        let mut best: Option<(T, T, Canonical<T>)> = None;
        for &h in solve_cubic_in(cubic, h_lo, h_hi).iter() {
            let Some((alpha, beta)) =
                barycentric_in_plane::<T>(self.vertex(0, h), a0 + a1 * h, b0 + b1 * h, x)
            else {
                continue;
            };
            // Several heights fit where the shell folds over itself, each with its own
            // (alpha, beta); prefer the one inside the base triangle, then the best fit.
            let outside = T::ZERO.max(-alpha).max(-beta).max(alpha + beta - T::ONE);
            let miss = (self.shell_point(alpha, beta, h) - x).length();
            if best.is_none_or(|(o, m, _)| outside < o || (outside == o && miss < m)) {
                best = Some((outside, miss, Canonical { alpha, beta, h }));
            }
        }
        best.map(|(_, _, c)| c)
    }
}

impl<T: Real> Prism<T> {
    /// Where a world ray crosses the prism's cross-section at height `h` (the flat triangle
    /// `S_0(h) S_1(h) S_2(h)`, Eq. 1 at constant `h`) inside the base triangle: `(t, alpha,
    /// beta)`. `None` when the ray is parallel to it, it is degenerate, or the crossing is
    /// outside. The prism's caps and the flat-microtriangle shortcut both use it.
    #[must_use]
    pub fn cross_section_hit(&self, ray: &crate::Ray<T>, h: T) -> Option<(T, T, T)> {
        let (t, alpha, beta) = self.cross_section_crossing(ray, h)?;
        (alpha >= T::ZERO && beta >= T::ZERO && alpha + beta <= T::ONE).then_some((t, alpha, beta))
    }

    /// Where a world ray crosses the plane of the prism's cross-section at height `h`,
    /// inside the base triangle or not: `(t, alpha, beta)` (see
    /// [`Prism::cross_section_hit`]). A caller that keeps points a rounding outside (onto the
    /// prism's wall, as the shell's object test does) needs the crossing outside too.
    #[must_use]
    pub fn cross_section_crossing(&self, ray: &crate::Ray<T>, h: T) -> Option<(T, T, T)> {
        let s0 = self.vertex(0, h);
        let (e0, e1) = (self.vertex(1, h) - s0, self.vertex(2, h) - s0);
        let denom = e0.cross(e1).dot(ray.dir);
        if denom == T::ZERO || !denom.is_finite() {
            return None;
        }
        let t = e0.cross(e1).dot(s0 - ray.origin) / denom;
        let (alpha, beta) = barycentric_in_plane::<T>(s0, e0, e1, ray.at(t))?;
        Some((t, alpha, beta))
    }
}

/// `(alpha, beta)` with `x = s0 + alpha e0 + beta e1`, from the two coordinate equations whose
/// 2x2 determinant is largest in magnitude (the three equations of Eq. 1 hold together when `x`
/// lies in the plane; the best-conditioned pair is the robust choice, as in Eq. 11). `None` when
/// `e0` and `e1` are parallel (a degenerate triangle at this height).
#[must_use]
pub(crate) fn barycentric_in_plane<T: Real>(
    s0: T::Vec3,
    e0: T::Vec3,
    e1: T::Vec3,
    x: T::Vec3,
) -> Option<(T, T)> {
    let r = x - s0;
    // The normal's components are the three 2x2 determinants (yz, zx, xy).
    let normal = e0.cross(e1);
    let axis = normal.max_abs_axis();
    let det = normal.get(axis);
    if det == T::ZERO || !det.is_finite() {
        return None;
    }
    // Drop `axis`; solve in the remaining two coordinates (i, j) with det = e0_i e1_j - e0_j e1_i.
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let alpha = nlrt_poly::difference_of_products(r.get(i), e1.get(j), r.get(j), e1.get(i)) / det;
    let beta = nlrt_poly::difference_of_products(e0.get(i), r.get(j), e0.get(j), r.get(i)) / det;
    Some((alpha, beta))
}
