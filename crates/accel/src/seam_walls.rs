//! Seam walls (`SeamRule::Closed`): where a base edge is a uv or normal seam, the two sides'
//! displaced surfaces are joined by a wall over the edge between their heights; its hits, and
//! the heights each side has along the edge.

use nlrt_poly::{Real, Vector2, solve_quadratic_in};
use nlrt_shellmap::{BaseEdges, Hit, NonlinearRay, Prism, alpha_beta_eq11};

use crate::displacement::{DisplacedSurface, WALL_PLANES};
use crate::leaving::Exclusion;
use crate::seam::{EDGE_VERTICES, NO_SEAM, edge_parameter};
use crate::surface_hit::{SurfaceHit, TexelPart};

impl<T: Real> DisplacedSurface<T> {
    /// `hit`, or a nearer hit on a seam wall of triangle `tri` (only with
    /// [`SeamRule::Closed`](crate::SeamRule::Closed) on a mesh with seams: elsewhere this is one length test).
    #[inline(always)]
    pub(crate) fn nearer_wall_hit(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        range: [T; 2],
        excluded: Option<Exclusion>,
        hit: Option<SurfaceHit<T>>,
    ) -> Option<SurfaceHit<T>> {
        if !self.has_walls {
            return hit;
        }
        self.nearer_wall_hit_of_seams(tri, prism, ray, range, excluded, hit)
    }

    /// [`DisplacedSurface::nearer_wall_hit`] on a mesh with seams closed by walls; kept out
    /// of line so that the common case, no seams, costs the hot loop one test of a flag.
    #[inline(never)]
    fn nearer_wall_hit_of_seams(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        [t_min, t_max]: [T; 2],
        excluded: Option<Exclusion>,
        hit: Option<SurfaceHit<T>>,
    ) -> Option<SurfaceHit<T>> {
        let Some(walls) = self.seams.of_triangle(tri) else {
            return hit;
        };
        if walls.iter().all(|&w| w == NO_SEAM) {
            return hit;
        }
        let t_max = hit.map_or(t_max, |h| h.hit.t);
        self.wall_hit(tri, walls, prism, ray, [t_min, t_max], excluded)
            .or(hit)
    }

    /// The nearest hit with `t` in `[t_min, t_max]` on the seam walls of triangle `tri`
    /// (`walls`: its edges' seam indices). The ray crosses base edge `k`'s side wall where the
    /// edge's quadratic vanishes (`BaseEdges`); the wall is there when the crossing's height
    /// lies between the two sides' surface heights at its edge parameter. Both prisms of a
    /// seam test it, each from its own crossing, and each conservatively: the crossing's
    /// height is known within the base-edge window `w` (which bounds its rounding), its edge
    /// parameter within the parameters at `h - w` and `h + w`, and the two surfaces'
    /// heights within their values there plus their slope times that spread
    /// ([`DisplacedSurface::wall_covers`]); a ray is stopped if any height it may have there
    /// lies on the wall. So no ray slips through between a wall and the surfaces it joins.
    /// The wall piece `excluded` (the one a ray leaves) is not hit.
    fn wall_hit(
        &self,
        tri: usize,
        walls: &[u32; 3],
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        [t_min, t_max]: [T; 2],
        excluded: Option<Exclusion>,
    ) -> Option<SurfaceHit<T>> {
        let edges = BaseEdges::new(ray);
        let (mut best, mut t_max) = (None, t_max);
        // A little beyond the wall's height range [0, 1], so that a crossing which rounding
        // moved out of it is still found; `wall_covers` decides.
        let reach = T::from_f64(1.0 / 1024.0);
        for (k, &seam) in walls.iter().enumerate() {
            // `may_cross` is false only where no solve could find a root (its bound exceeds
            // the solver's): the same crossings, without a solve for most prisms.
            if seam == NO_SEAM || !edges.may_cross(k, -reach, T::ONE + reach) {
                continue;
            }
            for &h in solve_quadratic_in(edges.edges[k], -reach, T::ONE + reach).iter() {
                let abh = WALL_PLANES[k].map(T::from_i32);
                let Some((alpha, beta)) = alpha_beta_eq11(ray, &abh, h) else {
                    continue;
                };
                // Onto the edge segment (the crossing is on it up to rounding).
                let s = edge_parameter(k, alpha, beta).max(T::ZERO).min(T::ONE);
                let (alpha, beta) = match k {
                    0 => (T::ZERO, s),
                    1 => (s, T::ZERO),
                    _ => (T::ONE - s, s),
                };
                // And onto the wall's heights: it spans those of the surfaces it joins, in
                // [0, 1]; a crossing found within `reach` outside is kept by `wall_covers`
                // only where its window meets them, so it is reported at that end.
                let on_wall = h.max(T::ZERO).min(T::ONE);
                let t = ray.signed_distance(prism, alpha, beta, on_wall);
                // Cheap tests first: most crossings lie behind a hit already found.
                if !(t >= t_min && t <= t_max) {
                    continue;
                }
                let w = edges.window(k, h).min(T::ONE);
                if !self.wall_covers(tri, k, seam as usize, ray, h.to_f64(), w.to_f64()) {
                    continue;
                }
                let hit = Hit::at(prism, t, alpha, beta, on_wall);
                let texel = [hit.u, hit.v]
                    .map(|c| crate::tlas::texel_floor((c / self.texel_size).to_f64()));
                let part = TexelPart::Wall { edge: k as u8 };
                if excluded.is_some_and(|e| {
                    e.excludes(texel, part.index()) || e.skips_wall(seam, t.to_f64())
                }) {
                    continue;
                }
                t_max = t;
                best = Some(SurfaceHit {
                    hit,
                    triangle: tri as u32,
                    texel,
                    part,
                });
            }
        }
        best
    }

    /// Whether the seam wall on base edge `k` of triangle `tri` (seam `seam`) may hold the
    /// ray's crossing at height `h`, known within `w` (see [`DisplacedSurface::wall_hit`]).
    /// Evaluated in f64 on the tracer's values, whose own rounding (1e-16 relative) is
    /// covered by the `SLACK` below.
    fn wall_covers(
        &self,
        tri: usize,
        k: usize,
        seam: usize,
        ray: &NonlinearRay<T>,
        h: f64,
        w: f64,
    ) -> bool {
        // f64 rounding of the evaluations below, on values in [0, 1] (heights, edge
        // parameters): some 100 ulps of 1.
        const SLACK: f64 = 1e-14;
        let fma = <f64 as Real>::mul_add;
        let q = |c: &[T; 3], x: f64| fma(fma(c[2].to_f64(), x, c[1].to_f64()), x, c[0].to_f64());
        let parameter = |x: f64| {
            let d = q(&ray.d, x);
            let (alpha, beta) = (q(&ray.alpha, x) / d, q(&ray.beta, x) / d);
            let s = edge_parameter(k, alpha, beta);
            s.is_finite().then_some(s)
        };
        let Some(s) = parameter(h) else {
            return false;
        };
        let (mut s_lo, mut s_hi) = (s, s);
        for x in [h - w, h + w] {
            match parameter(x) {
                Some(v) => {
                    s_lo = s_lo.min(v);
                    s_hi = s_hi.max(v);
                }
                // A pole of Eq. 8 in the window: the parameter is unknown there.
                None => return true,
            }
        }
        let (s_lo, s_hi) = (s_lo - SLACK, s_hi + SLACK);
        if s_hi < 0.0 || s_lo > 1.0 {
            return false;
        }
        let (s_lo, s_hi) = (s_lo.max(0.0), s_hi.min(1.0));
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut slope = [0.0f64; 2];
        for x in [s_lo, s.clamp(0.0, 1.0), s_hi] {
            let Some(sides) = self.seam_heights_of(tri, k, seam, x) else {
                return false;
            };
            for (side, (height, local)) in sides.into_iter().enumerate() {
                lo = lo.min(height);
                hi = hi.max(height);
                slope[side] = slope[side].max(local);
            }
        }
        // Between the samples a surface moves by at most its slope times the spread.
        let spread = slope[0].max(slope[1]) * (s_hi - s_lo);
        let (lo, hi) = (lo - spread, hi + spread);
        h + w >= lo - SLACK && h - w <= hi + SLACK
    }

    /// The two sides' surface heights (in `[0, 1]`, f64) at parameter `s` of base edge `edge`
    /// of triangle `tri`, this triangle's first, when that edge is a seam; `None` otherwise.
    /// The seam wall there spans the heights between them ([`SeamRule::Closed`](crate::SeamRule::Closed)).
    #[must_use]
    pub fn seam_heights(&self, tri: usize, edge: usize, s: f64) -> Option<[f64; 2]> {
        let seam = *self.seams.of_triangle(tri)?.get(edge)?;
        if seam == NO_SEAM {
            return None;
        }
        self.seam_heights_of(tri, edge, seam as usize, s)
            .map(|sides| sides.map(|(height, _)| height))
    }

    /// [`DisplacedSurface::seam_heights`] of seam `seam`, each with a bound on its slope per
    /// unit of `s` (the texel's slope times the edge's length in texels).
    fn seam_heights_of(
        &self,
        tri: usize,
        k: usize,
        seam: usize,
        s: f64,
    ) -> Option<[(f64, f64); 2]> {
        let edge = self.seams.edges().get(seam)?;
        let own = edge
            .sides
            .iter()
            .position(|side| side.triangle as usize == tri && usize::from(side.edge) == k)?;
        let texels = self.field.grid_side() as f64;
        let side_height = |index: usize| {
            let side = edge.sides[index];
            let prism = self.prism(side.triangle as usize);
            let [i, j] = EDGE_VERTICES[usize::from(side.edge)];
            // `s` is this triangle's parameter; the other side's runs the other way when the
            // seam is reversed.
            let t = if edge.reversed && index != own {
                1.0 - s
            } else {
                s
            };
            let texel = |c: T| c.to_f64() * texels;
            let (a, b) = (prism.uv[i], prism.uv[j]);
            let (ax, ay) = (texel(Vector2::x(a)), texel(Vector2::y(a)));
            let (bx, by) = (texel(Vector2::x(b)), texel(Vector2::y(b)));
            let length = nlrt_poly::Real::sqrt((bx - ax) * (bx - ax) + (by - ay) * (by - ay));
            let (height, slope) = self.field.height_at(ax + (bx - ax) * t, ay + (by - ay) * t);
            (height, slope * length)
        };
        Some([side_height(own), side_height(1 - own)])
    }
}
