//! Displacement-mapped surfaces: the TLAS over prisms and the implicit min-max mipmap BLAS
//! traversed by nonlinear rays (Ogaki 2023, sec. 4.4, 5.1, 5.4).

use core::fmt;
use nlrt_poly::{Real, Vector3};
use nlrt_poly::{decided_sign, solve_cubic_in, solve_quadratic_in};
use nlrt_shellmap::{
    BaseEdges, Hit, NonlinearRay, Prism, Ray, TextureCurve, TexturePlane, alpha_beta_eq11,
    facing_unit, world_normal,
};

use crate::bvh::{Aabb, Bvh4};
use crate::cells::{CURVE_STACK, walk_cells};
use crate::heightfield::{HEIGHT_ONE, HeightField};
use crate::mesh::{BaseMesh, MeshError};
use crate::pose::{PoseUpdate, TlasUpdate};
use crate::stats::TraversalStats;
use crate::tlas::{MAX_TEXEL_COORDINATE, PrismTlas, RootNodes, SetupError};

/// Why a displaced surface could not be built.
#[derive(Clone, Debug, PartialEq)]
pub enum DisplacementError {
    /// The height scale is NaN or infinite.
    BadHeightScale(f64),
    /// The tiling is not a finite number > 0.
    BadTiling(f64),
    /// A triangle's texture coordinates, after tiling, reach beyond
    /// [`MAX_TEXEL_COORDINATE`] texels.
    UvOutOfRange {
        /// The triangle.
        triangle: usize,
    },
}

impl fmt::Display for DisplacementError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadHeightScale(s) => write!(f, "height scale {s} is not a finite number"),
            Self::BadTiling(k) => write!(f, "tiling {k} is not a finite number > 0"),
            Self::UvOutOfRange { triangle } => write!(
                f,
                "triangle {triangle}: texture coordinates times tiling reach beyond {MAX_TEXEL_COORDINATE} texels"
            ),
        }
    }
}

/// Which part of a texel was hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelPart {
    /// The microtriangle `(x, y), (x + 1, y), (x + 1, y + 1)`.
    Lower,
    /// The microtriangle `(x, y), (x + 1, y + 1), (x, y + 1)`.
    Upper,
    /// The whole texel, flat (all four corners at one height; sec. 5.4).
    Flat,
}

/// A hit on a displaced surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit<T: Real> {
    /// The hit in the prism's coordinates.
    pub hit: Hit<T>,
    /// Base triangle.
    pub triangle: u32,
    /// Texel (in the infinite, tiled grid).
    pub texel: [i32; 2],
    /// Part of the texel.
    pub part: TexelPart,
}

/// A displacement-mapped mesh: base mesh, height field, height scale and tiling, with the
/// TLAS over its prisms and the per-triangle roots into the height field's pyramid.
#[derive(Clone, Debug)]
pub struct DisplacedSurface<T: Real> {
    pub(crate) prisms: PrismTlas<T>,
    pub(crate) field: HeightField,
    pub(crate) texel_size: T,
}

impl<T: Real> DisplacedSurface<T> {
    /// Builds the surface: validates parameters, finds each triangle's root nodes and builds
    /// the TLAS over the prisms (one prism per leaf). `tiling` is the number of repeats of the
    /// height map per unit of uv (the fur torus uses 8).
    ///
    /// # Errors
    /// A non-finite height scale, a tiling that is not finite and positive, or texture
    /// coordinates too large for the texel grid.
    pub fn new(
        mesh: BaseMesh<T>,
        field: HeightField,
        height_scale: T,
        tiling: T,
    ) -> Result<Self, DisplacementError> {
        let side = field.side() as f64;
        let prisms = PrismTlas::new(mesh, height_scale, tiling, side).map_err(|e| match e {
            SetupError::HeightScale(v) => DisplacementError::BadHeightScale(v),
            SetupError::Tiling(v) => DisplacementError::BadTiling(v),
            SetupError::UvOutOfRange(triangle) => DisplacementError::UvOutOfRange { triangle },
        })?;
        Ok(Self {
            prisms,
            field,
            texel_size: T::ONE / T::from_f64(side),
        })
    }

    /// The base mesh.
    #[must_use]
    pub fn mesh(&self) -> &BaseMesh<T> {
        &self.prisms.mesh
    }

    /// The height field.
    #[must_use]
    pub fn field(&self) -> &HeightField {
        &self.field
    }

    /// The height field, for editing; call [`HeightField::update_region`] after changing
    /// samples. The TLAS stays valid (prism boxes do not depend on the heights).
    pub fn field_mut(&mut self) -> &mut HeightField {
        &mut self.field
    }

    /// The TLAS.
    #[must_use]
    pub fn tlas(&self) -> &Bvh4<T> {
        &self.prisms.tlas
    }

    /// Moves the base mesh to a new pose (an animation frame: new vertex positions and
    /// normals, the same triangles and uvs) and updates the TLAS by `update`. The height
    /// field, its pyramid and the triangles' root nodes do not depend on the pose and stay
    /// as they are. Hits afterwards are those of a surface built afresh on the posed mesh.
    ///
    /// # Errors
    /// Another vertex count than the mesh's, or a NaN or infinite value (the surface is then
    /// unchanged).
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TlasUpdate, TraversalStats, Wrap};
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Ray;
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p.clone(), vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// let field = HeightField::new(4, vec![u16::MAX; 16], Wrap::Repeat).unwrap();
    /// let mut surface = DisplacedSurface::new(mesh, field, 0.5, 1.0).unwrap();
    /// // The next frame: the square lifted by 1.
    /// let lifted: Vec<DVec3> = p.iter().map(|p| *p + DVec3::Z).collect();
    /// surface.set_pose(&lifted, &[DVec3::Z; 4], TlasUpdate::DEFAULT).unwrap();
    /// let ray = Ray::new(DVec3::new(0.3, 0.6, 3.0), -DVec3::Z).unwrap();
    /// let hit = surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default()).unwrap();
    /// assert!((hit.hit.t - 1.5).abs() < 1e-12);
    /// ```
    pub fn set_pose(
        &mut self,
        positions: &[T::Vec3],
        normals: &[T::Vec3],
        update: TlasUpdate,
    ) -> Result<PoseUpdate, MeshError> {
        self.prisms.set_pose(positions, normals, update)
    }

    /// Root nodes of triangle `i`.
    #[must_use]
    pub fn roots(&self, i: usize) -> RootNodes {
        self.prisms.roots(i)
    }

    /// The prism of triangle `i` (built on the fly).
    #[must_use]
    #[inline]
    pub fn prism(&self, i: usize) -> Prism<T> {
        self.prisms.prism(i)
    }

    /// Bytes of the acceleration data: height samples and pyramid, TLAS, roots (the mesh is
    /// counted separately by [`BaseMesh::memory_bytes`]).
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.field.memory_bytes() + self.prisms.memory_bytes()
    }

    /// The uv side of one texel (`1 / side` of the map): texture coordinates divided by it
    /// are texel coordinates.
    #[must_use]
    pub fn texel_size(&self) -> T {
        self.texel_size
    }

    /// TLAS traversal over the prisms (conservative slab tests, nearest first):
    /// `per_prism(triangle, prism, t_max)` runs for each prism whose box the ray enters before
    /// the current `t_max` and returns a hit and its distance when it finds one nearer; the
    /// nearest such hit is returned. The building block of every per-prism method
    /// ([`DisplacedSurface::intersect`] is this with the BLAS walk as `per_prism`).
    pub fn traverse_prisms<H>(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        per_prism: impl FnMut(usize, &Prism<T>, T) -> Option<(H, T)>,
    ) -> Option<H> {
        self.prisms.traverse(ray, t_min, t_max, per_prism)
    }

    /// A stored sample (or pyramid bound) `s` as a texture height in `[0, 1]`.
    #[must_use]
    #[inline]
    pub fn height(s: u16) -> T {
        // Same division for samples and pyramid bounds: rounding is monotonic, so a bound
        // stays a bound after conversion.
        T::from_i32(i32::from(s)) / T::from_i32(i32::from(HEIGHT_ONE))
    }

    #[inline]
    fn coord(&self, i: i32) -> T {
        T::from_i32(i) * self.texel_size
    }

    /// The texture-space geometry of texel `(x, y)`: its uv square `[u0, v0, u1, v1]` and
    /// its corner heights `[h00, h10, h01, h11]` (the two microtriangles, or a flat texel).
    #[must_use]
    pub fn texel_geometry(&self, x: i32, y: i32) -> ([T; 4], [T; 4]) {
        let c = self.field.texel_corners(i64::from(x), i64::from(y));
        let h = c.map(Self::height);
        let uv = [
            self.coord(x),
            self.coord(y),
            self.coord(x + 1),
            self.coord(y + 1),
        ];
        (uv, h)
    }

    /// The plane of the microtriangle `part` of texel `(x, y)` (normal with `n_h > 0`); the
    /// flat plane `h = const` whenever the texel is flat, whatever `part` says.
    fn texel_plane(&self, x: i32, y: i32, part: TexelPart) -> Option<TexturePlane<T>> {
        let (uv, h) = self.texel_geometry(x, y);
        Self::plane_of(uv, h, part)
    }

    /// [`DisplacedSurface::texel_plane`] from the texel's geometry, already read.
    fn plane_of(
        [u0, v0, u1, v1]: [T; 4],
        [h00, h10, h01, h11]: [T; 4],
        part: TexelPart,
    ) -> Option<TexturePlane<T>> {
        let p = |u: T, v: T, h: T| T::Vec3::new(u, v, h);
        let flat = h00 == h10 && h00 == h01 && h00 == h11;
        match if flat { TexelPart::Flat } else { part } {
            TexelPart::Lower => {
                TexturePlane::through(&[p(u0, v0, h00), p(u1, v0, h10), p(u1, v1, h11)])
            }
            TexelPart::Upper => {
                TexturePlane::through(&[p(u0, v0, h00), p(u1, v1, h11), p(u0, v1, h01)])
            }
            TexelPart::Flat => Some(TexturePlane {
                normal: T::Vec3::new(T::ZERO, T::ZERO, T::ONE),
                k: -h00,
            }),
        }
    }

    /// The nearest hit on texel `(x, y)` with `t` in `[t_min, t_max]`.
    ///
    /// Testing microtriangles independently leaks: each solves its own plane's cubic and
    /// judges its edges from its own hit point, so a hit on or near an edge shared with a
    /// neighbour can land, after rounding, just outside both (measured: every f32 leak of the
    /// mountain and torus scenes was one). So edges are decided once, along the ray: the
    /// curve's heights are split where it crosses the texel's four edge lines and its
    /// diagonal (roots of `U - u_face D`, `V - v_face D` and `U - V - (u0 - v0) D`: the same
    /// quadratics, with the same coefficients, in the neighbouring texel), each piece lies
    /// wholly inside or outside the texel and on one side of the diagonal and is searched with
    /// that side's plane only, and at each split point the planes on its two sides (this
    /// texel's, or the neighbour's across an outer edge) are compared: in exact arithmetic
    /// their cubics have the same sign there (both planes contain the shared edge, above which
    /// the curve point lies), so differing or uncertain signs mean the surface is crossed at
    /// the split point itself, which is reported. A flat texel is the same with one plane.
    pub fn intersect_texel(
        &self,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        x: i32,
        y: i32,
        t_min: T,
        t_max: T,
    ) -> Option<(Hit<T>, TexelPart)> {
        let curve = TextureCurve::new(prism, ray);
        self.texel_hit(prism, ray, &BaseEdges::new(ray), &curve, x, y, t_min, t_max)
    }

    /// [`DisplacedSurface::intersect_texel`] with the base edges and the texture curve's error
    /// bounds computed once per prism.
    #[allow(clippy::too_many_arguments)]
    fn texel_hit(
        &self,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        edges: &BaseEdges<T>,
        curve: &TextureCurve<'_, T>,
        x: i32,
        y: i32,
        t_min: T,
        t_max: T,
    ) -> Option<(Hit<T>, TexelPart)> {
        let (uv, heights) = self.texel_geometry(x, y);
        let ([u0, v0, u1, v1], [h00, h10, h01, h11]) = (uv, heights);
        let flat = h00 == h10 && h00 == h01 && h00 == h11;
        let (part_l, part_u) = if flat {
            (TexelPart::Flat, TexelPart::Flat)
        } else {
            (TexelPart::Lower, TexelPart::Upper)
        };
        let (Some(plane_l), Some(plane_u)) = (
            Self::plane_of(uv, heights, part_l),
            Self::plane_of(uv, heights, part_u),
        ) else {
            return None;
        };
        let (cubic_l, cubic_u) = (plane_l.ray_cubic(ray), plane_u.ray_cubic(ray));
        let (abh_l, abh_u) = (plane_l.canonical(prism), plane_u.canonical(prism));
        let h_lo = h00.min(h10).min(h01).min(h11);
        let h_hi = h00.max(h10).max(h01).max(h11);
        // Edge lines times D: faces u = u0, u1, v = v0, v1 and the diagonal u - v = u0 - v0.
        let line = |a: &[T; 3], face: T| -> [T; 3] {
            core::array::from_fn(|i| (-face).mul_add(ray.d[i], a[i]))
        };
        let c = u0 - v0;
        let u_minus_v: [T; 3] = core::array::from_fn(|i| ray.u[i] - ray.v[i]);
        let diagonal = line(&u_minus_v, c);
        // Split points, each tagged with the edge it lies on (0-3 faces, 4 diagonal, 5 other).
        let mut splits = [(T::ZERO, 5u8); 24];
        let mut n = 0;
        for s in [h_lo, h_hi] {
            splits[n] = (s, 5);
            n += 1;
        }
        // Faces, base edges and a pole that the curve cannot reach on [h_lo, h_hi] (an interval
        // bound beyond the rounding of the quadratic and its evaluation) have no root to
        // solve for: the splits are the same, as the solver would find nothing there either;
        // the neighbouring texel decides the shared face by the same quadratic.
        let faces = [(&ray.u, u0), (&ray.u, u1), (&ray.v, v0), (&ray.v, v1)];
        for (edge, (num, face)) in faces.into_iter().enumerate() {
            if !curve.may_cross(edge / 2, face, h_lo, h_hi) {
                continue;
            }
            for &r in solve_quadratic_in(line(num, face), h_lo, h_hi).iter() {
                splits[n] = (r, edge as u8);
                n += 1;
            }
        }
        for &r in solve_quadratic_in(diagonal, h_lo, h_hi).iter() {
            splits[n] = (r, 4);
            n += 1;
        }
        if edges.may_have_pole(h_lo, h_hi) {
            for &r in solve_quadratic_in(ray.d, h_lo, h_hi).iter() {
                splits[n] = (r, 5);
                n += 1;
            }
        }
        // The base triangle's edges: alpha = 0, beta = 0, alpha + beta = 1 (times D).
        let base_edges = &edges.edges;
        for (k, q) in base_edges.iter().enumerate() {
            if !edges.may_cross(k, h_lo, h_hi) {
                continue;
            }
            for &r in solve_quadratic_in(*q, h_lo, h_hi).iter() {
                splits[n] = (r, 6 + k as u8);
                n += 1;
            }
        }
        let splits = &mut splits[..n];
        splits.sort_unstable_by(|a, b| a.0.partial_cmp(&b.0).unwrap_or(core::cmp::Ordering::Equal));

        let mut best: Option<(Hit<T>, TexelPart)> = None;
        let mut t_max = t_max;
        let mut consider = |h: T, abh: &[T; 4], part: TexelPart, t_max: &mut T| {
            let Some((alpha, beta)) = alpha_beta_eq11(ray, abh, h) else {
                return;
            };
            if !(alpha.is_finite() && beta.is_finite()) {
                return;
            }
            // The pieces decide inside-ness; Eq. 11 may put a point on an edge a rounding
            // error outside, so clamp it onto the base triangle.
            let (alpha, beta) = (alpha.max(T::ZERO), beta.max(T::ZERO));
            let sum = alpha + beta;
            let (alpha, beta) = if sum > T::ONE {
                (alpha / sum, beta / sum)
            } else {
                (alpha, beta)
            };
            let t = ray.signed_distance(prism, alpha, beta, h);
            if t >= t_min && t <= *t_max {
                *t_max = t;
                best = Some((Hit::at(prism, t, alpha, beta, h), part));
            }
        };
        // Where the piece around `h` lies: None outside the texel, else Some(lower side).
        let locate = |h: T| -> Option<bool> {
            let d = ray.d[2].mul_add(h, ray.d[1]).mul_add(h, ray.d[0]);
            if d == T::ZERO {
                return None;
            }
            let u = ray.u[2].mul_add(h, ray.u[1]).mul_add(h, ray.u[0]) / d;
            let v = ray.v[2].mul_add(h, ray.v[1]).mul_add(h, ray.v[0]) / d;
            if !(u >= u0 && u <= u1 && v >= v0 && v <= v1) {
                return None;
            }
            if !edges.contains(h) {
                return None;
            }
            let f = diagonal[2].mul_add(h, diagonal[1]).mul_add(h, diagonal[0]);
            Some((f >= T::ZERO) == (d > T::ZERO) || f == T::ZERO)
        };
        let side = |lower: bool| {
            if lower {
                (&cubic_l, &abh_l, part_l)
            } else {
                (&cubic_u, &abh_u, part_u)
            }
        };
        // The error window of a base-edge crossing (split tags 6-8).
        let edge_window = |edge: u8, s: T| edges.window(usize::from(edge - 6), s);
        if flat {
            // The curve meets the plane h = h00 at one point: a hit when that point is in the
            // texel (u(h), v(h) are the same numbers in every texel, so neighbours agree) and
            // in the base triangle, where a base edge whose crossing lies within its error
            // window of h00 counts as passed (as the pieces are extended above).
            let d = ray.d[2].mul_add(h00, ray.d[1]).mul_add(h00, ray.d[0]);
            if d != T::ZERO {
                let u = ray.u[2].mul_add(h00, ray.u[1]).mul_add(h00, ray.u[0]) / d;
                let v = ray.v[2].mul_add(h00, ray.v[1]).mul_add(h00, ray.v[0]) / d;
                let in_texel = u >= u0 && u <= u1 && v >= v0 && v <= v1;
                let positive = d > T::ZERO;
                let edge_ok = |k: usize| {
                    let q = &base_edges[k];
                    let value = q[2].mul_add(h00, q[1]).mul_add(h00, q[0]);
                    let value = if k == 2 { -value } else { value };
                    value == T::ZERO || (value > T::ZERO) == positive || {
                        let w = edge_window(6 + k as u8, h00);
                        !solve_quadratic_in(*q, h00 - w, h00 + w).is_empty()
                    }
                };
                if in_texel && edge_ok(0) && edge_ok(1) && edge_ok(2) {
                    consider(h00, &abh_l, TexelPart::Flat, &mut t_max);
                }
            }
            return best;
        }
        let mut previous: Option<bool> = None; // location of the piece before the split point
        for i in 0..splits.len() {
            let (a, edge) = splits[i];
            let here = (i + 1 < splits.len() && splits[i + 1].0 > a)
                .then(|| locate((a + splits[i + 1].0) * T::HALF))
                .flatten();
            // The planes on both sides of this split point must agree in sign: on the
            // diagonal this texel's two, on an outer edge this texel's and the neighbour's
            // (unless the curve only touches the edge from inside).
            let inside_next_to_split = previous.is_some() || here.is_some();
            let pair = match edge {
                _ if i == 0 || !inside_next_to_split => None,
                4 => Some((&cubic_l, &abh_l, part_l, Some(cubic_u))),
                0..=3 if previous.is_none() || here.is_none() => {
                    let (own_cubic, own_abh, own_part) = side(here.or(previous).unwrap_or(true));
                    let (nx, ny, part) = match edge {
                        0 => (x - 1, y, TexelPart::Lower),
                        1 => (x + 1, y, TexelPart::Upper),
                        2 => (x, y - 1, TexelPart::Upper),
                        _ => (x, y + 1, TexelPart::Lower),
                    };
                    let other = self.texel_plane(nx, ny, part).map(|p| p.ray_cubic(ray));
                    Some((own_cubic, own_abh, own_part, other))
                }
                _ => None,
            };
            if let Some((own_cubic, own_abh, own_part, Some(other))) = pair {
                let certain_same = match decided_sign(own_cubic, a) {
                    Some(own) => decided_sign(&other, a) == Some(own),
                    None => false,
                };
                if !certain_same {
                    consider(a, own_abh, own_part, &mut t_max);
                }
            }
            if let Some(lower) = here {
                let (b, edge_b) = splits[i + 1];
                let (cubic, abh, part) = side(lower);
                // Where the piece ends on a base-triangle edge, the neighbouring prism computes
                // the same crossing with its own rounding: extend the piece by a bound on this
                // crossing's error so the two prisms' pieces overlap (no gap to slip through);
                // a root found in the extension is reported on the edge.
                let lo = if edge >= 6 {
                    (a - edge_window(edge, a)).max(h_lo)
                } else {
                    a
                };
                let hi = if edge_b >= 6 {
                    (b + edge_window(edge_b, b)).min(h_hi)
                } else {
                    b
                };
                for &r in solve_cubic_in(*cubic, lo, hi).iter() {
                    consider(r.max(a).min(b), abh, part, &mut t_max);
                }
            }
            previous = here;
        }
        best
    }

    /// The nearest hit of `ray` on the displaced surface of triangle `tri` through the
    /// min-max pyramid (the BLAS): the ray's curve walked down the pyramid from the heights at
    /// which it is inside the prism, cut at each node's split lines, each piece clipped to
    /// its child's height bounds (see `traverse_curve_cells` in `cells.rs`), children in order
    /// of entry, pieces entered beyond the current nearest hit skipped, texels whose uv square
    /// misses the base triangle's uv triangle skipped (texel discard), and per texel
    /// the watertight piece search of [`DisplacedSurface::intersect_texel`], each plane's
    /// cubic solved only on the height interval of its piece.
    pub fn intersect_blas(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.walk_blas::<CURVE_STACK>(tri, prism, ray, t_min, t_max, stats)
    }

    /// [`DisplacedSurface::intersect_blas`] with a walk stack of `STACK_LEN` entries (tests
    /// use a tiny one to exercise the fallback).
    fn walk_blas<const STACK_LEN: usize>(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let mut best = None;
        let edges = BaseEdges::new(ray);
        let curve = TextureCurve::new(prism, ray);
        walk_cells::<T, STACK_LEN>(
            self.prisms.roots(tri),
            prism,
            &curve,
            &edges,
            self.texel_size,
            t_min,
            t_max,
            stats,
            |level, x, y| {
                let [lo, hi] = self.field.texel_bounds(level, i64::from(x), i64::from(y));
                [Self::height(lo), Self::height(hi)]
            },
            |x, y, _, t_max, stats| {
                stats.texel_tests += 1;
                let (hit, part) = self.texel_hit(prism, ray, &edges, &curve, x, y, t_min, t_max)?;
                best = Some(SurfaceHit {
                    hit,
                    triangle: tri as u32,
                    texel: [x, y],
                    part,
                });
                Some(hit.t)
            },
        );
        best
    }

    /// The same answer as [`DisplacedSurface::intersect_blas`] without the pyramid: every
    /// texel of the triangle's uv box is tested (the reference for tests).
    pub fn intersect_blas_brute_force(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
    ) -> Option<SurfaceHit<T>> {
        let [x0, y0, x1, y1] = self.prisms.roots(tri).texels;
        let mut best: Option<SurfaceHit<T>> = None;
        let mut t_max = t_max;
        for y in y0..=y1 {
            for x in x0..=x1 {
                if let Some((hit, part)) = self.intersect_texel(prism, ray, x, y, t_min, t_max) {
                    t_max = hit.t;
                    best = Some(SurfaceHit {
                        hit,
                        triangle: tri as u32,
                        texel: [x, y],
                        part,
                    });
                }
            }
        }
        best
    }

    /// The nearest hit of `ray` with `t` in `[t_min, t_max]`: TLAS traversal (conservative
    /// slab tests, nearest first), then the BLAS from the heights at which the ray is inside
    /// each prism.
    pub fn intersect(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.prisms
            .intersect(ray, t_min, t_max, stats, |tri, prism, nl, t_max, stats| {
                let hit = self.intersect_blas(tri, prism, nl, t_min, t_max, stats)?;
                Some((hit, hit.hit.t))
            })
    }

    /// The nearest hit testing every texel of every triangle (no TLAS, no pyramid, no prism
    /// gate): the reference for tests.
    pub fn intersect_brute_force(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<SurfaceHit<T>> {
        self.prisms
            .intersect_brute_force(ray, t_max, |tri, prism, nl, t_max| {
                let hit = self.intersect_blas_brute_force(tri, prism, nl, t_min, t_max)?;
                Some((hit, hit.hit.t))
            })
    }

    /// The world-space unit normal at a hit (Eq. 13), facing against the ray direction `dir`;
    /// `None` where the shell degenerates to a line or point.
    #[must_use]
    pub fn normal(&self, hit: &SurfaceHit<T>, dir: T::Vec3) -> Option<T::Vec3> {
        let prism = self.prism(hit.triangle as usize);
        let ([u0, v0, u1, v1], [h00, h10, h01, h11]) =
            self.texel_geometry(hit.texel[0], hit.texel[1]);
        let p = |u: T, v: T, h: T| T::Vec3::new(u, v, h);
        let plane = match hit.part {
            TexelPart::Flat => TexturePlane {
                normal: T::Vec3::new(T::ZERO, T::ZERO, T::ONE),
                k: -h00,
            },
            TexelPart::Lower => {
                TexturePlane::through(&[p(u0, v0, h00), p(u1, v0, h10), p(u1, v1, h11)])?
            }
            TexelPart::Upper => {
                TexturePlane::through(&[p(u0, v0, h00), p(u1, v1, h11), p(u0, v1, h01)])?
            }
        };
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

impl<T: Real> DisplacedSurface<T> {
    /// The prism boxes' union.
    #[must_use]
    pub fn bounds(&self) -> Aabb<T> {
        self.prisms.tlas.bounds()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{HeightField, Wrap};
    use alloc::vec;
    use alloc::vec::Vec;
    use nlrt_poly::glam::{DVec2, DVec3};

    /// A walk whose stack is too small for its pieces gives up and finishes the triangle by
    /// box tests: the same nearest hits as the full walk and as testing every texel, and the
    /// fallback is counted (the full walk never needs it here).
    #[test]
    fn walk_with_a_tiny_stack_falls_back_to_the_same_hits() {
        // Unequal normals: curved prisms, so the ray's texture-space curve is not a line.
        let normals = [
            DVec3::new(0.2, 0.1, 1.0),
            DVec3::new(-0.1, 0.2, 1.0),
            DVec3::new(0.0, -0.2, 1.0),
            DVec3::new(0.1, 0.0, 1.0),
        ]
        .map(DVec3::normalize);
        let mesh = BaseMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y],
            normals.to_vec(),
            vec![DVec2::ZERO, DVec2::X, DVec2::ONE, DVec2::Y],
            vec![[0, 1, 2], [0, 2, 3]],
        )
        .unwrap();
        let side = 32;
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let heights: Vec<f32> = (0..side * side)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (state >> 40) as f32 / (1u64 << 24) as f32
            })
            .collect();
        let field = HeightField::from_unit_heights(side, &heights, Wrap::Repeat).unwrap();
        let surface = DisplacedSurface::new(mesh, field, 0.2, 1.0).unwrap();
        let (mut fallbacks, mut hits) = (0, 0);
        // Hits on an edge shared by two texels may be found by either, at distances that
        // differ by rounding (distances here are O(1), f64).
        let same = |a: Option<SurfaceHit<f64>>, b: Option<SurfaceHit<f64>>| match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => (a.hit.t - b.hit.t).abs() < 1e-12,
            _ => false,
        };
        for i in 0..200 {
            let (a, b) = (f64::from(i % 20) / 20.0, f64::from(i / 20) / 10.0);
            let origin = DVec3::new(-0.5 + 2.0 * a, -0.3 + b, 0.8);
            let dir = DVec3::new(0.6 - 0.5 * a, 0.4 - 0.3 * b, -0.5);
            let ray = Ray::new(origin, dir).unwrap();
            for tri in 0..2 {
                let prism = surface.prism(tri);
                let nl = NonlinearRay::new(&prism, &ray);
                let (mut full, mut tiny) = (TraversalStats::default(), TraversalStats::default());
                let walked =
                    surface.intersect_blas(tri, &prism, &nl, 0.0, f64::INFINITY, &mut full);
                let fell_back =
                    surface.walk_blas::<2>(tri, &prism, &nl, 0.0, f64::INFINITY, &mut tiny);
                let brute =
                    surface.intersect_blas_brute_force(tri, &prism, &nl, 0.0, f64::INFINITY);
                assert!(same(walked, fell_back), "{walked:?} vs {fell_back:?}");
                assert!(same(walked, brute), "{walked:?} vs {brute:?}");
                assert_eq!(full.fallbacks, 0);
                fallbacks += tiny.fallbacks;
                hits += u32::from(walked.is_some());
            }
        }
        assert!(
            hits > 50 && fallbacks > 50,
            "hits {hits}, fallbacks {fallbacks}"
        );
    }
}
