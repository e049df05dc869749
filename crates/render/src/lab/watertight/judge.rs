//! The MPFR oracle's judgement of a tracer's hit on a displaced surface: the true hits on the
//! microtriangles around it ([`TrueSurface`]), and whether a reported point lies on the true
//! surface within the tolerance (the nearest points of the shell-mapped microtriangles) or on a
//! seam wall. What `nlrt watertight` counts as confirmed, grazing, too far or a ghost
//! ([`super::GhostCount`]).

use super::{LEAK_TOLERANCE, oracle_scene, to_f64};
use nlrt_poly::glam::{DVec2, DVec3};
use nlrt_poly::{Real, Vector2};
use nlrt_shellmap::Ray;

/// Per base triangle, the other triangles sharing a vertex position with it (bit-identical
/// positions, so the two sides of a uv or normal seam are neighbours): where the oracle looks
/// for a true hit that lies across a base edge.
pub(super) fn vertex_neighbours<T: Real>(mesh: &nlrt_accel::BaseMesh<T>) -> Vec<Vec<usize>> {
    use std::collections::HashMap;
    let key = |v: u32| to_f64::<T>(mesh.positions()[v as usize]).map(f64::to_bits);
    let mut by_vertex: HashMap<[u64; 3], Vec<usize>> = HashMap::new();
    for i in 0..mesh.triangle_count() {
        for v in mesh.triangle(i) {
            by_vertex.entry(key(v)).or_default().push(i);
        }
    }
    (0..mesh.triangle_count())
        .map(|i| {
            let mut others: Vec<usize> = mesh
                .triangle(i)
                .iter()
                .flat_map(|&v| by_vertex[&key(v)].iter().copied())
                .filter(|&o| o != i)
                .collect();
            others.sort_unstable();
            others.dedup();
            others
        })
        .collect()
}

/// The oracle's view of the microtriangles around a hit, exactly as the tracer has them (its
/// precision's prisms, ray, texel corners and heights).
pub(super) struct TrueSurface<'a, T: Real> {
    surface: &'a nlrt_accel::DisplacedSurface<T>,
    /// Per base triangle, the other triangles sharing a vertex position with it.
    neighbours: Vec<Vec<usize>>,
}

impl<'a, T: Real> TrueSurface<'a, T> {
    pub(super) fn new(surface: &'a nlrt_accel::DisplacedSurface<T>) -> Self {
        Self {
            surface,
            neighbours: vertex_neighbours(surface.mesh()),
        }
    }

    /// The nearest true hit at `t >= t_min` on the two microtriangles of `texel` in the prism
    /// of base triangle `triangle`.
    pub(super) fn texel_hit(
        &self,
        ray: &Ray<T>,
        triangle: usize,
        texel: [i32; 2],
        t_min: f64,
    ) -> Option<f64> {
        use nlrt_oracle::shell::true_microtriangle_hit;
        let field = self.surface.field();
        let texel_size = T::ONE / T::from_f64(field.grid_side() as f64);
        let coord = |i: i32| (T::from_i32(i) * texel_size).to_f64();
        let height = |s: u16| {
            (T::from_i32(i32::from(s)) / T::from_i32(i32::from(nlrt_accel::HEIGHT_ONE))).to_f64()
        };
        let prism = self.surface.prism(triangle);
        let [x, y] = texel;
        let c = field.texel_corners(i64::from(x), i64::from(y)).map(height);
        let (u0, v0, u1, v1) = (coord(x), coord(y), coord(x + 1), coord(y + 1));
        let corners = [
            [u0, v0, c[0]],
            [u1, v0, c[1]],
            [u1, v1, c[3]],
            [u0, v1, c[2]],
        ];
        let mut best: Option<f64> = None;
        for tri in [
            [corners[0], corners[1], corners[2]],
            [corners[0], corners[2], corners[3]],
        ] {
            let shell = oracle_scene(&prism, ray, tri);
            if let Some(h) = true_microtriangle_hit(&shell, 0.0, 1.0, t_min)
                && best.is_none_or(|b| h.t < b)
            {
                best = Some(h.t);
            }
        }
        best
    }

    /// The nearest true hit at `t >= t_min` on the 3 x 3 texels around `texel` in the prism
    /// of `triangle`; where there is none (a hit on a base triangle's edge may be truly in the
    /// neighbouring prism: the tracer's prisms overlap there by a rounding bound), in the
    /// prisms sharing a vertex with it, at the same texels.
    pub(super) fn hit_around(
        &self,
        ray: &Ray<T>,
        triangle: usize,
        texel: [i32; 2],
        t_min: f64,
    ) -> Option<f64> {
        let in_prism = |tri: usize| {
            let mut best: Option<f64> = None;
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let t = self.texel_hit(ray, tri, [texel[0] + dx, texel[1] + dy], t_min);
                    if let Some(t) = t
                        && best.is_none_or(|b| t < b)
                    {
                        best = Some(t);
                    }
                }
            }
            best
        };
        in_prism(triangle).or_else(|| {
            self.neighbours[triangle]
                .iter()
                .filter_map(|&other| in_prism(other))
                .min_by(f64::total_cmp)
        })
    }

    /// How the tracer's hit compares with the true surface there (see [`GhostCount`]); the
    /// hit texel alone settles almost every hit.
    pub(super) fn judge(&self, ray: &Ray<T>, hit: &nlrt_accel::SurfaceHit<T>) -> HitJudgement {
        let (triangle, texel, t) = (hit.triangle as usize, hit.texel, hit.hit.t.to_f64());
        let t_min = t * (1.0 - LEAK_TOLERANCE);
        if let nlrt_accel::TexelPart::Wall { edge } = hit.part {
            // A seam wall is no microtriangle: its hit is confirmed when the reported point is
            // on the wall and on the ray, and no true microtriangle hit around is nearer.
            return match self.hit_around(ray, triangle, texel, 0.0) {
                Some(truth) if truth < t_min => HitJudgement::TooFar,
                _ if self.on_wall(ray, hit, usize::from(edge)) => HitJudgement::Confirmed,
                _ if self.on_surface(ray, hit) => HitJudgement::Grazing,
                _ => HitJudgement::Ghost,
            };
        }
        let close = |truth: Option<f64>| truth.is_some_and(|x| x <= t * (1.0 + LEAK_TOLERANCE));
        if close(self.texel_hit(ray, triangle, texel, t_min))
            || close(self.hit_around(ray, triangle, texel, t_min))
        {
            return HitJudgement::Confirmed;
        }
        match self.hit_around(ray, triangle, texel, 0.0) {
            Some(truth) if truth < t_min => HitJudgement::TooFar,
            _ if self.on_surface(ray, hit) => HitJudgement::Grazing,
            _ => HitJudgement::Ghost,
        }
    }

    /// Whether a seam-wall hit lies on its wall, within [`LEAK_TOLERANCE`]: its canonical
    /// point on base edge `edge`, its height between the two sides' surface heights at its
    /// edge parameter, and its shell point (Eq. 1) on the ray within the tolerance times the
    /// distance. Evaluated in f64 on the tracer's values (as [`TrueSurface::on_surface`]).
    pub(super) fn on_wall(
        &self,
        ray: &Ray<T>,
        hit: &nlrt_accel::SurfaceHit<T>,
        edge: usize,
    ) -> bool {
        let tol = LEAK_TOLERANCE;
        let prism = self.surface.prism(hit.triangle as usize);
        let (a, b, h) = (
            hit.hit.alpha.to_f64(),
            hit.hit.beta.to_f64(),
            hit.hit.h.to_f64(),
        );
        let across = [a, b, 1.0 - a - b][edge];
        if across.abs() > tol {
            return false;
        }
        let s = nlrt_accel::edge_parameter(edge, a, b);
        let Some([h_a, h_b]) = self.surface.seam_heights(hit.triangle as usize, edge, s) else {
            return false;
        };
        if !(h >= h_a.min(h_b) - tol && h <= h_a.max(h_b) + tol) {
            return false;
        }
        shell_point_on_ray(&prism, ray, a, b, h, hit.hit.t.to_f64())
    }

    /// Whether the point the tracer reports lies on the true surface, within
    /// [`LEAK_TOLERANCE`] times the distance: its canonical coordinates `(alpha, beta)` in the
    /// base triangle and `h` in `[0, 1]`, its shell point (Eq. 1) on the ray, and a point of
    /// the true surface within that world distance of it ([`distance_to_surface`]), the
    /// measure the on-ray test and the confirmed hits use. Evaluated in f64 on the tracer's
    /// values, whose rounding (1e-16 relative) is far below the tolerance.
    ///
    /// The distance, not the difference between the point's height and the surface's at its
    /// texture coordinates: on a steep wall (the fur's hairs rise a unit height within a
    /// texel or two) a point a thousandth of a texel beside the wall lies several thousandths
    /// of a unit above the surface below it, far beyond the tolerance in height, while it is
    /// a millionth of the distance from the wall.
    pub(super) fn on_surface(&self, ray: &Ray<T>, hit: &nlrt_accel::SurfaceHit<T>) -> bool {
        let tol = LEAK_TOLERANCE;
        let triangle = hit.triangle as usize;
        let prism = self.surface.prism(triangle);
        let (a, b, h) = (
            hit.hit.alpha.to_f64(),
            hit.hit.beta.to_f64(),
            hit.hit.h.to_f64(),
        );
        let weights = [1.0 - a - b, a, b];
        if weights.iter().any(|&w| w < -tol) || !(-tol..=1.0 + tol).contains(&h) {
            return false;
        }
        let t = hit.hit.t.to_f64();
        if !shell_point_on_ray(&prism, ray, a, b, h, t) {
            return false;
        }
        let reach = tol * t * DVec3::from(to_f64::<T>(ray.dir)).length();
        distance_to_surface(&prism, self.surface.field(), a, b, h) <= reach
    }
}

/// The shell point `S(alpha, beta, h)` of `prism` (Eq. 1) in f64 on the prism's values.
pub(super) fn shell_point<T: Real>(
    prism: &nlrt_shellmap::Prism<T>,
    alpha: f64,
    beta: f64,
    h: f64,
) -> DVec3 {
    let v3 = |v: T::Vec3| DVec3::from(to_f64::<T>(v));
    let weights = [1.0 - alpha - beta, alpha, beta];
    (0..3)
        .map(|k| (v3(prism.p[k]) + v3(prism.n[k]) * h) * weights[k])
        .sum()
}

/// An upper bound on the world distance from the shell point `(alpha, beta, h)` of `prism`
/// to its displaced surface on the texels within [`SURFACE_REACH`] of the point's texture
/// coordinates, within the base triangle. The shell mapping
/// (Eq. 1) is quadratic over each microtriangle (the height and the interpolated normal are
/// both affine in its barycentric coordinates), so per microtriangle: the nearest point of
/// the flat triangle through its corners' shell points, then [`NEAREST_STEPS`] times the
/// nearest point of the mapping's tangent triangle there (its linearisation at the point,
/// taken at the corners: Gauss-Newton kept inside the microtriangle), each candidate
/// evaluated on the surface in f64. Every point evaluated lies on the surface, so the
/// bound holds however far the steps are from converging; the surface point at the point's
/// own canonical coordinates is one more (the only one on a prism whose texture triangle is
/// degenerate). `f64::INFINITY` where none of them lies in the base triangle.
pub(super) fn distance_to_surface<T: Real>(
    prism: &nlrt_shellmap::Prism<T>,
    field: &nlrt_accel::HeightField,
    alpha: f64,
    beta: f64,
    h: f64,
) -> f64 {
    let point = shell_point(prism, alpha, beta, h);
    let side = field.grid_side() as f64;
    let corner = |k: usize| DVec2::new(prism.uv[k].x().to_f64(), prism.uv[k].y().to_f64()) * side;
    let (c0, e1, e2) = (corner(0), corner(1) - corner(0), corner(2) - corner(0));
    let at = c0 + e1 * alpha + e2 * beta;
    // The surface point at the point's own canonical coordinates (the one above or below it
    // along the prism's height): a bound on any prism, one whose texture triangle is
    // degenerate included, which the search below cannot invert.
    let in_base = alpha >= 0.0 && beta >= 0.0 && alpha + beta <= 1.0;
    let mut best = if in_base {
        let (height, _) = field.height_at(at.x, at.y);
        (shell_point(prism, alpha, beta, height) - point).length()
    } else {
        f64::INFINITY
    };
    let det = e1.perp_dot(e2);
    if det == 0.0 || !det.is_finite() {
        return best;
    }
    // Canonical coordinates of texel coordinates, and whether they lie in the base triangle.
    let canonical = |x: DVec2| {
        let r = x - c0;
        (r.perp_dot(e2) / det, e1.perp_dot(r) / det)
    };
    let inside = |(a, b): (f64, f64)| a >= 0.0 && b >= 0.0 && a + b <= 1.0;
    let (tx, ty) = (at.x.floor(), at.y.floor());
    let unit = f64::from(nlrt_accel::HEIGHT_ONE);
    for dy in -SURFACE_REACH..=SURFACE_REACH {
        for dx in -SURFACE_REACH..=SURFACE_REACH {
            let (x, y) = (tx + f64::from(dx), ty + f64::from(dy));
            let heights = field
                .texel_corners(x as i64, y as i64)
                .map(|s| f64::from(s) / unit);
            let corners = [
                DVec2::new(x, y),
                DVec2::new(x + 1.0, y),
                DVec2::new(x, y + 1.0),
                DVec2::new(x + 1.0, y + 1.0),
            ];
            // The two microtriangles, as `HeightField::height_at` splits the texel.
            for part in [[0, 1, 3], [0, 2, 3]] {
                let uv = part.map(|k| corners[k]);
                let hs = part.map(|k| heights[k]);
                // The surface point at barycentric weights `w` of the microtriangle, if it lies
                // in the base triangle (there the shell point is this prism's surface).
                let surface = |w: [f64; 3]| {
                    let ab = canonical(uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2]);
                    let height = hs[0] * w[0] + hs[1] * w[1] + hs[2] * w[2];
                    (shell_point(prism, ab.0, ab.1, height), inside(ab))
                };
                let vertices = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
                let mut triangle = vertices.map(|v| surface(v).0);
                for _ in 0..=NEAREST_STEPS {
                    let w = nearest_on_triangle(point, triangle);
                    let (q, in_base) = surface(w);
                    if in_base {
                        best = best.min((q - point).length());
                    }
                    // The tangent triangle at `w`: `q + DS (e_k - w)`, the derivative along
                    // `e_k - w` exact by central differences (the mapping is quadratic).
                    triangle = vertices.map(|e| {
                        let (ahead, _) = surface(e);
                        let (behind, _) = surface([0, 1, 2].map(|i| 2.0 * w[i] - e[i]));
                        q + (ahead - behind) * 0.5
                    });
                }
            }
        }
    }
    best
}

/// Texels each way from the point's own that [`distance_to_surface`] searches: the 3 x 3
/// texels around the reported texel, which the point may lie just outside of, all lie within
/// two of the point's.
pub(super) const SURFACE_REACH: i32 = 2;

/// Tangent-triangle steps of [`distance_to_surface`] after the flat triangle's: the mapping
/// bends a microtriangle by a small fraction of its size, so each step gains several
/// digits; four take it far below the tolerance's scale.
pub(super) const NEAREST_STEPS: usize = 4;

/// Barycentric weights of the point of triangle `[a, b, c]` nearest to `p` (its Voronoi
/// regions: a vertex, an edge, or the face); a degenerate triangle gives non-finite weights.
pub(super) fn nearest_on_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> [f64; 3] {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return [0.0, 1.0, 0.0];
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return [1.0 - v, v, 0.0];
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return [0.0, 0.0, 1.0];
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return [1.0 - w, 0.0, w];
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return [0.0, 1.0 - w, w];
    }
    let (v, w) = (vb / (va + vb + vc), vc / (va + vb + vc));
    [1.0 - v - w, v, w]
}

/// Whether the shell point `(alpha, beta, h)` of `prism` (Eq. 1, in f64 on the tracer's
/// values) lies on `ray` at distance `t`, within [`LEAK_TOLERANCE`] times the distance.
pub(super) fn shell_point_on_ray<T: Real>(
    prism: &nlrt_shellmap::Prism<T>,
    ray: &Ray<T>,
    alpha: f64,
    beta: f64,
    h: f64,
    t: f64,
) -> bool {
    let v3 = |v: T::Vec3| DVec3::from(to_f64::<T>(v));
    let on_ray = v3(ray.origin) + v3(ray.dir) * t;
    (shell_point(prism, alpha, beta, h) - on_ray).length()
        <= LEAK_TOLERANCE * t * v3(ray.dir).length()
}

/// The oracle's verdict on one hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum HitJudgement {
    Confirmed,
    Grazing,
    Ghost,
    TooFar,
}
