//! Shell mapping of an instanced object: the object, given in texture space (one unit tile,
//! `(u, v, h)` in `[0, 1]^3`), repeats over the base mesh's uv plane; an implicit quadtree
//! over the tiles (no memory) leads to the object's texture-space BVH, whose triangles are
//! texture-space planes intersected by the nonlinear ray like microtriangles (Ogaki 2023,
//! sec. 5.2).

use alloc::vec::Vec;
use core::fmt;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{
    BaseEdges, Hit, NonlinearRay, Prism, Ray, TextureCurve, TexturePlane, WideRay, facing_unit,
    onto_base_triangle, world_normal,
};

use crate::affine::{AffinePatches, Walk, walk_straight_tiles};
use crate::bvh::{Aabb, Bvh4};
use crate::cells::{CURVE_STACK, CellSize, walk_cells};
use crate::leaving::{Exclusion, Origin};
use crate::mesh::{BaseMesh, MeshError};
use crate::object_edges::ObjectEdges;
use crate::object_hull::PrismHull;
use crate::pose::{PoseUpdate, TlasUpdate};
use crate::precision::{PrismSearch, Search};
use crate::stack::SpillStack;
use crate::stats::TraversalStats;
use crate::tlas::{MAX_TEXEL_COORDINATE, MAX_TEXEL_RANGE, PrismTlas, Query, RootNodes, SetupError};

mod object_tile;

use object_tile::TileQuery;

/// Why a shell object or surface was rejected.
#[derive(Clone, Debug, PartialEq)]
pub enum ShellError {
    /// A coordinate of object triangle `triangle` is NaN, infinite or outside `[0, 1]`.
    OutsideUnitTile {
        /// The triangle.
        triangle: usize,
    },
    /// The object has no triangle of non-zero area.
    EmptyObject,
    /// The height scale is not finite.
    BadHeightScale(f64),
    /// The tiling is not finite and positive.
    BadTiling(f64),
    /// A base triangle's uvs times the tiling reach beyond [`MAX_TEXEL_COORDINATE`] tiles.
    UvOutOfRange {
        /// The base triangle.
        triangle: usize,
    },
    /// A base triangle's positions or normals times the height scale reach beyond
    /// [`nlrt_shellmap::max_world_coordinate`] of the precision.
    WorldOutOfRange {
        /// The base triangle.
        triangle: usize,
    },
    /// A base triangle spans more than [`MAX_TEXEL_RANGE`] tiles along u or v (after
    /// tiling): subdivide the base mesh.
    TileRangeTooLarge {
        /// The base triangle.
        triangle: usize,
        /// Its extent in tiles along u and v.
        range: [f64; 2],
    },
}

impl fmt::Display for ShellError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::OutsideUnitTile { triangle } => write!(
                f,
                "object triangle {triangle} has a coordinate outside [0, 1] (or NaN): objects live in one unit tile"
            ),
            Self::EmptyObject => write!(f, "the object has no triangle of non-zero area"),
            Self::BadHeightScale(s) => write!(f, "height scale {s} is not a finite number"),
            Self::BadTiling(k) => write!(f, "tiling {k} is not a finite number > 0"),
            Self::UvOutOfRange { triangle } => write!(
                f,
                "base triangle {triangle}: uvs times tiling reach beyond {MAX_TEXEL_COORDINATE} tiles"
            ),
            Self::WorldOutOfRange { triangle } => write!(
                f,
                "base triangle {triangle}: a position, or a normal times the height scale, has a coordinate beyond the largest this precision traces (2^46 in f32, 2^494 in f64: see max_world_coordinate)"
            ),
            Self::TileRangeTooLarge { triangle, range } => write!(
                f,
                "base triangle {triangle} spans {} x {} tiles (u x v, after tiling); at most {MAX_TEXEL_RANGE} per axis are traced: subdivide the base mesh",
                range[0], range[1]
            ),
        }
    }
}

/// A plain error (no source): `?` carries it into `Box<dyn core::error::Error>`.
impl core::error::Error for ShellError {}

/// An object in texture space with its BVH.
#[derive(Clone, Debug)]
pub struct ShellObject<T: Real> {
    triangles: Vec<[T::Vec3; 3]>,
    bvh: Bvh4<T>,
    h_range: [T; 2],
    /// The edges two triangles share, made watertight.
    edges: ObjectEdges<T>,
    /// Triangles dropped because their three points are collinear (no plane).
    pub dropped_degenerate: usize,
}

/// The largest leaf the object's BVH is built with (each size up to it is tried).
const MAX_OBJECT_LEAF: usize = 4;

/// An object-triangle test's cost in box tests of the object's BVH, for choosing its leaf
/// size: about one in time. Instructions put it nearer 1.5, but a box test's divisions (its
/// uv enclosure) weigh more in time than in instructions: at 1.5 the feathers get a leaf
/// size that traces slower than leaves of 4, at 1 every shell scene gets its faster one
/// (docs/measurements.md, "The shell object's leaf size", has the counts and timings).
const TRIANGLE_TEST_COST: f64 = 1.0;

/// [`Bvh4::weighted_cost`] of an object's tree: a box is reached with the probability of
/// its uv rectangle's share of the root's, as the first test a box meets is the curve's uv
/// enclosure over the tile's heights against that rectangle (`intersect_tile`), which
/// short stretches of curve pass in proportion to its area.
fn object_tree_cost<T: Real>(tree: &Bvh4<T>) -> f64 {
    let uv_area = |b: &Aabb<T>| (b.hi[0] - b.lo[0]).to_f64() * (b.hi[1] - b.lo[1]).to_f64();
    tree.weighted_cost(1.0, TRIANGLE_TEST_COST, uv_area)
}

impl<T: Real> ShellObject<T> {
    /// An object from triangles with vertices `(u, v, h)` in `[0, 1]^3`; collinear triangles
    /// (no area, so nothing to hit) are dropped and counted.
    ///
    /// # Errors
    /// A coordinate outside `[0, 1]` or not finite; no triangle left.
    pub fn new(triangles: Vec<[T::Vec3; 3]>) -> Result<Self, ShellError> {
        let mut kept = Vec::with_capacity(triangles.len());
        let mut dropped = 0;
        for (i, t) in triangles.iter().enumerate() {
            let ok = t.iter().all(|p| {
                [p.x(), p.y(), p.z()]
                    .iter()
                    .all(|&c| c >= T::ZERO && c <= T::ONE)
            });
            if !ok {
                return Err(ShellError::OutsideUnitTile { triangle: i });
            }
            if TexturePlane::<T>::through(t).is_some() {
                kept.push(*t);
            } else {
                dropped += 1;
            }
        }
        if kept.is_empty() {
            return Err(ShellError::EmptyObject);
        }
        let boxes: Vec<Aabb<T>> = kept
            .iter()
            .map(|t| Aabb::of_points(t.iter().copied()))
            .collect();
        // The leaf size whose tree costs least (see `TRIANGLE_TEST_COST`): thin, overlapping
        // triangles (the scales) want small leaves, where larger ones save box tests.
        let bvh = Bvh4::build_cheapest(&boxes, MAX_OBJECT_LEAF, object_tree_cost);
        let b = bvh.bounds();
        let edges = ObjectEdges::new(&kept);
        Ok(Self {
            triangles: kept,
            bvh,
            h_range: [b.lo[2], b.hi[2]],
            edges,
            dropped_degenerate: dropped,
        })
    }

    /// Triangles kept.
    #[must_use]
    pub fn triangles(&self) -> &[[T::Vec3; 3]] {
        &self.triangles
    }

    /// Bytes of triangles and BVH (stored once, whatever the number of tiles).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.triangles.len() * core::mem::size_of::<[T::Vec3; 3]>()
            + self.bvh.memory_bytes()
            + self.edges.memory_bytes()
    }
}

/// A hit on a shell-mapped object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShellHit<T: Real> {
    /// The hit in the prism's coordinates.
    pub hit: Hit<T>,
    /// Base triangle.
    pub triangle: u32,
    /// Tile.
    pub tile: [i32; 2],
    /// Object triangle (index into [`ShellObject::triangles`]).
    pub object_triangle: u32,
}

impl<T: Real> ShellHit<T> {
    /// The distance along the ray (`hit.t`).
    #[must_use]
    pub fn t(&self) -> T {
        self.hit.t
    }

    /// The hit's world position on `ray`, the ray that found it (`origin + t dir`).
    #[must_use]
    pub fn position(&self, ray: &Ray<T>) -> T::Vec3 {
        ray.at(self.hit.t)
    }
}

/// A base mesh whose shell holds an object tiled `tiling x tiling` times per unit of uv.
#[derive(Clone, Debug)]
pub struct ShellSurface<T: Real> {
    pub(crate) prisms: PrismTlas<T>,
    object: ShellObject<T>,
    /// The mesh's affine patches (tiles as texels), walked along straight lines
    /// (`crate::affine`), in `f64` from the prisms in `T` widened exactly: the straight walk
    /// runs in `f64` whatever `T` (see [`ShellSurface::intersect_blas`] for the curved path).
    straight: AffinePatches<f64>,
    /// Whether affine patches are walked straight (else every prism takes the curved path).
    straight_walk: bool,
}

/// Inline entries of the object-BVH stack: a 4-ary walk holds at most 3 per level, so this
/// covers trees 10 levels deep (a million leaves); deeper walks spill to the heap.
const OBJECT_STACK: usize = 31;

impl<T: Real> ShellSurface<T> {
    /// Builds the surface: per base triangle its root tiles, and the TLAS.
    ///
    /// # Errors
    /// Bad height scale or tiling, or uvs too large.
    pub fn new(
        mesh: BaseMesh<T>,
        object: ShellObject<T>,
        height_scale: T,
        tiling: T,
    ) -> Result<Self, ShellError> {
        let prisms = PrismTlas::new(mesh, height_scale, [tiling; 2], 1.0).map_err(|e| match e {
            SetupError::HeightScale(v) => ShellError::BadHeightScale(v),
            SetupError::Tiling(v) => ShellError::BadTiling(v),
            SetupError::UvOutOfRange(triangle) => ShellError::UvOutOfRange { triangle },
            SetupError::WorldOutOfRange(triangle) => ShellError::WorldOutOfRange { triangle },
            SetupError::RangeTooLarge(triangle, range) => {
                ShellError::TileRangeTooLarge { triangle, range }
            }
        })?;
        let straight = straight_patches(&prisms);
        Ok(Self {
            prisms,
            object,
            straight,
            straight_walk: true,
        })
    }

    /// Whether prisms whose three displacement directions are equal (grouped into patches of
    /// neighbours that share one affine map) are walked along the ray's straight line in
    /// texture space, the object's boxes and triangles tested on that line (the default), or
    /// every prism along its curve (for comparison: the same surface, hits within rounding).
    pub fn set_straight_walk(&mut self, on: bool) {
        self.straight_walk = on;
    }

    /// The base triangles walked along straight lines when [`ShellSurface::set_straight_walk`]
    /// is on: the affine prisms, but those with a uv seam, a non-manifold edge or an
    /// ill-conditioned frame (a direction nearly in the base plane).
    #[must_use]
    pub fn straight_triangles(&self) -> usize {
        self.straight.straight_triangles()
    }

    /// The object.
    #[must_use]
    pub fn object(&self) -> &ShellObject<T> {
        &self.object
    }

    /// Root tiles of base triangle `i` (the `texels` field holds its tile range).
    #[must_use]
    pub fn roots(&self, i: usize) -> RootNodes {
        self.prisms.roots(i)
    }

    /// The base mesh.
    #[must_use]
    pub fn mesh(&self) -> &BaseMesh<T> {
        &self.prisms.mesh
    }

    /// The prism of base triangle `i`.
    #[must_use]
    pub fn prism(&self, i: usize) -> Prism<T> {
        self.prisms.prism(i)
    }

    /// Moves the base mesh to a new pose and updates the TLAS, as
    /// [`DisplacedSurface::set_pose`]: the object, its BVH and the root tiles stay as they
    /// are.
    ///
    /// # Errors
    /// Another vertex count than the mesh's, or a NaN or infinite value (the surface is then
    /// unchanged).
    ///
    /// [`DisplacedSurface::set_pose`]: crate::DisplacedSurface::set_pose
    pub fn set_pose(
        &mut self,
        positions: &[T::Vec3],
        normals: &[T::Vec3],
        update: TlasUpdate,
    ) -> Result<PoseUpdate, MeshError> {
        let update = self.prisms.set_pose(positions, normals, update)?;
        // A pose may make prisms affine or curved: the patches follow it.
        self.straight = straight_patches(&self.prisms);
        Ok(update)
    }

    /// The TLAS.
    #[must_use]
    pub fn tlas(&self) -> &Bvh4<T> {
        &self.prisms.tlas
    }

    /// TLAS traversal over the prisms, as [`DisplacedSurface::traverse_prisms`]
    /// (`per_prism(triangle, prism, t_max)` per prism box entered, nearest hit returned).
    ///
    /// [`DisplacedSurface::traverse_prisms`]: crate::DisplacedSurface::traverse_prisms
    pub fn traverse_prisms<H>(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        per_prism: impl FnMut(usize, &Prism<T>, T) -> Option<(H, T)>,
    ) -> Option<H> {
        self.prisms.traverse(ray, t_min, t_max, per_prism)
    }

    /// Bytes of acceleration data: object and its BVH (once), TLAS, roots. The quadtree
    /// costs nothing.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.object.memory_bytes() + self.prisms.memory_bytes() + self.straight.memory_bytes()
    }

    #[inline]
    fn shifted(tri: &[T::Vec3; 3], x: i32, y: i32) -> [T::Vec3; 3] {
        let d = T::Vec3::new(T::from_i32(x), T::from_i32(y), T::ZERO);
        [tri[0] + d, tri[1] + d, tri[2] + d]
    }

    /// Object triangle `k` placed in tile `(x, y)`, exactly as the tracer intersects it (the
    /// tile offset added in `T`, so an oracle judging a hit sees the same rounded vertices).
    /// `None` for an index beyond [`ShellObject::triangles`].
    #[must_use]
    pub fn placed_triangle(&self, k: u32, [x, y]: [i32; 2]) -> Option<[T::Vec3; 3]> {
        let tri = self.object.triangles.get(k as usize)?;
        Some(Self::shifted(tri, x, y))
    }

    /// Nearest hit on object triangle `k` placed in tile `(x, y)`, computed in `C` (the
    /// triangle placed in `T`, as [`Self::placed_triangle`] gives it to an oracle, and
    /// widened exactly).
    /// The object triangle hit is returned with the hit: `k`, or a neighbour across a shared
    /// edge of `k` at one of `heights` (where the walk found the curve in the tile;
    /// [`crate::object_edges`]).
    #[inline]
    #[allow(clippy::too_many_arguments)]
    fn intersect_object_triangle<C: Real>(
        &self,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        k: u32,
        [x, y]: [i32; 2],
        t_min: C,
        t_max: C,
        heights: [C; 2],
    ) -> Option<(Hit<C>, u32)> {
        let tri = widened::<T, C>(&Self::shifted(&self.object.triangles[k as usize], x, y));
        self.object.edges.intersect(
            k,
            [x, y],
            &tri,
            prism,
            ray,
            t_min,
            t_max,
            heights,
            |other| {
                self.placed_triangle(other, [x, y])
                    .map(|t| widened::<T, C>(&t))
            },
        )
    }

    /// The nearest hit of `ray` in base triangle `tri` with `t` in `[t_min, t_max]` along its
    /// straight line in texture space, where the triangle is in an affine patch (`None`
    /// otherwise; `Some(None)` for no hit): the tiles the line's padded slab meets, nearest
    /// first, and in each the object's BVH by slab tests and its triangles by the watertight
    /// test (no windows to bound: the test is exact about which side of a shared edge a line
    /// passes). In `f64` whatever `T`, on the prism, ray, boxes and placed triangles of `T`
    /// widened exactly, as the curved path traces an `f32` surface: on `cornell-floor` the
    /// walk in `f32` arithmetic was 1.15x faster with 80 to 170 times the distance error at
    /// the tail (docs/measurements.md, "Shells on affine prisms").
    fn intersect_straight(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &Ray<T>,
        [t_min, t_max]: [T; 2],
        excluded: Option<Exclusion>,
        stats: &mut TraversalStats,
    ) -> Option<Option<ShellHit<T>>> {
        // Every prism of a curved mesh passes here: it leaves before any set-up.
        if !(self.straight_walk && self.straight.is_straight(tri)) {
            return None;
        }
        let wide = Ray::<f64> {
            origin: ray.origin.to_dvec3(),
            dir: ray.dir.to_dvec3(),
        };
        let (t_min, t_max) = (t_min.to_f64(), t_max.to_f64());
        let (line, triangle) = self.straight.line(tri, &wide, t_min)?;
        let Some(walk) = line.and_then(|line| Walk::new(line, triangle, t_min, t_max)) else {
            return Some(None);
        };
        let [h_lo, h_hi] = self.object.h_range.map(|h| h.to_f64());
        let found = walk_straight_tiles(
            &walk,
            self.prisms.roots(tri),
            [h_lo, h_hi],
            stats,
            |x, y, t_best, stats| self.straight_tile(&walk, [x, y], t_best, excluded, stats),
        );
        let Some((tau, (q, object_triangle, tile))) = found else {
            return Some(None);
        };
        let t = walk.world_t(tau);
        if !(t <= t_max) {
            // The clip's upper end is `t_max - t0` rounded: the nearest hit may lie a rounding
            // beyond `t_max`.
            return Some(None);
        }
        let (alpha, beta) = triangle.canonical([q[0], q[1]]);
        let mut hit = Self::narrowed(ShellHit {
            hit: Hit {
                t,
                alpha,
                beta,
                h: q[2].clamp(0.0, 1.0),
                u: 0.0,
                v: 0.0,
            },
            triangle: tri as u32,
            tile,
            object_triangle,
        });
        // Rounding to `T` may carry the sum 1 ulp past 1.
        (hit.hit.alpha, hit.hit.beta) = onto_base_triangle(hit.hit.alpha, hit.hit.beta);
        let uv = prism.texture_uv(hit.hit.alpha, hit.hit.beta);
        (hit.hit.u, hit.hit.v) = (uv.x(), uv.y());
        Some(Some(hit))
    }

    /// The nearest hit in tile `tile` along `walk`'s line below line parameter `t_best`: the
    /// object's BVH nearest first, its boxes placed in the tile as its triangles are (the
    /// offset added in `T`, so that each box holds its placed triangles, then widened) and
    /// padded by the walk's rounding bounds; the line parameter, point, object triangle and
    /// tile.
    #[allow(clippy::type_complexity)]
    fn straight_tile(
        &self,
        walk: &Walk<'_, f64>,
        [x, y]: [i32; 2],
        t_best: f64,
        excluded: Option<Exclusion>,
        stats: &mut TraversalStats,
    ) -> Option<(f64, ([f64; 3], u32, [i32; 2]))> {
        let nodes = self.object.bvh.nodes();
        let order = self.object.bvh.primitive_order();
        if nodes.is_empty() {
            return None;
        }
        let (t_lo, _) = walk.interval();
        let (dx, dy) = (T::from_i32(x), T::from_i32(y));
        let mut t_best = t_best;
        let mut best = None;
        let mut stack = SpillStack::<_, OBJECT_STACK>::new((0u32, 0.0));
        stack.push((0, t_lo));
        while let Some((node, entry)) = stack.pop() {
            if entry > t_best {
                continue;
            }
            let node = &nodes[node as usize];
            // The four boxes side by side (unused slots left at 0 and masked out), tested in
            // one vector step.
            let (mut lo, mut hi) = ([[0.0; 4]; 3], [[0.0; 4]; 3]);
            let mut used = 0u8;
            for c in 0..4 {
                if !Bvh4::is_used(node, c) {
                    continue;
                }
                used |= 1 << c;
                let b = node.bounds(c);
                let w = T::to_f64;
                [lo[0][c], lo[1][c], lo[2][c]] = [w(b.lo[0] + dx), w(b.lo[1] + dy), w(b.lo[2])];
                [hi[0][c], hi[1][c], hi[2][c]] = [w(b.hi[0] + dx), w(b.hi[1] + dy), w(b.hi[2])];
            }
            stats.box_tests += used.count_ones();
            let (t_in, _, met) = walk.four_box_intervals(lo, hi, t_lo, t_best);
            let mut found: [(f64, usize); 4] = [(0.0, 0); 4];
            let mut n = 0;
            for (c, &t) in t_in.iter().enumerate() {
                if (met & used) >> c & 1 == 1 {
                    let mut i = n;
                    while i > 0 && found[i - 1].0 > t {
                        found[i] = found[i - 1];
                        i -= 1;
                    }
                    found[i] = (t, c);
                    n += 1;
                }
            }
            for &(t, c) in &found[..n] {
                if node.count[c] > 0 && t <= t_best {
                    let first = node.index[c] as usize;
                    for &k in &order[first..first + node.count[c] as usize] {
                        if excluded.is_some_and(|e| e.excludes([x, y], k)) {
                            continue;
                        }
                        stats.texel_tests += 1;
                        let placed = Self::shifted(&self.object.triangles[k as usize], x, y)
                            .map(|p| [p.x().to_f64(), p.y().to_f64(), p.z().to_f64()]);
                        if let Some((tau, q)) = walk.triangle_hit(placed, t_best) {
                            t_best = tau;
                            best = Some((tau, (q, k, [x, y])));
                        }
                    }
                }
            }
            for &(t, c) in found[..n].iter().rev() {
                if node.count[c] == 0 {
                    stack.push((node.index[c], t));
                }
            }
        }
        best
    }

    /// The nearest hit in base triangle `tri` through the implicit quadtree over tiles.
    ///
    /// A surface in a type narrower than `f64` traces every prism in `f64` from its own data
    /// (prism and ray widened exactly, [`nlrt_shellmap::in_f64`]; object triangles and boxes
    /// placed in their tile in `T`, as [`ShellSurface::placed_triangle`] gives them, and
    /// widened), the hit rounded back (counted in [`TraversalStats::f64_prisms`]): in `f32`
    /// the object test's rounding exceeded the bounds of its windows on thin, steep triangles
    /// (the feathers' barbs: 9 of 64,817 aimed rays leaked, at Eq. 6's conditions from 1 to
    /// 184 and in tiles from 1 to 122, so no cheaper rule picks the prisms), and the walk's
    /// tile and box tests must decide in the same arithmetic as the object test.
    pub fn intersect_blas(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        self.search(
            narrower_than_f64::<T>(),
            Search::Walk,
            None,
            tri,
            prism,
            ray,
            t_min,
            t_max,
            stats,
        )
    }

    /// Every object triangle in every tile of the triangle's uv box (the test reference), in
    /// the arithmetic of [`ShellSurface::intersect_blas`].
    pub fn intersect_blas_brute_force(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
    ) -> Option<ShellHit<T>> {
        let mut stats = TraversalStats::default();
        let in_f64 = narrower_than_f64::<T>();
        self.search(
            in_f64,
            Search::EveryCell,
            None,
            tri,
            prism,
            ray,
            t_min,
            t_max,
            &mut stats,
        )
    }

    /// The nearest hit: TLAS, the quadtree walked along the ray's curve, object BVH.
    pub fn intersect(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        self.walk_tlas(ray, [t_min, t_max], Query::Nearest, None, stats)
    }

    /// Whether `ray` meets the object at some `t` in `[t_min, t_max]` (a shadow ray's
    /// query): as [`ShellSurface::intersect`], but the first prism that holds a hit ends the
    /// search.
    pub fn occluded(&self, ray: &Ray<T>, t_min: T, t_max: T, stats: &mut TraversalStats) -> bool {
        self.walk_tlas(ray, [t_min, t_max], Query::Any, None, stats)
            .is_some()
    }

    /// The TLAS walk of [`ShellSurface::intersect`], [`ShellSurface::occluded`] and their
    /// leaving forms (`origin`: the element the ray leaves).
    pub(crate) fn walk_tlas(
        &self,
        ray: &Ray<T>,
        [t_min, t_max]: [T; 2],
        query: Query,
        origin: Option<&Origin>,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        let excluded_in = |tri: usize| origin.and_then(|o| o.excluded_in(self.mesh(), tri));
        if narrower_than_f64::<T>() {
            // Traced in `f64` (see `intersect_blas`): each prism's nonlinear ray is set up in
            // `f64` directly, with the ray's part once, not first in `T`.
            let wide = WideRay::new(ray);
            let t_min_f64 = t_min.to_f64();
            return self
                .prisms
                .traverse(ray, t_min, t_max, |tri, prism, t_max| {
                    if query.is_done(t_max) {
                        return None;
                    }
                    stats.prism_tests += 1;
                    let excluded = excluded_in(tri);
                    if let Some(found) =
                        self.intersect_straight(tri, prism, ray, [t_min, t_max], excluded, stats)
                    {
                        let hit = found?;
                        return Some((hit, query.range_after(hit.hit.t)));
                    }
                    stats.f64_prisms += 1;
                    let (prism, nl) = wide.in_prism(prism);
                    let (search, t_max) = (Search::Walk, t_max.to_f64());
                    let hit = self
                        .search_in(search, excluded, tri, &prism, &nl, t_min_f64, t_max, stats)?;
                    let hit = Self::narrowed(hit);
                    Some((hit, query.range_after(hit.hit.t)))
                });
        }
        // Eq. 6's frame depends on the ray alone: set up once for all its prisms.
        let frame = ray.perpendiculars();
        self.prisms
            .traverse(ray, t_min, t_max, |tri, prism, t_max| {
                if query.is_done(t_max) {
                    return None;
                }
                stats.prism_tests += 1;
                let excluded = excluded_in(tri);
                if let Some(found) =
                    self.intersect_straight(tri, prism, ray, [t_min, t_max], excluded, stats)
                {
                    let hit = found?;
                    return Some((hit, query.range_after(hit.hit.t)));
                }
                let nl = NonlinearRay::with_perpendiculars(prism, ray, frame);
                // Eq. 6 sees the origin only through its offset across the ray, which is below the
                // prism box's size for a ray that entered the box, and the box lies within
                // `max_world_coordinate` (checked at construction): finite. A NaN curve would have
                // the walk visit every node (every comparison with NaN fails).
                debug_assert!(nl.is_finite(), "{nl:?} in {prism:?}");
                let hit = self.search(
                    narrower_than_f64::<T>(),
                    Search::Walk,
                    excluded,
                    tri,
                    prism,
                    &nl,
                    t_min,
                    t_max,
                    stats,
                )?;
                Some((hit, query.range_after(hit.hit.t)))
            })
    }

    /// The nearest hit by brute force over every base triangle, tile and object triangle.
    pub fn intersect_brute_force(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<ShellHit<T>> {
        self.brute_force(ray, [t_min, t_max], None)
    }

    /// [`ShellSurface::intersect_brute_force`] with the element `origin` excluded.
    pub(crate) fn brute_force(
        &self,
        ray: &Ray<T>,
        [t_min, t_max]: [T; 2],
        origin: Option<&Origin>,
    ) -> Option<ShellHit<T>> {
        self.prisms
            .intersect_brute_force(ray, t_max, |tri, prism, nl, t_max| {
                let excluded = origin.and_then(|o| o.excluded_in(self.mesh(), tri));
                let hit = self.search(
                    narrower_than_f64::<T>(),
                    Search::EveryCell,
                    excluded,
                    tri,
                    prism,
                    nl,
                    t_min,
                    t_max,
                    &mut TraversalStats::default(),
                )?;
                Some((hit, hit.hit.t))
            })
    }

    /// World-space unit normal at a hit (Eq. 13), facing against `dir`.
    #[must_use]
    pub fn normal(&self, hit: &ShellHit<T>, dir: T::Vec3) -> Option<T::Vec3> {
        let prism = self.prism(hit.triangle as usize);
        let tri = Self::shifted(
            &self.object.triangles[hit.object_triangle as usize],
            hit.tile[0],
            hit.tile[1],
        );
        let plane = TexturePlane::through(&tri)?;
        let n = world_normal(
            &prism,
            &plane.canonical(&prism),
            hit.hit.alpha,
            hit.hit.beta,
            hit.hit.h,
        );
        facing_unit::<T>(n, dir)
    }
}

impl<T: Real> PrismSearch<T> for ShellSurface<T> {
    type Hit<C: Real> = ShellHit<C>;

    fn search_in<C: Real>(
        &self,
        search: Search,
        excluded: Option<Exclusion>,
        tri: usize,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        t_min: C,
        t_max: C,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<C>> {
        let mut best = None;
        match search {
            Search::Walk => {
                let [h_lo, h_hi] = self.object.h_range.map(|h| C::from_f64(h.to_f64()));
                let curve = TextureCurve::new(prism, ray);
                let hull = PrismHull::new(prism, &ray.ray, h_hi);
                let query = TileQuery {
                    tri,
                    prism,
                    curve: &curve,
                    hull: hull.as_ref(),
                    t_min,
                    excluded,
                };
                walk_cells::<C, CURVE_STACK>(
                    self.prisms.roots(tri),
                    prism,
                    &curve,
                    &BaseEdges::new(ray),
                    CellSize::new(C::ONE),
                    t_min,
                    t_max,
                    stats,
                    |_, _, _| [h_lo, h_hi],
                    |x, y, h, t_max, stats| {
                        let mut t = t_max;
                        self.intersect_tile(&query, (x, y), h, &mut t, &mut best, stats);
                        (t < t_max).then_some(t)
                    },
                );
            }
            Search::EveryCell => {
                let [x0, y0, x1, y1] = self.prisms.roots(tri).texels;
                let mut t_max = t_max;
                for y in y0..=y1 {
                    for x in x0..=x1 {
                        for k in 0..self.object.triangles.len() as u32 {
                            if excluded.is_some_and(|e| e.excludes([x, y], k)) {
                                continue;
                            }
                            if let Some((hit, object_triangle)) = self.intersect_object_triangle(
                                prism,
                                ray,
                                k,
                                [x, y],
                                t_min,
                                t_max,
                                [C::NEG_INFINITY, C::INFINITY],
                            ) && !excluded.is_some_and(|e| e.excludes([x, y], object_triangle))
                            {
                                t_max = hit.t;
                                best = Some(ShellHit {
                                    hit,
                                    triangle: tri as u32,
                                    tile: [x, y],
                                    object_triangle,
                                });
                            }
                        }
                    }
                }
            }
        }
        best
    }

    fn narrowed(hit: ShellHit<f64>) -> ShellHit<T> {
        ShellHit {
            hit: hit.hit.narrowed(),
            triangle: hit.triangle,
            tile: hit.tile,
            object_triangle: hit.object_triangle,
        }
    }
}

/// The affine patches of `prisms`' mesh in `f64`: each prism of `T` widened exactly, its
/// vertices taken as given to `T`'s roundoff.
fn straight_patches<T: Real>(prisms: &PrismTlas<T>) -> AffinePatches<f64> {
    let wide: Vec<Prism<f64>> = (0..prisms.mesh.triangle_count())
        .map(|i| {
            let p = prisms.prism(i);
            Prism::<f64>::new(
                p.p.map(Vector3::to_dvec3),
                p.n.map(Vector3::to_dvec3),
                p.uv.map(Vector2::to_dvec2),
            )
        })
        .collect();
    AffinePatches::from_prisms(&wide, 1, T::UNIT_ROUNDOFF.to_f64())
}

/// Whether a shell surface in `T` traces its prisms in `f64` (`T` is narrower).
fn narrower_than_f64<T: Real>() -> bool {
    T::MANTISSA_DIGITS < f64::MANTISSA_DIGITS
}

/// A triangle of `T` in `C`, each coordinate widened (exactly, where `C` is as wide).
fn widened<T: Real, C: Real>(tri: &[T::Vec3; 3]) -> [C::Vec3; 3] {
    let w = |v: T| C::from_f64(v.to_f64());
    tri.map(|p| C::Vec3::new(w(p.x()), w(p.y()), w(p.z())))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nlrt_poly::glam::DVec3;

    /// The object's tree is the cheapest of the leaf sizes tried, for thin overlapping
    /// triangles (where small leaves win) and for a grid of small ones.
    #[test]
    fn the_object_tree_is_the_cheapest_leaf_size() {
        let mut r = crate::test_util::unit_randoms(2024);
        let slivers: Vec<[DVec3; 3]> = (0..64)
            .map(|_| {
                let (u, v) = (r(), r());
                [
                    DVec3::new(u, v, 0.0),
                    DVec3::new(1.0 - u, 1.0 - v, 1.0),
                    DVec3::new(u, 1.0 - v, r()),
                ]
            })
            .collect();
        let grid: Vec<[DVec3; 3]> = (0..64)
            .map(|i| {
                let (x, y) = (f64::from(i % 8) / 8.0, f64::from(i / 8) / 8.0);
                [
                    DVec3::new(x, y, 0.1),
                    DVec3::new(x + 0.1, y, 0.2),
                    DVec3::new(x, y + 0.1, 0.3),
                ]
            })
            .collect();
        for triangles in [slivers, grid] {
            let boxes: Vec<Aabb<f64>> = triangles
                .iter()
                .map(|t| Aabb::of_points(t.iter().copied()))
                .collect();
            let object = ShellObject::<f64>::new(triangles).unwrap();
            let chosen = object_tree_cost(&object.bvh);
            for leaf in 1..=MAX_OBJECT_LEAF {
                let other = object_tree_cost(&Bvh4::build(&boxes, leaf));
                assert!(chosen <= other, "leaf {leaf}: {other} < {chosen}");
            }
        }
    }
}
