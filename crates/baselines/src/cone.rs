//! Cone tracing with correct silhouettes (Ouazzani Chahdi et al. 2021), as a per-prism method
//! on the same prisms and height field as nonlinear tracing.
//!
//! - Preprocessing: a *cone map*, per height sample the ratio (texels of radius per unit of
//!   height) of the widest upward cone with its apex at the sample that holds no higher sample
//!   (the conservative cones of Halli et al. 2008), and per base-mesh vertex the quadric
//!   `z = a x^2 + b y^2` of its neighbourhood in its tangent frame (the paper's Eq. 5-6).
//! - Per prism the ray enters, the march runs in the texture space of the entry point, in the
//!   relief-mapping convention of the paper (depth `1 - h`, 0 at the top of the shell): along
//!   the ray's linearisation at the entry point, bent by the interpolated quadric, so that the
//!   depth of a point at world distance `s` is `depth0 + g s + Q s^2` (the paper's Eq. 10 and
//!   12: the distance to the quadric along its normal). A convex base (`Q < 0`) bends the ray
//!   back out of the relief: where it returns to depth 0 the pixel belongs to the silhouette
//!   and the prism gives no hit.
//! - Step lengths by the cone of the texel under the current point (Eq. 4, generalised to a
//!   ray that may rise), with the quadric applied in one of the paper's two ways
//!   ([`Rectification`]); where the cone gives no step (the point is below the texel's top but
//!   above its surface) a fixed half-texel step; the crossing refined by binary search.
//!
//! Differences from the paper, on purpose: the march is bounded by the prism's exact entry
//! and exit (the paper marches from a rasterised fragment of the mesh with no bound but its
//! `t_max`); the quadric's depth is measured along the normal in both of the paper's cases
//! (its "inside" case, Eq. 7-9 and 11, measures it perpendicular to the ray instead); the
//! cones are conservative with a binary search after the first sample below the surface (the
//! relaxed cones' search); the hit's distance is that of the ray point where the march found
//! it. The cones are exact for the samples but the surface between samples is interpolated,
//! so a step may clip a texel's interpolated ridge; such misses, and the quadric's
//! approximation of the base, are measured by the report.

use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Hit, PrismSpan, Ray};

use nlrt_accel::{
    BaseMesh, DisplacedSurface, HEIGHT_ONE, HeightField, SurfaceHit, TraversalStats, Wrap,
};

use crate::march::SampledSurface;

/// The cone map of a height field: per sample the conservative cone ratio (see the module
/// documentation).
#[derive(Clone, Debug)]
pub struct ConeMap {
    side: usize,
    wrap: Wrap,
    /// `ratio[j * side + i]`: texels of cone radius per unit of height.
    ratio: Vec<f32>,
}

/// The side of a cone-mapped height field.
///
/// # Panics
/// On a map that is not square with a power-of-two side (cone maps are built over a square
/// max pyramid; `HeightField::square_side`).
fn square_side(field: &HeightField) -> usize {
    field
        .square_side()
        .expect("cone maps are built for square maps with a power-of-two side")
}

/// Pyramid of sample maxima: level 0 the samples, level `l` the maxima of `2^l` squares.
struct MaxPyramid {
    levels: Vec<Vec<u16>>,
}

impl MaxPyramid {
    fn new(field: &HeightField) -> Self {
        let side = square_side(field);
        let mut levels = vec![field.samples().to_vec()];
        let mut n = side;
        while n > 1 {
            let prev = levels.last().expect("level 0");
            let m = n / 2;
            let next = (0..m * m)
                .map(|k| {
                    let (x, y) = (2 * (k % m), 2 * (k / m));
                    prev[y * n + x]
                        .max(prev[y * n + x + 1])
                        .max(prev[(y + 1) * n + x])
                        .max(prev[(y + 1) * n + x + 1])
                })
                .collect();
            levels.push(next);
            n = m;
        }
        Self { levels }
    }
}

impl ConeMap {
    /// The cone map of `field` (all rows).
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap};
    /// use nlrt_baselines::ConeMap;
    /// // One spike of height 1 at (8, 8) on a flat map of height 0.5.
    /// let mut heights = vec![0.5; 16 * 16];
    /// heights[8 * 16 + 8] = 1.0;
    /// let field = HeightField::from_unit_heights(16, 16, &heights, Wrap::Clamp).unwrap();
    /// let cones = ConeMap::new(&field);
    /// // Three texels from the spike, which is half a unit higher: ratio 3 / 0.5.
    /// assert!((cones.ratio(5, 8) - 6.0).abs() < 1e-3);
    /// // Nothing is higher than the spike.
    /// assert!(cones.ratio(8, 8) > 1e6);
    /// ```
    ///
    /// # Panics
    /// On a map that is not square with a power-of-two side.
    #[must_use]
    pub fn new(field: &HeightField) -> Self {
        let builder = Self::builder(field);
        let mut ratio = vec![0.0; builder.len()];
        for (j, row) in ratio.chunks_mut(builder.row_len()).enumerate() {
            builder.fill_row(j, row);
        }
        builder.finish(ratio)
    }

    /// A builder whose rows can be filled in any order or in parallel (the work is
    /// `O(samples x log(side))`: seconds at 4096^2 on one core).
    ///
    /// # Panics
    /// On a map that is not square with a power-of-two side.
    #[must_use]
    pub fn builder(field: &HeightField) -> ConeMapBuilder<'_> {
        ConeMapBuilder {
            field,
            pyramid: MaxPyramid::new(field),
        }
    }

    /// The ratio of sample `(i, j)` (wrapped or clamped as the field is).
    #[must_use]
    pub fn ratio(&self, i: i64, j: i64) -> f32 {
        let n = self.side as i64;
        let index = |c: i64| match self.wrap {
            Wrap::Repeat => c.rem_euclid(n),
            Wrap::Clamp => c.clamp(0, n - 1),
        } as usize;
        self.ratio[index(j) * self.side + index(i)]
    }

    /// Bytes of the ratios.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.ratio.len() * core::mem::size_of::<f32>()
    }
}

/// Builds a [`ConeMap`] row by row ([`ConeMap::builder`]).
pub struct ConeMapBuilder<'a> {
    field: &'a HeightField,
    pyramid: MaxPyramid,
}

impl ConeMapBuilder<'_> {
    /// Samples of the map (the length of the buffer [`ConeMapBuilder::finish`] takes).
    #[must_use]
    pub fn len(&self) -> usize {
        square_side(self.field) * square_side(self.field)
    }

    /// Always false (maps have at least one sample).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        false
    }

    /// Samples per row.
    #[must_use]
    pub fn row_len(&self) -> usize {
        square_side(self.field)
    }

    /// The cone map from its rows, each filled by [`ConeMapBuilder::fill_row`].
    ///
    /// # Panics
    /// If `ratio` does not have [`ConeMapBuilder::len`] entries.
    #[must_use]
    pub fn finish(self, ratio: Vec<f32>) -> ConeMap {
        assert_eq!(ratio.len(), self.len(), "one ratio per sample");
        ConeMap {
            side: square_side(self.field),
            wrap: self.field.wrap(),
            ratio,
        }
    }

    /// Row `j` of the cone map: per sample, the smallest of `distance / (higher - own)`
    /// over blocks of the max pyramid in rings around it (level `l`: the blocks within 2 of
    /// the sample's block that the finer ring did not cover wholly, at their true distance; a
    /// block's maximum bounds its samples, so each bound is conservative), and beyond the
    /// coarsest ring (2 map sides away) the global maximum.
    pub fn fill_row(&self, j: usize, row: &mut [f32]) {
        let (field, pyramid) = (self.field, &self.pyramid);
        let side = square_side(field) as i64;
        let wrap = field.wrap();
        let global = pyramid.levels.last().expect("top")[0];
        let index = |c: i64, n: i64| match wrap {
            Wrap::Repeat => c.rem_euclid(n),
            Wrap::Clamp => c.clamp(0, n - 1),
        };
        for (i, out) in row.iter_mut().enumerate() {
            let (i, jj) = (i as i64, j as i64);
            let own = field.sample(i, jj);
            let mut best = f64::INFINITY;
            let mut consider = |distance: f64, higher: u16| {
                if higher > own {
                    let rise = f64::from(higher - own) / f64::from(HEIGHT_ONE);
                    best = best.min(distance / rise);
                }
            };
            for (level, heights) in pyramid.levels.iter().enumerate() {
                let size = 1i64 << level;
                let n = side >> level;
                let (bx, by) = (i >> level, jj >> level);
                // The finer ring: blocks of level - 1 within 2 of the sample's.
                let (fx, fy) = (i >> (level.max(1) - 1), jj >> (level.max(1) - 1));
                for dy in -2..=2 {
                    for dx in -2..=2 {
                        let (x, y) = (bx + dx, by + dy);
                        if level > 0 {
                            // Both children, 2b and 2b + 1, within [f - 2, f + 2].
                            let covered = |b: i64, f: i64| 2 * b >= f - 2 && 2 * b < f + 2;
                            if covered(x, fx) && covered(y, fy) {
                                continue;
                            }
                        } else if dx == 0 && dy == 0 {
                            continue;
                        }
                        // Distance from the sample to the block's sample positions.
                        let gap = |p: i64, lo: i64| {
                            let hi = lo + size - 1;
                            if p < lo {
                                lo - p
                            } else if p > hi {
                                p - hi
                            } else {
                                0
                            }
                        };
                        let (gx, gy) = (gap(i, x * size), gap(jj, y * size));
                        let distance = ((gx * gx + gy * gy) as f64).sqrt();
                        let h = heights[(index(y, n) * n + index(x, n)) as usize];
                        consider(distance, h);
                    }
                }
            }
            // Everything beyond the coarsest ring is at least 2 sides away.
            consider(2.0 * side as f64, global);
            // Rounded down to f32: the stored ratio stays a bound.
            let stored = best as f32;
            *out = if f64::from(stored) > best {
                stored.next_down()
            } else {
                stored
            };
        }
    }
}

/// Per vertex of a base mesh, the quadric `z = a x^2 + b y^2` fitted (least squares, the
/// paper's Eq. 6) to its neighbours in its tangent frame (`x` along the uv map's `u`
/// direction, `z` along the unit normal): the base's curvature for the silhouettes.
#[derive(Clone, Debug)]
pub struct VertexQuadrics<T: Real> {
    ab: Vec<[T; 2]>,
}

/// The unit vector along `v` minus its component along unit `n`, or `None`.
fn tangent_part<T: Real>(v: T::Vec3, n: T::Vec3) -> Option<T::Vec3> {
    let t = v - n * v.dot(n);
    let len = t.length();
    (len > T::ZERO && len.is_finite()).then(|| t * (T::ONE / len))
}

/// `dP/du` of a triangle with positions `p` and uvs `uv`; `None` where the uvs are degenerate.
fn position_gradient_u<T: Real>(p: [T::Vec3; 3], uv: [T::Vec2; 3]) -> Option<T::Vec3> {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (d1, d2) = (uv[1] - uv[0], uv[2] - uv[0]);
    let det = d1.x() * d2.y() - d1.y() * d2.x();
    if !(det != T::ZERO && det.is_finite()) {
        return None;
    }
    Some((e1 * d2.y() - e2 * d1.y()) * (T::ONE / det))
}

/// A tangent frame `(T, B, N)` for unit normal `n` with `T` along `du` where there is one.
fn frame<T: Real>(n: T::Vec3, du: Option<T::Vec3>) -> [T::Vec3; 3] {
    let t = du.and_then(|d| tangent_part::<T>(d, n)).unwrap_or_else(|| {
        // Any direction perpendicular to n: the axis least aligned with it.
        let axis = match n.max_abs_axis() {
            0 => T::Vec3::new(T::ZERO, T::ONE, T::ZERO),
            _ => T::Vec3::new(T::ONE, T::ZERO, T::ZERO),
        };
        tangent_part::<T>(axis, n).unwrap_or(axis)
    });
    [t, n.cross(t), n]
}

impl<T: Real> VertexQuadrics<T> {
    /// Fits the quadric of every vertex of `mesh`. A vertex whose neighbours do not determine
    /// both coefficients (all along one axis, or none) gets the isotropic fit `a = b`, and
    /// `a = b = 0` where that is undetermined too.
    #[must_use]
    pub fn new(mesh: &BaseMesh<T>) -> Self {
        let count = mesh.positions().len();
        let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); count];
        let mut du: Vec<T::Vec3> = vec![T::Vec3::new(T::ZERO, T::ZERO, T::ZERO); count];
        for t in 0..mesh.triangle_count() {
            let tri = mesh.triangle(t);
            let p = tri.map(|v| mesh.positions()[v as usize]);
            let uv = tri.map(|v| mesh.uvs()[v as usize]);
            let g = position_gradient_u::<T>(p, uv);
            for (k, &v) in tri.iter().enumerate() {
                if let Some(g) = g {
                    du[v as usize] = du[v as usize] + g;
                }
                for &w in &[tri[(k + 1) % 3], tri[(k + 2) % 3]] {
                    if !neighbours[v as usize].contains(&w) {
                        neighbours[v as usize].push(w);
                    }
                }
            }
        }
        let ab = (0..count)
            .map(|v| {
                let normal = mesh.normals()[v];
                let len = normal.length();
                if !(len > T::ZERO && len.is_finite()) {
                    return [T::ZERO; 2];
                }
                let n = normal * (T::ONE / len);
                let [tx, ty, tz] = frame::<T>(n, Some(du[v]));
                let (mut xx, mut xy, mut yy, mut xz, mut yz) =
                    (T::ZERO, T::ZERO, T::ZERO, T::ZERO, T::ZERO);
                for &w in &neighbours[v] {
                    let d = mesh.positions()[w as usize] - mesh.positions()[v];
                    let (x2, y2, z) = (d.dot(tx) * d.dot(tx), d.dot(ty) * d.dot(ty), d.dot(tz));
                    xx += x2 * x2;
                    xy += x2 * y2;
                    yy += y2 * y2;
                    xz += x2 * z;
                    yz += y2 * z;
                }
                let det = xx * yy - xy * xy;
                // Relative to the terms, below this the 2x2 system has lost all digits.
                if det > (xx * yy) * T::from_f64(1e-6) && det.is_finite() {
                    [(xz * yy - yz * xy) / det, (xx * yz - xy * xz) / det]
                } else {
                    let r = xx + T::TWO * xy + yy;
                    if r > T::ZERO && r.is_finite() {
                        let a = (xz + yz) / r;
                        [a, a]
                    } else {
                        [T::ZERO; 2]
                    }
                }
            })
            .collect();
        Self { ab }
    }

    /// All coefficients zero for `vertices` vertices: a flat base everywhere, which turns the
    /// silhouette correction off (the original cone tracing, for comparison).
    #[must_use]
    pub fn flat(vertices: usize) -> Self {
        Self {
            ab: vec![[T::ZERO; 2]; vertices],
        }
    }

    /// `(a, b)` of vertex `v`.
    #[must_use]
    pub fn coefficients(&self, v: usize) -> [T; 2] {
        self.ab[v]
    }

    /// Bytes of the coefficients.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.ab.len() * core::mem::size_of::<[T; 2]>()
    }
}

/// Where the quadric enters the march (the paper's two silhouette corrections; the hits are
/// tested alike, the step lengths differ).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rectification {
    /// Rectify the viewing ray (the paper's Alg. 3-4): the march follows the bent ray and
    /// steps by the cone at its bent point.
    Ray,
    /// Rectify the cone (Alg. 5-6): the march follows the straight ray and the cone's depth
    /// and radius are bent instead (`D' = D - Q s^2`, radius scaled by `D' / D`).
    Cone,
}

/// Settings of [`ConeTraced::intersect_cone_traced`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeOptions {
    /// The quadric's way into the march.
    pub rectification: Rectification,
    /// Most steps per prism.
    pub max_steps: usize,
}

impl Default for ConeOptions {
    fn default() -> Self {
        Self {
            rectification: Rectification::Ray,
            max_steps: 4096,
        }
    }
}

/// Everything cone tracing needs beside the surface: its cone map, quadrics and settings.
#[derive(Clone, Debug)]
pub struct ConeTracing<T: Real> {
    /// The height field's cone map.
    pub cones: ConeMap,
    /// The base mesh's vertex quadrics (the silhouette correction).
    pub quadrics: VertexQuadrics<T>,
    /// Settings.
    pub options: ConeOptions,
}

impl<T: Real> ConeTracing<T> {
    /// Builds the cone map and the quadrics of `surface` (one thread; see
    /// [`ConeMap::builder`] to fill the map's rows in parallel).
    ///
    /// # Panics
    /// On a map that is not square with a power-of-two side
    /// (`HeightField::square_side`).
    #[must_use]
    pub fn new(surface: &DisplacedSurface<T>, options: ConeOptions) -> Self {
        Self {
            cones: ConeMap::new(surface.field()),
            quadrics: VertexQuadrics::new(surface.mesh()),
            options,
        }
    }

    /// Bytes of the cone map and the quadrics.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.cones.memory_bytes() + self.quadrics.memory_bytes()
    }
}

/// Binary-search steps refining a crossing between two samples.
const REFINE_STEPS: usize = 10;

/// Cone tracing with correct silhouettes (Ouazzani Chahdi et al. 2021) on the paper's [`DisplacedSurface`].
pub trait ConeTraced<T: Real> {
    /// The nearest hit of `ray` with `t` in `(t_min, t_max)` by cone tracing with silhouettes
    /// (see the module documentation), with `cone` built from this surface's height field and
    /// mesh.
    fn intersect_cone_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        cone: &ConeTracing<T>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;
}

impl<T: Real> ConeTraced<T> for DisplacedSurface<T> {
    fn intersect_cone_traced(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        cone: &ConeTracing<T>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.per_prism_span(ray, t_min, t_max, stats, |tri, _, span, stats| {
            self.cone_trace_prism(tri, ray, span, cone, stats)
        })
    }
}

/// The steps of [`ConeTraced`].
pub(crate) trait ConeParts<T: Real> {
    fn cone_trace_prism(
        &self,
        tri: usize,
        ray: &Ray<T>,
        span: &PrismSpan<T>,
        cone: &ConeTracing<T>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>>;
}

impl<T: Real> ConeParts<T> for DisplacedSurface<T> {
    fn cone_trace_prism(
        &self,
        tri: usize,
        ray: &Ray<T>,
        span: &PrismSpan<T>,
        cone: &ConeTracing<T>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let (cones, quadrics, opts) = (&cone.cones, &cone.quadrics, &cone.options);
        let prism = self.prism(tri);
        // Entry point: its layer, barycentrics and the layer's barycentric gradient along
        // the ray (the linearisation of the map at the entry).
        let h0 = span.h_in;
        let s0 = prism.vertex(0, h0);
        let (e0, e1) = (prism.vertex(1, h0) - s0, prism.vertex(2, h0) - s0);
        let layer_normal = e0.cross(e1);
        let nn = layer_normal.dot(layer_normal);
        if !(nn > T::ZERO && nn.is_finite()) {
            return None;
        }
        let bary = |p: T::Vec3| {
            let r = p - s0;
            (
                r.cross(e1).dot(layer_normal) / nn,
                e0.cross(r).dot(layer_normal) / nn,
            )
        };
        let entry = ray.origin + ray.dir * span.t_in;
        let (a0, b0) = bary(entry);
        let (a1, b1) = bary(entry + ray.dir);
        let (da, db) = (a1 - a0, b1 - b0);
        // Tangent frame and thickness at the entry.
        let weights = [T::ONE - a0 - b0, a0, b0];
        let normal = prism.n[0] * weights[0] + prism.n[1] * weights[1] + prism.n[2] * weights[2];
        let thickness = normal.length();
        if !(thickness > T::ZERO && thickness.is_finite()) {
            return None;
        }
        let unit_normal = normal * (T::ONE / thickness);
        let du = prism_position_gradient_u(&prism);
        let [tx, ty, tz] = frame::<T>(unit_normal, du);
        let vertices = self.mesh().triangle(tri);
        let ab = vertices
            .iter()
            .zip(weights)
            .fold([T::ZERO; 2], |acc, (&v, w)| {
                let c = quadrics.coefficients(v as usize);
                [acc[0] + c[0] * w, acc[1] + c[1] * w]
            });
        let (vx, vy) = (ray.dir.dot(tx), ray.dir.dot(ty));
        // Depth (1 - h) per world unit along the ray and its quadric bending, Eq. 10/12:
        // depth below z = a x^2 + b y^2 is (a vx^2 + b vy^2) s^2 - vz s, over the thickness.
        let slope = -ray.dir.dot(tz) / thickness;
        let bend = (ab[0] * vx * vx + ab[1] * vy * vy) / thickness;
        let depth0 = T::ONE - h0;
        let length = span.t_out - span.t_in;
        let uv_of = |a: T, b: T| {
            let uv = prism.texture_uv(a, b);
            (uv.x() / self.texel_size(), uv.y() / self.texel_size())
        };
        let (x0, y0) = uv_of(a0, b0);
        let (x1, y1) = uv_of(a0 + da, b0 + db);
        let (gx, gy) = (x1 - x0, y1 - y0);
        let speed_xy = (gx * gx + gy * gy).sqrt();
        let half_texel = T::HALF / gx.abs().max(gy.abs()).max(T::EPSILON);
        let straight = |s: T| depth0 + slope * s;
        let bent = |s: T| straight(s) + bend * s * s;
        // Surface depth and the cone (apex depth = the texel's top, ratio = the least of its
        // corners') at world distance s.
        // floor to i32, as the texel lookups of the height field do: a huge or non-finite
        // coordinate (a degenerate prism's linearisation) saturates, and the neighbours at +1
        // stay in i64's range.
        let floor = |x: T| {
            let i = x.to_f64() as i32;
            i64::from(if f64::from(i) > x.to_f64() {
                i.saturating_sub(1)
            } else {
                i
            })
        };
        let surface_depth = |s: T| {
            let (u, v) = (a0 + da * s, b0 + db * s);
            let uv = prism.texture_uv(u, v);
            T::ONE - self.surface_height(uv.x(), uv.y()).0
        };
        // The cones of the four samples around the point at world distance s: their
        // horizontal distance from it, apex depth and ratio.
        let cones_at = |s: T| {
            let (x, y) = (x0 + gx * s, y0 + gy * s);
            let (i, j) = (floor(x), floor(y));
            let corners = self.field().texel_corners(i, j);
            let at = [(i, j), (i + 1, j), (i, j + 1), (i + 1, j + 1)];
            core::array::from_fn::<_, 4, _>(|k| {
                let (a, b) = at[k];
                let (dx, dy) = (x - T::from_f64(a as f64), y - T::from_f64(b as f64));
                let ratio = T::from_f64(f64::from(cones.ratio(a, b)));
                (
                    (dx * dx + dy * dy).sqrt(),
                    T::ONE - Self::height(corners[k]),
                    ratio,
                )
            })
        };
        let below = |s: T| bent(s) >= surface_depth(s);
        let mut previous = T::ZERO;
        let mut s = T::ZERO;
        for _ in 0..opts.max_steps {
            stats.texel_tests += 1;
            if bent(s) < T::ZERO && s > T::ZERO {
                // Back above the top of the relief: a silhouette, no hit in this prism.
                return None;
            }
            if below(s) {
                let (mut lo, mut hi) = (previous, s);
                for _ in 0..REFINE_STEPS {
                    let mid = (lo + hi) * T::HALF;
                    if below(mid) {
                        hi = mid;
                    } else {
                        lo = mid;
                    }
                }
                let (a, b) = (a0 + da * hi, b0 + db * hi);
                let uv = prism.texture_uv(a, b);
                let (_, texel, part) = self.surface_height(uv.x(), uv.y());
                return Some(SurfaceHit {
                    hit: Hit::at(&prism, span.t_in + hi, a, b, T::ONE - bent(hi)),
                    triangle: tri as u32,
                    texel,
                    part,
                });
            }
            if s >= length {
                return None;
            }
            // Eq. 4, for a cone whose apex is `offset` away horizontally and a ray whose
            // depth changes at `rate` per unit s: it stays in the cone while
            // offset + speed_xy ds <= ratio (apex - depth - rate ds). Any one of the four
            // cones that holds the point gives a step that meets no sample.
            let mut step = half_texel;
            for (offset, apex, ratio) in cones_at(s) {
                // The cone and the point's depth as the rectification sees them.
                let (apex, ratio, depth, rate) = match opts.rectification {
                    Rectification::Ray => (apex, ratio, bent(s), slope + T::TWO * bend * s),
                    Rectification::Cone => {
                        let bent_apex = apex - bend * s * s;
                        let scaled = if apex > T::ZERO {
                            ratio * (bent_apex / apex).max(T::ZERO)
                        } else {
                            ratio
                        };
                        (bent_apex, scaled, straight(s), slope)
                    }
                };
                let room = ratio * (apex - depth) - offset;
                if !(room > T::ZERO) {
                    continue;
                }
                let denominator = speed_xy + ratio * rate;
                let cone_step = if denominator > T::ZERO {
                    room / denominator
                } else {
                    length - s
                };
                step = step.max(cone_step);
            }
            previous = s;
            s = (s + step).min(length);
        }
        None
    }
}

/// `dP/du` of a prism's base triangle; `None` for degenerate uvs.
fn prism_position_gradient_u<T: Real>(prism: &nlrt_shellmap::Prism<T>) -> Option<T::Vec3> {
    position_gradient_u::<T>(prism.p, prism.uv)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::{DVec2, DVec3};

    fn wavy(side: usize) -> Vec<f32> {
        (0..side * side)
            .map(|k| {
                let (x, y) = ((k % side) as f32, (k / side) as f32);
                (0.5 + 0.4 * (x * 0.9).sin() * (y * 0.7).cos()).powi(2)
            })
            .collect()
    }

    /// Brute force over every copy of every sample within 3 map sides (the tiled or clamped
    /// plane): no higher sample inside the stored cone, and the stored ratio within 4x of the
    /// exact one for most samples (the rings trade accuracy for `O(log side)` work).
    #[test]
    fn cone_ratios_are_conservative_and_useful() {
        let side = 16i64;
        for wrap in [Wrap::Repeat, Wrap::Clamp] {
            let field = HeightField::from_unit_heights(16, 16, &wavy(16), wrap).unwrap();
            let cones = ConeMap::new(&field);
            let mut tight = 0;
            for j in 0..side {
                for i in 0..side {
                    let own = field.sample(i, j);
                    let mut exact = f64::INFINITY;
                    for y in -3 * side..4 * side {
                        for x in -3 * side..4 * side {
                            let h = field.sample(x, y);
                            if h > own {
                                let d = (((x - i).pow(2) + (y - j).pow(2)) as f64).sqrt();
                                let rise = f64::from(h - own) / f64::from(HEIGHT_ONE);
                                exact = exact.min(d / rise);
                            }
                        }
                    }
                    let stored = f64::from(cones.ratio(i, j));
                    assert!(stored <= exact, "{wrap:?} ({i}, {j}): {stored} > {exact}");
                    if stored * 4.0 >= exact {
                        tight += 1;
                    }
                }
            }
            assert!(tight > 200, "{wrap:?}: {tight} of 256 within 4x");
        }
    }

    #[test]
    fn sphere_vertices_fit_the_sphere_curvature() {
        // A latitude-longitude sphere of radius 2: z = -(x^2 + y^2) / (2 R) near each vertex.
        let (rows, cols, r) = (12usize, 24usize, 2.0);
        let mut positions = Vec::new();
        let mut uvs = Vec::new();
        for i in 0..=rows {
            for j in 0..=cols {
                let (theta, phi) = (
                    core::f64::consts::PI * (0.15 + 0.7 * i as f64 / rows as f64),
                    core::f64::consts::TAU * j as f64 / cols as f64,
                );
                let n = DVec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                );
                positions.push(n * r);
                uvs.push(DVec2::new(j as f64 / cols as f64, i as f64 / rows as f64));
            }
        }
        let normals: Vec<DVec3> = positions.iter().map(|p| p.normalize()).collect();
        let mut triangles = Vec::new();
        let at = |i: usize, j: usize| (i * (cols + 1) + j) as u32;
        for i in 0..rows {
            for j in 0..cols {
                triangles.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                triangles.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let mesh = BaseMesh::<f64>::new(positions, normals, uvs, triangles).unwrap();
        let quadrics = VertexQuadrics::new(&mesh);
        // Interior vertices (full neighbourhoods): both coefficients near -1 / (2 R).
        for i in 1..rows {
            for j in 1..cols {
                let [a, b] = quadrics.coefficients(at(i, j) as usize);
                for c in [a, b] {
                    assert!((c + 0.25).abs() < 0.03, "({i}, {j}): {a} {b}");
                }
            }
        }
    }

    /// Flat base, equal normals: no quadric, the relief is met where nonlinear tracing meets
    /// it (the binary search's resolution: 2^-10 of a half-texel step).
    #[test]
    fn a_plane_is_hit_where_nonlinear_tracing_hits_it() {
        let side = 32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (x, y) = (
                    (k % side) as f32 / side as f32,
                    (k / side) as f32 / side as f32,
                );
                0.5 + 0.3 * (6.0 * x).sin() * (5.0 * y).cos()
            })
            .collect();
        let mesh = crate::test_util::unit_square(DVec3::Z, [[0, 1, 2], [0, 2, 3]]);
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp).unwrap();
        let surface = DisplacedSurface::new(mesh, field, 0.3, 1.0).unwrap();
        for rectification in [Rectification::Ray, Rectification::Cone] {
            let opts = ConeOptions {
                rectification,
                ..ConeOptions::default()
            };
            let cone = ConeTracing::new(&surface, opts);
            let mut hits = 0;
            for k in 0..400 {
                let (x, y) = ((k % 20) as f64 / 20.0, (k / 20) as f64 / 20.0);
                let ray = Ray::new(
                    DVec3::new(x - 0.3, y - 0.2, 1.0),
                    DVec3::new(0.5, 0.4, -0.8),
                )
                .unwrap();
                let mut st = TraversalStats::default();
                let exact = surface.intersect(&ray, 0.0, f64::INFINITY, &mut st);
                let coned = surface.intersect_cone_traced(&ray, 0.0, f64::INFINITY, &cone, &mut st);
                match (exact, coned) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a.hit.t - b.hit.t).abs() < 1e-3, "{k}: {a:?} {b:?}");
                    }
                    (None, None) => {}
                    (a, b) => panic!("{rectification:?} ray {k}: {a:?} vs {b:?}"),
                }
            }
            assert!(hits > 200, "{hits}");
        }
    }

    #[test]
    fn degenerate_triangles_give_a_defined_outcome() {
        let field = HeightField::from_unit_heights(4, 4, &[0.5; 16], Wrap::Clamp).unwrap();
        let line = crate::test_util::world_line_triangle();
        let flat = DisplacedSurface::new(line, field.clone(), 1.0, 1.0).unwrap();
        let uv_line =
            DisplacedSurface::new(crate::test_util::uv_line_triangle(), field, 1.0, 1.0).unwrap();
        let mut st = TraversalStats::default();
        let opts = ConeOptions::default();
        for s in [&flat, &uv_line] {
            let cone = ConeTracing::new(s, opts);
            for dir in [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 1.0, -1.0)] {
                let ray = Ray::new(DVec3::new(0.2, 0.2, 0.25) - dir, dir).unwrap();
                let hit = s.intersect_cone_traced(&ray, 0.0, f64::INFINITY, &cone, &mut st);
                if core::ptr::eq(s, &flat) {
                    // Zero world area: no shell, no hit from any side.
                    assert!(hit.is_none(), "{hit:?}");
                } else if dir.y == 0.0 {
                    // Zero uv area: still a volume; the constant map is met at height 0.5.
                    let hit = hit.expect("a uv-degenerate prism still has volume");
                    assert!((hit.hit.t - 0.75).abs() < 1e-3, "{hit:?}");
                }
            }
        }
    }
}
