//! World rays and their images in a prism: nonlinear rays (Ogaki 2023, sec. 4.1-4.2).

use crate::prism::Prism;
use nlrt_poly::{
    Real, Vector2, Vector3, difference_of_products, quadratic_range, solve_quadratic_in,
};

/// A world-space ray `o + t w` with unit direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray<T: Real> {
    /// Origin `o`.
    pub origin: T::Vec3,
    /// Unit direction `w`.
    pub dir: T::Vec3,
}

impl<T: Real> Ray<T> {
    /// A ray; the direction is normalized. `None` when the direction is zero or anything is
    /// not finite.
    #[must_use]
    pub fn new(origin: T::Vec3, dir: T::Vec3) -> Option<Self> {
        let len = dir.length();
        let finite = [origin.x(), origin.y(), origin.z()]
            .iter()
            .all(|v| v.is_finite());
        if !(len > T::ZERO && len.is_finite() && finite) {
            return None;
        }
        Some(Self {
            origin,
            dir: dir * (T::ONE / len),
        })
    }

    /// The point at parameter `t`.
    #[must_use]
    #[inline]
    pub fn at(&self, t: T) -> T::Vec3 {
        self.origin + self.dir * t
    }

    /// Two unit vectors perpendicular to the direction and to each other (Duff et al. 2017,
    /// "Building an Orthonormal Basis, Revisited": branch-free, no cancellation).
    #[must_use]
    pub fn perpendiculars(&self) -> [T::Vec3; 2] {
        let n = self.dir;
        let sign = T::ONE.copysign(n.z());
        let a = -T::ONE / (sign + n.z());
        let b = n.x() * n.y() * a;
        [
            T::Vec3::new(T::ONE + sign * n.x() * n.x() * a, sign * b, -sign * n.x()),
            T::Vec3::new(b, sign + n.y() * n.y() * a, -n.y()),
        ]
    }
}

/// Whether, at height `h`, the curve of `ray` in `prism` lies beyond doubt outside the base
/// triangle across edge `k` (as in [`BaseEdges::window`]), decided in `f64` from the same
/// inputs: for `f32` tracing, where a base-edge crossing's error window can reach far outside
/// the triangle (a ray nearly parallel to the prism's layers, `D(h)` tiny), so that `f32`
/// cannot tell on which side of the edge a root in the window lies. The `f32` inputs convert
/// exactly; the frame of Eq. 6 is two cross products of the direction with coordinate axes
/// (exact in `f64`, and exactly perpendicular to it, unlike a rounded orthonormal basis), so
/// the `f64` curve is that of the very same ray and prism, and [`BaseEdges::decidedly_outside`]
/// bounds its rounding. Always `false` for `f64` (no wider type here): callers keep every root.
#[must_use]
pub fn decidedly_outside_in_f64<T: Real>(prism: &Prism<T>, ray: &Ray<T>, k: usize, h: T) -> bool {
    if T::MANTISSA_DIGITS >= f64::MANTISSA_DIGITS || k > 2 {
        return false;
    }
    let (_, curve) = in_f64(prism, ray);
    BaseEdges::new(&curve).decidedly_outside(k, h.to_f64())
}

/// Whether a root `r` of `plane`'s cubic along the curve of `ray` in `prism`, found in `T` on
/// `[lo, hi]`, lies beyond doubt outside the base triangle across edge `k`: as
/// [`decidedly_outside_in_f64`], at the `f64` root of the same plane (its values widened
/// exactly) nearest `r` on `[lo, hi]`, or at `r` where `f64` finds none there. The `T` root
/// errs by its cubic's rounding, which carries it across the edge where the ray crosses the
/// surface on the edge itself: each of two `f32` prisms then found its root on the other's
/// side and left it to the other (an `f32` leak of the torus at 1M rays, roots about 20 ulps
/// from the `f64` ones; docs/watertightness.md). `false` for `f64`.
#[must_use]
pub fn root_decidedly_outside_in_f64<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    plane: &crate::TexturePlane<T>,
    k: usize,
    r: T,
    [lo, hi]: [T; 2],
) -> bool {
    if T::MANTISSA_DIGITS >= f64::MANTISSA_DIGITS || k > 2 {
        return false;
    }
    let (_, curve) = in_f64(prism, ray);
    let plane = plane_in_f64(plane);
    let r = r.to_f64();
    let h = nlrt_poly::solve_cubic_in(plane.ray_cubic(&curve), lo.to_f64(), hi.to_f64())
        .iter()
        .copied()
        .min_by(|a, b| (a - r).abs().total_cmp(&(b - r).abs()))
        .unwrap_or(r);
    BaseEdges::new(&curve).decidedly_outside(k, h)
}

/// `plane` widened to `f64` exactly (its normal and offset as they are in `T`).
fn plane_in_f64<T: Real>(plane: &crate::TexturePlane<T>) -> crate::TexturePlane<f64> {
    crate::TexturePlane::<f64> {
        normal: plane.normal.to_dvec3(),
        k: plane.k.to_f64(),
    }
}

/// Whether the cubics of two planes along the curve of `ray` in `prism` have the same sign
/// beyond doubt at height `h`, decided in `f64` on the same inputs (as
/// [`decidedly_outside_in_f64`]). For `f32` tracing, where the texel test compares the planes
/// on the two sides of a split point and `f32` cannot tell their signs apart: near a pole of
/// the curve (`D(h)` about a tenth of its coefficients, a coarse, strongly bent prism) the
/// cubics' values fall below their rounding bounds while the curve passes the shared edge
/// several thousandths of a unit of height above it, and reporting the split point gave a
/// ghost hit there (`docs/watertightness.md`, "Coarse prisms"). Always `false` for `f64`.
#[must_use]
pub fn planes_agree_in_f64<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    planes: [&crate::TexturePlane<T>; 2],
    h: T,
) -> bool {
    if T::MANTISSA_DIGITS >= f64::MANTISSA_DIGITS {
        return false;
    }
    let (_, curve) = in_f64(prism, ray);
    let [a, b] =
        planes.map(|p| nlrt_poly::decided_sign(&plane_in_f64(p).ray_cubic(&curve), h.to_f64()));
    a.is_some() && a == b
}

/// Whether `plane`'s cubic along the curve of `ray` in `prism` has, in `f64` on the same
/// inputs, no root on `[lo, hi]` and the same sign beyond doubt at both ends: the curve does
/// not cross the plane there, whatever `T`'s rounding found. For `f32` roots the texel test
/// cannot vouch for (its cubic's sign undecided at an end of the piece, or equal at both): the
/// ghost of [`planes_agree_in_f64`] was also a root at the split point. Always `false` for
/// `f64`.
#[must_use]
pub fn piece_clear_in_f64<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    plane: &crate::TexturePlane<T>,
    [lo, hi]: [T; 2],
) -> bool {
    if T::MANTISSA_DIGITS >= f64::MANTISSA_DIGITS {
        return false;
    }
    let (_, curve) = in_f64(prism, ray);
    let cubic = plane_in_f64(plane).ray_cubic(&curve);
    let (lo, hi) = (lo.to_f64(), hi.to_f64());
    let sign = nlrt_poly::decided_sign(&cubic, lo);
    sign.is_some()
        && sign == nlrt_poly::decided_sign(&cubic, hi)
        && nlrt_poly::solve_cubic_in(cubic, lo, hi).is_empty()
}

/// `prism` and `ray` in `f64` (each value converted exactly) and the nonlinear ray of the two
/// computed in `f64` in an exact frame: Eq. 6's two vectors perpendicular to the direction are
/// its cross products with the two coordinate axes other than its largest component's
/// (independent, and exact in `f64` for an `f32` direction: each component a product of two
/// of its components, or 0), unlike a rounded orthonormal basis. For `f32` inputs this is
/// the curve of the very same ray and prism, with about 29 more bits. A ray traced through
/// many prisms this way sets up its part once ([`WideRay`]).
#[must_use]
pub fn in_f64<T: Real>(prism: &Prism<T>, ray: &Ray<T>) -> (Prism<f64>, NonlinearRay<f64>) {
    WideRay::new(ray).in_prism(prism)
}

/// A ray in `f64` (its values converted exactly) with the exact frame of [`in_f64`], set up
/// once for the prisms it is traced through.
#[derive(Clone, Copy, Debug)]
pub struct WideRay {
    ray: Ray<f64>,
    frame: [nlrt_poly::glam::DVec3; 2],
}

impl WideRay {
    /// `ray` widened, and its frame.
    #[must_use]
    pub fn new<T: Real>(ray: &Ray<T>) -> Self {
        use nlrt_poly::glam::DVec3;
        let dir = ray.dir.to_dvec3();
        let largest = Vector3::max_abs_axis(dir);
        let axes = [DVec3::X, DVec3::Y, DVec3::Z];
        Self {
            ray: Ray::<f64> {
                origin: ray.origin.to_dvec3(),
                dir,
            },
            frame: [
                dir.cross(axes[(largest + 1) % 3]),
                dir.cross(axes[(largest + 2) % 3]),
            ],
        }
    }

    /// `prism` widened and the nonlinear ray in it, as [`in_f64`] gives them.
    #[must_use]
    pub fn in_prism<T: Real>(&self, prism: &Prism<T>) -> (Prism<f64>, NonlinearRay<f64>) {
        let prism = Prism::<f64>::new(
            prism.p.map(Vector3::to_dvec3),
            prism.n.map(Vector3::to_dvec3),
            prism.uv.map(Vector2::to_dvec2),
        );
        let curve = NonlinearRay::with_perpendiculars(&prism, &self.ray, self.frame);
        (prism, curve)
    }
}

/// A linear function `c0 + c1 h`.
type Linear<T> = [T; 2];

/// `f g - k l` for linear `f, g, k, l`: a quadratic whose coefficients are accurate differences
/// of products (the constant and quadratic ones directly, the middle one as two).
#[inline]
fn det_of_linears<T: Real>(f: Linear<T>, g: Linear<T>, k: Linear<T>, l: Linear<T>) -> [T; 3] {
    [
        difference_of_products(f[0], g[0], k[0], l[0]),
        difference_of_products(f[0], g[1], k[0], l[1])
            + difference_of_products(f[1], g[0], k[1], l[0]),
        difference_of_products(f[1], g[1], k[1], l[1]),
    ]
}

#[inline(always)]
fn quadratic_at<T: Real>(c: &[T; 3], h: T) -> T {
    c[2].mul_add(h, c[1]).mul_add(h, c[0])
}

/// The largest world coordinate (of a prism's positions and of its normals scaled by the
/// height scale) for which every coefficient of a [`NonlinearRay`] is finite in `T`, for
/// every ray whose line passes within the same distance of the prism's first vertex (every
/// ray that enters the prism's box): `2^46` in f32, `2^494` in f64. The surfaces refuse
/// meshes beyond it.
///
/// Eq. 6 sees the ray's origin only through its offset across the ray (the rows are dotted
/// with two unit vectors perpendicular to the direction), so a distant origin along the ray
/// costs nothing. With every such coordinate within `2^L` and texture coordinates within
/// `2^22` (`MAX_TEXEL_COORDINATE`), each entry of Eq. 6's rows is a dot product of a unit
/// vector with a difference of two coordinate vectors, at most `sqrt(3) 2^(L+1) < 2^(L+2)`;
/// each coefficient of the 2x2 determinants (`d`, `alpha`, `beta`) is at most two differences
/// of products, `2^(2L+6)`; `u` and `v` add the texture coordinates' spans, `2^(2L+6) (2^22 +
/// 2^24) < 2^(2L+31)`; and the walk's split-line quadratics `U - c D` (`|c| <= 2^22`)
/// evaluated at heights in `[-1, 1]` stay below `2^(2L+34)`. `2L + 34` below `T`'s largest
/// exponent, with a bit to spare for rounding, gives `L = (MAX_EXPONENT - 35) / 2`.
#[must_use]
pub fn max_world_coordinate<T: Real>() -> T {
    T::pow2((T::MAX_EXPONENT - 35) / 2)
}

/// A world ray seen in one prism: the curve `h -> (alpha(h), beta(h), h)` in canonical space
/// and `h -> (u(h), v(h), h)` in texture space, each coordinate a ratio of quadratics with the
/// common denominator `d(h)` (Eq. 7 and 8).
///
/// Built from Eq. 6 (the ray equation dotted with two unit vectors perpendicular to the ray),
/// by Cramer's rule, with every 2x2 determinant an accurate difference of products.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NonlinearRay<T: Real> {
    /// Numerator of `alpha(h)`, ascending powers.
    pub alpha: [T; 3],
    /// Numerator of `beta(h)`, ascending powers.
    pub beta: [T; 3],
    /// Common denominator `d(h)`, ascending powers.
    pub d: [T; 3],
    /// Numerator of `u(h)` (Eq. 8), ascending powers.
    pub u: [T; 3],
    /// Numerator of `v(h)` (Eq. 8), ascending powers.
    pub v: [T; 3],
    /// The two rows of Eq. 6: `(a(h), b(h), r(h))` with `a alpha + b beta = r`, each linear in `h`;
    /// kept for the best-conditioned solve of Eq. 11.
    pub rows: [[Linear<T>; 3]; 2],
    /// The world ray.
    pub ray: Ray<T>,
}

impl<T: Real> NonlinearRay<T> {
    /// The condition number of Eq. 6's 2x2 system at height `h`: `(|a e| + |b c|) / |a e - b
    /// c|` for the rows `a alpha + b beta = r`, `c alpha + e beta = s` (infinite where the
    /// determinant vanishes, NaN where the rows are not finite). The determinant is the
    /// curve's denominator `D(h)`; where it cancels (the ray nearly parallel to the prism's
    /// layer at `h`), every coefficient of the curve carries a relative error of about this
    /// number times the unit roundoff, which no bound on the later steps sees.
    #[must_use]
    pub fn condition(&self, h: T) -> T {
        let (magnitude, determinant) = self.eq6_terms(h);
        magnitude / determinant.abs()
    }

    /// Whether [`NonlinearRay::condition`] at `h` is at most `limit` (`false` where it is not
    /// a number or the determinant is 0), without its division.
    #[must_use]
    #[inline]
    pub fn condition_at_most(&self, h: T, limit: T) -> bool {
        let (magnitude, determinant) = self.eq6_terms(h);
        let determinant = determinant.abs();
        determinant > T::ZERO && magnitude <= limit * determinant
    }

    /// `(|a e| + |b c|, a e - b c)` of Eq. 6's rows at `h`.
    #[inline]
    fn eq6_terms(&self, h: T) -> (T, T) {
        let at = |l: Linear<T>| l[1].mul_add(h, l[0]);
        let ([a, b], [c, e]) = (
            [at(self.rows[0][0]), at(self.rows[0][1])],
            [at(self.rows[1][0]), at(self.rows[1][1])],
        );
        (
            (a * e).abs() + (b * c).abs(),
            difference_of_products(a, e, b, c),
        )
    }

    /// The nonlinear ray of `ray` in `prism`.
    #[must_use]
    pub fn new(prism: &Prism<T>, ray: &Ray<T>) -> Self {
        Self::with_perpendiculars(prism, ray, ray.perpendiculars())
    }

    /// The nonlinear ray of `ray` in `prism` from two given vectors perpendicular to the
    /// ray's direction (Eq. 6 dots the ray equation with them); any two independent ones give
    /// the same curve, since `alpha`, `beta`, `u` and `v` are ratios in which their frame
    /// cancels. For a frame exactly perpendicular to a direction whose rounding
    /// [`Ray::perpendiculars`] would perturb (e.g. cross products of `f32` vectors, exact in
    /// `f64`).
    #[must_use]
    pub fn with_perpendiculars(prism: &Prism<T>, ray: &Ray<T>, [e0, e1]: [T::Vec3; 2]) -> Self {
        let [(a0, a1), (b0, b1)] = prism.edges();
        let o0 = ray.origin - prism.p[0];
        let row = |e: T::Vec3| -> [Linear<T>; 3] {
            [
                [e.dot(a0), e.dot(a1)],
                [e.dot(b0), e.dot(b1)],
                [e.dot(o0), -e.dot(prism.n[0])],
            ]
        };
        let (r0, r1) = (row(e0), row(e1));
        let ([a, b, r], [c, e, s]) = (r0, r1);
        // Cramer: d = a e - b c, alpha d = r e - b s, beta d = a s - r c.
        let d = det_of_linears(a, e, b, c);
        let alpha = det_of_linears(r, e, b, s);
        let beta = det_of_linears(a, s, r, c);
        let [t0, t1, t2] = prism.uv;
        let (du1, du2) = (t1.x() - t0.x(), t2.x() - t0.x());
        let (dv1, dv2) = (t1.y() - t0.y(), t2.y() - t0.y());
        let u =
            core::array::from_fn(|i| d[i].mul_add(t0.x(), alpha[i].mul_add(du1, beta[i] * du2)));
        let v =
            core::array::from_fn(|i| d[i].mul_add(t0.y(), alpha[i].mul_add(dv1, beta[i] * dv2)));
        Self {
            alpha,
            beta,
            d,
            u,
            v,
            rows: [r0, r1],
            ray: *ray,
        }
    }

    /// Whether every coefficient is finite: always, for prisms within
    /// [`max_world_coordinate`] and rays whose line passes within it of them; beyond it the
    /// curve cannot be followed in `T`.
    #[must_use]
    #[inline]
    pub fn is_finite(&self) -> bool {
        let quadratics = [self.alpha, self.beta, self.d, self.u, self.v];
        let rows = self.rows.iter().flatten().flatten();
        // Non-short-circuit: a fixed number of compares, no branch per value.
        quadratics
            .iter()
            .flatten()
            .chain(rows)
            .fold(true, |ok, v| ok & v.is_finite())
    }

    /// Canonical `(alpha, beta)` at height `h` by Eq. 7; `None` where the denominator is 0
    /// (the ray is parallel to the prism's cross-section there, or that is degenerate).
    #[must_use]
    #[inline]
    pub fn alpha_beta(&self, h: T) -> Option<(T, T)> {
        let d = quadratic_at(&self.d, h);
        (d != T::ZERO).then(|| {
            (
                quadratic_at(&self.alpha, h) / d,
                quadratic_at(&self.beta, h) / d,
            )
        })
    }

    /// Texture `(u, v)` at height `h` by Eq. 8; `None` where the denominator is 0.
    #[must_use]
    #[inline]
    pub fn uv(&self, h: T) -> Option<(T, T)> {
        let d = quadratic_at(&self.d, h);
        (d != T::ZERO).then(|| (quadratic_at(&self.u, h) / d, quadratic_at(&self.v, h) / d))
    }

    /// The signed distance along the world ray to the shell point `S(alpha, beta, h)`
    /// (sec. 4.3: Eq. 5 dotted with the unit direction).
    #[must_use]
    #[inline]
    pub fn signed_distance(&self, prism: &Prism<T>, alpha: T, beta: T, h: T) -> T {
        self.ray
            .dir
            .dot(prism.shell_point(alpha, beta, h) - self.ray.origin)
    }
}

/// The base triangle's edges seen along a nonlinear ray: `alpha(h) = 0`, `beta(h) = 0` and
/// `alpha(h) + beta(h) = 1`, times the denominator (the quadratics `A`, `B` and `A + B - D`),
/// with bounds on where their computed crossings may lie. Where a ray leaves one prism and
/// enters its neighbour, both compute the crossing of the shared edge with their own
/// rounding; the window of [`BaseEdges::window`] around a crossing holds both, so searches
/// extended by it overlap and leave no gap between prisms.
#[derive(Clone, Copy, Debug)]
pub struct BaseEdges<T: Real> {
    /// `A`, `B` and `A + B - D`, ascending powers.
    pub edges: [[T; 3]; 3],
    /// The denominator `D`.
    d: [T; 3],
    /// `gamma(32) row_max^2`: see [`BaseEdges::window`].
    error_scale: T,
}

impl<T: Real> BaseEdges<T> {
    /// The edges of `ray`'s prism.
    #[must_use]
    pub fn new(ray: &NonlinearRay<T>) -> Self {
        let sum: [T; 3] = core::array::from_fn(|i| ray.alpha[i] + ray.beta[i] - ray.d[i]);
        let row_max = ray
            .rows
            .iter()
            .flatten()
            .flatten()
            .fold(T::ZERO, |m, &x| m.max(x.abs()));
        let g32 =
            T::from_i32(32) * T::UNIT_ROUNDOFF / (T::ONE - T::from_i32(32) * T::UNIT_ROUNDOFF);
        Self {
            edges: [ray.alpha, ray.beta, sum],
            d: ray.d,
            error_scale: g32 * row_max * row_max,
        }
    }

    /// Half-width of a window around `s`, a computed crossing of edge `k` (0: `alpha = 0`,
    /// 1: `beta = 0`, 2: `alpha + beta = 1`), that holds the exact crossing: each coefficient
    /// of the edge's quadratic is a difference of products of Eq. 6's rows (entries at most
    /// `row_max`) and errs by less than `gamma(32) row_max^2` (a generous count of
    /// roundings); divided by the slope at `s`, that bounds how far the root moves. Infinite
    /// where the slope is 0.
    #[must_use]
    #[inline]
    pub fn window(&self, k: usize, s: T) -> T {
        let q = &self.edges[k];
        let slope = (T::TWO * q[2]).mul_add(s, q[1]).abs();
        let a = s.abs();
        let err = self.error_scale * (T::ONE + a + a * a);
        if slope > T::ZERO {
            err / slope
        } else {
            T::INFINITY
        }
    }

    /// Whether the curve at height `h` is inside the base triangle (edges included): each
    /// edge function (times `D`) has the sign of `D`, the third reversed. `false` where `D` is
    /// 0.
    #[must_use]
    #[inline]
    pub fn contains(&self, h: T) -> bool {
        let d = quadratic_at(&self.d, h);
        if d == T::ZERO {
            return false;
        }
        let positive = d > T::ZERO;
        let same = |x: T| x == T::ZERO || (x > T::ZERO) == positive;
        same(quadratic_at(&self.edges[0], h))
            && same(quadratic_at(&self.edges[1], h))
            && same(-quadratic_at(&self.edges[2], h))
    }

    /// Whether the curve at height `h` is outside the base triangle across edge `k` (as in
    /// [`BaseEdges::window`]) beyond the rounding of this computation: the edge's function and
    /// the denominator both away from 0 by more than the bound on their coefficients'
    /// rounding (the margin of [`BaseEdges::misses`]), with the signs of outside. `false`
    /// where either is within that bound, or `h` is not finite.
    #[must_use]
    #[inline]
    pub fn decidedly_outside(&self, k: usize, h: T) -> bool {
        let a = h.abs();
        let margin = self.error_scale * (T::ONE + a + a * a);
        let d = quadratic_at(&self.d, h);
        let e = quadratic_at(&self.edges[k], h);
        if !(d.abs() > margin && e.abs() > margin) {
            return false;
        }
        // Inside needs sign(D) * A >= 0, sign(D) * B >= 0 and sign(D) * (A + B - D) <= 0.
        let e = if k == 2 { -e } else { e };
        (e > T::ZERO) != (d > T::ZERO)
    }

    /// Whether the curve is outside the triangle at every height of `[h_lo, h_hi]`, decided
    /// cheaply: the denominator keeps one sign and one edge function the other, by their
    /// ranges (ends and vertex of each quadratic) with the coefficient error bound of
    /// [`BaseEdges::window`] as margin, so the exact functions have those signs too and no
    /// crossing or window is lost. Most prisms whose box a ray enters but which it misses
    /// (overlapping boxes of thick shells) are rejected here without solving a quadratic.
    #[must_use]
    #[inline]
    pub fn misses(&self, h_lo: T, h_hi: T) -> bool {
        let a = h_lo.abs().max(h_hi.abs());
        let margin = self.error_scale * (T::ONE + a + a * a);
        let range = |c: &[T; 3]| {
            let (lo, hi) = quadratic_range(c, h_lo, h_hi);
            (lo - margin, hi + margin)
        };
        let (d_lo, d_hi) = range(&self.d);
        let sign = if d_lo > T::ZERO {
            T::ONE
        } else if d_hi < T::ZERO {
            -T::ONE
        } else {
            return false;
        };
        // Inside needs sign * A >= 0, sign * B >= 0 and sign * (A + B - D) <= 0.
        (0..3).any(|k| {
            let (lo, hi) = range(&self.edges[k]);
            let (lo, hi) = if sign > T::ZERO { (lo, hi) } else { (-hi, -lo) };
            if k < 2 { hi < T::ZERO } else { lo > T::ZERO }
        })
    }

    /// Whether the quadratic `c` (an edge's or the denominator's, whose coefficients err by
    /// less than the bound of [`BaseEdges::window`]) may vanish at a height in `[a, b]`: false
    /// only where its range there stays away from 0 by more than that bound, which also
    /// exceeds the evaluation bound by which a solver on `[a, b]` would report an end as a
    /// root, so such a solve would find nothing (or only a root that rounding moved in from
    /// outside, where no sign change is).
    #[inline]
    fn may_vanish(&self, c: &[T; 3], a: T, b: T) -> bool {
        let x = a.abs().max(b.abs());
        let margin = self.error_scale * (T::ONE + x + x * x);
        let (lo, hi) = quadratic_range(c, a, b);
        !(lo > margin || hi < -margin)
    }

    /// Whether the curve may cross base edge `k` (as in [`BaseEdges::window`]) at a height in
    /// `[a, b]`: false only where the edge's quadratic keeps one sign there by more than the
    /// bound on its coefficients' rounding (which exceeds the evaluation bound by which a
    /// solver on `[a, b]` would report an end as a root), so no root needs solving for.
    #[must_use]
    #[inline]
    pub fn may_cross(&self, k: usize, a: T, b: T) -> bool {
        self.may_vanish(&self.edges[k], a, b)
    }

    /// Whether the denominator `D` may vanish (a pole of the curve: the ray parallel to the
    /// prism's cross-section) at a height in `[a, b]`, decided as [`BaseEdges::may_cross`].
    #[must_use]
    #[inline]
    pub fn may_have_pole(&self, a: T, b: T) -> bool {
        self.may_vanish(&self.d, a, b)
    }

    /// Calls `stretch(h_in, h_out)` for each interval of heights in `[h_lo, h_hi]` where the
    /// curve is inside the base triangle, i.e. the ray inside the prism cut to those heights;
    /// an end on an edge is widened by that crossing's [`BaseEdges::window`] (kept within
    /// `[h_lo, h_hi]`). Between consecutive crossings and poles inside-ness cannot change, so
    /// each piece is decided at its midpoint; a curve that only touches the triangle gives
    /// `h_in == h_out`.
    ///
    /// A crossing a rounding beyond `h_lo` or `h_hi` counts too when its window reaches into
    /// the range (a ray through a prism wall exactly at the lowest height asked for, such as an
    /// object's flat floor: without it the neighbour prisms could both leave the point out).
    /// Where an edge is within its coefficients' rounding bound of 0 at an end, the search for
    /// its crossings and the pieces extend twice its window there beyond that end (twice: the
    /// window of a crossing just beyond is the end's own up to the change of the slope between
    /// them), and the stretches are cut back to `[h_lo, h_hi]`.
    pub fn stretches(&self, h_lo: T, h_hi: T, mut stretch: impl FnMut(T, T)) {
        if !(h_lo <= h_hi) || self.misses(h_lo, h_hi) {
            return;
        }
        let (lo, hi) = (self.beyond(h_lo, -T::ONE), self.beyond(h_hi, T::ONE));
        // (height, window) of each candidate: the ends, the edge crossings, the poles.
        let mut cuts = [(T::ZERO, T::ZERO); 10];
        cuts[0] = (lo, T::ZERO);
        cuts[1] = (hi, T::ZERO);
        let mut n = 2;
        // Edges (and a pole) the curve cannot reach on [lo, hi] have no root to solve for.
        for k in 0..3 {
            if !self.may_cross(k, lo, hi) {
                continue;
            }
            for &r in solve_quadratic_in(self.edges[k], lo, hi).iter() {
                cuts[n] = (r, self.window(k, r));
                n += 1;
            }
        }
        if self.may_have_pole(lo, hi) {
            for &r in solve_quadratic_in(self.d, lo, hi).iter() {
                cuts[n] = (r, T::ZERO);
                n += 1;
            }
        }
        let cuts = &mut cuts[..n];
        cuts.sort_unstable_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(core::cmp::Ordering::Equal));
        let mut emit = |from: T, to: T| {
            let (from, to) = (from.max(h_lo), to.min(h_hi));
            if from <= to {
                stretch(from, to);
            }
        };
        let mut open: Option<T> = None;
        for i in 0..n - 1 {
            let ((c0, w0), (c1, _)) = (cuts[i], cuts[i + 1]);
            let inside = if c1 > c0 {
                self.contains((c0 + c1) * T::HALF)
            } else {
                continue;
            };
            match (inside, open) {
                (true, None) => open = Some(c0 - w0),
                (false, Some(from)) => {
                    let (to, w) = cuts[i];
                    emit(from, to + w);
                    open = None;
                }
                _ => {}
            }
        }
        if let Some(from) = open {
            let (to, w) = cuts[n - 1];
            emit(from, to + w);
        } else if lo == hi && self.contains(lo) {
            emit(lo, hi);
        }
    }

    /// `end` moved `side` (-1 or 1) by twice the largest window of an edge within its
    /// coefficients' rounding bound of 0 there (see [`BaseEdges::stretches`]); `end` itself
    /// where none is. At most `1 + |end|` (a window wider than the prism's heights already
    /// spans them; it is infinite where the edge is tangent).
    #[inline]
    fn beyond(&self, end: T, side: T) -> T {
        let a = end.abs();
        let margin = self.error_scale * (T::ONE + a + a * a);
        let mut reach = T::ZERO;
        for k in 0..3 {
            if quadratic_at(&self.edges[k], end).abs() <= margin {
                reach = reach.max(T::TWO * self.window(k, end));
            }
        }
        end + side * reach.min(T::ONE + a)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Prisms and origins with every coordinate at `+-max_world_coordinate` (random signs,
    /// the worst case of the bound's derivation), texture coordinates at `+-2^22`, random
    /// directions: every coefficient of the nonlinear ray is finite, and so are the split-line
    /// quadratics `U - c D` the walk evaluates, at heights in `[-1, 1]`.
    fn coefficients_stay_finite_at_the_limit<T: Real>() {
        let limit = max_world_coordinate::<T>();
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let mut signed = |scale: T| if next() & 1 == 0 { scale } else { -scale };
        let uv_limit = T::pow2(22);
        for _ in 0..2000 {
            let mut corner = || T::Vec3::new(signed(limit), signed(limit), signed(limit));
            let (p, n) = (
                [corner(), corner(), corner()],
                [corner(), corner(), corner()],
            );
            let origin = corner();
            let uv = [(); 3].map(|()| T::Vec2::new(signed(uv_limit), signed(uv_limit)));
            let dir = T::Vec3::new(signed(T::ONE), signed(T::HALF), signed(T::from_f64(0.3)));
            let Some(ray) = Ray::new(origin, dir) else {
                panic!("a unit direction");
            };
            let nl = NonlinearRay::new(&Prism::new(p, n, uv), &ray);
            assert!(nl.is_finite(), "{nl:?}");
            for h in [-T::ONE, T::ZERO, T::ONE] {
                for c in [-uv_limit, uv_limit] {
                    let line = quadratic_at(&nl.u, h) - c * quadratic_at(&nl.d, h);
                    assert!(line.is_finite(), "{nl:?} at h = {h:?}, line {c:?}");
                }
            }
        }
    }

    #[test]
    fn coefficients_stay_finite_at_the_limit_f32() {
        coefficients_stay_finite_at_the_limit::<f32>();
    }

    #[test]
    fn coefficients_stay_finite_at_the_limit_f64() {
        coefficients_stay_finite_at_the_limit::<f64>();
    }
}
