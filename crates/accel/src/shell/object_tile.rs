//! The object's BVH in one tile of a curved prism: its boxes entered by the hull test
//! ([`PrismHull`]) or, in a prism without one, by the curve's box test, nearest first; a
//! leaf's triangles by their own hulls, then the object test.

use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::{Prism, TextureCurve};

use super::{OBJECT_STACK, ShellHit, ShellSurface};
use crate::leaving::Exclusion;
use crate::object_hull::PrismHull;
use crate::stack::SpillStack;
use crate::stats::TraversalStats;

/// What the object's BVH is walked with in every tile of one prism: the base triangle, its
/// prism, the ray's curve in it, the hull test where the prism has one, the least distance
/// and the element a leaving ray excludes.
#[derive(Clone, Copy)]
pub(super) struct TileQuery<'a, 'c, C: Real> {
    pub(super) tri: usize,
    pub(super) prism: &'a Prism<C>,
    pub(super) curve: &'a TextureCurve<'c, C>,
    pub(super) hull: Option<&'a PrismHull<C>>,
    pub(super) t_min: C,
    pub(super) excluded: Option<Exclusion>,
}

impl<T: Real> ShellSurface<T> {
    /// The object's BVH in tile `(x, y)` along the prism's curve, nearest first, its boxes
    /// cut to the heights `h` at which the curve is in the tile (from the walk: a box's part
    /// outside them is outside the tile or the prism); updates `best` and `t_max`.
    ///
    /// A box is entered where the world ray meets the hull of its mapped corners
    /// ([`PrismHull`], a slab test in the prism's frame, four boxes in one vector step);
    /// where the prism has no hull test (a base triangle degenerate in uv or in space), where
    /// the curve clipped in texture space meets it ([`TextureCurve::box_span_in`]).
    pub(super) fn intersect_tile<C: Real>(
        &self,
        query: &TileQuery<'_, '_, C>,
        (x, y): (i32, i32),
        [h_in, h_out]: [C; 2],
        t_max: &mut C,
        best: &mut Option<ShellHit<C>>,
        stats: &mut TraversalStats,
    ) {
        let nodes = self.object.bvh.nodes();
        let order = self.object.bvh.primitive_order();
        if nodes.is_empty() {
            return;
        }
        let TileQuery {
            tri,
            prism,
            curve,
            hull,
            t_min,
            excluded,
        } = *query;
        let (dx, dy) = (T::from_i32(x), T::from_i32(y));
        let ray = curve.ray();
        // Without a hull: the curve's uv enclosure over a node's heights (the tile's for the
        // root; for a box, the one its own test formed) holds the curve over its children's
        // heights, which lie within them: a child whose uv rectangle misses it is rejected by
        // four comparisons, before its own, tighter enclosure is formed (three divisions).
        // Sound as the box test's rejection is (`TextureCurve::uv_enclosure`); a node whose
        // enclosure does not exist (the denominator may vanish) hands down its parent's.
        let tile_enclosure = if hull.is_none() {
            curve.uv_enclosure(h_in, h_out)
        } else {
            None
        };
        let mut stack = SpillStack::<_, OBJECT_STACK>::new((0u32, C::ZERO, None));
        stack.push((0, t_min, tile_enclosure));
        while let Some((node, entry, node_enclosure)) = stack.pop() {
            if entry > *t_max {
                continue;
            }
            let node = &nodes[node as usize];
            // The four children's boxes: shifted in `T`, as the triangles are placed, so each
            // box holds its triangles' placed vertices (rounding is monotonic), then widened;
            // heights cut to the tile's.
            let w = |v: T| C::from_f64(v.to_f64());
            let (mut lo, mut hi) = ([[C::ZERO; 4]; 3], [[C::ZERO; 4]; 3]);
            for c in 0..4 {
                let b = node.bounds(c);
                [lo[0][c], lo[1][c], lo[2][c]] =
                    [w(b.lo[0] + dx), w(b.lo[1] + dy), w(b.lo[2]).max(h_in)];
                [hi[0][c], hi[1][c], hi[2][c]] =
                    [w(b.hi[0] + dx), w(b.hi[1] + dy), w(b.hi[2]).min(h_out)];
            }
            let used = node.used();
            stats.box_tests += used.count_ones();
            let (t_in, met, enclosures) = match hull {
                Some(hull) => {
                    let (t_in, met) = hull.entries(lo, hi, used, t_min, *t_max);
                    (t_in, met, [None; 4])
                }
                None => Self::curve_entries(curve, node_enclosure, lo, hi, used, t_min, *t_max),
            };
            let mut found: [(C, usize, Option<[C; 4]>); 4] = [(C::ZERO, 0, None); 4];
            let mut n = 0;
            for c in 0..4 {
                if met >> c & 1 == 0 {
                    continue;
                }
                let mut i = n;
                while i > 0 && found[i - 1].0 > t_in[c] {
                    found[i] = found[i - 1];
                    i -= 1;
                }
                found[i] = (t_in[c], c, enclosures[c].or(node_enclosure));
                n += 1;
            }
            for &(t, c, _) in found[..n].iter() {
                if node.count[c] > 0 && t <= *t_max {
                    let first = node.index[c] as usize;
                    let leaf = &order[first..first + node.count[c] as usize];
                    let met = match hull {
                        Some(hull) if leaf.len() > 1 => {
                            self.triangles_met(hull, leaf, [x, y], [h_in, h_out], t_min, *t_max)
                        }
                        _ => u8::MAX,
                    };
                    for (i, &k) in leaf.iter().enumerate() {
                        if met >> i & 1 == 0 || excluded.is_some_and(|e| e.excludes([x, y], k)) {
                            continue;
                        }
                        stats.texel_tests += 1;
                        if let Some((hit, object_triangle)) = self.intersect_object_triangle(
                            prism,
                            ray,
                            k,
                            [x, y],
                            t_min,
                            *t_max,
                            [h_in, h_out],
                        ) && !excluded.is_some_and(|e| e.excludes([x, y], object_triangle))
                        {
                            *t_max = hit.t;
                            *best = Some(ShellHit {
                                hit,
                                triangle: tri as u32,
                                tile: [x, y],
                                object_triangle,
                            });
                        }
                    }
                }
            }
            for &(t, c, enclosure) in found[..n].iter().rev() {
                if node.count[c] == 0 {
                    stack.push((node.index[c], t, enclosure));
                }
            }
        }
    }

    /// Which of a leaf's (at most four) object triangles `leaf`, placed in the tile at
    /// `(x, y)` as the object test places them, the ray may meet: bit `i` where the hull of
    /// triangle `leaf[i]`'s own box, cut to the tile's heights, is entered within
    /// `[t_min, t_max]` (the leaf's box is the union of up to four of them).
    fn triangles_met<C: Real>(
        &self,
        hull: &PrismHull<C>,
        leaf: &[u32],
        [x, y]: [i32; 2],
        [h_in, h_out]: [C; 2],
        t_min: C,
        t_max: C,
    ) -> u8 {
        let (mut lo, mut hi) = ([[C::ZERO; 4]; 3], [[C::ZERO; 4]; 3]);
        let mut slots = 0u8;
        for (i, &k) in leaf.iter().take(4).enumerate() {
            let placed = Self::shifted(&self.object.triangles[k as usize], x, y);
            for a in 0..3 {
                let values = placed.map(|p| C::from_f64(p.get(a).to_f64()));
                lo[a][i] = values[0].min(values[1]).min(values[2]);
                hi[a][i] = values[0].max(values[1]).max(values[2]);
            }
            lo[2][i] = lo[2][i].max(h_in);
            hi[2][i] = hi[2][i].min(h_out);
            slots |= 1 << i;
        }
        hull.entries(lo, hi, slots, t_min, t_max).1 | !((1u8 << leaf.len().min(4)) - 1)
    }

    /// The curve's box test of four boxes (`lo`, `hi` by axis and child; `used` the slots to
    /// test): their uv enclosures in one vector step, each box rejected by the parent's
    /// enclosure or clipped by [`TextureCurve::box_span_in`]; the entry distances, the
    /// entered boxes as bits, and each entered box's enclosure for its children.
    #[allow(clippy::type_complexity)]
    fn curve_entries<C: Real>(
        curve: &TextureCurve<'_, C>,
        node_enclosure: Option<[C; 4]>,
        lo: [[C; 4]; 3],
        hi: [[C; 4]; 3],
        used: u8,
        t_min: C,
        t_max: C,
    ) -> ([C; 4], u8, [Option<[C; 4]>; 4]) {
        // An unused slot or an empty height range takes the tile's bottom (any finite
        // interval: its enclosure is not used).
        let live = |c: usize| used >> c & 1 == 1 && lo[2][c] <= hi[2][c];
        let bottom = lo[2].iter().copied().fold(C::INFINITY, C::min);
        let heights = |c: usize, end: [[C; 4]; 3]| if live(c) { end[2][c] } else { bottom };
        let enclosures = curve.uv_enclosures(
            core::array::from_fn(|c| heights(c, lo)),
            core::array::from_fn(|c| heights(c, hi)),
        );
        let (mut t_in, mut met) = ([C::ZERO; 4], 0u8);
        for c in 0..4 {
            if !live(c) {
                continue;
            }
            if let Some([u_lo, u_hi, v_lo, v_hi]) = node_enclosure
                && (u_hi < lo[0][c] || u_lo > hi[0][c] || v_hi < lo[1][c] || v_lo > hi[1][c])
            {
                continue;
            }
            let (l, h) = (
                [lo[0][c], lo[1][c], lo[2][c]],
                [hi[0][c], hi[1][c], hi[2][c]],
            );
            if let Some(span) = curve.box_span_in(enclosures[c], l, h, t_min, t_max) {
                t_in[c] = span.t_in;
                met |= 1 << c;
            }
        }
        (t_in, met, enclosures)
    }
}
