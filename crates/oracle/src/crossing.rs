//! Exact ray-triangle crossings (GMP rationals): where a ray given by f32/f64 values meets a
//! flat triangle given by f32/f64 values, with no rounding at all. The watertightness
//! measurement uses it to decide, without trusting floating point, that a ray reaches a base
//! triangle of a displaced surface (so it must have crossed the height field above it).

use rug::Rational;

/// An exact crossing.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossing {
    /// Distance along the ray (exact), as the nearest f64.
    pub t: f64,
    /// Whether the ray arrives from the side `(b - a) x (c - a)` points to.
    pub from_front: bool,
}

fn q(x: f64) -> Rational {
    Rational::from_f64(x).expect("finite input")
}

fn sub(a: &[Rational; 3], b: &[Rational; 3]) -> [Rational; 3] {
    [0, 1, 2].map(|i| Rational::from(&a[i] - &b[i]))
}

fn cross(a: &[Rational; 3], b: &[Rational; 3]) -> [Rational; 3] {
    [
        Rational::from(&a[1] * &b[2]) - Rational::from(&a[2] * &b[1]),
        Rational::from(&a[2] * &b[0]) - Rational::from(&a[0] * &b[2]),
        Rational::from(&a[0] * &b[1]) - Rational::from(&a[1] * &b[0]),
    ]
}

fn dot(a: &[Rational; 3], b: &[Rational; 3]) -> Rational {
    Rational::from(&a[0] * &b[0]) + Rational::from(&a[1] * &b[1]) + Rational::from(&a[2] * &b[2])
}

/// The crossing of the ray `o + t d` (`t > 0`) with the triangle `a b c` (edges included),
/// exactly; `None` when it misses, runs parallel to the plane, or an input is not finite.
#[must_use]
pub fn ray_triangle(o: [f64; 3], d: [f64; 3], tri: [[f64; 3]; 3]) -> Option<Crossing> {
    if !o
        .iter()
        .chain(&d)
        .chain(tri.iter().flatten())
        .all(|v| v.is_finite())
    {
        return None;
    }
    let (o, d) = (o.map(q), d.map(q));
    let [a, b, c] = tri.map(|p| p.map(q));
    let (e1, e2) = (sub(&b, &a), sub(&c, &a));
    let n = cross(&e1, &e2);
    let denom = dot(&n, &d);
    if denom == 0 {
        return None;
    }
    // t = n.(a - o) / n.d; barycentrics from the sub-areas (Cramer's rule).
    let s = sub(&o, &a);
    let t = -dot(&n, &s) / &denom;
    if t <= 0 {
        return None;
    }
    let p = [0, 1, 2].map(|i| &s[i] + Rational::from(&d[i] * &t));
    let nn = dot(&n, &n);
    let beta = dot(&cross(&p, &e2), &n) / nn.clone();
    let gamma = dot(&cross(&e1, &p), &n) / nn;
    if beta < 0 || gamma < 0 || Rational::from(&beta + &gamma) > 1 {
        return None;
    }
    Some(Crossing {
        t: t.to_f64(),
        from_front: denom < 0,
    })
}

/// Whether the triangle `a b c` has zero area exactly (its vertices are collinear or
/// coincide), decided on the exact values; `false` for non-finite input.
#[must_use]
pub fn has_zero_area(tri: [[f64; 3]; 3]) -> bool {
    if !tri.iter().flatten().all(|v| v.is_finite()) {
        return false;
    }
    let [a, b, c] = tri.map(|p| p.map(q));
    cross(&sub(&b, &a), &sub(&c, &a)).iter().all(|x| *x == 0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zero_area_is_exact() {
        assert!(has_zero_area([[0.0; 3], [1.0, 2.0, 3.0], [0.5, 1.0, 1.5]]));
        assert!(has_zero_area([[1.0; 3]; 3]));
        // Off the line by one ulp, or by 1e-300: not zero.
        assert!(!has_zero_area([
            [0.0; 3],
            [1.0, 2.0, 3.0],
            [0.5, 1.0, 1.5f64.next_up()]
        ]));
        assert!(!has_zero_area([
            [0.0; 3],
            [1.0, 0.0, 0.0],
            [0.5, 1e-300, 0.0]
        ]));
        assert!(!has_zero_area([
            [f64::NAN; 3],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0]
        ]));
    }

    #[test]
    fn crossings_are_exact_on_edges_and_sides() {
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let c = ray_triangle([0.25, 0.25, 2.0], [0.0, 0.0, -1.0], tri).unwrap();
        assert_eq!(
            c,
            Crossing {
                t: 2.0,
                from_front: true
            }
        );
        // Exactly on the hypotenuse: inside (edges included), from below: back side.
        let c = ray_triangle([0.5, 0.5, -1.0], [0.0, 0.0, 1.0], tri).unwrap();
        assert!(!c.from_front && c.t == 1.0);
        // One ulp beyond the hypotenuse: outside.
        let x = 0.5f64.next_up();
        assert!(ray_triangle([x, 0.5, 1.0], [0.0, 0.0, -1.0], tri).is_none());
        // Parallel, behind, NaN.
        assert!(ray_triangle([0.2, 0.2, 1.0], [1.0, 0.0, 0.0], tri).is_none());
        assert!(ray_triangle([0.2, 0.2, 1.0], [0.0, 0.0, 1.0], tri).is_none());
        assert!(ray_triangle([f64::NAN, 0.2, 1.0], [0.0, 0.0, -1.0], tri).is_none());
    }
}
