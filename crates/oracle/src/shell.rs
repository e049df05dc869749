//! High-precision shell mapping: the true hit of a world ray on a texture-space microtriangle of
//! a prism (Ogaki 2023, Eq. 1-11), for inputs given as f32/f64 values (exact rationals).
//!
//! Everything is computed in MPFR at [`PREC`] bits, far beyond what the products of a few
//! dozen f64 inputs need, and the plane cubic is solved by the rigorous root finder of
//! [`crate::exact`] on its exact rational coefficients.

use crate::exact::ExactPoly;
use rug::{Float, Rational};

/// Working precision, bits.
pub const PREC: u32 = 512;

#[derive(Clone, Debug)]
struct V3([Float; 3]);

impl V3 {
    fn from(v: [f64; 3]) -> Self {
        Self(v.map(|x| Float::with_val(PREC, x)))
    }
    fn sub(&self, o: &Self) -> Self {
        Self([0, 1, 2].map(|i| Float::with_val(PREC, &self.0[i] - &o.0[i])))
    }
    fn add(&self, o: &Self) -> Self {
        Self([0, 1, 2].map(|i| Float::with_val(PREC, &self.0[i] + &o.0[i])))
    }
    fn scale(&self, s: &Float) -> Self {
        Self([0, 1, 2].map(|i| Float::with_val(PREC, &self.0[i] * s)))
    }
    fn dot(&self, o: &Self) -> Float {
        let mut r = Float::new(PREC);
        for i in 0..3 {
            r += Float::with_val(PREC, &self.0[i] * &o.0[i]);
        }
        r
    }
    fn cross(&self, o: &Self) -> Self {
        let c = |i: usize, j: usize| {
            Float::with_val(PREC, &self.0[i] * &o.0[j])
                - Float::with_val(PREC, &self.0[j] * &o.0[i])
        };
        Self([c(1, 2), c(2, 0), c(0, 1)])
    }
}

/// A prism, a ray and a texture-space triangle, as f64 values (f32 inputs widen exactly).
#[derive(Clone, Copy, Debug)]
pub struct ShellScene {
    /// Base triangle.
    pub p: [[f64; 3]; 3],
    /// Vertex normals.
    pub n: [[f64; 3]; 3],
    /// Texture coordinates.
    pub uv: [[f64; 2]; 3],
    /// Ray origin.
    pub origin: [f64; 3],
    /// Ray direction (as stored by the tracer: already normalized in its precision).
    pub dir: [f64; 3],
    /// Texture-space triangle `(u, v, h)`.
    pub tri: [[f64; 3]; 3],
}

/// The true hit: distance along the ray (in units of the given direction's length) and the
/// canonical coordinates, rounded to f64 for comparison.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrueHit {
    /// Distance along the ray.
    pub t: f64,
    /// Height.
    pub h: f64,
    /// Canonical alpha.
    pub alpha: f64,
    /// Canonical beta.
    pub beta: f64,
}

type Lin = [Float; 2];

fn det_lin(f: &Lin, g: &Lin, k: &Lin, l: &Lin) -> [Float; 3] {
    let m = |a: &Float, b: &Float| Float::with_val(PREC, a * b);
    [
        m(&f[0], &g[0]) - m(&k[0], &l[0]),
        m(&f[0], &g[1]) + m(&f[1], &g[0]) - m(&k[0], &l[1]) - m(&k[1], &l[0]),
        m(&f[1], &g[1]) - m(&k[1], &l[1]),
    ]
}

fn quad_at(c: &[Float; 3], h: &Float) -> Float {
    let mut r = Float::with_val(PREC, &c[2]);
    r *= h;
    r += &c[1];
    r *= h;
    r += &c[0];
    r
}

/// The nearest true hit with `t >= t_min` and `h` in `[h_lo, h_hi]`, or `None`. Inside tests
/// are exact comparisons at this precision (points within 2^-400 of an edge count as inside).
#[must_use]
pub fn true_microtriangle_hit(
    scene: &ShellScene,
    h_lo: f64,
    h_hi: f64,
    t_min: f64,
) -> Option<TrueHit> {
    let p = scene.p.map(V3::from);
    let n = scene.n.map(V3::from);
    let o = V3::from(scene.origin);
    let w = V3::from(scene.dir);
    // Two vectors spanning the plane perpendicular to w (not normalized: Eq. 6's solution does
    // not depend on the choice).
    let axis =
        if scene.dir[0].abs() <= scene.dir[1].abs() && scene.dir[0].abs() <= scene.dir[2].abs() {
            [1.0, 0.0, 0.0]
        } else if scene.dir[1].abs() <= scene.dir[2].abs() {
            [0.0, 1.0, 0.0]
        } else {
            [0.0, 0.0, 1.0]
        };
    let e0 = w.cross(&V3::from(axis));
    let e1 = w.cross(&e0);
    let (a0, a1) = (p[1].sub(&p[0]), n[1].sub(&n[0]));
    let (b0, b1) = (p[2].sub(&p[0]), n[2].sub(&n[0]));
    let o0 = o.sub(&p[0]);
    let row = |e: &V3| -> [Lin; 3] {
        [
            [e.dot(&a0), e.dot(&a1)],
            [e.dot(&b0), e.dot(&b1)],
            [e.dot(&o0), -e.dot(&n[0])],
        ]
    };
    let ([a, b, r], [c, e, s]) = (row(&e0), row(&e1));
    let d = det_lin(&a, &e, &b, &c);
    let alpha = det_lin(&r, &e, &b, &s);
    let beta = det_lin(&a, &s, &r, &c);
    let t = scene.uv.map(|x| x.map(|v| Float::with_val(PREC, v)));
    let num = |k: usize| -> [Float; 3] {
        let (d1, d2) = (
            Float::with_val(PREC, &t[1][k] - &t[0][k]),
            Float::with_val(PREC, &t[2][k] - &t[0][k]),
        );
        [0, 1, 2].map(|i| {
            Float::with_val(PREC, &d[i] * &t[0][k])
                + Float::with_val(PREC, &alpha[i] * &d1)
                + Float::with_val(PREC, &beta[i] * &d2)
        })
    };
    let (u, v) = (num(0), num(1));
    let tri = scene.tri.map(V3::from);
    let normal = tri[1].sub(&tri[0]).cross(&tri[2].sub(&tri[0]));
    let k = -normal.dot(&tri[0]);
    let [nu, nv, nh] = normal.0.clone();
    let m = |x: &Float, y: &Float| Float::with_val(PREC, x * y);
    let cubic = [
        m(&nu, &u[0]) + m(&nv, &v[0]) + m(&k, &d[0]),
        m(&nu, &u[1]) + m(&nv, &v[1]) + m(&k, &d[1]) + m(&nh, &d[0]),
        m(&nu, &u[2]) + m(&nv, &v[2]) + m(&k, &d[2]) + m(&nh, &d[1]),
        m(&nh, &d[2]),
    ];
    let exact = ExactPoly::from_rationals(
        cubic
            .iter()
            .map(|c| c.to_rational().expect("finite"))
            .collect::<Vec<Rational>>(),
    );
    let mut best: Option<TrueHit> = None;
    for root in exact.real_roots() {
        let h = Float::with_val(PREC, &root.value);
        if h < h_lo || h > h_hi {
            continue;
        }
        let dh = quad_at(&d, &h);
        if dh.is_zero() {
            continue;
        }
        let al = Float::with_val(PREC, quad_at(&alpha, &h) / &dh);
        let be = Float::with_val(PREC, quad_at(&beta, &h) / &dh);
        let one = Float::with_val(PREC, 1);
        let slack = Float::with_val(PREC, 1) >> 400u32;
        if al < -slack.clone()
            || be < -slack.clone()
            || Float::with_val(PREC, &al + &be) > Float::with_val(PREC, &one + &slack)
        {
            continue;
        }
        // Inside the texture-space triangle: same-side tests in the projection dropping the
        // dominant axis of its normal.
        let uu = Float::with_val(PREC, quad_at(&u, &h) / &dh);
        let vv = Float::with_val(PREC, quad_at(&v, &h) / &dh);
        let q = V3([uu, vv, h.clone()]);
        let axis = (0..3)
            .max_by(|&x, &y| {
                normal.0[x]
                    .clone()
                    .abs()
                    .partial_cmp(&normal.0[y].clone().abs())
                    .unwrap()
            })
            .unwrap();
        let (i, j) = ((axis + 1) % 3, (axis + 2) % 3);
        let edge = |a: &V3, b: &V3| {
            let f = |x: &Float, y: &Float| Float::with_val(PREC, x - y);
            Float::with_val(PREC, f(&b.0[i], &a.0[i]) * f(&q.0[j], &a.0[j]))
                - Float::with_val(PREC, f(&b.0[j], &a.0[j]) * f(&q.0[i], &a.0[i]))
        };
        let ws = [
            edge(&tri[0], &tri[1]),
            edge(&tri[1], &tri[2]),
            edge(&tri[2], &tri[0]),
        ];
        let pos = ws.iter().all(|x| *x >= -slack.clone());
        let neg = ws.iter().all(|x| *x <= slack);
        if !(pos || neg) {
            continue;
        }
        // World point and distance.
        let s0 = p[0].add(&n[0].scale(&h));
        let e0h = a0.add(&a1.scale(&h));
        let e1h = b0.add(&b1.scale(&h));
        let x = s0.add(&e0h.scale(&al)).add(&e1h.scale(&be));
        let tt = w.dot(&x.sub(&o)) / w.dot(&w);
        let tt = Float::with_val(PREC, tt);
        if tt < t_min {
            continue;
        }
        let hit = TrueHit {
            t: tt.to_f64(),
            h: h.to_f64(),
            alpha: al.to_f64(),
            beta: be.to_f64(),
        };
        if best.is_none_or(|b| hit.t < b.t) {
            best = Some(hit);
        }
    }
    best
}

/// True canonical coordinates of a world point (the inverse of Eq. 1 through the cubic of
/// Eq. 4, solved exactly), one per height in `[h_lo, h_hi]` where the shell covers the
/// point (several where it folds). Each is `(alpha, beta, h)` rounded to f64.
#[must_use]
pub fn true_world_to_canonical(
    p: [[f64; 3]; 3],
    n: [[f64; 3]; 3],
    x: [f64; 3],
    h_lo: f64,
    h_hi: f64,
) -> Vec<[f64; 3]> {
    let p = p.map(V3::from);
    let n = n.map(V3::from);
    let x = V3::from(x);
    let (a0, a1) = (p[1].sub(&p[0]), n[1].sub(&n[0]));
    let (b0, b1) = (p[2].sub(&p[0]), n[2].sub(&n[0]));
    // N(h) = E0(h) x E1(h) = c0 + c1 h + c2 h^2; (x - S0(h)) . N(h) = 0 with x - S0 = d0 + d1 h.
    let c0 = a0.cross(&b0);
    let c1 = a0.cross(&b1).add(&a1.cross(&b0));
    let c2 = a1.cross(&b1);
    let d0 = x.sub(&p[0]);
    let d1 = n[0].scale(&Float::with_val(PREC, -1));
    let cubic = [
        d0.dot(&c0),
        Float::with_val(PREC, d0.dot(&c1) + d1.dot(&c0)),
        Float::with_val(PREC, d0.dot(&c2) + d1.dot(&c1)),
        d1.dot(&c2),
    ];
    let exact = ExactPoly::from_rationals(
        cubic
            .iter()
            .map(|c| c.to_rational().expect("finite"))
            .collect::<Vec<Rational>>(),
    );
    let mut out = Vec::new();
    for root in exact.real_roots() {
        let h = Float::with_val(PREC, &root.value);
        if h < h_lo || h > h_hi {
            continue;
        }
        let s0 = p[0].add(&n[0].scale(&h));
        let e0 = a0.add(&a1.scale(&h));
        let e1 = b0.add(&b1.scale(&h));
        let normal = e0.cross(&e1);
        let nn = normal.dot(&normal);
        if nn.is_zero() {
            continue;
        }
        let r = x.sub(&s0);
        let alpha = Float::with_val(PREC, r.cross(&e1).dot(&normal) / &nn);
        let beta = Float::with_val(PREC, e0.cross(&r).dot(&normal) / &nn);
        out.push([alpha.to_f64(), beta.to_f64(), h.to_f64()]);
    }
    out
}

/// True texture coordinates `(u, v)` of the nonlinear ray of `scene` at height `h` (Eq. 8 at
/// 512 bits), with the denominator `D(h)` relative to its terms' size (how close the ray is to
/// parallel to the cross-section there); `None` where `D(h) = 0`.
#[must_use]
pub fn true_nonlinear_uv(scene: &ShellScene, h: f64) -> Option<(f64, f64, f64)> {
    let (alpha, beta, det, size) = true_canonical_at(scene, h)?;
    let uv = scene.uv.map(|x| x.map(|v| Float::with_val(PREC, v)));
    let at = |k: usize| {
        Float::with_val(
            PREC,
            &uv[0][k]
                + Float::with_val(PREC, &alpha * Float::with_val(PREC, &uv[1][k] - &uv[0][k]))
                + Float::with_val(PREC, &beta * Float::with_val(PREC, &uv[2][k] - &uv[0][k])),
        )
    };
    let relative_det = (Float::with_val(PREC, det.abs_ref()) / &size).to_f64();
    Some((at(0).to_f64(), at(1).to_f64(), relative_det))
}

/// True canonical coordinates `(alpha, beta)` of the nonlinear ray of `scene` at height `h`
/// (Eq. 7 at 512 bits, by Cramer's rule on Eq. 5), rounded to f64 (which keeps their signs);
/// `None` where the ray is parallel to the prism's cross-section there.
#[must_use]
pub fn true_nonlinear_alpha_beta(scene: &ShellScene, h: f64) -> Option<(f64, f64)> {
    true_canonical_at(scene, h).map(|(alpha, beta, _, _)| (alpha.to_f64(), beta.to_f64()))
}

/// `(alpha, beta)` of the nonlinear ray of `scene` at `h`, the determinant of Eq. 5's system
/// and the size of its terms, at [`PREC`] bits; `None` where the determinant is 0.
fn true_canonical_at(scene: &ShellScene, h: f64) -> Option<(Float, Float, Float, Float)> {
    let p = scene.p.map(V3::from);
    let n = scene.n.map(V3::from);
    let o = V3::from(scene.origin);
    let w = V3::from(scene.dir);
    // Cramer on Eq. 5 directly at this h: o + t w = S0(h) + alpha E0(h) + beta E1(h).
    let h = Float::with_val(PREC, h);
    let s0 = p[0].add(&n[0].scale(&h));
    let e0 = p[1].sub(&p[0]).add(&n[1].sub(&n[0]).scale(&h));
    let e1 = p[2].sub(&p[0]).add(&n[2].sub(&n[0]).scale(&h));
    let r = o.sub(&s0);
    // alpha E0 + beta E1 - t w = r: det [E0 E1 -w].
    let neg_w = w.scale(&Float::with_val(PREC, -1));
    let det = e0.cross(&e1).dot(&neg_w);
    if det.is_zero() {
        return None;
    }
    let size = Float::with_val(
        PREC,
        e0.dot(&e0).sqrt() * e1.dot(&e1).sqrt() * w.dot(&w).sqrt(),
    );
    let alpha = Float::with_val(PREC, r.cross(&e1).dot(&neg_w) / &det);
    let beta = Float::with_val(PREC, e0.cross(&r).dot(&neg_w) / &det);
    Some((alpha, beta, det, size))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn straight_down_onto_a_flat_microtriangle() {
        let scene = ShellScene {
            p: [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            n: [[0.0, 0.0, 1.0]; 3],
            uv: [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]],
            origin: [0.2, 0.2, 3.0],
            dir: [0.0, 0.0, -1.0],
            tri: [[0.0, 0.0, 0.25], [1.0, 0.0, 0.75], [0.0, 1.0, 0.25]],
        };
        let hit = true_microtriangle_hit(&scene, 0.0, 1.0, 0.0).unwrap();
        // h = 0.25 + 0.5 u at u = 0.2
        assert!(
            (hit.h - 0.35).abs() < 1e-15 && (hit.t - 2.65).abs() < 1e-15,
            "{hit:?}"
        );
    }
}
