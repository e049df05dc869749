//! World-space bounds of the shell object's boxes: the hull of a box's 8 mapped corners,
//! tested against the straight world ray by slab tests in the prism's own frame.
//!
//! Inside one prism the shell map (Eq. 1 with Eq. 2-3 inverted) is
//! `X(u, v, h) = P(u, v) + h N(u, v)` with `P` and `N` affine in `(u, v)`: the map is affine
//! in `(u, v)` and in `h` separately, with no `u v` term, so it is multilinear on any box
//! `[u0, u1] x [v0, v1] x [h0, h1]`, and a multilinear map sends a box into the convex hull
//! of its corners' images (each point of the box is a convex combination of the corners with
//! product weights, and the map carries the combination over). A ray that misses the hull's
//! bounding box misses every object triangle inside the box. The bound is the same for every
//! ray, and the test is a straight slab test in world space, where the box test it replaces
//! (`TextureCurve::box_span_in`) clips the ray's curve in texture space (three divisions and
//! quadratics per box).
//!
//! The boxes are taken in the prism's frame (the base triangle's unit normal, the direction
//! of increasing `u` in the base plane, their cross product), in which a tile's boxes lie
//! along the axes even where the base triangle is tilted: world-axis boxes of the same
//! corners are loose there (on `highpoly`, 2.2x the box tests). Any linear frame is exact
//! for the test (the ray and the corners go through the same matrix as computed, and a
//! slab test is exact about a line and a box in any coordinates); it only has to be near
//! orthonormal to be tight.
//!
//! The box's `(u, v)` is clipped to the base triangle's uv box (a hit lies in the
//! triangle), so that a tile much larger than a base triangle does not map its far corners
//! through the affine extension of `P` and `N`.
//!
//! # Padding
//! The walk's hits are those of the ray's curve (Eq. 6-8, computed from the world ray with
//! rounding) on the object's triangles, and the exact box test it replaces was conservative
//! about that curve, not about the exact ray. Each padded bound therefore holds every point
//! the object test can report:
//! - the curve's coefficients are Cramer ratios of Eq. 6's rows, each an accurate
//!   difference of products, and its evaluation at a height errs by a few roundings of its
//!   terms; all of it is the exact curve of rows perturbed by a few unit roundoffs relative
//!   to their terms (`e . (P_i - P_0)`, `e . N_i`, `e . (o - P_0)`), so a reported point
//!   lies within `c u S` of the exact ray, where `S` bounds `|X - P_0|` over the prism's
//!   part of the tile plus `|o - P_0|` (1-norms), with `c` about 20;
//! - the map's coefficients here (`(P_1 - P_0) dv_2 - (P_2 - P_0) dv_1` over the uv
//!   determinant, and alike) err by a few roundings of their terms' magnitudes, which `S`
//!   takes (so a sliver uv triangle, whose determinant cancels, pads by its magnitudes);
//! - the rotation into the frame, the corners' evaluation (three fused multiply-adds per
//!   coordinate) and the ray's origin and direction in the frame (`o - P_0` and a direction
//!   error times the distance) err by a few roundings of `S`;
//! - the object test's reach across a shared edge (`crate::object_edges`: a point within the
//!   first-order bound of its error from an edge is decided by the piece search, which reports
//!   hits on the edge) is within the same error of the triangle, so within the padded box of
//!   either triangle of the edge.
//!
//! These add to less than `64 u S`; the padding is [`PAD_ROUNDINGS`] `u S`, 16x more, so that
//! no term missed in this count matters, at no cost in culling (a few `1e-13` of the prism's
//! size in `f64`). The slab test then pads its own distances ([`SlabRay::entry`]). A test
//! (`the_hull_enters_every_box_the_curve_enters`) checks on grazing, pole-crossing and
//! sliver prisms that no box the exact curve test enters is rejected.

use nlrt_poly::{LaneMask, Lanes4, Real, Vector2, Vector3, difference_of_products};
use nlrt_shellmap::{Prism, Ray};

use crate::bvh::{ARITY, Node4, SlabRay};

/// The padding of a hull box, in unit roundoffs of the prism's magnitude `S` (see the module
/// docs): 16 times the at most 64 roundings counted there.
const PAD_ROUNDINGS: f64 = 1024.0;

/// One prism's shell map in its own frame, with the ray in that frame, for the hull test of
/// the object's boxes (set up once per prism and ray).
#[derive(Clone, Copy, Debug)]
pub(crate) struct PrismHull<C: Real> {
    /// `P(u, v) - P_0 = pu (u - u_0) + pv (v - v_0)`, by frame axis.
    pu: [C; 3],
    pv: [C; 3],
    /// `N(u, v) = n0 + nu (u - u_0) + nv (v - v_0)`, by frame axis.
    n0: [C; 3],
    nu: [C; 3],
    nv: [C; 3],
    /// The base triangle's texture coordinates `(u_0, v_0)`.
    uv0: [C; 2],
    /// The base triangle's uv box `[u_lo, v_lo]`, `[u_hi, v_hi]`.
    uv_lo: [C; 2],
    uv_hi: [C; 2],
    /// The ray in the frame, relative to `P_0`.
    ray: SlabRay<C>,
    /// The padding of every box (see the module docs).
    pad: C,
}

/// `|a|` componentwise, summed.
fn norm1<C: Real>(v: C::Vec3) -> C {
    v.x().abs() + v.y().abs() + v.z().abs()
}

impl<C: Real> PrismHull<C> {
    /// The hull test of `prism` for `ray`, with object heights in `[0, h_max]`. `None` where
    /// the base triangle is degenerate in uv or in world space (no frame or no map): the
    /// caller keeps the curve's box test there.
    pub(crate) fn new(prism: &Prism<C>, ray: &Ray<C>, h_max: C) -> Option<Self> {
        let [uv0, uv1, uv2] = prism.uv;
        let (du1, du2) = (uv1.x() - uv0.x(), uv2.x() - uv0.x());
        let (dv1, dv2) = (uv1.y() - uv0.y(), uv2.y() - uv0.y());
        let det = difference_of_products(du1, dv2, du2, dv1);
        let e0 = prism.p[1] - prism.p[0];
        let e1 = prism.p[2] - prism.p[0];
        let (m0, m1) = (prism.n[1] - prism.n[0], prism.n[2] - prism.n[0]);
        let normal = e0.cross(e1);
        let normal_len = normal.length();
        if !(det != C::ZERO && det.is_finite() && normal_len > C::ZERO && normal_len.is_finite()) {
            return None;
        }
        let inv = C::ONE / det;
        // d(alpha, beta)/du = (dv2, -dv1) / det, d(alpha, beta)/dv = (-du2, du1) / det.
        let pu_w = (e0 * dv2 - e1 * dv1) * inv;
        let pv_w = (e1 * du1 - e0 * du2) * inv;
        let nu_w = (m0 * dv2 - m1 * dv1) * inv;
        let nv_w = (m1 * du1 - m0 * du2) * inv;
        // The frame: the base normal, the direction of increasing u in the base plane, and
        // their cross product.
        let n_hat = normal * (C::ONE / normal_len);
        let along = pu_w - n_hat * n_hat.dot(pu_w);
        let along_len = along.length();
        if !(along_len > C::ZERO && along_len.is_finite()) {
            return None;
        }
        let t_hat = along * (C::ONE / along_len);
        let b_hat = n_hat.cross(t_hat);
        let frame = [t_hat, b_hat, n_hat];
        let rotate = |v: C::Vec3| -> [C; 3] { core::array::from_fn(|a| frame[a].dot(v)) };
        let origin = ray.origin - prism.p[0];
        let (o, d) = (rotate(origin), rotate(ray.dir));
        let uv_lo = [
            uv0.x().min(uv1.x()).min(uv2.x()),
            uv0.y().min(uv1.y()).min(uv2.y()),
        ];
        let uv_hi = [
            uv0.x().max(uv1.x()).max(uv2.x()),
            uv0.y().max(uv1.y()).max(uv2.y()),
        ];
        // S: the magnitudes of every term, over the triangle's uv box and the heights
        // (module docs, "Padding").
        let (ru, rv) = (
            (uv_lo[0] - uv0.x()).abs().max((uv_hi[0] - uv0.x()).abs()),
            (uv_lo[1] - uv0.y()).abs().max((uv_hi[1] - uv0.y()).abs()),
        );
        let inv_abs = inv.abs();
        let mag = |a: C::Vec3, sa: C, b: C::Vec3, sb: C| {
            (norm1::<C>(a) * sa.abs() + norm1::<C>(b) * sb.abs()) * inv_abs
        };
        let extent = mag(e0, dv2, e1, dv1) * ru
            + mag(e1, du1, e0, du2) * rv
            + h_max.abs()
                * (norm1::<C>(prism.n[0])
                    + mag(m0, dv2, m1, dv1) * ru
                    + mag(m1, du1, m0, du2) * rv);
        let scale = norm1::<C>(origin) + extent;
        let pad = C::from_f64(PAD_ROUNDINGS) * C::UNIT_ROUNDOFF * scale;
        if !pad.is_finite() {
            return None;
        }
        Some(Self {
            pu: rotate(pu_w),
            pv: rotate(pv_w),
            n0: rotate(prism.n[0]),
            nu: rotate(nu_w),
            nv: rotate(nv_w),
            uv0: [uv0.x(), uv0.y()],
            uv_lo,
            uv_hi,
            ray: SlabRay::new(
                C::Vec3::new(o[0], o[1], o[2]),
                C::Vec3::new(d[0], d[1], d[2]),
            ),
            pad,
        })
    }

    /// The entry distances into the hull boxes of four texture-space boxes (`lo`, `hi` by
    /// axis and child, `(u, v, h)` as the object is placed in its tile), each clipped to the
    /// base triangle's uv box, and as bit `c` of the mask whether box `c` is entered within
    /// `[t_min, t_max]`. Only the slots of `slots` are tested (an empty or unused box is
    /// never entered).
    pub(crate) fn entries(
        &self,
        lo: [[C; ARITY]; 3],
        hi: [[C; ARITY]; 3],
        slots: u8,
        t_min: C,
        t_max: C,
    ) -> ([C; ARITY], u8) {
        self.entries_in::<C::Four>(lo, hi, slots, t_min, t_max)
    }

    #[inline(always)]
    fn entries_in<L: Lanes4<C>>(
        &self,
        lo: [[C; ARITY]; 3],
        hi: [[C; ARITY]; 3],
        slots: u8,
        t_min: C,
        t_max: C,
    ) -> ([C; ARITY], u8) {
        // The boxes' uv clipped to the triangle's, relative to its vertex 0.
        let clip = |a: usize| {
            let (clip_lo, clip_hi, at) = (
                L::splat(self.uv_lo[a]),
                L::splat(self.uv_hi[a]),
                L::splat(self.uv0[a]),
            );
            let l = L::from_array(lo[a]).greater(clip_lo);
            let h = L::from_array(hi[a]).lesser(clip_hi);
            (l.le(h), l - at, h - at)
        };
        let (u_ok, u0, u1) = clip(0);
        let (v_ok, v0, v1) = clip(1);
        let (h0, h1) = (L::from_array(lo[2]), L::from_array(hi[2]));
        let live = slots & (u_ok & v_ok).bits() & h0.le(h1).bits();
        let mut node = Node4::<C> {
            lo: [[C::ZERO; ARITY]; 3],
            hi: [[C::ZERO; ARITY]; 3],
            index: [0; ARITY],
            count: [0; ARITY],
        };
        let pad = L::splat(self.pad);
        for a in 0..3 {
            let (pu, pv) = (L::splat(self.pu[a]), L::splat(self.pv[a]));
            let (n0, nu, nv) = (
                L::splat(self.n0[a]),
                L::splat(self.nu[a]),
                L::splat(self.nv[a]),
            );
            let mut low = L::splat(C::INFINITY);
            let mut high = L::splat(C::NEG_INFINITY);
            for u in [u0, u1] {
                for v in [v0, v1] {
                    let p = pu.mul_add(u, pv * v);
                    let n = nu.mul_add(u, nv.mul_add(v, n0));
                    for h in [h0, h1] {
                        let x = n.mul_add(h, p);
                        low = low.lesser(x);
                        high = high.greater(x);
                    }
                }
            }
            node.lo[a] = (low - pad).to_array();
            node.hi[a] = (high + pad).to_array();
        }
        let (t, met) = self.ray.entries(&node, t_min, t_max);
        (t, met & live)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use nlrt_poly::lanes4::Portable4;
    use nlrt_shellmap::{NonlinearRay, TextureCurve};

    /// Which prisms a case draws.
    #[derive(Clone, Copy, Debug)]
    enum Family {
        /// Near the unit right triangle, normals sheared.
        Sheared,
        /// Rotated, far from the origin, a uv triangle much smaller than its tile.
        FarAndSmall,
        /// A sliver in uv (its third uv vertex nearly on the line of the other two).
        UvSliver,
    }

    /// The vector step (`Real::Four`) gives the portable lanes' decisions and entry bits. Every
    /// box the curve's exact box test enters (`TextureCurve::box_pieces`, the test the
    /// hull replaces), clipped to the triangle's uv box as the hull clips it, is entered by
    /// the hull test, no later: on sheared, far and sliver prisms, with rays aimed at points
    /// inside the prism (some grazing its layers, whose curves have poles) and boxes from a
    /// whole tile down to 1e-6. The hull must also reject a share of the boxes the curve
    /// misses (a hull that entered everything would pass the first check).
    fn hull_holds_the_curve<C: Real>() {
        let mut r = crate::test_util::unit_randoms(0x4855_4c4c);
        let mut s = move || r() * 2.0 - 1.0;
        let v =
            |x: f64, y: f64, z: f64| C::Vec3::new(C::from_f64(x), C::from_f64(y), C::from_f64(z));
        let (mut entered, mut missed, mut rejected, mut poles, mut points) =
            (0usize, 0usize, 0usize, 0usize, 0usize);
        let ill_conditioned = C::ONE / (C::from_f64(1024.0) * C::UNIT_ROUNDOFF);
        for case in 0..6_000 {
            let family = [Family::Sheared, Family::FarAndSmall, Family::UvSliver][case % 3];
            let mut p = [
                [0.1 * s(), 0.1 * s(), 0.1 * s()],
                [1.0 + 0.1 * s(), 0.1 * s(), 0.1 * s()],
                [0.1 * s(), 1.0 + 0.1 * s(), 0.1 * s()],
            ];
            let mut n = [[0.0; 3]; 3].map(|_| [0.5 * s(), 0.5 * s(), 0.3 + 0.2 * s()]);
            let (mut uv, shift) = ([[3.0, 5.0], [4.0, 5.0], [3.0, 6.0]], [100.0, -40.0, 7.0]);
            for t in &mut uv {
                t[0] += 0.2 * s();
                t[1] += 0.2 * s();
            }
            match family {
                Family::Sheared => {}
                Family::FarAndSmall => {
                    // A rotation about the axis (1, 1, 1) by a random angle, then a shift.
                    let a = s() * 3.0;
                    let (c, sn) = (a.cos(), a.sin());
                    let k = (1.0 - c) / 3.0;
                    let q = 1.0 / 3f64.sqrt();
                    let rot = [
                        [c + k, k - q * sn, k + q * sn],
                        [k + q * sn, c + k, k - q * sn],
                        [k - q * sn, k + q * sn, c + k],
                    ];
                    let turn = |x: [f64; 3]| {
                        core::array::from_fn::<f64, 3, _>(|i| {
                            rot[i][0] * x[0] + rot[i][1] * x[1] + rot[i][2] * x[2]
                        })
                    };
                    p = p.map(|x| {
                        let y = turn(x);
                        [y[0] + shift[0], y[1] + shift[1], y[2] + shift[2]]
                    });
                    n = n.map(turn);
                    for t in &mut uv {
                        t[0] = 3.4 + (t[0] - 3.0) * 0.05;
                        t[1] = 5.4 + (t[1] - 5.0) * 0.05;
                    }
                }
                Family::UvSliver => {
                    let eps = 10f64.powf(-3.0 - 3.0 * (s() + 1.0));
                    uv[2] = [
                        uv[0][0] + 0.5 * (uv[1][0] - uv[0][0]),
                        uv[0][1] + 0.5 * (uv[1][1] - uv[0][1]) + eps,
                    ];
                }
            }
            let prism = Prism::<C>::new(
                p.map(|x| v(x[0], x[1], x[2])),
                n.map(|x| v(x[0], x[1], x[2])),
                uv.map(|t| C::Vec2::new(C::from_f64(t[0]), C::from_f64(t[1]))),
            );
            // Aimed at a point of the prism, from up to 3 units away; a third nearly in the
            // base plane.
            let (a, b, h) = ((s() + 1.0) / 2.0, (s() + 1.0) / 2.0, (s() + 1.0) / 2.0);
            let (a, b) = if a + b > 1.0 {
                (1.0 - a, 1.0 - b)
            } else {
                (a, b)
            };
            let target = prism.shell_point(C::from_f64(a), C::from_f64(b), C::from_f64(h));
            let at = |i: usize, a: f64, b: f64| {
                uv[0][i] + (uv[1][i] - uv[0][i]) * a + (uv[2][i] - uv[0][i]) * b
            };
            let aim = [at(0, a, b), at(1, a, b), h];
            // (alpha, beta) of a texture point, by Cramer's rule in f64 on the prism's uvs.
            let uv = prism.uv.map(|t| [t.x().to_f64(), t.y().to_f64()]);
            let barycentric = |u: f64, w: f64| {
                let (du1, du2) = (uv[1][0] - uv[0][0], uv[2][0] - uv[0][0]);
                let (dv1, dv2) = (uv[1][1] - uv[0][1], uv[2][1] - uv[0][1]);
                let det = du1 * dv2 - du2 * dv1;
                let (x, y) = (u - uv[0][0], w - uv[0][1]);
                ((x * dv2 - y * du2) / det, (du1 * y - dv1 * x) / det)
            };
            let normal = (prism.p[1] - prism.p[0]).cross(prism.p[2] - prism.p[0]);
            let mut dir = v(s(), s(), s());
            if case % 7 < 2 {
                dir = dir - normal * (dir.dot(normal) / normal.dot(normal));
                dir = dir + normal * C::from_f64(1e-4 * s());
            }
            let Some(ray) = Ray::new(target - dir * C::from_f64(3.0), dir) else {
                continue;
            };
            let nl = NonlinearRay::new(&prism, &ray);
            if !nl.is_finite() {
                continue;
            }
            let curve = TextureCurve::new(&prism, &nl);
            let Some(hull) = PrismHull::new(&prism, &ray, C::ONE) else {
                assert!(matches!(family, Family::UvSliver), "{family:?}: no hull");
                continue;
            };
            for _ in 0..8 {
                // Four boxes, sizes from the tile to 1e-6: two anywhere in the tile
                // [3, 4] x [5, 6], two around the point the ray is aimed at.
                let (mut lo, mut hi) = ([[C::ZERO; 4]; 3], [[C::ZERO; 4]; 3]);
                for c in 0..4 {
                    for axis in 0..3 {
                        let size = 10f64.powf(-3.0 * (s() + 1.0));
                        let at = if c < 2 {
                            [3.0, 5.0, 0.0][axis] + (1.0 - size) * (s() + 1.0) / 2.0
                        } else {
                            aim[axis] - size * (s() + 1.0) / 2.0
                        };
                        lo[axis][c] = C::from_f64(at);
                        hi[axis][c] = C::from_f64(at + size);
                    }
                }
                // A point of each box clipped to the triangle's uv box (uv into barycentrics
                // in f64) mapped to world space: a ray through it enters the box's hull no
                // later than the point.
                for c in 0..4 {
                    let (mut l, mut h) = ([0.0; 3], [0.0; 3]);
                    for a in 0..3 {
                        (l[a], h[a]) = (lo[a][c].to_f64(), hi[a][c].to_f64());
                        if a < 2 {
                            l[a] = l[a].max(hull.uv_lo[a].to_f64());
                            h[a] = h[a].min(hull.uv_hi[a].to_f64());
                        }
                    }
                    if !(l[0] <= h[0] && l[1] <= h[1]) {
                        continue;
                    }
                    let q: [f64; 3] =
                        core::array::from_fn(|a| l[a] + (h[a] - l[a]) * (s() + 1.0) / 2.0);
                    let (alpha, beta) = barycentric(q[0], q[1]);
                    let wide = |x: C::Vec3| x.to_dvec3();
                    let x = Prism::<f64>::new(
                        prism.p.map(wide),
                        prism.n.map(wide),
                        prism.uv.map(|t| t.to_dvec2()),
                    )
                    .shell_point(alpha, beta, q[2]);
                    let x = v(x.x, x.y, x.z);
                    let Some(through) = Ray::new(x - dir * C::from_f64(2.0), dir) else {
                        continue;
                    };
                    let Some(hull) = PrismHull::new(&prism, &through, C::ONE) else {
                        continue;
                    };
                    let distance = (x - through.origin).length();
                    let (t, met) = hull.entries(lo, hi, 1 << c, C::ZERO, C::INFINITY);
                    assert!(
                        met == 1 << c && t[c] <= distance,
                        "{family:?} case {case}: the ray through {q:?} misses its box's hull"
                    );
                    points += 1;
                }
                let (t, met) = hull.entries(lo, hi, 0b1111, C::ZERO, C::INFINITY);
                // The native lanes give the portable lanes' (the scalar operations') bits.
                let (t_portable, met_portable) =
                    hull.entries_in::<Portable4<C>>(lo, hi, 0b1111, C::ZERO, C::INFINITY);
                assert_eq!(met, met_portable, "{family:?} case {case}");
                for c in 0..4 {
                    if met >> c & 1 == 1 {
                        assert_eq!(
                            t[c].to_bits_u64(),
                            t_portable[c].to_bits_u64(),
                            "case {case}"
                        );
                    }
                }
                for c in 0..4 {
                    let clipped_lo: [C; 3] = core::array::from_fn(|a| {
                        if a < 2 {
                            lo[a][c].max(hull.uv_lo[a])
                        } else {
                            lo[a][c]
                        }
                    });
                    let clipped_hi: [C; 3] = core::array::from_fn(|a| {
                        if a < 2 {
                            hi[a][c].min(hull.uv_hi[a])
                        } else {
                            hi[a][c]
                        }
                    });
                    // A piece at a pole of the curve (the layer at that height parallel to
                    // the ray: every distance, or the curve's coefficients' relative error
                    // above 2^-10 at an end) is the exact test's conservative answer where
                    // `(u, v)` is undefined, not a point of the ray in the box: not counted
                    // (the points of the box are checked below, pole or not).
                    let mut first = None::<C>;
                    curve.box_pieces(clipped_lo, clipped_hi, C::ZERO, C::INFINITY, |piece| {
                        let at_pole = piece.t_out == C::INFINITY
                            || !nl.condition_at_most(piece.h_in, ill_conditioned)
                            || !nl.condition_at_most(piece.h_out, ill_conditioned);
                        if at_pole {
                            poles += 1;
                        } else {
                            first = Some(first.map_or(piece.t_in, |f| f.min(piece.t_in)));
                        }
                    });
                    match first {
                        Some(t_in) => {
                            // Entered; not compared by distance: where Eq. 6 is ill-conditioned
                            // the curve's points lie on a line within rounding of the ray but
                            // far along it (its distances err, its side of a box does not).
                            entered += 1;
                            assert!(
                                met >> c & 1 == 1,
                                "{family:?} case {case}: the curve enters box {c} at {t_in:?}, the hull not"
                            );
                        }
                        None => {
                            missed += 1;
                            rejected += usize::from(met >> c & 1 == 0);
                        }
                    }
                }
            }
        }
        assert!(entered > 5_000, "{entered} boxes entered");
        assert!(poles < entered / 10, "{poles} pole touches");
        assert!(points > 50_000, "{points} points");
        assert!(
            rejected * 10 > missed * 8,
            "the hull rejects {rejected} of the {missed} boxes the curve misses"
        );
    }

    #[test]
    fn the_hull_enters_every_box_the_curve_enters() {
        hull_holds_the_curve::<f32>();
        hull_holds_the_curve::<f64>();
    }
}
