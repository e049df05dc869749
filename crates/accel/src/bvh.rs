//! A 4-ary bounding volume hierarchy: binned SAH build (no spatial splits), flat nodes, and a
//! nearest-first traversal with a conservative slab test (Ize 2013). One builder serves the
//! TLAS over prisms, an instanced object's texture-space BVH and the pre-tessellated
//! reference.

use alloc::vec::Vec;
use nlrt_poly::{LaneMask, Lanes4, Real, Vector3};

use crate::stack::SpillStack;

/// An axis-aligned box `[lo, hi]`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb<T> {
    /// Lower corner.
    pub lo: [T; 3],
    /// Upper corner.
    pub hi: [T; 3],
}

impl<T: Real> Aabb<T> {
    /// The empty box (union identity).
    pub const EMPTY: Self = Self {
        lo: [T::INFINITY; 3],
        hi: [T::NEG_INFINITY; 3],
    };

    /// The smallest box holding `points`.
    #[must_use]
    pub fn of_points(points: impl IntoIterator<Item = T::Vec3>) -> Self {
        let mut b = Self::EMPTY;
        for p in points {
            b.grow_point(p);
        }
        b
    }

    /// Grows to hold `p`.
    pub fn grow_point(&mut self, p: T::Vec3) {
        for i in 0..3 {
            self.lo[i] = self.lo[i].min(p.get(i));
            self.hi[i] = self.hi[i].max(p.get(i));
        }
    }

    /// The union.
    #[must_use]
    pub fn union(&self, o: &Self) -> Self {
        Self {
            lo: core::array::from_fn(|i| self.lo[i].min(o.lo[i])),
            hi: core::array::from_fn(|i| self.hi[i].max(o.hi[i])),
        }
    }

    /// Half the surface area (the SAH cost weight); 0 when empty.
    #[must_use]
    pub fn half_area(&self) -> T {
        let d: [T; 3] = core::array::from_fn(|i| (self.hi[i] - self.lo[i]).max(T::ZERO));
        d[0] * d[1] + d[1] * d[2] + d[2] * d[0]
    }

    /// Centre along axis `i`.
    #[must_use]
    pub fn centre(&self, i: usize) -> T {
        (self.lo[i] + self.hi[i]) * T::HALF
    }

    /// Whether every bound is finite (a box with a NaN or infinite corner is rejected).
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.lo.iter().chain(self.hi.iter()).all(|v| v.is_finite())
    }
}

/// A ray prepared for slab tests: origin and reciprocal direction.
#[derive(Clone, Copy, Debug)]
pub struct SlabRay<T> {
    origin: [T; 3],
    inv_dir: [T; 3],
}

impl<T: Real> SlabRay<T> {
    /// From origin and direction (direction components may be zero: their reciprocals are
    /// infinite and the slab test handles them).
    #[must_use]
    pub fn new(origin: T::Vec3, dir: T::Vec3) -> Self {
        Self {
            origin: core::array::from_fn(|i| origin.get(i)),
            inv_dir: core::array::from_fn(|i| T::ONE / dir.get(i)),
        }
    }

    /// Entry distance into `b` within `[t_min, t_max]`, or `None`. Conservative: the exit
    /// distance is enlarged by `1 + 2 gamma(3)` (Ize 2013, "Robust BVH Ray Traversal"), so
    /// rounding in the slab distances never culls a box the exact ray meets. A `0 * inf` NaN
    /// (origin on a slab plane, direction parallel to it) is ignored by `min`/`max`, which
    /// keeps that axis unconstrained: conservative too.
    #[must_use]
    #[inline]
    pub fn entry(&self, lo: [T; 3], hi: [T; 3], t_min: T, t_max: T) -> Option<T> {
        let three_u = T::THREE * T::UNIT_ROUNDOFF;
        let widen = T::ONE + T::TWO * (three_u / (T::ONE - three_u));
        let mut t0 = t_min;
        let mut t1 = t_max;
        for i in 0..3 {
            let a = (lo[i] - self.origin[i]) * self.inv_dir[i];
            let b = (hi[i] - self.origin[i]) * self.inv_dir[i];
            let (near, far) = if a <= b { (a, b) } else { (b, a) };
            t0 = t0.max(near);
            t1 = t1.min(far * widen);
        }
        (t0 <= t1).then_some(t0)
    }

    /// [`SlabRay::entry`] of the four child boxes of `node` in one vector step
    /// ([`Real::Four`]): each entry distance and, as bit `c` of the mask, whether box `c`
    /// is entered (unused slots give garbage: mask them with [`Node4::used`]). The same
    /// decisions and entry values as four calls of `entry` (tested; a zero's sign may
    /// differ). Where a reciprocal direction is infinite or 0 (a slab is then a NaN
    /// product, which `entry` resolves with `Real::min`/`max`), it makes those calls.
    #[must_use]
    #[inline]
    pub fn entries(&self, node: &Node4<T>, t_min: T, t_max: T) -> ([T; ARITY], u8) {
        if self.inv_dir.iter().all(|v| v.is_finite() && *v != T::ZERO) {
            return self.entries_in::<T::Four>(node, t_min, t_max);
        }
        self.entries_scalar(node, t_min, t_max)
    }

    /// [`SlabRay::entries`] one box at a time: the reference of the vector step.
    fn entries_scalar(&self, node: &Node4<T>, t_min: T, t_max: T) -> ([T; ARITY], u8) {
        let (mut entries, mut met) = ([T::ZERO; ARITY], 0);
        for (c, entry) in entries.iter_mut().enumerate() {
            let b = node.bounds(c);
            if let Some(t) = self.entry(b.lo, b.hi, t_min, t_max) {
                *entry = t;
                met |= 1 << c;
            }
        }
        (entries, met)
    }

    /// [`SlabRay::entries`] in lanes `L` for finite, nonzero reciprocals: a used slot's
    /// slab ends are then never NaN, so the lanes' `lesser`/`greater` pick what `entry`'s
    /// swap and `Real::min`/`max` pick (up to the sign of a zero).
    #[inline(always)]
    fn entries_in<L: Lanes4<T>>(&self, node: &Node4<T>, t_min: T, t_max: T) -> ([T; ARITY], u8) {
        let three_u = T::THREE * T::UNIT_ROUNDOFF;
        let widen = L::splat(T::ONE + T::TWO * (three_u / (T::ONE - three_u)));
        let mut t0 = L::splat(t_min);
        let mut t1 = L::splat(t_max);
        for i in 0..3 {
            let (o, inv) = (L::splat(self.origin[i]), L::splat(self.inv_dir[i]));
            let a = (L::from_array(node.lo[i]) - o) * inv;
            let b = (L::from_array(node.hi[i]) - o) * inv;
            t0 = a.lesser(b).greater(t0);
            t1 = (a.greater(b) * widen).lesser(t1);
        }
        (t0.to_array(), t0.le(t1).bits())
    }
}

/// Children per node.
pub const ARITY: usize = 4;
/// Marks an unused child slot.
const EMPTY_CHILD: u32 = u32::MAX;

/// A node: up to four children, each an inner node (`count == 0`, `index` = node) or a leaf
/// (`count > 0` primitives at `index` in the primitive order). The children's boxes are
/// stored by axis, the four children side by side (`lo[axis][child]`), so that one vector
/// step tests all four ([`SlabRay::entries`]); an unused slot holds the empty box.
#[derive(Clone, Copy, Debug)]
pub struct Node4<T> {
    /// Lower corners of the child boxes, by axis.
    pub lo: [[T; ARITY]; 3],
    /// Upper corners of the child boxes, by axis.
    pub hi: [[T; ARITY]; 3],
    /// Node index or first primitive.
    pub index: [u32; ARITY],
    /// 0 for an inner node, else the primitive count.
    pub count: [u32; ARITY],
}

impl<T: Real> Node4<T> {
    /// A node with every slot unused.
    const UNUSED: Self = Self {
        lo: [[T::INFINITY; ARITY]; 3],
        hi: [[T::NEG_INFINITY; ARITY]; 3],
        index: [EMPTY_CHILD; ARITY],
        count: [0; ARITY],
    };

    /// The box of child `slot`.
    #[must_use]
    #[inline]
    pub fn bounds(&self, slot: usize) -> Aabb<T> {
        Aabb {
            lo: core::array::from_fn(|a| self.lo[a][slot]),
            hi: core::array::from_fn(|a| self.hi[a][slot]),
        }
    }

    /// Sets the box of child `slot`.
    fn set_bounds(&mut self, slot: usize, b: Aabb<T>) {
        for a in 0..3 {
            self.lo[a][slot] = b.lo[a];
            self.hi[a][slot] = b.hi[a];
        }
    }

    /// The used slots as bits (bit `c` slot `c`).
    #[must_use]
    #[inline]
    pub fn used(&self) -> u8 {
        let mut bits = 0;
        for c in 0..ARITY {
            bits |= u8::from(self.index[c] != EMPTY_CHILD) << c;
        }
        bits
    }

    /// The union of the used children's boxes.
    fn union_of_children(&self) -> Aabb<T> {
        (0..ARITY)
            .filter(|&c| self.index[c] != EMPTY_CHILD)
            .fold(Aabb::EMPTY, |b, c| b.union(&self.bounds(c)))
    }
}

/// A 4-ary BVH over primitives given by their boxes.
#[derive(Clone, Debug)]
pub struct Bvh4<T> {
    nodes: Vec<Node4<T>>,
    order: Vec<u32>,
    root_bounds: Aabb<T>,
    /// Boxes given to the build (finite or not): what [`Bvh4::refit`] expects.
    built_from: usize,
}

/// Binary depth after which the builder switches from SAH to median splits, so that any
/// input (e.g. exponentially spaced boxes, where SAH peels one box per level) gives a tree of
/// depth at most `MEDIAN_AFTER_DEPTH + log2(n)`.
const MEDIAN_AFTER_DEPTH: usize = 40;
/// Inline entries of the traversal stack: a 4-ary node pushes at most 3 entries more than it
/// pops, so this covers trees 10 levels deep (a million leaves); deeper walks (the builder
/// bounds the depth by the binary depth, below `MEDIAN_AFTER_DEPTH + 32`) spill to the heap.
const STACK: usize = 31;

/// Nodes of at most this many primitives are split at the median instead of by SAH.
const SMALL_NODE: usize = 8;

/// Bins of the SAH sweep.
const BINS: usize = 16;

/// Bounds and centre bounds of one side of a split.
type Sides<T> = (Aabb<T>, Aabb<T>);

struct Build<'a, T> {
    boxes: &'a [Aabb<T>],
    centres: Vec<[T; 3]>,
    max_leaf: usize,
    /// Bounds and centre bounds of the two sides of the last SAH split.
    children: core::cell::RefCell<Option<[Sides<T>; 2]>>,
}

/// A binary node before collapsing to 4-ary.
enum Binary<T> {
    Leaf {
        bounds: Aabb<T>,
        first: u32,
        count: u32,
    },
    Inner {
        bounds: Aabb<T>,
        children: [usize; 2],
        /// Its primitives, `count` from `first` in the order (contiguous below any node).
        first: u32,
        count: u32,
    },
}

impl<T: Real> Binary<T> {
    /// As a leaf when it holds at most `leaf_at` primitives: `(bounds, first, count)`.
    fn as_leaf(&self, leaf_at: usize) -> Option<(Aabb<T>, u32, u32)> {
        match *self {
            Binary::Leaf {
                bounds,
                first,
                count,
            } => Some((bounds, first, count)),
            Binary::Inner {
                bounds,
                first,
                count,
                ..
            } => (count as usize <= leaf_at).then_some((bounds, first, count)),
        }
    }
}

impl<T: Real> Build<'_, T> {
    /// Splits at the median centre along the widest centre axis; `None` for a leaf.
    fn median_split(&self, order: &mut [u32]) -> Option<usize> {
        let n = order.len();
        if n <= self.max_leaf {
            return None;
        }
        let mut cb = Aabb::<T>::EMPTY;
        for &p in order.iter() {
            let c = self.centres[p as usize];
            cb.grow_point(T::Vec3::new(c[0], c[1], c[2]));
        }
        let axis = (0..3)
            .max_by(|&a, &b| {
                (cb.hi[a] - cb.lo[a])
                    .partial_cmp(&(cb.hi[b] - cb.lo[b]))
                    .unwrap_or(core::cmp::Ordering::Equal)
            })
            .unwrap_or(0);
        order.select_nth_unstable_by(n / 2, |&a, &b| {
            self.centres[a as usize][axis]
                .partial_cmp(&self.centres[b as usize][axis])
                .unwrap_or(core::cmp::Ordering::Equal)
        });
        Some(n / 2)
    }

    /// Splits `order[range]` by the binned SAH; `None` to make a leaf.
    fn split(&self, order: &mut [u32], cb: &Aabb<T>) -> Option<usize> {
        let n = order.len();
        if n <= 1 {
            return None;
        }
        let mut best: Option<(T, usize, usize)> = None; // cost, axis, bin
        // One pass over the primitives bins all three axes.
        let scale: [T; 3] = core::array::from_fn(|axis| {
            let extent = cb.hi[axis] - cb.lo[axis];
            if extent > T::ZERO {
                T::from_i32(BINS as i32) / extent
            } else {
                T::ZERO
            }
        });
        let mut bins = [[(Aabb::<T>::EMPTY, 0usize); BINS]; 3];
        for &p in order.iter() {
            let c = self.centres[p as usize];
            let b = &self.boxes[p as usize];
            for axis in 0..3 {
                let k = (((c[axis] - cb.lo[axis]) * scale[axis]).to_f64() as usize).min(BINS - 1);
                let bin = &mut bins[axis][k];
                bin.0 = bin.0.union(b);
                bin.1 += 1;
            }
        }
        for axis in 0..3 {
            if scale[axis] == T::ZERO {
                continue;
            }
            let bins = &bins[axis];
            let mut right = [T::ZERO; BINS];
            let (mut acc, mut cnt) = (Aabb::<T>::EMPTY, 0);
            for i in (1..BINS).rev() {
                acc = acc.union(&bins[i].0);
                cnt += bins[i].1;
                right[i] = acc.half_area() * T::from_i32(cnt as i32);
            }
            let (mut acc, mut cnt) = (Aabb::<T>::EMPTY, 0);
            for i in 0..BINS - 1 {
                acc = acc.union(&bins[i].0);
                cnt += bins[i].1;
                let cost = acc.half_area() * T::from_i32(cnt as i32) + right[i + 1];
                if cnt > 0 && cnt < n && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, i));
                }
            }
        }
        let Some((_, axis, bin)) = best else {
            // All centres coincide: split in the middle of the list (or make a leaf).
            return (n > self.max_leaf).then_some(n / 2);
        };
        if n <= self.max_leaf {
            let mut parent = Aabb::<T>::EMPTY;
            for &p in order.iter() {
                parent = parent.union(&self.boxes[p as usize]);
            }
            // Leaf when splitting does not pay (SAH with traversal cost ~ 1 intersection).
            let leaf_cost = parent.half_area() * T::from_i32(n as i32);
            let (cost, _, _) = best?;
            if !(cost + parent.half_area() < leaf_cost) {
                return None;
            }
        }
        let (scale, lo) = (scale[axis], cb.lo[axis]);
        let mut left = 0;
        // The children's bounds and centre bounds, gathered while partitioning (saves each
        // child a pass over its primitives).
        let mut sides = [(Aabb::<T>::EMPTY, Aabb::<T>::EMPTY); 2];
        for i in 0..n {
            let p = order[i] as usize;
            let c = self.centres[p];
            let b = ((c[axis] - lo) * scale).to_f64();
            let side = if (b as usize).min(BINS - 1) <= bin {
                order.swap(i, left);
                left += 1;
                &mut sides[0]
            } else {
                &mut sides[1]
            };
            side.0 = side.0.union(&self.boxes[p]);
            side.1.grow_point(T::Vec3::new(c[0], c[1], c[2]));
        }
        *self.children.borrow_mut() = Some(sides);
        (left > 0 && left < n).then_some(left)
    }
}

impl<T: Real> Bvh4<T> {
    /// Builds over `boxes` with at most `max_leaf` primitives per leaf (1 for the TLAS: one
    /// prism per leaf). Boxes that are not finite are left out of the tree (they can hold no
    /// finite hit); [`Bvh4::primitive_count`] tells how many went in.
    #[must_use]
    pub fn build(boxes: &[Aabb<T>], max_leaf: usize) -> Self {
        let binary = BinaryTree::build(boxes, max_leaf);
        binary.collapsed(0, boxes.len())
    }

    /// Of the trees [`Bvh4::build`] gives with leaves of `1..=max_leaf` primitives (`max_leaf`
    /// at most 8), the one `cost` prices lowest (of equals, the one with the largest leaves:
    /// the fewest nodes, and `build(max_leaf)` where `cost` cannot tell), from one build: a node
    /// of at most 8 primitives is split at its median whatever the leaf size, and a larger
    /// one the same way for each of these sizes, so the tree with leaves of `k` is the one
    /// with leaves of 1 cut at its first nodes of at most `k` primitives (the same
    /// primitives in each leaf; their order within a leaf may differ).
    #[must_use]
    pub fn build_cheapest(boxes: &[Aabb<T>], max_leaf: usize, cost: impl Fn(&Self) -> f64) -> Self {
        let binary = BinaryTree::build(boxes, 1);
        let largest = max_leaf.clamp(1, SMALL_NODE);
        let mut best = binary.collapsed(largest, boxes.len());
        let mut best_cost = cost(&best);
        for leaf_at in (1..largest).rev() {
            let tree = binary.collapsed(leaf_at, boxes.len());
            let c = cost(&tree);
            if c < best_cost {
                (best, best_cost) = (tree, c);
            }
        }
        best
    }
}

/// The binary tree of a build, before its collapse to four children per node.
struct BinaryTree<T> {
    nodes: Vec<Binary<T>>,
    order: Vec<u32>,
}

impl<T: Real> BinaryTree<T> {
    /// The binary tree of [`Bvh4::build`].
    fn build(boxes: &[Aabb<T>], max_leaf: usize) -> Self {
        let max_leaf = max_leaf.max(1);
        let mut order: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| boxes[i as usize].is_finite())
            .collect();
        let centres = boxes
            .iter()
            .map(|b| core::array::from_fn(|i| b.centre(i)))
            .collect();
        let build = Build {
            boxes,
            centres,
            max_leaf,
            children: core::cell::RefCell::new(None),
        };
        // Binary tree first (explicit stack), then collapse.
        let mut binary: Vec<Binary<T>> = Vec::new();
        // Bounds of the primitives and of their centres, in one pass.
        let bounds_of = |order: &[u32], centres: &[[T; 3]]| {
            let (mut b, mut cb) = (Aabb::<T>::EMPTY, Aabb::<T>::EMPTY);
            for &p in order {
                b = b.union(&boxes[p as usize]);
                let c = centres[p as usize];
                cb.grow_point(T::Vec3::new(c[0], c[1], c[2]));
            }
            (b, cb)
        };
        if order.is_empty() {
            return Self {
                nodes: Vec::new(),
                order,
            };
        }
        // (start, end, slot in `binary` to fill)
        binary.push(Binary::Leaf {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        let mut stack = alloc::vec![(0usize, order.len(), 0usize, 0usize, None)];
        while let Some((start, end, slot, depth, known)) = stack.pop() {
            let (bounds, centre_bounds) =
                known.unwrap_or_else(|| bounds_of(&order[start..end], &build.centres));
            build.children.replace(None);
            // Small nodes split at the median centre: binning them costs more than the
            // SAH gains this close to the leaves.
            let split = if depth < MEDIAN_AFTER_DEPTH && end - start > SMALL_NODE {
                build.split(&mut order[start..end], &centre_bounds)
            } else {
                build.median_split(&mut order[start..end])
            };
            match split {
                None => {
                    binary[slot] = Binary::Leaf {
                        bounds,
                        first: start as u32,
                        count: (end - start) as u32,
                    };
                }
                Some(mid) => {
                    let (l, r) = (binary.len(), binary.len() + 1);
                    for _ in 0..2 {
                        binary.push(Binary::Leaf {
                            bounds: Aabb::EMPTY,
                            first: 0,
                            count: 0,
                        });
                    }
                    binary[slot] = Binary::Inner {
                        bounds,
                        children: [l, r],
                        first: start as u32,
                        count: (end - start) as u32,
                    };
                    let sides = build.children.take();
                    stack.push((start, start + mid, l, depth + 1, sides.map(|s| s[0])));
                    stack.push((start + mid, end, r, depth + 1, sides.map(|s| s[1])));
                }
            }
        }
        Self {
            nodes: binary,
            order,
        }
    }

    /// The 4-ary tree, every node of at most `leaf_at` primitives a leaf (0: the binary
    /// tree's leaves), over `built_from` boxes.
    fn collapsed(&self, leaf_at: usize, built_from: usize) -> Bvh4<T> {
        let Some(root) = self.nodes.first() else {
            return Bvh4 {
                nodes: Vec::new(),
                order: self.order.clone(),
                root_bounds: Aabb::EMPTY,
                built_from,
            };
        };
        let root_bounds = match root {
            Binary::Leaf { bounds, .. } | Binary::Inner { bounds, .. } => *bounds,
        };
        let mut nodes = Vec::new();
        collapse(&self.nodes, 0, leaf_at, &mut nodes);
        Bvh4 {
            nodes,
            order: self.order.clone(),
            root_bounds,
            built_from,
        }
    }
}

impl<T: Real> Bvh4<T> {
    /// Primitives in the tree.
    #[must_use]
    pub fn primitive_count(&self) -> usize {
        self.order.len()
    }

    /// The nodes; node 0 is the root (for traversals with other ray kinds, e.g. nonlinear
    /// rays in texture space).
    #[must_use]
    pub fn nodes(&self) -> &[Node4<T>] {
        &self.nodes
    }

    /// Primitive indices in leaf order: a leaf child names `count` of them from `index`.
    #[must_use]
    pub fn primitive_order(&self) -> &[u32] {
        &self.order
    }

    /// Whether `slot` of `node` is used.
    #[must_use]
    pub fn is_used(node: &Node4<T>, slot: usize) -> bool {
        node.index[slot] != EMPTY_CHILD
    }

    /// Inner nodes.
    #[must_use]
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Bytes of nodes and primitive order.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * core::mem::size_of::<Node4<T>>() + self.order.len() * 4
    }

    /// Bounds of everything.
    #[must_use]
    pub fn bounds(&self) -> Aabb<T> {
        self.root_bounds
    }

    /// Refits the tree to new boxes of the same primitives (an animated mesh's prisms):
    /// keeps the topology and primitive order, recomputes every child box bottom-up. `false`
    /// (and the tree unchanged) when the refit cannot be exact: `boxes` has another length
    /// than at the build, a box in the tree is no longer finite, or a box left out at the
    /// build (not finite then) is finite now; the caller then builds afresh.
    #[must_use]
    pub fn refit(&mut self, boxes: &[Aabb<T>]) -> bool {
        if boxes.len() != self.built_from || self.nodes.is_empty() {
            return boxes.len() == self.built_from && boxes.iter().all(|b| !b.is_finite());
        }
        let finite = boxes.iter().filter(|b| b.is_finite()).count();
        if finite != self.order.len() || !self.order.iter().all(|&p| boxes[p as usize].is_finite())
        {
            return false;
        }
        // Children follow their parent in `nodes` (pre-order collapse), so one reverse pass
        // sees every child before its parent.
        for n in (0..self.nodes.len()).rev() {
            for slot in 0..ARITY {
                let node = &self.nodes[n];
                if node.index[slot] == EMPTY_CHILD {
                    continue;
                }
                let (index, count) = (node.index[slot] as usize, node.count[slot] as usize);
                let bounds = if count > 0 {
                    self.order[index..index + count]
                        .iter()
                        .fold(Aabb::EMPTY, |b, &p| b.union(&boxes[p as usize]))
                } else {
                    self.nodes[index].union_of_children()
                };
                self.nodes[n].set_bounds(slot, bounds);
            }
        }
        self.root_bounds = self.nodes[0].union_of_children();
        true
    }

    /// The surface-area cost of the tree for rays uniform over its bounds: the expected
    /// number of child-box tests plus primitive tests per ray, each weighted 1 (a prism test
    /// costs far more than a box test, so the figure is for comparing trees over the same
    /// primitives, e.g. a refitted tree against a fresh build, not an absolute time).
    /// 0 for an empty tree.
    #[must_use]
    pub fn sah_cost(&self) -> f64 {
        // Every slot of a node reached counted as a box test.
        self.expected_tests(|b| b.half_area().to_f64(), |_| ARITY as f64, 1.0)
    }

    /// The expected cost of a query through the tree, each child-box test weighted
    /// `box_test` and each primitive test `primitive_test`: a node reached tests its used
    /// children's boxes, a leaf entered tests its primitives, and a box is reached with the
    /// probability `reach(box) / reach(root)` (the root always): for straight rays uniform
    /// over the bounds, [`Aabb::half_area`] (the surface-area heuristic); for the shell's
    /// texture-space curves, the box's uv rectangle (see `ShellObject::new`). Unlike
    /// [`Bvh4::sah_cost`] (every slot counted, both weights 1) it prices unused slots at
    /// nothing, so trees of different leaf sizes over the same primitives compare. 0 for an
    /// empty tree.
    #[must_use]
    pub fn weighted_cost(
        &self,
        box_test: f64,
        primitive_test: f64,
        reach: impl Fn(&Aabb<T>) -> f64,
    ) -> f64 {
        let used = |node: &Node4<T>| (0..ARITY).filter(|&c| node.index[c] != EMPTY_CHILD).count();
        self.expected_tests(reach, |node| used(node) as f64 * box_test, primitive_test)
    }

    /// The cost of [`Bvh4::sah_cost`] and [`Bvh4::weighted_cost`]: a node reached (with the
    /// probability `reach(its box) / reach(root)`, the root always) costs `node_tests(node)`,
    /// a leaf entered `primitive_test` per primitive. 0 for an empty tree or a root of no
    /// reach.
    fn expected_tests(
        &self,
        reach: impl Fn(&Aabb<T>) -> f64,
        node_tests: impl Fn(&Node4<T>) -> f64,
        primitive_test: f64,
    ) -> f64 {
        let root = reach(&self.root_bounds);
        let Some(first) = self.nodes.first() else {
            return 0.0;
        };
        if !(root > 0.0) {
            return 0.0;
        }
        let mut cost = node_tests(first);
        for node in &self.nodes {
            for slot in 0..ARITY {
                if node.index[slot] == EMPTY_CHILD {
                    continue;
                }
                let tests = if node.count[slot] > 0 {
                    f64::from(node.count[slot]) * primitive_test
                } else {
                    node_tests(&self.nodes[node.index[slot] as usize])
                };
                cost += reach(&node.bounds(slot)) / root * tests;
            }
        }
        cost
    }

    /// Nearest-first traversal: calls `hit(primitive, t_max)` for every primitive whose leaf
    /// box the ray enters before the current `t_max`; `hit` returns the distance of a hit
    /// nearer than `t_max`, which then shrinks it. Returns the final `t_max` (the input when
    /// nothing was hit).
    pub fn traverse(
        &self,
        ray: &SlabRay<T>,
        t_min: T,
        mut t_max: T,
        mut hit: impl FnMut(u32, T) -> Option<T>,
    ) -> T {
        if self.nodes.is_empty() {
            return t_max;
        }
        let mut stack = SpillStack::<_, STACK>::new((0u32, T::ZERO));
        stack.push((0, t_min));
        while let Some((node, entry)) = stack.pop() {
            if entry > t_max {
                continue;
            }
            let node = &self.nodes[node as usize];
            let mut order: [(T, usize); ARITY] = [(T::ZERO, 0); ARITY];
            let mut n = 0;
            let (entries, met) = ray.entries(node, t_min, t_max);
            for (c, &t) in entries.iter().enumerate() {
                if (met & node.used()) >> c & 1 == 1 {
                    // Insertion sort, nearest first.
                    let mut k = n;
                    while k > 0 && order[k - 1].0 > t {
                        order[k] = order[k - 1];
                        k -= 1;
                    }
                    order[k] = (t, c);
                    n += 1;
                }
            }
            // Leaves now, nearest first; inner nodes pushed farthest first.
            for &(t, c) in order[..n].iter() {
                if node.count[c] > 0 && t <= t_max {
                    let first = node.index[c] as usize;
                    for &p in &self.order[first..first + node.count[c] as usize] {
                        if let Some(th) = hit(p, t_max)
                            && th < t_max
                        {
                            t_max = th;
                        }
                    }
                }
            }
            for &(t, c) in order[..n].iter().rev() {
                if node.count[c] == 0 {
                    stack.push((node.index[c], t));
                }
            }
        }
        t_max
    }
}

/// Collapses the binary subtree at `b` into 4-ary nodes appended to `nodes`, each binary
/// node of at most `leaf_at` primitives a leaf; returns the node's index.
fn collapse<T: Real>(
    binary: &[Binary<T>],
    b: usize,
    leaf_at: usize,
    nodes: &mut Vec<Node4<T>>,
) -> u32 {
    let me = nodes.len();
    nodes.push(Node4::UNUSED);
    // Children: open the binary children, then open inner grandchildren while room remains.
    let (mut kids, mut n) = ([0usize; ARITY], 1);
    match &binary[b] {
        Binary::Inner { children, .. } if binary[b].as_leaf(leaf_at).is_none() => {
            kids[..2].copy_from_slice(children);
            n = 2;
        }
        _ => kids[0] = b,
    }
    while n < ARITY {
        // Open the largest inner child.
        let pick = kids[..n]
            .iter()
            .enumerate()
            .filter_map(|(i, &k)| match &binary[k] {
                Binary::Inner { bounds, .. } if binary[k].as_leaf(leaf_at).is_none() => {
                    Some((i, bounds.half_area()))
                }
                _ => None,
            })
            .fold(None::<(usize, T)>, |best, (i, a)| match best {
                Some((_, ba)) if !(a > ba) => best,
                _ => Some((i, a)),
            });
        let Some((i, _)) = pick else { break };
        let Binary::Inner { children, .. } = &binary[kids[i]] else {
            unreachable!()
        };
        let children = *children;
        kids[i] = children[0];
        kids[n] = children[1];
        n += 1;
    }
    for (slot, &k) in kids[..n].iter().enumerate() {
        if let Some((bounds, first, count)) = binary[k].as_leaf(leaf_at) {
            nodes[me].set_bounds(slot, bounds);
            nodes[me].index[slot] = first;
            nodes[me].count[slot] = count;
        } else if let Binary::Inner { bounds, .. } = &binary[k] {
            let child = collapse(binary, k, leaf_at, nodes);
            nodes[me].set_bounds(slot, *bounds);
            nodes[me].index[slot] = child;
            nodes[me].count[slot] = 0;
        }
    }
    me as u32
}

/// Möller-Trumbore: `(t, b1, b2)` of the crossing of the ray `origin + t dir` with the flat
/// triangle `tri` (edges included; `b1`, `b2` the weights of vertices 1 and 2); `None` when
/// the ray is parallel to it, misses it, or an input is not finite. Not watertight: two
/// triangles sharing an edge decide it independently (the methods that use it say so).
#[must_use]
#[inline]
pub fn ray_triangle<T: Real>(
    tri: &[T::Vec3; 3],
    origin: T::Vec3,
    dir: T::Vec3,
) -> Option<(T, T, T)> {
    let (e1, e2) = (tri[1] - tri[0], tri[2] - tri[0]);
    let p = dir.cross(e2);
    let det = e1.dot(p);
    if !(det != T::ZERO && det.is_finite()) {
        return None;
    }
    let inv = T::ONE / det;
    let s = origin - tri[0];
    let b1 = s.dot(p) * inv;
    if !(b1 >= T::ZERO && b1 <= T::ONE) {
        return None;
    }
    let q = s.cross(e1);
    let b2 = dir.dot(q) * inv;
    if !(b2 >= T::ZERO && b1 + b2 <= T::ONE) {
        return None;
    }
    Some((e2.dot(q) * inv, b1, b2))
}

/// A lower bound on the SAH cost ([`Bvh4::sah_cost`]) of any tree over these primitive boxes: each
/// primitive is tested whenever the ray enters its leaf's box, which holds the primitive's,
/// so the primitive tests alone cost at least the boxes' areas over the root's.
#[must_use]
pub fn sah_lower_bound<T: Real>(boxes: &[Aabb<T>], root: &Aabb<T>) -> f64 {
    let root = root.half_area().to_f64();
    if !(root > 0.0) {
        return 0.0;
    }
    boxes.iter().map(|b| b.half_area().to_f64()).sum::<f64>() / root
}

/// `cost` over [`sah_lower_bound`] of `boxes` under `tree`'s root (1 when the bound is 0:
/// flat or empty boxes, where no tree can do better or worse).
pub(crate) fn sah_excess<T: Real>(cost: f64, boxes: &[Aabb<T>], tree: &Bvh4<T>) -> f64 {
    let bound = sah_lower_bound(boxes, &tree.bounds());
    if bound > 0.0 { cost / bound } else { 1.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::DVec3;

    fn boxes(n: usize) -> Vec<Aabb<f64>> {
        let mut r = crate::test_util::unit_randoms(12345);
        (0..n)
            .map(|_| {
                let c = DVec3::new(r(), r(), r()) * 10.0;
                let e = DVec3::new(r(), r(), r()) * 0.3;
                Aabb::of_points([c - e, c + e])
            })
            .collect()
    }

    #[test]
    fn traversal_finds_the_nearest_box_like_a_linear_scan() {
        let bs = boxes(2000);
        for max_leaf in [1, 4] {
            let bvh = Bvh4::build(&bs, max_leaf);
            assert_eq!(bvh.primitive_count(), bs.len());
            let mut unit = crate::test_util::unit_randoms(99);
            let mut r = move || unit() - 0.5;
            for _ in 0..500 {
                let o = DVec3::new(r(), r(), r()) * 30.0 + DVec3::splat(5.0);
                let d = DVec3::new(r(), r(), r()).normalize();
                let ray = SlabRay::new(o, d);
                let linear = bs
                    .iter()
                    .filter_map(|b| ray.entry(b.lo, b.hi, 0.0, f64::INFINITY))
                    .fold(f64::INFINITY, f64::min);
                let mut visited = 0;
                let t = bvh.traverse(&ray, 0.0, f64::INFINITY, |p, t_max| {
                    visited += 1;
                    let b = &bs[p as usize];
                    ray.entry(b.lo, b.hi, 0.0, t_max)
                });
                assert_eq!(t, linear);
                assert!(visited <= bs.len());
            }
        }
    }

    /// The vector slab step against four scalar slab tests and the portable lanes, on every
    /// node of a tree, for rays of every slope (near-axis ones included) from inside and
    /// outside the boxes, some from a box's face: the same decisions and entries.
    fn slab_steps_agree<T: Real>() {
        let mut r = crate::test_util::unit_randoms(4647);
        let v =
            |x: f64, y: f64, z: f64| T::Vec3::new(T::from_f64(x), T::from_f64(y), T::from_f64(z));
        let bs: Vec<Aabb<T>> = (0..300)
            .map(|_| {
                let c = [r() * 10.0, r() * 10.0, r() * 10.0];
                let e = [r() * 0.5, r() * 0.5, r() * 0.5];
                Aabb::of_points([
                    v(c[0] - e[0], c[1] - e[1], c[2] - e[2]),
                    v(c[0] + e[0], c[1] + e[1], c[2] + e[2]),
                ])
            })
            .collect();
        let bvh = Bvh4::build(&bs, 2);
        let (mut cases, mut met, mut missed) = (0, 0, 0);
        for i in 0..400 {
            let mut component = || crate::test_util::direction_component(&mut r);
            let d = v(component(), component(), component());
            // Every fourth ray starts on a box's lower face.
            let o = if i % 4 == 0 {
                let b = &bs[i % bs.len()];
                T::Vec3::new(b.lo[0], b.centre(1), b.centre(2))
            } else {
                v(r() * 14.0 - 2.0, r() * 14.0 - 2.0, r() * 14.0 - 2.0)
            };
            let ray = SlabRay::new(o, d);
            let t_max = if i % 3 == 0 {
                T::INFINITY
            } else {
                T::from_f64(r() * 10.0)
            };
            for node in bvh.nodes() {
                let scalar = ray.entries_scalar(node, T::ZERO, t_max);
                let used = node.used();
                let same = |(e, m): ([T; ARITY], u8)| {
                    m & used == scalar.1 & used
                        && (0..ARITY).all(|c| (m & used) >> c & 1 == 0 || e[c] == scalar.0[c])
                };
                assert!(same(ray.entries(node, T::ZERO, t_max)));
                if ray.inv_dir.iter().all(|v| v.is_finite() && *v != T::ZERO) {
                    assert!(same(ray.entries_in::<T::Four>(node, T::ZERO, t_max)));
                    assert!(same(ray.entries_in::<nlrt_poly::lanes4::Portable4<T>>(
                        node,
                        T::ZERO,
                        t_max
                    )));
                    cases += 1;
                    met += (scalar.1 & used).count_ones();
                    missed += (!scalar.1 & used).count_ones();
                }
            }
        }
        assert!(
            cases > 10_000 && met > 1_000 && missed > 10_000,
            "{cases} {met} {missed}"
        );
    }

    #[test]
    fn the_vector_slab_step_is_the_scalar_one() {
        slab_steps_agree::<f32>();
        slab_steps_agree::<f64>();
    }

    /// Every used slot's box holds what is below it: its primitives' boxes, or its child
    /// node's slots.
    fn assert_boxes_hold_their_children(bvh: &Bvh4<f64>, bs: &[Aabb<f64>]) {
        let holds = |outer: &Aabb<f64>, inner: &Aabb<f64>| {
            (0..3).all(|i| outer.lo[i] <= inner.lo[i] && inner.hi[i] <= outer.hi[i])
        };
        for node in bvh.nodes() {
            for slot in (0..ARITY).filter(|&s| Bvh4::is_used(node, s)) {
                let (index, count) = (node.index[slot] as usize, node.count[slot] as usize);
                if count > 0 {
                    for &p in &bvh.primitive_order()[index..index + count] {
                        assert!(holds(&node.bounds(slot), &bs[p as usize]));
                    }
                } else {
                    let child = &bvh.nodes()[index];
                    for c in (0..ARITY).filter(|&c| Bvh4::is_used(child, c)) {
                        assert!(holds(&node.bounds(slot), &child.bounds(c)));
                    }
                }
            }
        }
    }

    #[test]
    fn refit_to_the_same_boxes_reproduces_the_build_and_to_moved_boxes_stays_exact() {
        let bs = boxes(1000);
        let built = Bvh4::build(&bs, 1);
        let mut refitted = built.clone();
        assert!(refitted.refit(&bs));
        for (a, b) in built.nodes().iter().zip(refitted.nodes()) {
            assert_eq!((a.lo, a.hi), (b.lo, b.hi));
        }
        assert_eq!(built.sah_cost(), refitted.sah_cost());
        // Move every box (a shear and a wave): the refitted tree's boxes hold the new boxes,
        // and its traversal finds the nearest box like a linear scan.
        let moved: Vec<Aabb<f64>> = bs
            .iter()
            .map(|b| {
                let shift = DVec3::new(0.3 * b.lo[1], (b.lo[0]).sin(), -0.2 * b.lo[2]);
                Aabb::of_points([DVec3::from(b.lo) + shift, DVec3::from(b.hi) + shift])
            })
            .collect();
        assert!(refitted.refit(&moved));
        assert_boxes_hold_their_children(&refitted, &moved);
        let fresh = Bvh4::build(&moved, 1);
        assert!(refitted.sah_cost() >= fresh.sah_cost() * 0.9);
        let mut unit = crate::test_util::unit_randoms(7);
        let mut r = move || unit() - 0.5;
        for _ in 0..300 {
            let o = DVec3::new(r(), r(), r()) * 30.0 + DVec3::splat(5.0);
            let ray = SlabRay::new(o, DVec3::new(r(), r(), r()).normalize());
            let linear = moved
                .iter()
                .filter_map(|b| ray.entry(b.lo, b.hi, 0.0, f64::INFINITY))
                .fold(f64::INFINITY, f64::min);
            let t = refitted.traverse(&ray, 0.0, f64::INFINITY, |p, t_max| {
                let b = &moved[p as usize];
                ray.entry(b.lo, b.hi, 0.0, t_max)
            });
            assert_eq!(t, linear);
        }
    }

    /// Two unit cubes half a unit apart (so the SAH keeps them in one leaf when it may) in
    /// one leaf of two or in two leaves under one node: the weighted cost by hand, and the
    /// leaf size that wins flips with the primitive's price.
    #[test]
    fn weighted_cost_prices_box_and_primitive_tests() {
        let cube =
            |x: f64| Aabb::of_points([DVec3::new(x, 0.0, 0.0), DVec3::new(x + 1.0, 1.0, 1.0)]);
        let bs = [cube(0.0), cube(0.5)];
        // Root box 1.5 x 1 x 1: half area 1.5 + 1.5 + 1 = 4; each cube's 3.
        let (one, two) = (Bvh4::build(&bs, 1), Bvh4::build(&bs, 2));
        let (box_test, primitive_test) = (1.0, 5.0);
        let area = |b: &Aabb<f64>| b.half_area();
        let cost = |t: &Bvh4<f64>, primitive_test| t.weighted_cost(1.0, primitive_test, area);
        // Leaves of one: the root's two boxes, then each leaf entered with probability 3/4.
        let expected_one = 2.0 * box_test + 2.0 * (3.0 / 4.0) * primitive_test;
        // One leaf of two: the root's one box, then the leaf (the whole root) entered always.
        let expected_two = box_test + 2.0 * primitive_test;
        assert!((cost(&one, primitive_test) - expected_one).abs() < 1e-12);
        assert_eq!(
            two.nodes().len(),
            1,
            "one leaf of two: {:?}",
            two.nodes()[0].count
        );
        assert!((cost(&two, primitive_test) - expected_two).abs() < 1e-12);
        assert!(cost(&one, 5.0) < cost(&two, 5.0));
        assert!(cost(&one, 0.1) > cost(&two, 0.1));
        // Another measure of reach: the x extent (1.5 for the root, 1 for each cube).
        let x_extent = |b: &Aabb<f64>| b.hi[0] - b.lo[0];
        let by_extent = 2.0 * box_test + 2.0 * (1.0 / 1.5) * primitive_test;
        assert!((one.weighted_cost(box_test, primitive_test, x_extent) - by_extent).abs() < 1e-12);
        assert_eq!(
            Bvh4::<f64>::build(&[], 2).weighted_cost(1.0, 1.5, area),
            0.0
        );
    }

    /// The cheapest build's candidates are the trees of `build` with each leaf size: the
    /// same nodes, boxes and leaf primitives (the order within a leaf aside).
    #[test]
    fn build_cheapest_chooses_among_the_builds_of_each_leaf_size() {
        let bs = boxes(700);
        let leaves = |t: &Bvh4<f64>| {
            let mut out = Vec::new();
            for node in t.nodes() {
                for slot in (0..ARITY).filter(|&s| Bvh4::is_used(node, s)) {
                    let (index, count) = (node.index[slot] as usize, node.count[slot] as usize);
                    let mut set: Vec<u32> = t.primitive_order()[index..index + count].to_vec();
                    set.sort_unstable();
                    out.push((
                        node.bounds(slot),
                        if count > 0 {
                            set
                        } else {
                            alloc::vec![index as u32]
                        },
                    ));
                }
            }
            out
        };
        for k in 1..=4usize {
            let largest_leaf =
                |t: &Bvh4<f64>| t.nodes().iter().flat_map(|n| n.count).max().unwrap_or(0) as usize;
            let chosen = Bvh4::build_cheapest(&bs, 4, |t| largest_leaf(t).abs_diff(k) as f64);
            let built = Bvh4::build(&bs, k);
            assert_eq!(largest_leaf(&built), k);
            assert_eq!(leaves(&chosen), leaves(&built), "leaves of {k}");
            assert_eq!(chosen.bounds(), built.bounds());
        }
        let none = Bvh4::<f64>::build_cheapest(&[], 4, |_| 0.0);
        assert_eq!(none.primitive_count(), 0);
        // A cost that cannot tell the trees apart keeps the largest leaves.
        let indifferent = Bvh4::build_cheapest(&bs, 4, |_| 1.0);
        assert_eq!(leaves(&indifferent), leaves(&Bvh4::build(&bs, 4)));
    }

    #[test]
    fn refit_refuses_what_it_cannot_do_exactly() {
        let mut bs = boxes(20);
        let mut bvh = Bvh4::build(&bs, 1);
        assert!(!bvh.refit(&bs[..19]), "another primitive count");
        let before = (bvh.nodes()[0].lo, bvh.nodes()[0].hi);
        bs[4].hi[1] = f64::INFINITY;
        assert!(!bvh.refit(&bs), "a box in the tree is no longer finite");
        assert_eq!(
            (bvh.nodes()[0].lo, bvh.nodes()[0].hi),
            before,
            "a refused refit changes nothing"
        );
        let mut left_out = Bvh4::build(&bs, 1);
        assert_eq!(left_out.primitive_count(), 19);
        bs[4].hi[1] = bs[4].lo[1] + 1.0;
        assert!(
            !left_out.refit(&bs),
            "a box left out at the build is finite now"
        );
        assert!(Bvh4::<f64>::build(&[], 1).refit(&[]));
        assert_eq!(Bvh4::<f64>::build(&[], 1).sah_cost(), 0.0);
    }

    #[test]
    fn non_finite_boxes_are_left_out() {
        let mut bs = boxes(10);
        bs[3].lo[0] = f64::NAN;
        let bvh = Bvh4::build(&bs, 1);
        assert_eq!(bvh.primitive_count(), 9);
        assert_eq!(Bvh4::<f64>::build(&[], 1).primitive_count(), 0);
    }
}
