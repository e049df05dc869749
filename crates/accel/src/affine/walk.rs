//! The straight walk: the min-max pyramid walked along a ray's line in a patch's texel space,
//! texels decided by the watertight ray-triangle test (see the parent module).

use nlrt_poly::{LaneMask, Lanes4, Real};
use nlrt_shellmap::Hit;

use super::patches::{StraightLine, TexelTriangle};
use crate::heightfield::{HEIGHT_ONE, HeightField};
use crate::leaving::Exclusion;
use crate::stats::TraversalStats;
use crate::tlas::RootNodes;

/// Entries of the walk's stack: up to 4 roots, then each popped node pushes at most 4
/// children (3 more than it took), once per level on the way down, 23 levels at most (cell
/// coordinates are below `2^22`).
const STACK: usize = 4 + 3 * 23;

#[derive(Clone, Copy, Default)]
struct Node<T> {
    level: u32,
    x: i32,
    y: i32,
    t_in: T,
    t_out: T,
}

/// A hit of the straight walk: distance, canonical coordinates, height, texel, whether the
/// upper microtriangle (or a flat texel) was hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct StraightHit<T: Real> {
    pub(crate) hit: Hit<T>,
    /// The line parameter of the hit.
    tau: T,
    pub(crate) texel: [i32; 2],
    /// 0 lower, 1 upper, 2 flat.
    pub(crate) part: u8,
}

/// The walk's per-prism state: the line, its clip to the triangle, the paddings.
pub(crate) struct Walk<'a, T: Real> {
    line: StraightLine<T>,
    triangle: &'a TexelTriangle<T>,
    /// Woop's frame: the dominant axis of the direction last, shears of the other two.
    axes: [usize; 3],
    shear: [T; 3],
    pad_xy: T,
    /// The padding of the line's heights, in height units (`[0, 1]` the shell).
    pad_h: T,
    /// How far beyond an open base edge (one shared with a triangle walked on another line
    /// or on its curve) a hit point is still owned, in texels: a bound on the hit point's
    /// error, so that a hit on this side is never disowned by rounding alone.
    window: T,
    /// The line's height at `t` in sample units (`65535` per unit height): `origin + t dir`,
    /// so that node bounds are compared as stored, without a division.
    sample_origin: T,
    sample_dir: T,
    /// The padding of the line's heights, in sample units.
    pad_samples: T,
    /// The world ray's `t` at the line's origin, and the smallest `t` accepted.
    t0: T,
    t_min: T,
    /// The line's parameters inside the triangle's prism (the clip, padded).
    t_lo: T,
    t_hi: T,
    /// The element the ray leaves (`crate::leaving`), not hit.
    excluded: Option<Exclusion>,
}

/// A sample as a height in `[0, 1]`, as the curved path converts it.
#[inline]
fn height<T: Real>(s: u16) -> T {
    T::from_i32(i32::from(s)) / T::from_i32(i32::from(HEIGHT_ONE))
}

/// The `t` interval in which `o + t d` lies in `[lo, hi]` (`inv = 1 / d`).
#[inline]
fn slab<T: Real>(lo: T, hi: T, o: T, d: T, inv: T) -> (T, T) {
    if d == T::ZERO {
        return if o >= lo && o <= hi {
            (-T::INFINITY, T::INFINITY)
        } else {
            (T::INFINITY, -T::INFINITY)
        };
    }
    let (a, b) = ((lo - o) * inv, (hi - o) * inv);
    (a.min(b), a.max(b))
}

/// A texel corner in Woop's sheared frame: `(X, Y, Z)` relative to the line's origin. A
/// function of the corner alone, so that shared corners transform to the same numbers.
#[inline]
fn sheared<T: Real>(walk: &Walk<'_, T>, p: [T; 3]) -> [T; 3] {
    let [kx, ky, kz] = walk.axes;
    let rel = [
        p[0] - walk.line.origin[0],
        p[1] - walk.line.origin[1],
        p[2] - walk.line.origin[2],
    ];
    [
        (-walk.shear[0]).mul_add(rel[kz], rel[kx]),
        (-walk.shear[1]).mul_add(rel[kz], rel[ky]),
        walk.shear[2] * rel[kz],
    ]
}

/// The watertight test (Woop et al. 2013, two-sided) of the triangle `a, b, c` (sheared
/// corners): `(t, barycentrics)` or `None`. Edge functions are differences of plain products
/// of the corners' numbers: the triangle across an edge computes the same value negated.
#[inline]
fn watertight<T: Real>(a: [T; 3], b: [T; 3], c: [T; 3]) -> Option<(T, [T; 3])> {
    let edge = |p: [T; 3], q: [T; 3]| {
        let e = p[0] * q[1] - p[1] * q[0];
        if e == T::ZERO && T::MANTISSA_DIGITS < 53 {
            // Exact products of 24-bit significands, one rounding of their difference in
            // f64: the sign is exact.
            let w = |v: T| v.to_f64();
            T::from_f64(w(p[0]) * w(q[1]) - w(p[1]) * w(q[0]))
        } else {
            e
        }
    };
    let u = edge(c, b);
    let v = edge(a, c);
    let w = edge(b, a);
    let negative = u < T::ZERO || v < T::ZERO || w < T::ZERO;
    let positive = u > T::ZERO || v > T::ZERO || w > T::ZERO;
    if negative && positive {
        return None;
    }
    let det = u + v + w;
    if det == T::ZERO {
        return None;
    }
    let t = u.mul_add(a[2], v.mul_add(b[2], w * c[2])) / det;
    Some((t, [u / det, v / det, w / det]))
}

impl<'a, T: Real> Walk<'a, T> {
    /// The walk of `line` through `triangle`'s prism for world distances in `[t_min,
    /// t_max]`: the line clipped to the prism (`None` when it misses), Woop's frame, the
    /// paddings of its rounding.
    pub(crate) fn new(
        line: StraightLine<T>,
        triangle: &'a TexelTriangle<T>,
        t_min: T,
        t_max: T,
    ) -> Option<Self> {
        // In line parameters (`tau = t - t0`).
        let (t0, _) = line.t0;
        let (t_lo, t_hi) = clip(&line, triangle, t_min.to_f64() - t0, t_max.to_f64() - t0)?;
        let kz = {
            let d = line.dir.map(|v| v.abs());
            if d[0] >= d[1] && d[0] >= d[2] {
                0
            } else if d[1] >= d[2] {
                1
            } else {
                2
            }
        };
        let (kx, ky) = ((kz + 1) % 3, (kz + 2) % 3);
        let shear = [
            line.dir[kx] / line.dir[kz],
            line.dir[ky] / line.dir[kz],
            T::ONE / line.dir[kz],
        ];
        // The test's rounding: four roundings in the shear of a corner, on magnitudes up to twice
        // its distance from the origin (the shears are at most 1), and the same for the line's
        // point at the walk's far end; in texel units, and in heights.
        let far = t_hi.abs().max(t_lo.abs());
        let eps = T::EPSILON;
        let corner = triangle
            .corners
            .iter()
            .fold(T::ONE, |m, c| m.max(c[0].abs()).max(c[1].abs()));
        let reach = |a: usize| line.origin[a].abs() + far * line.dir[a].abs();
        let eight = T::from_i32(8);
        let pad_xy = eight * eps * (reach(0).max(reach(1)) + corner + T::ONE);
        let pad_h = eight * eps * (reach(2) + T::ONE);
        // Heights in sample units: the scaling rounds the origin and direction once more each
        // (two roundings on magnitudes up to the reach).
        let samples = T::from_i32(i32::from(HEIGHT_ONE));
        let pad_samples = samples * (pad_h + T::TWO * eps * (reach(2) + T::ONE));
        // The hit point's error in `x, y`: the line's (`pad_xy`) and the test's barycentric
        // combination of the corners (the same roundings on the same magnitudes, `pad_xy` again),
        // plus the shift along the line that its height error makes where it meets a surface
        // that is nearly level in texel space (heights span `[0, 1]` over thousands of texels):
        // `pad_h` times the line's run per unit of rise. Capped at one texel, the clip's
        // padding across an edge: no hit farther beyond it is ever reported, and a hit whose
        // point is uncertain by a texel is a grazing one, whose side no rounding decides.
        let run = line.dir[0].abs().max(line.dir[1].abs());
        let window = (T::TWO * pad_xy + pad_h * run / line.dir[2].abs()).min(T::ONE);
        Some(Walk {
            line,
            triangle,
            axes: [kx, ky, kz],
            shear,
            pad_xy,
            pad_h,
            window,
            sample_origin: line.origin[2] * samples,
            sample_dir: line.dir[2] * samples,
            pad_samples,
            t0: line.t0.1,
            t_min,
            t_lo,
            t_hi,
            excluded: None,
        })
    }

    /// The walk with the element `excluded` (the one the ray leaves) not hit.
    #[must_use]
    pub(crate) fn excluding(self, excluded: Option<Exclusion>) -> Self {
        Self { excluded, ..self }
    }
}

impl<T: Real> Walk<'_, T> {
    /// The world ray's `t` at line parameter `tau`.
    #[inline]
    pub(crate) fn world_t(&self, tau: T) -> T {
        self.t0 + tau
    }

    /// The line parameters at which the line is inside the prism (the clip, padded).
    #[inline]
    pub(crate) fn interval(&self) -> (T, T) {
        (self.t_lo, self.t_hi)
    }

    /// The hit of the line on the triangle with corners `p` (texel space: `x, y` and
    /// height) at a line parameter up to `t_max` (and a world distance from `t_min` on)
    /// whose point the base triangle owns: the line parameter and the point. Two-sided, by
    /// the watertight test: two triangles that share an edge (the same corner numbers)
    /// compute its edge function negated, so no line passes between them.
    #[inline]
    pub(crate) fn triangle_hit(&self, p: [[T; 3]; 3], t_max: T) -> Option<(T, [T; 3])> {
        let s = p.map(|q| sheared(self, q));
        let (t, bary) = watertight(s[0], s[1], s[2])?;
        if !(t <= t_max && self.t0 + t >= self.t_min) {
            return None;
        }
        let point =
            |a: usize| bary[0].mul_add(p[0][a], bary[1].mul_add(p[1][a], bary[2] * p[2][a]));
        let q = [point(0), point(1), point(2)];
        self.triangle
            .owns([q[0], q[1]], self.window)
            .then_some((t, q))
    }

    /// The line parameters at which the line is in the box `[lo, hi]` (texel space), the
    /// box padded by the walk's rounding bounds (so that it holds every hit the
    /// [`Walk::triangle_hit`] of a triangle inside it can report), within `[lo_t, hi_t]`;
    /// empty when the first exceeds the second.
    #[inline]
    pub(crate) fn box_interval(&self, lo: [T; 3], hi: [T; 3], lo_t: T, hi_t: T) -> (T, T) {
        let l = &self.line;
        let (p, ph) = (self.pad_xy, self.pad_h);
        let (ax, bx) = slab(lo[0] - p, hi[0] + p, l.origin[0], l.dir[0], l.inv[0]);
        let (ay, by) = slab(lo[1] - p, hi[1] + p, l.origin[1], l.dir[1], l.inv[1]);
        let (ah, bh) = slab(lo[2] - ph, hi[2] + ph, l.origin[2], l.dir[2], l.inv[2]);
        (
            greater(greater(ax, ay), greater(ah, lo_t)),
            lesser(lesser(bx, by), lesser(bh, hi_t)),
        )
    }

    /// [`Walk::box_interval`] of four boxes in one vector step ([`Real::Four`], lane `k` box
    /// `k`; `lo[axis][k]`, `hi[axis][k]`): the intervals' ends and, as bit `k` of the mask,
    /// whether box `k`'s is not empty. The same bits as four calls of `box_interval`
    /// (tested): where the line's direction has a component whose reciprocal is not finite
    /// (0, or below `1 / MAX`), whose slab is not a product by it, it makes those calls.
    #[inline]
    pub(crate) fn four_box_intervals(
        &self,
        lo: [[T; 4]; 3],
        hi: [[T; 4]; 3],
        lo_t: T,
        hi_t: T,
    ) -> ([T; 4], [T; 4], u8) {
        if self.line.inv.iter().all(|v| v.is_finite()) {
            return self.four_box_intervals_in::<T::Four>(lo, hi, lo_t, hi_t);
        }
        self.four_box_intervals_scalar(lo, hi, lo_t, hi_t)
    }

    /// [`Walk::four_box_intervals`] one box at a time: the reference of the vector step.
    fn four_box_intervals_scalar(
        &self,
        lo: [[T; 4]; 3],
        hi: [[T; 4]; 3],
        lo_t: T,
        hi_t: T,
    ) -> ([T; 4], [T; 4], u8) {
        let (mut t_in, mut t_out, mut mask) = ([T::ZERO; 4], [T::ZERO; 4], 0);
        for k in 0..4 {
            let corner = |c: &[[T; 4]; 3]| [c[0][k], c[1][k], c[2][k]];
            (t_in[k], t_out[k]) = self.box_interval(corner(&lo), corner(&hi), lo_t, hi_t);
            mask |= u8::from(t_in[k] <= t_out[k]) << k;
        }
        (t_in, t_out, mask)
    }

    /// [`Walk::four_box_intervals`] in lanes `L`, for a line whose direction's reciprocals
    /// are finite: a slab's ends are then never NaN (finite differences times finite
    /// reciprocals), where `lesser` and `greater` pick what `Real::min` and `Real::max`
    /// pick (two equal ends of one slab are the same number: its sides are `2 p` apart).
    #[inline(always)]
    fn four_box_intervals_in<L: Lanes4<T>>(
        &self,
        lo: [[T; 4]; 3],
        hi: [[T; 4]; 3],
        lo_t: T,
        hi_t: T,
    ) -> ([T; 4], [T; 4], u8) {
        let l = &self.line;
        let slab = |axis: usize, pad: T| {
            let (o, inv, pad) = (
                L::splat(l.origin[axis]),
                L::splat(l.inv[axis]),
                L::splat(pad),
            );
            let a = (L::from_array(lo[axis]) - pad - o) * inv;
            let b = (L::from_array(hi[axis]) + pad - o) * inv;
            (a.lesser(b), a.greater(b))
        };
        let (ax, bx) = slab(0, self.pad_xy);
        let (ay, by) = slab(1, self.pad_xy);
        let (ah, bh) = slab(2, self.pad_h);
        let t_in = ax.greater(ay).greater(ah.greater(L::splat(lo_t)));
        let t_out = bx.lesser(by).lesser(bh.lesser(L::splat(hi_t)));
        (t_in.to_array(), t_out.to_array(), t_in.le(t_out).bits())
    }
}

/// The tiles (unit cells of texel space) of the root nodes `roots` whose padded boxes over
/// `heights` the line meets, nearest first through the implicit quadtree over them (the
/// shell's tiles on an affine prism, whose object fills at most those heights in every
/// tile): `leaf(x, y, t_best, stats)` tests tile `(x, y)` and returns a hit's line
/// parameter below `t_best` with what it hit. Returns the nearest.
pub(crate) fn walk_straight_tiles<T: Real, H>(
    walk: &Walk<'_, T>,
    roots: RootNodes,
    heights: [T; 2],
    stats: &mut TraversalStats,
    mut leaf: impl FnMut(i32, i32, T, &mut TraversalStats) -> Option<(T, H)>,
) -> Option<(T, H)> {
    let (t_lo, mut t_best) = walk.interval();
    let node_box = |level: u32, x: i32, y: i32, lo: T, hi: T| {
        let size = T::pow2(level as i32);
        let (x0, y0) = (T::from_i32(x) * size, T::from_i32(y) * size);
        walk.box_interval(
            [x0, y0, heights[0]],
            [x0 + size, y0 + size, heights[1]],
            lo,
            hi,
        )
    };
    let mut best = None;
    let mut stack = [Node::<T>::default(); STACK];
    let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
    let mut top = push_roots(&mut stack, roots, stats, |x, y| {
        let (t_in, t_out) = node_box(roots.level, x, y, t_lo, t_best);
        (t_in <= t_out).then_some((t_in, t_out))
    });
    while top > 0 {
        top -= 1;
        let node = stack[top];
        if node.t_in > t_best {
            continue;
        }
        if node.level == 0 {
            if let Some((t, hit)) = leaf(node.x, node.y, t_best, stats) {
                t_best = t;
                best = Some((t, hit));
            }
            continue;
        }
        // The four children's boxes side by side, tested in one vector step.
        let size = T::pow2(node.level as i32 - 1);
        let corner = |c: i32, k: usize| T::from_i32(2 * c + k as i32) * size;
        let x0: [T; 4] = core::array::from_fn(|k| corner(node.x, k & 1));
        let y0: [T; 4] = core::array::from_fn(|k| corner(node.y, k >> 1));
        let (lo, hi) = (
            [x0, y0, [heights[0]; 4]],
            [x0.map(|v| v + size), y0.map(|v| v + size), [heights[1]; 4]],
        );
        let (t_in, t_out, met) =
            walk.four_box_intervals(lo, hi, node.t_in, lesser(node.t_out, t_best));
        stats.box_tests += 4;
        let mut n = 0;
        for k in 0..4 {
            if met >> k & 1 == 1 {
                let (x, y) = (2 * node.x + (k & 1) as i32, 2 * node.y + (k >> 1) as i32);
                entries[n] = (t_in[k], t_out[k], x, y);
                n += 1;
            }
        }
        top = push_nearest_last(&mut stack, top, node.level - 1, &mut entries[..n]);
    }
    best
}

impl<T: Real> Walk<'_, T> {
    /// Tests texel `(x, y)`: the nearer of its two microtriangles' hits at line parameters
    /// up to `t_max` (and world distances from `t_min` on) whose point the triangle owns;
    /// the hit's `t` is the world ray's.
    fn texel(&self, x: i32, y: i32, corners: [u16; 4], t_max: T) -> Option<StraightHit<T>> {
        let h = corners.map(height::<T>);
        let (fx, fy) = (T::from_i32(x), T::from_i32(y));
        let (gx, gy) = (fx + T::ONE, fy + T::ONE);
        let p = [
            [fx, fy, h[0]],
            [gx, fy, h[1]],
            [fx, gy, h[2]],
            [gx, gy, h[3]],
        ];
        let s = p.map(|q| sheared(self, q));
        let flat = h[0] == h[1] && h[0] == h[2] && h[0] == h[3];
        let mut best: Option<StraightHit<T>> = None;
        let mut t_max = t_max;
        for (part, [i, j, k]) in [(0u8, [0, 1, 3]), (1u8, [0, 3, 2])] {
            let part = if flat { 2 } else { part };
            if self
                .excluded
                .is_some_and(|e| e.excludes([x, y], u32::from(part)))
            {
                continue;
            }
            let Some((t, bary)) = watertight(s[i], s[j], s[k]) else {
                continue;
            };
            if !(t <= t_max && self.t0 + t >= self.t_min) {
                continue;
            }
            let point =
                |a: usize| bary[0].mul_add(p[i][a], bary[1].mul_add(p[j][a], bary[2] * p[k][a]));
            let q = [point(0), point(1)];
            if !self.triangle.owns(q, self.window) {
                continue;
            }
            // A ray leaving the surface touching a neighbour at its origin
            // (`Exclusion::skips`): the line's climb above the plane through the three
            // corners, `d/dt (h - H(u, v))`, from the plane's slopes along u and v.
            if self.excluded.is_some_and(|e| {
                e.skips([x, y], u32::from(part), (self.t0 + t).to_f64(), || {
                    let (slope_u, slope_v) = if k == 3 {
                        (h[1] - h[0], h[3] - h[1])
                    } else {
                        (h[3] - h[2], h[2] - h[0])
                    };
                    let d = self.line.dir;
                    d[2] - slope_u * d[0] - slope_v * d[1]
                })
            }) {
                continue;
            }
            let (alpha, beta) = self.triangle.canonical(q);
            t_max = t;
            best = Some(StraightHit {
                tau: t,
                hit: Hit {
                    t: self.t0 + t,
                    alpha,
                    beta,
                    h: point(2).max(T::ZERO).min(T::ONE),
                    u: T::ZERO,
                    v: T::ZERO,
                },
                texel: [x, y],
                part,
            });
        }
        best
    }

    /// The nearest owned hit in the four texels of node `[x, y]` of level 1, whose line
    /// interval is `interval`: their corners are `block[at[1] + j][at[0] + i]`, `i, j` in
    /// `0..3`; texels nearest first, until one lies beyond `t_max`.
    #[inline(always)]
    fn level_one<const N: usize>(
        &self,
        block: &[[u16; N]; N],
        at: [usize; 2],
        [x, y]: [i32; 2],
        interval: (T, T),
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<StraightHit<T>> {
        stats.box_tests += 4;
        let corners = |k: usize| {
            let (i, j) = (at[0] + (k & 1), at[1] + (k >> 1));
            [
                block[j][i],
                block[j][i + 1],
                block[j + 1][i],
                block[j + 1][i + 1],
            ]
        };
        let bounds = core::array::from_fn(|k| {
            let c = corners(k);
            [
                c[0].min(c[1]).min(c[2]).min(c[3]),
                c[0].max(c[1]).max(c[2]).max(c[3]),
            ]
        });
        let (intervals, meeting) =
            self.children_meeting(1, x, y, interval.0, lesser(interval.1, t_max), bounds);
        let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
        let mut n = 0;
        for (k, &interval) in intervals.iter().enumerate() {
            if meeting >> k & 1 == 1 {
                entries[n] = (interval.0, interval.1, k as i32, 0);
                n += 1;
            }
        }
        sort_entries(&mut entries[..n], false);
        let mut best = None;
        let mut t_max = t_max;
        for &(t_in, _, k, _) in &entries[..n] {
            if t_in > t_max {
                break;
            }
            let k = k as usize;
            let (tx, ty) = (2 * x + (k & 1) as i32, 2 * y + (k >> 1) as i32);
            stats.texel_tests += 1;
            if let Some(hit) = self.texel(tx, ty, corners(k), t_max) {
                t_max = hit.tau;
                best = Some(hit);
            }
        }
        best
    }

    /// The `t` intervals of the line in the four children of node `(x, y)` of `level >= 1`
    /// (in the order `(0, 0), (1, 0), (0, 1), (1, 1)`), each padded, within `[lo, hi]`: the
    /// two split lines' crossings computed once for all four.
    #[inline]
    fn children(&self, level: u32, x: i32, y: i32, lo: T, hi: T) -> [(T, T); 4] {
        let size = T::pow2(level as i32 - 1);
        let l = &self.line;
        let p = self.pad_xy;
        let axis = |a: usize, c: i32| -> [(T, T); 2] {
            let c0 = T::from_i32(c) * (size + size);
            let (cm, c1) = (c0 + size, c0 + size + size);
            if l.dir[a] == T::ZERO {
                let o = l.origin[a];
                let inside = |lo: T, hi: T| {
                    if o >= lo && o <= hi {
                        (-T::INFINITY, T::INFINITY)
                    } else {
                        (T::INFINITY, -T::INFINITY)
                    }
                };
                return [inside(c0 - p, cm + p), inside(cm - p, c1 + p)];
            }
            let t = |v: T| (v - l.origin[a]) * l.inv[a];
            let (a0, a1, b0, b1) = (t(c0 - p), t(cm + p), t(cm - p), t(c1 + p));
            [
                (lesser(a0, a1), greater(a0, a1)),
                (lesser(b0, b1), greater(b0, b1)),
            ]
        };
        let (sx, sy) = (axis(0, x), axis(1, y));
        core::array::from_fn(|k| {
            let (i, j) = (k & 1, k >> 1);
            (
                greater(greater(sx[i].0, sy[j].0), lo),
                lesser(lesser(sx[i].1, sy[j].1), hi),
            )
        })
    }

    /// The four children of node `(x, y)` of `level >= 1` (in the order of
    /// [`Walk::children`]): their padded `t` intervals within `[lo, hi]` and, as bit `k` of the
    /// mask, whether child `k`'s interval is not empty and the line's heights over it may meet
    /// its sample bounds `bounds[k]` ([`Walk::meets`]): the two split lines' crossings and the
    /// four height tests in one vector step ([`Real::Four`]; construction 4 of the speed
    /// issue on the straight walk). The same operations as [`Walk::children`] and
    /// [`Walk::meets`] lane by lane, so the same bits (tested). A line parallel to an axis
    /// takes the scalar step: its slab on that axis is not a product by the reciprocal.
    #[inline(always)]
    fn children_meeting(
        &self,
        level: u32,
        x: i32,
        y: i32,
        lo: T,
        hi: T,
        bounds: [[u16; 2]; 4],
    ) -> ([(T, T); 4], u8) {
        if self.line.dir[0] == T::ZERO || self.line.dir[1] == T::ZERO {
            return self.children_meeting_scalar(level, x, y, lo, hi, bounds);
        }
        self.children_meeting_in::<T::Four>(level, x, y, lo, hi, bounds)
    }

    /// [`Walk::children_meeting`] one child at a time: the reference of the vector step.
    fn children_meeting_scalar(
        &self,
        level: u32,
        x: i32,
        y: i32,
        lo: T,
        hi: T,
        bounds: [[u16; 2]; 4],
    ) -> ([(T, T); 4], u8) {
        let intervals = self.children(level, x, y, lo, hi);
        let mut meeting = 0;
        for k in 0..4 {
            meeting |= u8::from(self.meets(intervals[k], bounds[k])) << k;
        }
        (intervals, meeting)
    }

    /// [`Walk::children_meeting`] in lanes `L` (lane `k` child `k`), for a line whose `x`
    /// and `y` directions are not 0.
    #[inline(always)]
    fn children_meeting_in<L: Lanes4<T>>(
        &self,
        level: u32,
        x: i32,
        y: i32,
        lo: T,
        hi: T,
        bounds: [[u16; 2]; 4],
    ) -> ([(T, T); 4], u8) {
        let size = T::pow2(level as i32 - 1);
        let l = &self.line;
        let p = self.pad_xy;
        // A node's padded split on one axis: the first child's slab `[c0 - p, cm + p]`, the
        // second's `[cm - p, c1 + p]`.
        let split = |c: i32| {
            let c0 = T::from_i32(c) * (size + size);
            let (cm, c1) = (c0 + size, c0 + size + size);
            ([c0 - p, cm - p], [cm + p, c1 + p])
        };
        let t = |axis: usize, v: [T; 4]| {
            (L::from_array(v) - L::splat(l.origin[axis])) * L::splat(l.inv[axis])
        };
        // Lane `k` is child `(k & 1, k >> 1)`: its `x` slab is the split's `k & 1`, its `y`
        // slab the split's `k >> 1`.
        let ([x0, x1], [x2, x3]) = split(x);
        let ([y0, y1], [y2, y3]) = split(y);
        let (xa, xb) = (t(0, [x0, x1, x0, x1]), t(0, [x2, x3, x2, x3]));
        let (ya, yb) = (t(1, [y0, y0, y1, y1]), t(1, [y2, y2, y3, y3]));
        let t_in = xa.lesser(xb).greater(ya.lesser(yb)).greater(L::splat(lo));
        let t_out = xa.greater(xb).lesser(ya.greater(yb)).lesser(L::splat(hi));
        let (sd, so) = (L::splat(self.sample_dir), L::splat(self.sample_origin));
        let (ha, hb) = (t_in.mul_add(sd, so), t_out.mul_add(sd, so));
        let pad = L::splat(self.pad_samples);
        let sample = |i: usize| L::from_array(bounds.map(|b| T::from_i32(i32::from(b[i]))));
        let meeting = t_in.le(t_out)
            & (ha.lesser(hb) - pad).le(sample(1))
            & (ha.greater(hb) + pad).ge(sample(0));
        let (a, b) = (t_in.to_array(), t_out.to_array());
        (core::array::from_fn(|k| (a[k], b[k])), meeting.bits())
    }

    /// The `t` interval of the line in node `(x, y)` of `level` (padded), within `[lo, hi]`.
    fn node(&self, level: u32, x: i32, y: i32, lo: T, hi: T) -> (T, T) {
        let size = T::pow2(level as i32);
        let l = &self.line;
        let p = self.pad_xy;
        let (x0, y0) = (T::from_i32(x) * size, T::from_i32(y) * size);
        let (ax, bx) = slab(x0 - p, x0 + size + p, l.origin[0], l.dir[0], l.inv[0]);
        let (ay, by) = slab(y0 - p, y0 + size + p, l.origin[1], l.dir[1], l.inv[1]);
        (ax.max(ay).max(lo), bx.min(by).min(hi))
    }

    /// Whether the line's heights over the nonempty interval `(t_in, t_out)` (padded) may
    /// meet a node's `bounds`.
    #[inline(always)]
    fn meets(&self, (t_in, t_out): (T, T), bounds: [u16; 2]) -> bool {
        if !(t_in <= t_out) {
            return false;
        }
        let ha = t_in.mul_add(self.sample_dir, self.sample_origin);
        let hb = t_out.mul_add(self.sample_dir, self.sample_origin);
        let (line_lo, line_hi) = (
            lesser(ha, hb) - self.pad_samples,
            greater(ha, hb) + self.pad_samples,
        );
        line_lo <= T::from_i32(i32::from(bounds[1])) && line_hi >= T::from_i32(i32::from(bounds[0]))
    }
}

/// The smaller of two numbers that are not NaN (one comparison: the walk's `t` and heights
/// never are NaN, so `Real::min`'s NaN handling is not paid for).
#[inline(always)]
fn lesser<T: Real>(a: T, b: T) -> T {
    if a < b { a } else { b }
}

/// The larger of two numbers that are not NaN (see [`lesser`]).
#[inline(always)]
fn greater<T: Real>(a: T, b: T) -> T {
    if a > b { a } else { b }
}

/// Pushes `entries` (nodes `(t_in, t_out, x, y)` of `level`) onto the walk's stack at
/// `top`, farthest first, so that the nearest is popped next; returns the new top.
#[inline]
fn push_nearest_last<T: Real>(
    stack: &mut [Node<T>; STACK],
    top: usize,
    level: u32,
    entries: &mut [(T, T, i32, i32)],
) -> usize {
    sort_entries(entries, true);
    for (k, &(t_in, t_out, x, y)) in entries.iter().enumerate() {
        stack[top + k] = Node {
            level,
            x,
            y,
            t_in,
            t_out,
        };
    }
    top + entries.len()
}

/// The root nodes of `roots` whose line interval `enter(x, y)` exists (each counted as a
/// box test), pushed onto an empty stack by [`push_nearest_last`]; returns the top.
#[inline]
fn push_roots<T: Real>(
    stack: &mut [Node<T>; STACK],
    roots: RootNodes,
    stats: &mut TraversalStats,
    mut enter: impl FnMut(i32, i32) -> Option<(T, T)>,
) -> usize {
    let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
    let mut n = 0;
    for j in 0..i32::from(roots.ny) {
        for i in 0..i32::from(roots.nx) {
            let (x, y) = (roots.x + i, roots.y + j);
            stats.box_tests += 1;
            if let Some((t_in, t_out)) = enter(x, y) {
                entries[n] = (t_in, t_out, x, y);
                n += 1;
            }
        }
    }
    push_nearest_last(stack, 0, roots.level, &mut entries[..n])
}

/// Up to four `(t_in, t_out, x, y)` sorted by `t_in`, farthest first (`descending`) or
/// nearest first.
#[inline]
fn sort_entries<T: Real>(entries: &mut [(T, T, i32, i32)], descending: bool) {
    // An insertion sort: at most four entries.
    for i in 1..entries.len() {
        let mut j = i;
        while j > 0 && ((entries[j].0 > entries[j - 1].0) == descending) {
            entries.swap(j, j - 1);
            j -= 1;
        }
    }
}

/// The nearest hit of the straight `line` on the displaced surface over `triangle` (its root
/// nodes `roots`) with `t` in `[t_min, t_max]`: the min-max pyramid walked nearest first
/// along the line, texels tested by the watertight test. The hit's texture coordinates are
/// left at 0 (the caller has the prism). The element `excluded` (the one a ray leaves) is not
/// hit.
pub(crate) fn walk_straight<T: Real>(
    field: &HeightField,
    roots: RootNodes,
    line: StraightLine<T>,
    triangle: &TexelTriangle<T>,
    [t_min, t_max]: [T; 2],
    excluded: Option<Exclusion>,
    stats: &mut TraversalStats,
) -> Option<StraightHit<T>> {
    let walk = Walk::new(line, triangle, t_min, t_max)?.excluding(excluded);
    let (t_lo, t_hi) = (walk.t_lo, walk.t_hi);
    let mut best: Option<StraightHit<T>> = None;
    let mut t_best = t_hi;
    let mut stack = [Node::<T>::default(); STACK];
    let mut entries = [(T::ZERO, T::ZERO, 0i32, 0i32); 4];
    let mut top = push_roots(&mut stack, roots, stats, |x, y| {
        let bounds = field.texel_bounds(roots.level, i64::from(x), i64::from(y));
        let interval = walk.node(roots.level, x, y, t_lo, t_hi);
        walk.meets(interval, bounds).then_some(interval)
    });
    while top > 0 {
        top -= 1;
        let node = stack[top];
        if node.t_in > t_best {
            continue;
        }
        match node.level {
            0 => {
                // A root texel (a triangle within two texels per axis).
                stats.texel_tests += 1;
                let corners = field.texel_corners(i64::from(node.x), i64::from(node.y));
                if let Some(hit) = walk.texel(node.x, node.y, corners, t_best) {
                    t_best = hit.tau;
                    best = Some(hit);
                }
            }
            1 => {
                let block = field.samples_block::<3>(2 * i64::from(node.x), 2 * i64::from(node.y));
                let interval = (node.t_in, node.t_out);
                if let Some(hit) =
                    walk.level_one(&block, [0, 0], [node.x, node.y], interval, t_best, stats)
                {
                    t_best = hit.tau;
                    best = Some(hit);
                }
            }
            2 => {
                // The node's 4 x 4 texels from its 5 x 5 samples, read once: its four children
                // nearest first, each one's texels nearest first.
                let block = field.samples_block::<5>(4 * i64::from(node.x), 4 * i64::from(node.y));
                let bounds = core::array::from_fn(|k| {
                    let (i, j) = (2 * (k & 1), 2 * (k >> 1));
                    let mut b = [u16::MAX, 0];
                    for row in &block[j..j + 3] {
                        for &s in &row[i..i + 3] {
                            b = [b[0].min(s), b[1].max(s)];
                        }
                    }
                    b
                });
                let (intervals, meeting) = walk.children_meeting(
                    2,
                    node.x,
                    node.y,
                    node.t_in,
                    lesser(node.t_out, t_best),
                    bounds,
                );
                stats.box_tests += 4;
                let mut n = 0;
                for (k, &interval) in intervals.iter().enumerate() {
                    if meeting >> k & 1 == 1 {
                        entries[n] = (interval.0, interval.1, k as i32, 0);
                        n += 1;
                    }
                }
                sort_entries(&mut entries[..n], false);
                for &(t_in, t_out, k, _) in &entries[..n] {
                    if t_in > t_best {
                        break;
                    }
                    let k = k as usize;
                    let (i, j) = (k & 1, k >> 1);
                    let (x, y) = (2 * node.x + i as i32, 2 * node.y + j as i32);
                    if let Some(hit) = walk.level_one(
                        &block,
                        [2 * i, 2 * j],
                        [x, y],
                        (t_in, lesser(t_out, t_best)),
                        t_best,
                        stats,
                    ) {
                        t_best = hit.tau;
                        best = Some(hit);
                    }
                }
            }
            level => {
                stats.box_tests += 4;
                let mut n = 0;
                let four =
                    field.four_bounds(level - 1, 2 * i64::from(node.x), 2 * i64::from(node.y));
                let (intervals, meeting) = walk.children_meeting(
                    level,
                    node.x,
                    node.y,
                    node.t_in,
                    lesser(node.t_out, t_best),
                    four,
                );
                for (k, &interval) in intervals.iter().enumerate() {
                    let (x, y) = (2 * node.x + (k & 1) as i32, 2 * node.y + (k >> 1) as i32);
                    if meeting >> k & 1 == 1 {
                        entries[n] = (interval.0, interval.1, x, y);
                        n += 1;
                    }
                }
                // Farthest first onto the stack: the nearest child is popped next; the
                // others' memory is fetched while it is walked.
                sort_entries(&mut entries[..n], true);
                for &(t_in, t_out, x, y) in &entries[..n] {
                    field.prefetch_node(level - 1, i64::from(x), i64::from(y));
                    stack[top] = Node {
                        level: level - 1,
                        x,
                        y,
                        t_in,
                        t_out,
                    };
                    top += 1;
                }
            }
        }
    }
    // The clip's upper end is `t_max - t0` rounded: the nearest hit may lie a rounding
    // beyond `t_max`.
    best.filter(|b| b.hit.t <= t_max)
}

/// The line's `t` interval inside the triangle's texel-space prism, padded by one texel
/// across each base edge and its box by one texel, and by `1/64` in height (far beyond the rounding of the `T` line
/// against the `f64` one it is computed from: half an ulp of coordinates below `2^22`, at
/// most a quarter texel in `f32`), within `[tau_min, tau_max]` (line parameters); `None` when
/// empty. Computed in
/// `f64` on the unrounded line: it only bounds the walk, the test decides the hits.
fn clip<T: Real>(
    line: &StraightLine<T>,
    triangle: &TexelTriangle<T>,
    tau_min: f64,
    tau_max: f64,
) -> Option<(T, T)> {
    let (o, d) = line.wide;
    let (mut lo, mut hi) = (tau_min, tau_max);
    let mut bound = |value: f64, rate: f64| {
        // value + t rate >= 0
        if rate == 0.0 {
            if value < 0.0 {
                hi = f64::NEG_INFINITY;
            }
        } else if rate > 0.0 {
            lo = lo.max(-value / rate);
        } else {
            hi = hi.min(-value / rate);
        }
    };
    let pad_h = 1.0 / 64.0;
    bound(o[2] + pad_h, d[2]);
    bound(1.0 + pad_h - o[2], -d[2]);
    let c = triangle.corners.map(|c| [c[0].to_f64(), c[1].to_f64()]);
    // The triangle's box, padded by a texel: it bounds a sliver along its length, which its
    // padded edges do not (the edges of a triangle 4e-24 texels wide and 9,152 long meet
    // 10^23 texels beyond its ends, and the paddings, which follow the walk's reach, then
    // admitted every node: 151M texel tests in 11 s, `fuzz/slow/displacement_f32/
    // straight-sliver`).
    for axis in 0..2 {
        let lo_c = c.iter().map(|p| p[axis]).fold(f64::INFINITY, f64::min) - 1.0;
        let hi_c = c.iter().map(|p| p[axis]).fold(f64::NEG_INFINITY, f64::max) + 1.0;
        bound(o[axis] - lo_c, d[axis]);
        bound(hi_c - o[axis], -d[axis]);
    }
    let orientation =
        (c[1][0] - c[0][0]) * (c[2][1] - c[0][1]) - (c[1][1] - c[0][1]) * (c[2][0] - c[0][0]);
    let sign = if orientation > 0.0 { 1.0 } else { -1.0 };
    for k in 0..3 {
        let (a, b) = (c[k], c[(k + 1) % 3]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let length = (e[0] * e[0] + e[1] * e[1]).sqrt();
        let value = sign * (e[0] * (o[1] - a[1]) - e[1] * (o[0] - a[0])) + length;
        let rate = sign * (e[0] * d[1] - e[1] * d[0]);
        bound(value, rate);
    }
    (lo <= hi).then(|| (T::from_f64(lo), T::from_f64(hi)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_util::{direction_component, unit_randoms};
    use nlrt_poly::lanes4::Portable4;
    use nlrt_poly::{Vector2, Vector3};
    use nlrt_shellmap::Prism;

    /// The unit right triangle with a flat, vertical prism on a map of `side` texels per
    /// unit: a texel triangle for walks whose steps the tests compare.
    fn unit_triangle<T: Real>(side: i32) -> TexelTriangle<T> {
        let v3 =
            |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
        let uv = |x: f64, y: f64| T::Vec2::new(T::from_f64(x), T::from_f64(y));
        let prism = Prism::new(
            [v3(0.0, 0.0, 0.0), v3(1.0, 0.0, 0.0), v3(0.0, 1.0, 0.0)],
            [v3(0.0, 0.0, 1.0); 3],
            [uv(0.0, 0.0), uv(1.0, 0.0), uv(0.0, 1.0)],
        );
        TexelTriangle::new(&prism, T::from_i32(side), [false; 3])
    }

    /// The vector child step against the scalar one and against the portable lanes, bit for
    /// bit, on lines of every slope (near-axis ones, whose reciprocals are huge, included),
    /// far origins, nodes on and off the line's path from level 1 to 12, and random sample
    /// bounds around the line's heights.
    fn child_steps_agree<T: Real>() {
        let triangle = unit_triangle::<T>(4096);
        let mut r = unit_randoms(46);
        let (mut cases, mut met, mut missed) = (0, 0, 0);
        for _ in 0..20_000 {
            let dir = [
                direction_component(&mut r),
                direction_component(&mut r),
                direction_component(&mut r) * 1e-3,
            ];
            let origin = [
                r() * 8192.0 - 2048.0,
                r() * 8192.0 - 2048.0,
                r() * 3.0 - 1.0,
            ];
            let t = |v: f64| T::from_f64(v);
            let line = StraightLine {
                origin: origin.map(t),
                dir: dir.map(t),
                inv: dir.map(|d| T::ONE / t(d)),
                t0: (0.0, T::ZERO),
                wide: (origin, dir),
            };
            if line.dir[0] == T::ZERO || line.dir[1] == T::ZERO {
                continue;
            }
            let samples = T::from_i32(i32::from(HEIGHT_ONE));
            let pad = t(r() * 1e-3);
            let walk = Walk {
                line,
                triangle: &triangle,
                axes: [0, 1, 2],
                shear: [T::ZERO; 3],
                pad_xy: pad,
                pad_h: pad,
                window: T::ZERO,
                sample_origin: line.origin[2] * samples,
                sample_dir: line.dir[2] * samples,
                pad_samples: pad * samples,
                t0: T::ZERO,
                t_min: T::ZERO,
                t_lo: T::ZERO,
                t_hi: T::ZERO,
                excluded: None,
            };
            let level = 1 + (r() * 12.0) as u32;
            let size = f64::from(1u32 << level);
            // A node on the line's path at a random parameter, or a random one.
            let tau = (r() - 0.5) * 8192.0;
            let (px, py) = if r() < 0.7 {
                (origin[0] + tau * dir[0], origin[1] + tau * dir[1])
            } else {
                (r() * 8192.0, r() * 8192.0)
            };
            let (x, y) = ((px / size).floor() as i32, (py / size).floor() as i32);
            let (lo, hi) = walk.node(level, x, y, t(-1e12), t(1e12));
            let h = |tau: f64| {
                let s = (origin[2] + tau * dir[2]) * 65535.0;
                s.clamp(0.0, 65535.0) as u16
            };
            let bounds: [[u16; 2]; 4] = core::array::from_fn(|_| {
                let (a, b) = (h(tau + (r() - 0.5) * size), h(tau + (r() - 0.5) * size));
                [a.min(b), a.max(b)]
            });
            let scalar = walk.children_meeting_scalar(level, x, y, lo, hi, bounds);
            let native = walk.children_meeting_in::<T::Four>(level, x, y, lo, hi, bounds);
            let portable = walk.children_meeting_in::<Portable4<T>>(level, x, y, lo, hi, bounds);
            let bits = |(i, m): ([(T, T); 4], u8)| (i.map(|(a, b)| (a.to_bits(), b.to_bits())), m);
            assert_eq!(
                bits(native),
                bits(scalar),
                "{line:?} level {level} node {x} {y}"
            );
            assert_eq!(
                bits(portable),
                bits(scalar),
                "{line:?} level {level} node {x} {y}"
            );
            assert_eq!(
                walk.children_meeting(level, x, y, lo, hi, bounds).1,
                scalar.1
            );
            cases += 1;
            met += scalar.1.count_ones();
            missed += 4 - scalar.1.count_ones();
        }
        // Both outcomes, often: the comparison saw children kept and children culled.
        assert!(
            cases > 15_000 && met > 5_000 && missed > 5_000,
            "{cases} {met} {missed}"
        );
    }

    /// The vector box step against four scalar box tests and the portable lanes, bit for bit:
    /// boxes around points on the line and anywhere, of every size, on lines of every slope.
    fn box_steps_agree<T: Real>() {
        let triangle = unit_triangle::<T>(64);
        let mut r = unit_randoms(4646);
        let t = |v: f64| T::from_f64(v);
        let (mut cases, mut met, mut missed) = (0, 0, 0);
        for _ in 0..20_000 {
            let dir: [f64; 3] = core::array::from_fn(|_| direction_component(&mut r));
            let origin = [r() * 64.0, r() * 64.0, r() * 2.0 - 0.5];
            let line = StraightLine {
                origin: origin.map(t),
                dir: dir.map(t),
                inv: dir.map(|d| T::ONE / t(d)),
                t0: (0.0, T::ZERO),
                wide: (origin, dir),
            };
            let walk = Walk::new(line, &triangle, T::ZERO, T::INFINITY);
            let Some(walk) = walk else { continue };
            let (t_lo, t_hi) = walk.interval();
            let mut boxes = |k: usize| -> ([T; 3], [T; 3]) {
                let size = 10f64.powf(r() * 4.0 - 3.0);
                let tau = t_lo.to_f64() + r() * (t_hi.to_f64() - t_lo.to_f64()).min(100.0);
                let centre: [f64; 3] = core::array::from_fn(|a| {
                    if k == 3 {
                        r() * 64.0
                    } else {
                        origin[a] + tau * dir[a] + (r() - 0.5) * size
                    }
                });
                let lo = centre.map(|c| t(c - size * r()));
                let hi = centre.map(|c| t(c + size * r()));
                (lo, hi)
            };
            let four: [([T; 3], [T; 3]); 4] = core::array::from_fn(&mut boxes);
            let lo = core::array::from_fn(|a| core::array::from_fn(|k| four[k].0[a]));
            let hi = core::array::from_fn(|a| core::array::from_fn(|k| four[k].1[a]));
            let scalar = walk.four_box_intervals_scalar(lo, hi, t_lo, t_hi);
            let bits = |(a, b, m): ([T; 4], [T; 4], u8)| (a.map(T::to_bits), b.map(T::to_bits), m);
            assert_eq!(
                bits(walk.four_box_intervals(lo, hi, t_lo, t_hi)),
                bits(scalar)
            );
            if walk.line.inv.iter().all(|v| v.is_finite()) {
                let native = walk.four_box_intervals_in::<T::Four>(lo, hi, t_lo, t_hi);
                let portable = walk.four_box_intervals_in::<Portable4<T>>(lo, hi, t_lo, t_hi);
                assert_eq!(bits(native), bits(scalar), "{line:?}");
                assert_eq!(bits(portable), bits(scalar), "{line:?}");
                cases += 1;
                met += scalar.2.count_ones();
                missed += 4 - scalar.2.count_ones();
            }
        }
        assert!(
            cases > 5_000 && met > 5_000 && missed > 5_000,
            "{cases} {met} {missed}"
        );
    }

    #[test]
    fn the_vector_box_step_is_the_scalar_one() {
        box_steps_agree::<f32>();
        box_steps_agree::<f64>();
    }

    #[test]
    fn the_vector_child_step_is_the_scalar_one() {
        child_steps_agree::<f32>();
        child_steps_agree::<f64>();
    }
}
