//! Smooth shell mapping by ray marching (Jeschke, Mantler and Wimmer 2007, sec. 4.2-4.3), on
//! the same prisms and height field as nonlinear tracing: per prism, the ray's entry and exit
//! points are mapped to canonical space (the height `w` by the bisection of sec. 4.2, 12
//! steps, then barycentrics in the triangle at that height), the ray is sampled linearly
//! between them in canonical space, and a sample whose world point strays from the ray by more
//! than an angle (the image-space error limit of sec. 4.3) is corrected onto the ray: the ray
//! is intersected with the triangle at the sample's height. The first sample inside the prism
//! and on or below the height field, and the binary search between it and the sample before,
//! give the hit.
//!
//! Differences from the paper, on purpose: entry and exit come from the exact ray-prism test
//! (the paper intersects the prism's convex hull; it notes that any points slightly outside
//! suffice); no 3D distance map (sec. 4.4), so the step is a fixed fraction of a texel, and
//! thin features narrower than a step can be missed, which the report measures.

use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Hit, Prism, PrismSpan, Ray, intersect_prism};

use nlrt_accel::{DisplacedSurface, SurfaceHit, TexelPart, TraversalStats};
use nlrt_shellmap::facing_unit;

use crate::DistanceMap;

/// Settings of [`Marching::intersect_marching`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MarchOptions {
    /// Samples per texel crossed in uv (at least 1; more misses fewer thin features).
    pub samples_per_texel: f64,
    /// Largest angle (radians) between the ray and the direction to a sample before it is
    /// corrected onto the ray (sec. 4.3's image-space error: about one pixel).
    pub max_angle: f64,
    /// Most samples per prism (a bound on the work of one ray).
    pub max_samples: usize,
}

impl Default for MarchOptions {
    fn default() -> Self {
        Self {
            samples_per_texel: 2.0,
            // A pixel of a 320-pixel-wide image with a 45 degree field of view.
            max_angle: 2.5e-3,
            max_samples: 8192,
        }
    }
}

/// Bisection steps for the height of a world point (sec. 4.2: "12 iterations").
const HEIGHT_BISECTIONS: usize = 12;
/// Binary-search steps refining a hit between two samples.
const REFINE_STEPS: usize = 10;

/// Canonical `(alpha, beta)` of world point `p` in the triangle of the shell at height `w`.
fn barycentric_at<T: Real>(prism: &Prism<T>, p: T::Vec3, w: T) -> Option<(T, T)> {
    let s0 = prism.vertex(0, w);
    let (e0, e1) = (prism.vertex(1, w) - s0, prism.vertex(2, w) - s0);
    let n = e0.cross(e1);
    let nn = n.dot(n);
    if !(nn > T::ZERO && nn.is_finite()) {
        return None;
    }
    let r = p - s0;
    Some((r.cross(e1).dot(n) / nn, e0.cross(r).dot(n) / nn))
}

/// Sec. 4.2: the height `w` of world point `p` by bisection on the sign of the distance to
/// the triangle at height `w`, then its barycentrics there.
fn world_to_canonical_bisect<T: Real>(prism: &Prism<T>, p: T::Vec3) -> Option<[T; 3]> {
    let side = |w: T| {
        let s0 = prism.vertex(0, w);
        let n = (prism.vertex(1, w) - s0).cross(prism.vertex(2, w) - s0);
        n.dot(p - s0)
    };
    // Keep the sign change in [lo, hi], compared with the lower end's sign; a point exactly
    // on the base or the top (zero distance there) is at that end.
    let (f0, f1) = (side(T::ZERO), side(T::ONE));
    let (mut lo, mut hi) = (T::ZERO, T::ONE);
    if f0 == T::ZERO {
        hi = T::ZERO;
    } else if f1 == T::ZERO {
        lo = T::ONE;
    } else {
        let above_lo = f0 > T::ZERO;
        for _ in 0..HEIGHT_BISECTIONS {
            let mid = (lo + hi) * T::HALF;
            if (side(mid) > T::ZERO) == above_lo {
                lo = mid;
            } else {
                hi = mid;
            }
        }
    }
    let w = (lo + hi) * T::HALF;
    let (alpha, beta) = barycentric_at(prism, p, w)?;
    Some([alpha, beta, w])
}

/// Sample steps for a segment crossing `cells` cells (texels, voxels): `samples_per_texel`
/// per cell, rounded up, at least 1 and at most `max_samples - 1` (capped before rounding, so
/// an infinite or NaN span from a degenerate prism becomes the cap instead of overflowing).
pub(crate) fn sample_count(cells: f64, opts: &MarchOptions) -> usize {
    let cap = opts.max_samples.max(2) - 1;
    let wanted = (cells * opts.samples_per_texel).min(cap as f64);
    let whole = wanted as usize; // ceil without std:
    let steps = if (whole as f64) < wanted {
        whole + 1
    } else {
        whole
    };
    steps.clamp(1, cap)
}

/// What [`DisplacedSurface::march_prism`] samples.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Marched<'a> {
    /// The smooth shell, fixed steps.
    Smooth,
    /// The smooth shell, steps lengthened by a distance map.
    DistanceMap(&'a DistanceMap),
    /// The curved shell (Coons patches), fixed steps.
    Curved,
}

/// Shell mapping by ray marching (Jeschke et al. 2007) on the paper's [`DisplacedSurface`]: smooth, curved, and accelerated by a distance map.
pub trait Marching<T: Real> {
    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` by smooth shell mapping with
    /// ray marching (Jeschke et al. 2007; see the module documentation).
    fn intersect_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;

    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` by curved shell mapping
    /// (Jeschke et al. 2007, sec. 3.2 and 4.5): marched like
    /// [`Marching::intersect_marching`], each sample's texture height by the paper's
    /// Eq. 2 ([`Prism::curved_texture_height`]) between the Coons-patch surfaces of heights 0
    /// and 1. The surface is `Phi_c(u, v, height(u, v))`, a different one from the smooth
    /// shell's: its parts that bend out of the prism (curvature beyond the height compression
    /// `w / 2 + 1 / 4`) are not found, as in the paper. The hit's `h` is the texture height;
    /// [`Marching::curved_normal`] gives its normal.
    fn intersect_curved_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;

    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` by smooth shell mapping with ray
    /// marching accelerated by the 3D distance map `map` of this surface's height field (sec.
    /// 4.4): where the sample's cell has an empty radius longer than the fixed step, the
    /// march jumps that far along its texture-space path; the last step before a hit is
    /// always a fixed one, so the hits are those of
    /// [`Marching::intersect_marching`] except where the correction of sec. 4.3 moved
    /// a sample off the path (as in the paper, the jumps are safe on the path, not off it),
    /// and where a feature is thinner than a step: the jumps shift the sampling phase, so
    /// either marcher may catch a thin tip the other steps over.
    fn intersect_sphere_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        map: &DistanceMap,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;

    /// The world-space unit normal at a hit of [`Marching::intersect_curved_marching`],
    /// facing against `dir`: that of the curved images of the hit microtriangle's corners
    /// (the flat triangle the pre-tessellated curved reference holds). On a uv-degenerate
    /// base triangle (no inverse of Eq. 2-3 for the corners) the normal of the shell's triangle
    /// at the hit's height instead. `None` where the shell degenerates.
    #[must_use]
    fn curved_normal(&self, hit: &SurfaceHit<T>, dir: T::Vec3) -> Option<T::Vec3>;
}

impl<T: Real> Marching<T> for DisplacedSurface<T> {
    fn intersect_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.per_prism_span(ray, t_min, t_max, stats, |tri, prism, span, stats| {
            self.march_prism(tri, prism, ray, span, opts, Marched::Smooth, stats)
        })
    }

    fn intersect_curved_marching(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.per_prism_span(ray, t_min, t_max, stats, |tri, prism, span, stats| {
            self.march_prism(tri, prism, ray, span, opts, Marched::Curved, stats)
        })
    }

    fn intersect_sphere_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        map: &DistanceMap,
        opts: &MarchOptions,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.per_prism_span(ray, t_min, t_max, stats, |tri, prism, span, stats| {
            self.march_prism(
                tri,
                prism,
                ray,
                span,
                opts,
                Marched::DistanceMap(map),
                stats,
            )
        })
    }

    fn curved_normal(&self, hit: &SurfaceHit<T>, dir: T::Vec3) -> Option<T::Vec3> {
        let prism = self.prism(hit.triangle as usize);
        let (t0, e0, e1) = (
            prism.uv[0],
            prism.uv[1] - prism.uv[0],
            prism.uv[2] - prism.uv[0],
        );
        let det = e0.x() * e1.y() - e0.y() * e1.x();
        if !(det != T::ZERO && det.is_finite()) {
            let layer = [0, 1, 2].map(|i| prism.vertex(i, hit.hit.h * T::HALF + T::HALF * T::HALF));
            let n = (layer[1] - layer[0]).cross(layer[2] - layer[0]);
            return facing_unit::<T>(n, dir);
        }
        let world = |u: T, v: T, h: T| {
            let (du, dv) = (u - t0.x(), v - t0.y());
            let alpha = (du * e1.y() - dv * e1.x()) / det;
            let beta = (e0.x() * dv - e0.y() * du) / det;
            prism.curved_shell_point(alpha, beta, h)
        };
        let ([u0, v0, u1, v1], [h00, h10, h01, h11]) =
            self.texel_geometry(hit.texel[0], hit.texel[1]);
        // The half of the texel that holds the hit (a flat texel reports no half).
        let (a, b) = ((hit.hit.u - u0) / (u1 - u0), (hit.hit.v - v0) / (v1 - v0));
        let corners = if a >= b {
            [world(u0, v0, h00), world(u1, v0, h10), world(u1, v1, h11)]
        } else {
            [world(u0, v0, h00), world(u1, v1, h11), world(u0, v1, h01)]
        };
        let n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        facing_unit::<T>(n, dir)
    }
}

/// The parts of [`Marching`] that other methods of this crate reuse.
pub(crate) trait SampledSurface<T: Real> {
    fn per_prism_span(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
        method: impl FnMut(
            usize,
            &Prism<T>,
            &PrismSpan<T>,
            &mut TraversalStats,
        ) -> Option<SurfaceHit<T>>,
    ) -> Option<SurfaceHit<T>>;

    fn sample_steps(&self, a: T::Vec2, b: T::Vec2, opts: &MarchOptions) -> usize;

    fn sampled_hit(&self, tri: usize, prism: &Prism<T>, c: [T; 3], t: T) -> SurfaceHit<T>;

    fn surface_height(&self, u: T, v: T) -> (T, [i32; 2], TexelPart);

    #[allow(clippy::too_many_arguments)]
    fn march_prism(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &Ray<T>,
        span: &PrismSpan<T>,
        opts: &MarchOptions,
        shell: Marched<'_>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;
}

impl<T: Real> SampledSurface<T> for DisplacedSurface<T> {
    fn per_prism_span(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
        mut method: impl FnMut(
            usize,
            &Prism<T>,
            &PrismSpan<T>,
            &mut TraversalStats,
        ) -> Option<SurfaceHit<T>>,
    ) -> Option<SurfaceHit<T>> {
        self.traverse_prisms(ray, t_min, t_max, |tri, prism, t_max| {
            stats.prism_tests += 1;
            let span = intersect_prism(prism, ray, t_min, t_max)?;
            let hit = method(tri, prism, &span, stats)?;
            (hit.hit.t > t_min && hit.hit.t < t_max).then_some((hit, hit.hit.t))
        })
    }

    fn sample_steps(&self, a: T::Vec2, b: T::Vec2, opts: &MarchOptions) -> usize {
        let texels =
            ((b.x() - a.x()).abs().max((b.y() - a.y()).abs()) / self.texel_size()).to_f64();
        sample_count(texels, opts)
    }

    fn sampled_hit(&self, tri: usize, prism: &Prism<T>, c: [T; 3], t: T) -> SurfaceHit<T> {
        let uv = prism.texture_uv(c[0], c[1]);
        let (_, texel, part) = self.surface_height(uv.x(), uv.y());
        SurfaceHit {
            hit: Hit::at(prism, t, c[0], c[1], c[2]),
            triangle: tri as u32,
            texel,
            part,
        }
    }

    fn surface_height(&self, u: T, v: T) -> (T, [i32; 2], TexelPart) {
        let (fu, fv) = (u / self.texel_size(), v / self.texel_size());
        let floor = |x: T| {
            let i = x.to_f64() as i32;
            // Saturating: a coordinate below i32's range (a degenerate prism) stays in it.
            if T::from_i32(i) > x {
                i.saturating_sub(1)
            } else {
                i
            }
        };
        let (x, y) = (floor(fu), floor(fv));
        let (a, b) = (fu - T::from_i32(x), fv - T::from_i32(y));
        let [h00, h10, h01, h11] = self
            .field()
            .texel_corners(i64::from(x), i64::from(y))
            .map(Self::height);
        let flat = h00 == h10 && h00 == h01 && h00 == h11;
        if flat {
            return (h00, [x, y], TexelPart::Flat);
        }
        if a >= b {
            // (0,0), (1,0), (1,1)
            (
                h00 + (h10 - h00) * a + (h11 - h10) * b,
                [x, y],
                TexelPart::Lower,
            )
        } else {
            // (0,0), (1,1), (0,1)
            (
                h00 + (h11 - h01) * a + (h01 - h00) * b,
                [x, y],
                TexelPart::Upper,
            )
        }
    }

    #[allow(clippy::too_many_arguments)]
    fn march_prism(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &Ray<T>,
        span: &PrismSpan<T>,
        opts: &MarchOptions,
        shell: Marched<'_>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let medium = HeightMedium {
            surface: self,
            shell,
        };
        let (c, t) = march_segment(prism, ray, span, opts, &medium, stats)?;
        Some(self.sampled_hit(
            tri,
            prism,
            [c[0], c[1], medium.texture_height(prism, &c)],
            t,
        ))
    }
}

/// What a marcher samples in a prism's canonical space: which points are solid, how many
/// fixed steps a segment needs, and how far it may jump through empty space.
pub(crate) trait Medium<T: Real> {
    /// Whether canonical point `c` (alpha, beta, h) of `prism` is solid.
    fn solid(&self, prism: &Prism<T>, c: &[T; 3]) -> bool;
    /// Fixed steps for the canonical segment from `start` to `end`.
    fn steps(&self, prism: &Prism<T>, start: &[T; 3], end: &[T; 3], opts: &MarchOptions) -> usize;
    /// The fraction of the segment from `current` to `end` that is known to be empty (0
    /// where nothing is known).
    fn empty_fraction(&self, _prism: &Prism<T>, _current: &[T; 3], _end: &[T; 3]) -> T {
        T::ZERO
    }
}

/// The height field as a marcher sees it.
struct HeightMedium<'a, T: Real> {
    surface: &'a DisplacedSurface<T>,
    shell: Marched<'a>,
}

impl<T: Real> HeightMedium<'_, T> {
    /// The sample's texture height: the smooth shell's height itself, or by Eq. 2 between the
    /// curved shell's bounding surfaces.
    fn texture_height(&self, prism: &Prism<T>, c: &[T; 3]) -> T {
        if matches!(self.shell, Marched::Curved) {
            prism.curved_texture_height(c[0], c[1], c[2])
        } else {
            c[2]
        }
    }
}

impl<T: Real> Medium<T> for HeightMedium<'_, T> {
    fn solid(&self, prism: &Prism<T>, c: &[T; 3]) -> bool {
        let p = prism.texture_uv(c[0], c[1]);
        self.texture_height(prism, c) <= self.surface.surface_height(p.x(), p.y()).0
    }

    fn steps(&self, prism: &Prism<T>, start: &[T; 3], end: &[T; 3], opts: &MarchOptions) -> usize {
        let uv = |c: &[T; 3]| prism.texture_uv(c[0], c[1]);
        self.surface.sample_steps(uv(start), uv(end), opts)
    }

    /// The distance map's empty radius (its cells: `cell_texels` texels in u and v,
    /// 1 / layers in height) over the segment's extent in cells.
    fn empty_fraction(&self, prism: &Prism<T>, current: &[T; 3], end: &[T; 3]) -> T {
        let Marched::DistanceMap(map) = self.shell else {
            return T::ZERO;
        };
        let size = self.surface.texel_size();
        let (a, b) = (
            prism.texture_uv(current[0], current[1]),
            prism.texture_uv(end[0], end[1]),
        );
        let r = map.radius_at(a.x() / size, a.y() / size, current[2]);
        if r == 0 {
            return T::ZERO;
        }
        let cell = size * T::from_i32(map.cell_texels() as i32);
        let extent = ((b.x() - a.x()).abs() / cell)
            .max((b.y() - a.y()).abs() / cell)
            .max((end[2] - current[2]).abs() * T::from_i32(map.layers() as i32));
        T::from_i32(i32::from(r)) / extent
    }
}

/// Marches `ray` through `prism` over `span` in canonical space (sec. 4.2-4.3, see the module
/// documentation): the refined canonical point of the first solid sample and its distance.
pub(crate) fn march_segment<T: Real>(
    prism: &Prism<T>,
    ray: &Ray<T>,
    span: &PrismSpan<T>,
    opts: &MarchOptions,
    medium: &impl Medium<T>,
    stats: &mut TraversalStats,
) -> Option<([T; 3], T)> {
    let world = |t: T| ray.origin + ray.dir * t;
    // Entry and exit heights by sec. 4.2's bisection, except where the prism test saw the
    // ray cross a cap (height exactly 0 or 1): there the cap's height is known, and the
    // bisection's 2^-13 would lift an exit through the base above a zero-height surface, so
    // the ray would leave without hitting it.
    let canonical = |t: T, h: T| {
        if h == T::ZERO || h == T::ONE {
            barycentric_at(prism, world(t), h).map(|(a, b)| [a, b, h])
        } else {
            world_to_canonical_bisect(prism, world(t))
        }
    };
    let start = canonical(span.t_in, span.h_in)?;
    let end = canonical(span.t_out, span.h_out)?;
    let count = medium.steps(prism, &start, &end, opts) + 1;
    let cos_limit = T::from_f64(opts.max_angle).cos();
    let inside = |c: &[T; 3]| c[0] >= T::ZERO && c[1] >= T::ZERO && c[0] + c[1] <= T::ONE;
    let lerp = |a: &[T; 3], b: &[T; 3], s: T| {
        [
            a[0] + (b[0] - a[0]) * s,
            a[1] + (b[1] - a[1]) * s,
            a[2] + (b[2] - a[2]) * s,
        ]
    };
    let mut previous = start;
    let mut current = start;
    // Fixed steps left to the exit (fractional after jumps through empty space).
    let mut remaining = T::from_i32(count as i32);
    for _ in 0..opts.max_samples.max(2) {
        if !(remaining > T::ZERO) {
            break;
        }
        stats.texel_tests += 1;
        // Linear step from the last (possibly corrected) sample towards the exit: one fixed
        // step, or the known empty space where that is longer.
        let mut fraction = T::ONE / remaining;
        let jump = medium.empty_fraction(prism, &current, &end);
        let jumped = jump > fraction;
        if jumped {
            fraction = jump;
        }
        let fraction = fraction.min(T::ONE);
        remaining = if fraction == T::ONE {
            T::ZERO
        } else if jumped {
            remaining * (T::ONE - fraction)
        } else {
            remaining - T::ONE
        };
        let mut sample = lerp(&current, &end, fraction);
        // Sec. 4.3: correct the sample onto the ray when its direction strays too far.
        let q = prism.shell_point(sample[0], sample[1], sample[2]);
        let to_q = q - ray.origin;
        let len = to_q.length();
        if len > T::ZERO && to_q.dot(ray.dir) < cos_limit * len {
            let s0 = prism.vertex(0, sample[2]);
            let n = (prism.vertex(1, sample[2]) - s0).cross(prism.vertex(2, sample[2]) - s0);
            let denom = n.dot(ray.dir);
            if denom != T::ZERO {
                let t = n.dot(s0 - ray.origin) / denom;
                if let Some((a, b)) = barycentric_at(prism, world(t), sample[2]) {
                    sample = [a, b, sample[2]];
                }
            }
        }
        // The paper's test: the first sample inside the prism and in the solid is a hit. So
        // the volume under a height field is solid: where a mesh border's open side is seen
        // (the mountain's edges), its side walls are hit, which the other methods (a
        // surface, not a solid) do not do; the report measures the difference.
        if inside(&sample) && medium.solid(prism, &sample) {
            // Binary search between the last sample outside and this one.
            let (mut lo, mut hi) = (previous, sample);
            for _ in 0..REFINE_STEPS {
                let mid = lerp(&lo, &hi, T::HALF);
                if medium.solid(prism, &mid) {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            let p = prism.shell_point(hi[0], hi[1], hi[2]);
            return Some((hi, (p - ray.origin).dot(ray.dir)));
        }
        previous = sample;
        current = sample;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_accel::{HeightField, Wrap};
    use nlrt_poly::glam::{DVec2, DVec3};

    #[test]
    fn bisection_finds_heights_to_its_resolution() {
        let prism = Prism::<f64>::new(
            [DVec3::ZERO, DVec3::X, DVec3::Y],
            [
                DVec3::new(0.1, 0.0, 1.0),
                DVec3::new(-0.1, 0.1, 0.9),
                DVec3::new(0.0, -0.1, 1.1),
            ],
            [DVec2::ZERO, DVec2::X, DVec2::Y],
        );
        let p = prism.shell_point(0.3, 0.2, 0.7);
        let c = world_to_canonical_bisect(&prism, p).unwrap();
        // 12 halvings of [0, 1]: within 2^-13 in height, and alpha/beta follow.
        assert!((c[2] - 0.7).abs() <= 1.0 / 8192.0, "{c:?}");
        assert!(
            (c[0] - 0.3).abs() < 1e-3 && (c[1] - 0.2).abs() < 1e-3,
            "{c:?}"
        );
    }

    #[test]
    fn a_flat_map_on_a_constant_normal_prism_is_hit_exactly_enough() {
        // Constant normals: the mapping is linear, the surface a plane at the stored height.
        let (surface, stored) = crate::test_util::flat_map_square(0.4);
        let opts = MarchOptions::default();
        crate::test_util::assert_slanted_rays_meet_height(stored, |ray| {
            let mut stats = TraversalStats::default();
            let hit = surface.intersect_marching(ray, 0.0, f64::INFINITY, &opts, &mut stats)?;
            Some(hit.hit.t)
        });
    }

    #[test]
    fn curved_marching_of_a_flat_prism_finds_the_compressed_height() {
        // Flat base, equal normals: the Coons patches are flat, only w' = w / 2 + 1 / 4 stays.
        let (surface, stored) = crate::test_util::flat_map_square(0.4);
        let opts = MarchOptions::default();
        crate::test_util::assert_slanted_rays_meet_height(stored / 2.0 + 0.25, |ray| {
            let mut stats = TraversalStats::default();
            let hit =
                surface.intersect_curved_marching(ray, 0.0, f64::INFINITY, &opts, &mut stats)?;
            assert!((hit.hit.h - stored).abs() < 2e-3, "{}", hit.hit.h);
            let n = surface.curved_normal(&hit, ray.dir).unwrap();
            assert!((n - DVec3::Z).length() < 1e-12, "{n}");
            Some(hit.hit.t)
        });
    }

    #[test]
    fn uv_degenerate_triangles_are_marched_too() {
        let mesh = crate::test_util::uv_line_triangle();
        let field = HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).unwrap();
        let surface = DisplacedSurface::new(mesh, field, 1.0, 1.0).unwrap();
        let ray = Ray::new(DVec3::new(0.2, 0.2, 2.0), DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let mut stats = TraversalStats::default();
        let exact = surface
            .intersect(&ray, 0.0, f64::INFINITY, &mut stats)
            .unwrap();
        let marched = surface
            .intersect_marching(
                &ray,
                0.0,
                f64::INFINITY,
                &MarchOptions::default(),
                &mut stats,
            )
            .unwrap();
        assert!((exact.hit.t - marched.hit.t).abs() < 1e-3);
    }
}

#[cfg(test)]
mod agreement {
    use super::*;
    use alloc::vec::Vec;
    use nlrt_accel::{HeightField, Wrap};
    use nlrt_poly::glam::DVec3;

    /// On a smooth map (features much wider than a sample step) over affine prisms (a plane
    /// with constant normals, the triangles' normals pointing down and up), marching finds
    /// the exact tracer's hits: distances within the refinement's resolution (2^-10 of a
    /// half-texel step, ~1e-5 here; 1e-3 leaves room for grazing rays).
    #[test]
    fn smooth_map_agrees_with_nonlinear_tracing() {
        let side = 64;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (i, j) = (
                    (k % side) as f32 / side as f32,
                    (k / side) as f32 / side as f32,
                );
                0.5 + 0.3 * (6.0 * i).sin() * (5.0 * j).cos()
            })
            .collect();
        let mesh = crate::test_util::unit_square(DVec3::Z, [[0, 2, 1], [0, 3, 2]]);
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp).unwrap();
        let surface = DisplacedSurface::new(mesh, field, 0.3, 1.0).unwrap();
        let mut bad = 0;
        for k in 0..400 {
            let (x, y) = ((k % 20) as f64 / 20.0, (k / 20) as f64 / 20.0);
            let o = DVec3::new(x - 0.5, y - 0.5, 1.0);
            let ray = Ray::new(o, DVec3::new(0.5, 0.4, -0.6)).unwrap();
            let mut st = TraversalStats::default();
            let a = surface
                .intersect(&ray, 0.0, f64::INFINITY, &mut st)
                .map(|h| h.hit.t);
            let b = surface
                .intersect_marching(&ray, 0.0, f64::INFINITY, &MarchOptions::default(), &mut st)
                .map(|h| h.hit.t);
            let ok = match (a, b) {
                (Some(a), Some(b)) => (a - b).abs() < 1e-3,
                (None, None) => true,
                _ => false,
            };
            if !ok {
                bad += 1;
            }
        }
        assert_eq!(bad, 0);
    }

    /// The distance map's jumps skip only empty space: on a smooth map the hits are the
    /// fixed-step marcher's crossings (bracketed by other samples, so equal to the binary search's resolution:
    /// 2^-10 of a half-texel step, ~1e-5 here; 1e-4 is still far below a texel, 0.016), with
    /// fewer samples; over a wrapped, tiled map too.
    #[test]
    fn distance_map_jumps_find_the_fixed_step_hits_with_fewer_samples() {
        let side = 64;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (i, j) = ((k % side) as f32, (k / side) as f32);
                // Periodic and smooth (features wider than a step: no sampling-phase misses).
                let bump = (-((i - 20.0).powi(2) + (j - 40.0).powi(2)) / 30.0).exp();
                let tau = core::f32::consts::TAU / side as f32;
                let waves = (1.0 + (3.0 * tau * i).sin()) * (1.0 + (2.0 * tau * j).cos());
                0.05 + 0.6 * bump + 0.06 * waves
            })
            .collect();
        for (wrap, tiling) in [(Wrap::Clamp, 1.0), (Wrap::Repeat, 3.0)] {
            let mesh = crate::test_util::unit_square(DVec3::Z, [[0, 2, 1], [0, 3, 2]]);
            let field = HeightField::from_unit_heights(side, side, &heights, wrap).unwrap();
            let map = crate::DistanceMap::new(&field, 16, 16);
            let surface = DisplacedSurface::new(mesh, field, 0.3, tiling).unwrap();
            let opts = MarchOptions::default();
            let (mut fixed_samples, mut jump_samples, mut hits) = (0, 0, 0);
            for k in 0..900 {
                let (x, y) = ((k % 30) as f64 / 30.0, (k / 30) as f64 / 30.0);
                let o = DVec3::new(x - 0.4, y - 0.3, 0.8);
                let ray = Ray::new(o, DVec3::new(0.5, 0.4, -0.7)).unwrap();
                let (mut a_st, mut b_st) = (TraversalStats::default(), TraversalStats::default());
                let a = surface
                    .intersect_marching(&ray, 0.0, f64::INFINITY, &opts, &mut a_st)
                    .map(|h| h.hit.t);
                let b = surface
                    .intersect_sphere_traced(&ray, 0.0, f64::INFINITY, &map, &opts, &mut b_st)
                    .map(|h| h.hit.t);
                match (a, b) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a - b).abs() < 1e-4, "ray {k}: {a} vs {b}");
                    }
                    (None, None) => {}
                    _ => panic!("ray {k}: {a:?} vs {b:?}"),
                }
                fixed_samples += a_st.texel_tests;
                jump_samples += b_st.texel_tests;
            }
            assert!(hits > 300, "{hits}");
            assert!(
                2 * jump_samples < fixed_samples,
                "{wrap:?}: {jump_samples} vs {fixed_samples}"
            );
        }
    }
}
