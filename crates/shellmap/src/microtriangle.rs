//! Nonlinear ray against texture-space planes and microtriangles (Ogaki 2023, sec. 4.3).

use crate::prism::Prism;
use crate::ray::NonlinearRay;
use nlrt_poly::{Real, Vector3, difference_of_products, solve_cubic_in};

/// A plane `n_u u + n_v v + n_h h + k = 0` in texture space, normalized (`|n| = 1`): the paper
/// notes that dividing by `|n_uvh|` first makes the microtriangle test robust, since
/// microtriangles, and so their unnormalized normals, are tiny.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexturePlane<T: Real> {
    /// Unit normal `(n_u, n_v, n_h)`.
    pub normal: T::Vec3,
    /// Offset `k`.
    pub k: T,
}

impl<T: Real> TexturePlane<T> {
    /// The plane through three texture-space points `(u, v, h)`; `None` if they are collinear.
    #[must_use]
    pub fn through(p: &[T::Vec3; 3]) -> Option<Self> {
        let n = (p[1] - p[0]).cross(p[2] - p[0]);
        let len = n.length();
        if !(len > T::ZERO && len.is_finite()) {
            return None;
        }
        let normal = n * (T::ONE / len);
        Some(Self {
            normal,
            k: -normal.dot(p[0]),
        })
    }

    /// Cubic in `h` whose roots are where the nonlinear ray meets the plane: Eq. 8 substituted
    /// into Eq. 9 with the denominator cleared.
    #[must_use]
    pub fn ray_cubic(&self, ray: &NonlinearRay<T>) -> [T; 4] {
        let (nu, nv, nh, k) = (self.normal.x(), self.normal.y(), self.normal.z(), self.k);
        let (u, v, d) = (&ray.u, &ray.v, &ray.d);
        [
            nu.mul_add(u[0], nv.mul_add(v[0], k * d[0])),
            nu.mul_add(u[1], nv.mul_add(v[1], k.mul_add(d[1], nh * d[0]))),
            nu.mul_add(u[2], nv.mul_add(v[2], k.mul_add(d[2], nh * d[1]))),
            nh * d[2],
        ]
    }

    /// The plane in canonical coordinates (Eq. 10): `(n_alpha, n_beta, n_h, K_abh)`.
    #[must_use]
    pub fn canonical(&self, prism: &Prism<T>) -> [T; 4] {
        use nlrt_poly::Vector2;
        let [t0, t1, t2] = prism.uv;
        let (nu, nv) = (self.normal.x(), self.normal.y());
        [
            nu.mul_add(t1.x() - t0.x(), nv * (t1.y() - t0.y())),
            nu.mul_add(t2.x() - t0.x(), nv * (t2.y() - t0.y())),
            self.normal.z(),
            nu.mul_add(t0.x(), nv.mul_add(t0.y(), self.k)),
        ]
    }
}

/// A hit of a nonlinear ray on a microtriangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit<T: Real> {
    /// Distance along the world ray.
    pub t: T,
    /// Canonical coordinates of the hit.
    pub alpha: T,
    /// Canonical coordinates of the hit.
    pub beta: T,
    /// Height of the hit.
    pub h: T,
    /// Texture coordinates of the hit.
    pub u: T,
    /// Texture coordinates of the hit.
    pub v: T,
}

impl<T: Real> Hit<T> {
    /// The hit at distance `t` on the canonical point `(alpha, beta, h)` of `prism`, with its
    /// texture coordinates.
    #[must_use]
    #[inline]
    pub fn at(prism: &Prism<T>, t: T, alpha: T, beta: T, h: T) -> Self {
        let uv = prism.texture_uv(alpha, beta);
        Self {
            t,
            alpha,
            beta,
            h,
            u: nlrt_poly::Vector2::x(uv),
            v: nlrt_poly::Vector2::y(uv),
        }
    }
}

impl Hit<f64> {
    /// The hit of an `f64` trace, each value rounded to `T` (a distance in `[t_min, t_max]`
    /// of `T` stays there: rounding is monotonic and the ends are values of `T`).
    #[must_use]
    #[inline]
    pub fn narrowed<T: Real>(self) -> Hit<T> {
        let n = T::from_f64;
        Hit {
            t: n(self.t),
            alpha: n(self.alpha),
            beta: n(self.beta),
            h: n(self.h),
            u: n(self.u),
            v: n(self.v),
        }
    }
}

/// `(alpha, beta)` at height `h` from the two of Eq. 11's three linear equations whose 2x2
/// determinant is largest in magnitude: the two rows of Eq. 6 and the plane in canonical space
/// (Eq. 10). Eq. 6 alone fails where its determinant vanishes (e.g. `h_in = h_out`, Fig. 5).
#[must_use]
pub fn alpha_beta_eq11<T: Real>(ray: &NonlinearRay<T>, plane_abh: &[T; 4], h: T) -> Option<(T, T)> {
    let lin = |l: [T; 2]| l[1].mul_add(h, l[0]);
    let rows = [
        [
            lin(ray.rows[0][0]),
            lin(ray.rows[0][1]),
            lin(ray.rows[0][2]),
        ],
        [
            lin(ray.rows[1][0]),
            lin(ray.rows[1][1]),
            lin(ray.rows[1][2]),
        ],
        [
            plane_abh[0],
            plane_abh[1],
            -plane_abh[2].mul_add(h, plane_abh[3]),
        ],
    ];
    let det =
        |i: usize, j: usize| difference_of_products(rows[i][0], rows[j][1], rows[i][1], rows[j][0]);
    let candidates = [(0, 1, det(0, 1)), (0, 2, det(0, 2)), (1, 2, det(1, 2))];
    let (i, j, d) = candidates.into_iter().fold(candidates[0], |best, c| {
        if c.2.abs() > best.2.abs() { c } else { best }
    });
    if d == T::ZERO || !d.is_finite() {
        return None;
    }
    let alpha = difference_of_products(rows[i][2], rows[j][1], rows[i][1], rows[j][2]) / d;
    let beta = difference_of_products(rows[i][0], rows[j][2], rows[i][2], rows[j][0]) / d;
    Some((alpha, beta))
}

/// Whether `q` lies in the texture-space triangle `tri` (edges and vertices included),
/// judged in the 2D projection that drops the dominant axis of `normal`.
#[must_use]
pub fn inside_triangle<T: Real>(tri: &[T::Vec3; 3], normal: T::Vec3, q: T::Vec3) -> bool {
    let axis = normal.max_abs_axis();
    let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
    let edge = |a: T::Vec3, b: T::Vec3| {
        difference_of_products(
            b.get(i) - a.get(i),
            q.get(j) - a.get(j),
            b.get(j) - a.get(j),
            q.get(i) - a.get(i),
        )
    };
    let (w0, w1, w2) = (
        edge(tri[0], tri[1]),
        edge(tri[1], tri[2]),
        edge(tri[2], tri[0]),
    );
    (w0 >= T::ZERO && w1 >= T::ZERO && w2 >= T::ZERO)
        || (w0 <= T::ZERO && w1 <= T::ZERO && w2 <= T::ZERO)
}

/// The hit of the world ray on a flat microtriangle (all three vertices at height `h`), the
/// shortcut of sec. 5.4: at constant `h` the microtriangle lies in the prism's cross-section
/// `S_0(h) S_1(h) S_2(h)`, a flat world-space triangle, so a rectilinear ray-plane test and
/// barycentric coordinates replace the cubic. Inside-ness is still decided in texture space,
/// so a base triangle degenerate in uv is handled as in the general test. `None` when the ray
/// is parallel to the cross-section or the cross-section is degenerate.
#[must_use]
pub fn intersect_flat_microtriangle<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    tri: &[T::Vec3; 3],
    t_min: T,
    t_max: T,
) -> Option<Hit<T>> {
    let h = tri[0].z();
    let (t, alpha, beta) = prism.cross_section_hit(&ray.ray, h)?;
    if !(t >= t_min && t <= t_max) {
        return None;
    }
    let uv = prism.texture_uv(alpha, beta);
    let q = T::Vec3::new(nlrt_poly::Vector2::x(uv), nlrt_poly::Vector2::y(uv), h);
    let normal = T::Vec3::new(T::ZERO, T::ZERO, T::ONE); // the microtriangle's plane is h = const
    inside_triangle::<T>(tri, normal, q).then_some(Hit {
        t,
        alpha,
        beta,
        h,
        u: q.x(),
        v: q.y(),
    })
}

/// The hit of the world ray on a flat texel: the texture-space rectangle `[u0, u1] x [v0, v1]`
/// at constant height `h` (sec. 5.4: a texel whose min and max heights agree is tested as one
/// flat rectangle instead of two microtriangles). Same cross-section test as
/// [`intersect_flat_microtriangle`], with a rectangle for the inside test (edges included).
#[must_use]
pub fn intersect_flat_texel<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    lo: [T; 2],
    hi: [T; 2],
    h: T,
    t_min: T,
    t_max: T,
) -> Option<Hit<T>> {
    let (t, alpha, beta) = prism.cross_section_hit(&ray.ray, h)?;
    if !(t >= t_min && t <= t_max) {
        return None;
    }
    let uv = prism.texture_uv(alpha, beta);
    let (u, v) = (nlrt_poly::Vector2::x(uv), nlrt_poly::Vector2::y(uv));
    (u >= lo[0] && u <= hi[0] && v >= lo[1] && v <= hi[1]).then_some(Hit {
        t,
        alpha,
        beta,
        h,
        u,
        v,
    })
}

/// The nearest hit with `t` in `[t_min, t_max]` of a nonlinear ray on a texture-space
/// microtriangle `tri` (vertices `(u, v, h)`), with `h` restricted to `[h_lo, h_hi]` (the
/// ray's height range in the prism). Every root of the plane cubic in the range is tried:
/// along a curved ray the smallest `h` need not be the nearest hit. A flat microtriangle (all
/// vertices at one height) takes [`intersect_flat_microtriangle`].
#[must_use]
pub fn intersect_microtriangle<T: Real>(
    prism: &Prism<T>,
    ray: &NonlinearRay<T>,
    tri: &[T::Vec3; 3],
    h_lo: T,
    h_hi: T,
    t_min: T,
    t_max: T,
) -> Option<Hit<T>> {
    let h0 = tri[0].z();
    if tri[1].z() == h0 && tri[2].z() == h0 {
        if !(h0 >= h_lo && h0 <= h_hi) {
            return None;
        }
        return intersect_flat_microtriangle(prism, ray, tri, t_min, t_max);
    }
    let plane = TexturePlane::through(tri)?;
    let plane_abh = plane.canonical(prism);
    let mut best: Option<Hit<T>> = None;
    for &h in solve_cubic_in(plane.ray_cubic(ray), h_lo, h_hi).iter() {
        let Some((alpha, beta)) = alpha_beta_eq11(ray, &plane_abh, h) else {
            continue;
        };
        // Inside the prism's base triangle (edges included).
        if !(alpha >= T::ZERO && beta >= T::ZERO && alpha + beta <= T::ONE) {
            continue;
        }
        let uv = prism.texture_uv(alpha, beta);
        let q = T::Vec3::new(nlrt_poly::Vector2::x(uv), nlrt_poly::Vector2::y(uv), h);
        if !inside_triangle::<T>(tri, plane.normal, q) {
            continue;
        }
        let t = ray.signed_distance(prism, alpha, beta, h);
        if t >= t_min && t <= t_max && best.is_none_or(|b| t < b.t) {
            best = Some(Hit {
                t,
                alpha,
                beta,
                h,
                u: q.x(),
                v: q.y(),
            });
        }
    }
    best
}

/// The world-space normal at a hit (Eq. 13): the cofactor matrix of `M = (E0(h), E1(h), N_s)`
/// applied to the canonical plane normal `(n_alpha, n_beta, n_h)`, which is `M^-T n` up to the
/// positive-or-negative factor `det M` (so callers normalize and orient it). Defined even where
/// the prism is flat (`det M = 0`); zero where it degenerates to a line or point.
#[must_use]
pub fn world_normal<T: Real>(
    prism: &Prism<T>,
    plane_abh: &[T; 4],
    alpha: T,
    beta: T,
    h: T,
) -> T::Vec3 {
    let s0 = prism.vertex(0, h);
    let e0 = prism.vertex(1, h) - s0;
    let e1 = prism.vertex(2, h) - s0;
    let ns = prism.n[0] + (prism.n[1] - prism.n[0]) * alpha + (prism.n[2] - prism.n[0]) * beta;
    // M^-T has columns (E1 x Ns, Ns x E0, E0 x E1) / det M.
    e1.cross(ns) * plane_abh[0] + ns.cross(e0) * plane_abh[1] + e0.cross(e1) * plane_abh[2]
}

/// `n` (a world normal from Eq. 13, any length and sign) as a unit vector facing against the
/// ray direction `dir`; `None` where it is zero (the shell degenerates to a line or point).
#[must_use]
pub fn facing_unit<T: Real>(n: T::Vec3, dir: T::Vec3) -> Option<T::Vec3> {
    let len = n.length();
    if !(len > T::ZERO && len.is_finite()) {
        return None;
    }
    let n = n * (T::ONE / len);
    Some(if n.dot(dir) > T::ZERO { -n } else { n })
}
