//! Microtriangle hits in f32 and f64 against the MPFR oracle's true hit, on microtriangles of
//! texel size 1/64, 1/4096 and 1/65536 (where n_uvh is tiny and the paper's normalization
//! matters).
//!
//! Tolerance on the distance: 1024 u (the shell map on O(1) data) plus four times the
//! root's attainable error, 64 u sum|c_i||h|^i / |p'(h)| for the plane cubic `p` as the
//! tracer computed it (its coefficients carry a few dozen roundings).

mod common;

use nlrt_oracle::ExactPoly;
use nlrt_oracle::shell::{ShellScene, true_microtriangle_hit, true_nonlinear_alpha_beta};
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{
    BaseEdges, NonlinearRay, Prism, Ray, TextureCurve, TexturePlane, decidedly_outside_in_f64,
    intersect_microtriangle,
};
use nlrt_tests::geometry::SplitMix64;
use proptest::prelude::*;
use rug::Rational;

fn config() -> ProptestConfig {
    common::proptest_config(64, 2000)
}

fn v3<T: Real>(v: T::Vec3) -> [f64; 3] {
    [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()]
}

fn check<T: Real>(
    r: &[f64; 12],
    texel: f64,
    corner: [f64; 2],
    bary: [f64; 2],
    heights: [f64; 3],
    o: [f64; 2],
) -> Result<(), TestCaseError> {
    let v = |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
    // Unit uvs: alpha = u, beta = v. Gently tilted normals (an unfolded prism).
    let prism = gentle_prism::<T>(r);
    let (u0, v0) = (corner[0] * 0.5, corner[1] * 0.5);
    let tri = [
        v(u0, v0, heights[0]),
        v(u0 + texel, v0, heights[1]),
        v(u0, v0 + texel, heights[2]),
    ];
    // Aim at an interior point of the microtriangle (margins of at least 0.2 x 0.2 = 0.04 in
    // its barycentrics).
    let (a, b) = (bary[0], bary[1]);
    let (u, vv) = (u0 + a * texel, v0 + b * texel);
    let h = (1.0 - a - b) * heights[0] + a * heights[1] + b * heights[2];
    let aim = prism.shell_point(T::from_f64(u), T::from_f64(vv), T::from_f64(h));
    let origin = v(o[0], o[1], 4.0);
    let ray = Ray::new(origin, aim - origin).expect("non-degenerate ray");
    let nl = NonlinearRay::new(&prism, &ray);
    let ours = intersect_microtriangle(&prism, &nl, &tri, T::ZERO, T::ONE, T::ZERO, T::INFINITY);
    let scene = ShellScene {
        p: prism.p.map(v3::<T>),
        n: prism.n.map(v3::<T>),
        uv: prism.uv.map(|t| [t.x().to_f64(), t.y().to_f64()]),
        origin: v3::<T>(ray.origin),
        dir: v3::<T>(ray.dir),
        tri: tri.map(v3::<T>),
    };
    // The aimed point is computed in T: for f32 and the smallest texels its rounding (and the
    // rounding of the normalized direction) can move the exact ray off the microtriangle. The
    // claim is about rays the oracle says hit.
    let truth = true_microtriangle_hit(&scene, 0.0, 1.0, 0.0);
    prop_assert!(
        truth.is_some() || T::MANTISSA_DIGITS == 24,
        "f64: the oracle misses the aimed interior point"
    );
    let Some(truth) = truth else { return Ok(()) };
    let ours = ours
        .ok_or_else(|| TestCaseError::fail(format!("{}: missed hit, truth {truth:?}", T::NAME)))?;
    let plane = TexturePlane::<T>::through(&tri).unwrap();
    let cubic = plane.ray_cubic(&nl);
    let magnitude = nlrt_poly::horner(&cubic.map(T::abs), ours.h.abs());
    let slope =
        nlrt_poly::horner(&[cubic[1], T::TWO * cubic[2], T::THREE * cubic[3]], ours.h).abs();
    let u_f = T::UNIT_ROUNDOFF.to_f64();
    let h_error = 64.0 * u_f * (magnitude / slope).to_f64();
    let tol = 1024.0 * u_f * 4.0 + 4.0 * h_error;
    let err = (ours.t.to_f64() - truth.t).abs();
    prop_assert!(
        err <= tol,
        "{}: t {} vs true {} (error {err:e} > {tol:e}), texel {texel}",
        T::NAME,
        ours.t,
        truth.t
    );
    Ok(())
}

macro_rules! oracle_properties {
    ($($t:ident: $texels:expr),*) => {$(
        mod $t {
            use super::*;
            proptest! {
                #![proptest_config(config())]
                #[test]
                fn microtriangle_hits_match_the_oracle(
                    r in prop::array::uniform12(-1.0f64..1.0),
                    texel in prop::sample::select($texels),
                    corner in prop::array::uniform2(0.05f64..0.5),
                    a in 0.2f64..0.6,
                    b_frac in 0.2f64..0.8,
                    heights in prop::array::uniform3(0.2f64..0.8),
                    o in prop::array::uniform2(-1.0f64..1.0),
                ) {
                    let b = b_frac * (0.8 - a);
                    check::<$t>(&r, texel, corner, [a, b], heights, o)?;
                }
            }
        }
    )*};
}

// f32 disagrees with the oracle on a small fraction of rays (missed hits on tiny texels, an
// earlier hit than the true one): measured, not asserted, by `f32_disagreement_rates`, until
// the microtriangle test is made robust in f32 (open work of the shellmap issue).
oracle_properties!(f64: vec![1.0 / 64.0, 1.0 / 4096.0, 1.0 / 65536.0]);

/// Measures (does not assert) how often f32 disagrees with the oracle, per texel size:
/// `cargo test --release -p nlrt-tests --test shellmap_oracle -- --ignored --nocapture`.
#[test]
#[ignore]
fn f32_disagreement_rates() {
    let mut rng = nlrt_oracle::families::SplitMix64::new(12345);
    let mut unit = || rng.unit();
    for texel in [1.0 / 64.0, 1.0 / 4096.0, 1.0 / 65536.0] {
        let (mut hits, mut misses, mut errors) = (0, 0, 0);
        for _ in 0..20_000 {
            let r: [f64; 12] = std::array::from_fn(|_| 2.0 * unit() - 1.0);
            let corner = [0.05 + 0.45 * unit(), 0.05 + 0.45 * unit()];
            let a = 0.2 + 0.4 * unit();
            let b = (0.2 + 0.6 * unit()) * (0.8 - a);
            let heights = [0.2 + 0.6 * unit(), 0.2 + 0.6 * unit(), 0.2 + 0.6 * unit()];
            let o = [2.0 * unit() - 1.0, 2.0 * unit() - 1.0];
            match check::<f32>(&r, texel, corner, [a, b], heights, o) {
                Err(e) if e.to_string().contains("oracle misses") => {}
                Ok(()) => hits += 1,
                Err(e) if e.to_string().contains("missed") => misses += 1,
                Err(_) => errors += 1,
            }
        }
        println!(
            "f32 texel {texel:e}: {hits} agree, {misses} missed, {errors} distance errors over tolerance"
        );
    }
}

/// A well-shaped prism: base near the unit right triangle, normals tilted by at most
/// 0.1 x sqrt 2, unit uvs (so alpha = u, beta = v).
fn gentle_prism<T: Real>(r: &[f64; 12]) -> Prism<T> {
    let v = |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
    let w = |x: f64, y: f64| T::Vec2::new(T::from_f64(x), T::from_f64(y));
    Prism::new(
        [
            v(0.1 * r[0], 0.1 * r[1], 0.0),
            v(1.0, 0.1 * r[2], 0.1 * r[3]),
            v(0.1 * r[4], 1.0, 0.1 * r[5]),
        ],
        [
            v(0.1 * r[6], 0.1 * r[7], 1.0),
            v(0.1 * r[8], 0.1 * r[9], 1.0),
            v(0.1 * r[10], 0.1 * r[11], 1.0),
        ],
        [w(0.0, 0.0), w(1.0, 0.0), w(0.0, 1.0)],
    )
}

/// World -> canonical (Eq. 4) against the oracle's exact cubic. The largest f64 error over
/// the cases, and for f32 the same measured: the returned figures are printed by the test.
/// Tolerance: `TOL_ULPS` ulps of the type (on O(1) coordinates): the Eq. 4 cubic's
/// coefficients are sums of triple products of O(1) values (a few dozen roundings), and on
/// these unfolded prisms its root has a slope |p'(h)| of order the prism's volume (>= 0.3),
/// so the error stays within a few hundred u; 4096 leaves a factor of 10 over that.
const TOL_ULPS: f64 = 4096.0;

fn mapping_error<T: Real>(r: &[f64; 12], q: [f64; 3]) -> f64 {
    let prism = gentle_prism::<T>(r);
    let (alpha, beta, h) = (q[0], q[1] * (1.0 - q[0]), q[2]);
    let x = prism.shell_point(T::from_f64(alpha), T::from_f64(beta), T::from_f64(h));
    let truth = nlrt_oracle::shell::true_world_to_canonical(
        prism.p.map(v3::<T>),
        prism.n.map(v3::<T>),
        v3::<T>(x),
        0.0,
        1.0,
    );
    let inside: Vec<_> = truth
        .iter()
        .filter(|c| c[0] >= -1e-9 && c[1] >= -1e-9 && c[0] + c[1] <= 1.0 + 1e-9)
        .collect();
    assert_eq!(
        inside.len(),
        1,
        "an unfolded prism covers the point once: {truth:?}"
    );
    let c = prism
        .world_to_canonical(x, T::ZERO, T::ONE)
        .expect("the point is in the prism");
    let t = inside[0];
    (c.alpha.to_f64() - t[0])
        .abs()
        .max((c.beta.to_f64() - t[1]).abs())
        .max((c.h.to_f64() - t[2]).abs())
}

/// The nonlinear ray's texture coordinates at a height (Eq. 8) against the oracle, relative
/// to the conditioning of Eq. 5 there (`relative_det`: how far from parallel to the
/// cross-section the ray is); returns the error scaled by that conditioning.
fn nonlinear_uv_error<T: Real>(r: &[f64; 12], o: [f64; 3], aim: [f64; 2], h: f64) -> Option<f64> {
    let prism = gentle_prism::<T>(r);
    let v = |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
    let target = prism.shell_point(T::from_f64(aim[0]), T::from_f64(aim[1]), T::from_f64(0.5));
    let origin = v(o[0] * 2.0, o[1] * 2.0, 1.0 + 3.0 * o[2].abs());
    let ray = Ray::new(origin, target - origin)?;
    let nl = NonlinearRay::new(&prism, &ray);
    let (u, w) = nl.uv(T::from_f64(h))?;
    let scene = ShellScene {
        p: prism.p.map(v3::<T>),
        n: prism.n.map(v3::<T>),
        uv: prism.uv.map(|t| [t.x().to_f64(), t.y().to_f64()]),
        origin: v3::<T>(ray.origin),
        dir: v3::<T>(ray.dir),
        tri: [[0.0; 3]; 3],
    };
    let (tu, tv, relative_det) = nlrt_oracle::shell::true_nonlinear_uv(&scene, h)?;
    // Eq. 5 at this h is a 3x3 system; its solution's error scales with 1 / relative_det.
    Some((u.to_f64() - tu).abs().max((w.to_f64() - tv).abs()) * relative_det)
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn world_to_canonical_matches_the_oracle(
        r in prop::array::uniform12(-1.0f64..1.0),
        q in prop::array::uniform3(0.0f64..1.0),
    ) {
        let u64_ = f64::UNIT_ROUNDOFF;
        let err = mapping_error::<f64>(&r, q);
        prop_assert!(err <= TOL_ULPS * u64_, "f64 error {err:e}");
        let err32 = mapping_error::<f32>(&r, q);
        prop_assert!(err32 <= TOL_ULPS * f64::from(f32::UNIT_ROUNDOFF), "f32 error {err32:e}");
    }

    #[test]
    fn nonlinear_ray_uv_matches_the_oracle(
        r in prop::array::uniform12(-1.0f64..1.0),
        o in prop::array::uniform3(-1.0f64..1.0),
        aim in prop::array::uniform2(0.05f64..0.45),
        h in 0.0f64..1.0,
    ) {
        if let Some(err) = nonlinear_uv_error::<f64>(&r, o, aim, h) {
            prop_assert!(err <= TOL_ULPS * f64::UNIT_ROUNDOFF, "f64 scaled error {err:e}");
        }
        if let Some(err) = nonlinear_uv_error::<f32>(&r, o, aim, h) {
            prop_assert!(err <= TOL_ULPS * f64::from(f32::UNIT_ROUNDOFF), "f32 scaled error {err:e}");
        }
    }

    #[test]
    fn uv_enclosure_holds_the_curve(
        r in prop::array::uniform24(-1.0f64..1.0),
        o in prop::array::uniform3(-1.0f64..1.0),
        ends in prop::array::uniform2(0.0f64..1.0),
        shrink in 0i32..16,
    ) {
        uv_enclosure_check::<f64>(&r, o, ends, shrink)?;
        uv_enclosure_check::<f32>(&r, o, ends, shrink)?;
    }
}

proptest! {
    // Lines within rounding of the curve are a small part of the offsets: enough cases that a
    // bound left out is caught (with a zero margin this fails within the first 4,096).
    #![proptest_config(common::proptest_config(4096, 50000))]

    #[test]
    fn side_of_line_agrees_with_exact_arithmetic(
        r in prop::array::uniform24(-1.0f64..1.0),
        o in prop::array::uniform3(-1.0f64..1.0),
        h in 0.0f64..1.0,
        axis in 0usize..2,
        offset_exponent in -8i32..48,
        negative in any::<bool>(),
    ) {
        side_of_line_check::<f64>(&r, o, h, axis, offset_exponent, negative)?;
        side_of_line_check::<f32>(&r, o, h, axis, offset_exponent, negative)?;
    }
}

/// [`TextureCurve::side_of_line`] at height `h` for a line `u = c` (or `v = c`) placed
/// `2^offset_exponent` unit roundoffs (relative) to either side of the curve's computed
/// coordinate there, from within rounding of it to far away: a decided side is the side of
/// the exact curve (`U / D` evaluated in rationals), and a line `2^40` roundoffs away is
/// decided.
fn side_of_line_check<T: Real>(
    r: &[f64; 24],
    o: [f64; 3],
    h: f64,
    axis: usize,
    offset_exponent: i32,
    negative: bool,
) -> Result<(), TestCaseError> {
    let prism = sheared_prism::<T>(r);
    let Some(nl) = ray_from_above(&prism, o) else {
        return Ok(());
    };
    let curve = TextureCurve::new(&prism, &nl);
    let h = T::from_f64(h);
    let Some((uv, _)) = curve.uv_with_error(h) else {
        return Ok(());
    };
    let offset =
        uv[axis].abs().max(T::ONE) * T::UNIT_ROUNDOFF * T::from_f64(2f64.powi(offset_exponent));
    let c = if negative {
        uv[axis] - offset
    } else {
        uv[axis] + offset
    };
    let side = curve.side_of_line(axis, c, h);
    let exact = |p: &[T; 3]| ExactPoly::from_f64s(&p.map(|x| x.to_f64())).expect("finite");
    let q = |x: T| Rational::from_f64(x.to_f64()).expect("finite");
    let num = exact(if axis == 0 { &nl.u } else { &nl.v });
    let d = exact(&nl.d).eval(&q(h));
    if d.cmp0() == core::cmp::Ordering::Equal {
        return Ok(());
    }
    let coordinate = num.eval(&q(h)) / &d;
    if let Some(beyond) = side {
        prop_assert_eq!(
            beyond,
            coordinate > q(c),
            "{}: side {:?} of {} at h = {}, exact {}",
            T::NAME,
            side,
            c,
            h,
            coordinate.to_f64()
        );
    }
    if offset_exponent >= 40 {
        prop_assert!(side.is_some(), "{}: a line far away undecided", T::NAME);
    }
    Ok(())
}

/// A sheared prism for the enclosure: normals tilted by up to 0.5, uvs a distorted triangle
/// away from the origin (so `u` and `D` vary together, the case the centred form is for).
fn sheared_prism<T: Real>(r: &[f64; 24]) -> Prism<T> {
    let v = |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
    let w = |x: f64, y: f64| T::Vec2::new(T::from_f64(x), T::from_f64(y));
    Prism::new(
        [
            v(0.1 * r[0], 0.1 * r[1], 0.1 * r[2]),
            v(1.0 + 0.1 * r[3], 0.1 * r[4], 0.1 * r[5]),
            v(0.1 * r[6], 1.0 + 0.1 * r[7], 0.1 * r[8]),
        ],
        [
            v(0.5 * r[9], 0.5 * r[10], 1.0 + 0.3 * r[11]),
            v(0.5 * r[12], 0.5 * r[13], 1.0 + 0.3 * r[14]),
            v(0.5 * r[15], 0.5 * r[16], 1.0 + 0.3 * r[17]),
        ],
        [
            w(3.0 + 0.2 * r[18], 5.0 + 0.2 * r[19]),
            w(4.0 + 0.2 * r[20], 5.0 + 0.2 * r[21]),
            w(3.0 + 0.2 * r[22], 6.0 + 0.2 * r[23]),
        ],
    )
}

/// The nonlinear ray in `prism` of a ray from above it (origin from `o`, each in `[-1, 1]`)
/// through a point inside it; `None` for a degenerate direction.
fn ray_from_above<T: Real>(prism: &Prism<T>, o: [f64; 3]) -> Option<NonlinearRay<T>> {
    let v = |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
    let target = prism.shell_point(T::from_f64(0.3), T::from_f64(0.3), T::from_f64(0.5));
    let origin = v(o[0] * 2.0, o[1] * 2.0, 1.5 + 3.0 * o[2].abs());
    let ray = Ray::new(origin, target - origin)?;
    Some(NonlinearRay::new(prism, &ray))
}

/// [`TextureCurve::uv_enclosure`] over `[a, b]` (random ends in `[0, 1]`, the interval then
/// shrunk by `2^shrink` towards `a`, down to the short stretches of a walk's deep nodes) holds
/// the curve of the ray's quadratics, `U(h) / D(h)` and `V(h) / D(h)` evaluated exactly
/// (rationals), at 65 heights of the interval: no tolerance, the enclosure is a bound.
fn uv_enclosure_check<T: Real>(
    r: &[f64; 24],
    o: [f64; 3],
    ends: [f64; 2],
    shrink: i32,
) -> Result<(), TestCaseError> {
    let prism = sheared_prism::<T>(r);
    let Some(nl) = ray_from_above(&prism, o) else {
        return Ok(());
    };
    let curve = TextureCurve::new(&prism, &nl);
    let a = ends[0].min(ends[1]);
    let b = a + (ends[0] - ends[1]).abs() * 2f64.powi(-shrink);
    let (a, b) = (T::from_f64(a), T::from_f64(b));
    let Some([u_lo, u_hi, v_lo, v_hi]) = curve.uv_enclosure(a, b) else {
        return Ok(());
    };
    prop_assert!(
        u_lo <= u_hi && v_lo <= v_hi,
        "{:?}",
        [u_lo, u_hi, v_lo, v_hi]
    );
    let exact = |c: &[T; 3]| ExactPoly::from_f64s(&c.map(|x| x.to_f64())).expect("finite");
    let (u, w, d) = (exact(&nl.u), exact(&nl.v), exact(&nl.d));
    let q = |x: T| Rational::from_f64(x.to_f64()).expect("finite");
    for i in 0..=64 {
        let h = (a + (b - a) * T::from_f64(f64::from(i) / 64.0))
            .max(a)
            .min(b);
        let h = q(h);
        let dh = d.eval(&h);
        prop_assert!(
            dh.cmp0() != core::cmp::Ordering::Equal,
            "a pole inside an enclosure"
        );
        let (uh, vh) = (u.eval(&h) / &dh, w.eval(&h) / &dh);
        prop_assert!(
            q(u_lo) <= uh && uh <= q(u_hi),
            "u = {} outside [{u_lo}, {u_hi}] on [{a}, {b}] ({})",
            uh.to_f64(),
            T::NAME
        );
        prop_assert!(
            q(v_lo) <= vh && vh <= q(v_hi),
            "v = {} outside [{v_lo}, {v_hi}] on [{a}, {b}] ({})",
            vh.to_f64(),
            T::NAME
        );
    }
    Ok(())
}

/// `decidedly_outside_in_f64` never calls a height outside the base triangle across an edge
/// where the exact curve (MPFR, from the same f32 inputs) is inside it, and decides the
/// heights in the f32 crossings' error windows that f32 itself cannot: f32 sheared prisms,
/// steep and grazing rays (nearly parallel to the prism's layers, where the windows are
/// widest), heights at fractions of each f32 edge crossing's window on both sides and at
/// random.
#[test]
fn edge_sides_decided_in_f64_agree_with_the_oracle() {
    let mut rng = SplitMix64::new(0x0ed9e);
    let (mut decided, mut windows_decided, mut windows) = (0u32, 0u32, 0u32);
    // Window heights that f32 leaves undecided and f64 decides.
    let mut only_in_f64 = 0u32;
    for case in 0..3000 {
        let r: [f64; 24] = core::array::from_fn(|_| rng.unit() * 2.0 - 1.0);
        let prism = sheared_prism::<f32>(&r);
        let target = prism.shell_point(
            rng.unit() as f32 * 0.6 + 0.1,
            rng.unit() as f32 * 0.6 + 0.1,
            rng.unit() as f32,
        );
        // Every other ray grazes: its height component 1e-4 to 1e-1 of its length.
        let angle = rng.unit() * core::f64::consts::TAU;
        let rise = if case % 2 == 0 {
            (rng.unit() * 3.0 - 4.0).exp2() * 10f64.powi(-(rng.unit() * 3.0) as i32)
        } else {
            0.3 + rng.unit()
        };
        let dir = nlrt_poly::glam::Vec3::new(angle.cos() as f32, angle.sin() as f32, -rise as f32);
        let Some(ray) = Ray::new(target - dir * 3.0, dir) else {
            continue;
        };
        let nl = NonlinearRay::new(&prism, &ray);
        let edges = BaseEdges::new(&nl);
        let scene = ShellScene {
            p: prism.p.map(|v| [v.x, v.y, v.z].map(f64::from)),
            n: prism.n.map(|v| [v.x, v.y, v.z].map(f64::from)),
            uv: prism.uv.map(|v| [v.x, v.y].map(f64::from)),
            origin: [ray.origin.x, ray.origin.y, ray.origin.z].map(f64::from),
            dir: [ray.dir.x, ray.dir.y, ray.dir.z].map(f64::from),
            tri: [[0.0; 3]; 3],
        };
        let quadratics = [
            nl.alpha,
            nl.beta,
            core::array::from_fn(|i| nl.alpha[i] + nl.beta[i] - nl.d[i]),
        ];
        for (k, quadratic) in quadratics.into_iter().enumerate() {
            let mut heights: Vec<(f32, bool)> = vec![(rng.unit() as f32, false)];
            for &s in nlrt_poly::solve_quadratic_in(quadratic, 0.0, 1.0).iter() {
                let w = edges.window(k, s).min(1.0);
                for f in [-1.0, -0.5, -0.25, 0.25, 0.5, 1.0] {
                    heights.push((s + w * f, true));
                }
            }
            for (h, in_window) in heights {
                windows += u32::from(in_window);
                if !decidedly_outside_in_f64(&prism, &ray, k, h) {
                    continue;
                }
                decided += 1;
                windows_decided += u32::from(in_window);
                only_in_f64 += u32::from(in_window && !edges.decidedly_outside(k, h));
                let Some((alpha, beta)) = true_nonlinear_alpha_beta(&scene, f64::from(h)) else {
                    panic!("case {case}: decided at a pole (h = {h})");
                };
                let outside = match k {
                    0 => alpha < 0.0,
                    1 => beta < 0.0,
                    _ => alpha + beta > 1.0,
                };
                assert!(
                    outside,
                    "case {case}, edge {k}, h = {h}: called outside, exact ({alpha}, {beta})"
                );
            }
        }
    }
    // The decision is not vacuous: most window heights beyond the crossing are decided.
    assert!(
        decided > 1000 && windows_decided * 4 > windows && only_in_f64 * 4 > windows_decided,
        "{decided} decided; in windows {windows_decided} of {windows}, {only_in_f64} only in f64"
    );
    assert!(!decidedly_outside_in_f64(
        &sheared_prism::<f64>(&[0.0; 24]),
        &Ray::new(nlrt_poly::glam::DVec3::Z, -nlrt_poly::glam::DVec3::Z).unwrap(),
        0,
        -1.0
    ));
}
