//! Displacement-mapped surfaces: the TLAS over prisms and the implicit min-max mipmap BLAS
//! traversed by nonlinear rays (Ogaki 2023, sec. 4.4, 5.1, 5.4).

use core::fmt;
use nlrt_poly::quadratic_range;
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{
    BaseEdges, NonlinearRay, Prism, Ray, TextureCurve, TexturePlane, facing_unit, world_normal,
};

use crate::affine::{AffinePatches, walk_straight};
use crate::bvh::{Aabb, Bvh4};
use crate::cells::{CURVE_STACK, CellSize, walk_cells};
use crate::heightfield::{HEIGHT_ONE, HeightField};
use crate::leaving::{Exclusion, Origin};
use crate::mesh::{BaseMesh, MeshError};
use crate::pose::{PoseUpdate, TlasUpdate};
use crate::precision::{PrismSearch, Search};
use crate::seam::{SeamRule, Seams};
use crate::stats::TraversalStats;
use crate::surface_hit::{SurfaceHit, TexelPart};
use crate::tlas::{MAX_TEXEL_COORDINATE, MAX_TEXEL_RANGE, PrismTlas, Query, RootNodes, SetupError};

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
    /// A triangle's positions or normals times the height scale reach beyond
    /// [`nlrt_shellmap::max_world_coordinate`] of the precision.
    WorldOutOfRange {
        /// The triangle.
        triangle: usize,
    },
    /// A triangle spans more than [`MAX_TEXEL_RANGE`] texels along u or v (after tiling):
    /// subdivide the base mesh.
    TexelRangeTooLarge {
        /// The triangle.
        triangle: usize,
        /// Its extent in texels along u and v.
        range: [f64; 2],
    },
    /// The midlevel is not a number in `[0, 1]`.
    BadMidlevel(f64),
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
            Self::WorldOutOfRange { triangle } => write!(
                f,
                "triangle {triangle}: a position, or a normal times the height scale, has a coordinate beyond the largest this precision traces (2^46 in f32, 2^494 in f64: see max_world_coordinate)"
            ),
            Self::TexelRangeTooLarge { triangle, range } => write!(
                f,
                "triangle {triangle} spans {} x {} texels (u x v, after tiling); at most {MAX_TEXEL_RANGE} per axis are traced: subdivide the base mesh",
                range[0], range[1]
            ),
            Self::BadMidlevel(m) => write!(
                f,
                "midlevel {m} is not a number in [0, 1] (the height at which the map leaves the base mesh where it is)"
            ),
        }
    }
}

/// A plain error (no source): `?` carries it into `Box<dyn core::error::Error>`.
impl core::error::Error for DisplacementError {}

/// The side walls over the base edges as planes in canonical coordinates
/// `(n_alpha, n_beta, n_h, K)` (Eq. 10): `alpha = 0`, `beta = 0`, `alpha + beta = 1`.
pub(crate) const WALL_PLANES: [[i32; 4]; 3] = [[1, 0, 0, 0], [0, 1, 0, 0], [1, 1, 0, -1]];

/// A displacement-mapped mesh: base mesh, height field, height scale and tiling, with the
/// TLAS over its prisms and the per-triangle roots into the height field's pyramid.
///
/// The surface is two-sided: a ray from below the displaced sheet hits it from below (the
/// base triangle itself is no surface). An edge two triangles share is watertight; on an
/// open outer border nothing lies beyond the edge, and a ray exactly on it may hit or miss.
///
/// ```
/// use nlrt_accel::glam::{DVec2, DVec3};
/// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, Ray, TraversalStats, Wrap};
/// // The unit square displaced by 0.5 everywhere: a sheet at z = 0.5.
/// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
/// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
/// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
/// let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Clamp).unwrap();
/// let surface = DisplacedSurface::new(mesh, field, 0.5, 1.0).unwrap();
/// let first = |o: DVec3, d: DVec3| {
///     let ray = Ray::new(o, d).unwrap();
///     surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default())
/// };
/// // From below the base, up through it: the sheet's underside at z = 0.5.
/// assert_eq!(first(DVec3::new(0.3, 0.6, -1.0), DVec3::Z).unwrap().hit.t, 1.5);
/// // Down beside the border: a miss.
/// assert!(first(DVec3::new(1.0 + 1e-9, 0.5, 2.0), -DVec3::Z).is_none());
/// ```
#[derive(Clone, Debug)]
pub struct DisplacedSurface<T: Real> {
    pub(crate) prisms: PrismTlas<T>,
    pub(crate) field: HeightField,
    pub(crate) texel_size: T,
    pub(crate) seams: Seams,
    seam_rule: SeamRule,
    /// `seam_rule` is [`SeamRule::Closed`] and the mesh has seams: walls are tested.
    pub(crate) has_walls: bool,
    /// The mesh's affine patches, walked along straight lines (`crate::affine`).
    straight: AffinePatches<T>,
    /// Whether affine patches are walked straight (else every prism takes the curved path).
    straight_walk: bool,
    /// The height that stays on the base mesh ([`DisplacedSurface::with_midlevel`]).
    midlevel: T,
}

impl<T: Real> DisplacedSurface<T> {
    /// Builds the surface: validates parameters, finds each triangle's root nodes and builds
    /// the TLAS over the prisms (one prism per leaf). `tiling` is the number of repeats of the
    /// height map per unit of uv (the fur torus uses 8). Seams of the mesh are closed
    /// ([`SeamRule::Closed`]: welded displacement directions and seam walls); a mesh without
    /// seams is traced as it is.
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
        Self::with_seam_rule(mesh, field, height_scale, tiling, SeamRule::Closed)
    }

    /// [`DisplacedSurface::new`] with the seams treated by `rule` ([`SeamRule::Open`] keeps
    /// the cracks, to measure them).
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, SeamRule, TexelPart, TraversalStats, Wrap, HEIGHT_ONE};
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Ray;
    /// // A unit square whose two triangles take their uvs from different parts of a clamped
    /// // map: heights 1 right of its middle, 0 left of it. The lower-right triangle is
    /// // displaced by the full height scale, the upper-left one not at all: a step along the
    /// // diagonal they share.
    /// let p = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let positions = vec![p[0], p[1], p[2], p[0], p[2], p[3]];
    /// let uvs: Vec<DVec2> = positions.iter().enumerate().map(|(i, q)| {
    ///     let shift = if i < 3 { DVec2::new(0.5, 0.0) } else { DVec2::new(-0.5, 0.0) };
    ///     DVec2::new(q.x, q.y) * 0.25 + shift
    /// }).collect();
    /// let mesh = BaseMesh::new(positions, vec![DVec3::Z; 6], uvs, vec![[0, 1, 2], [3, 4, 5]]).unwrap();
    /// let field = HeightField::new(2, 2, vec![0, HEIGHT_ONE, 0, HEIGHT_ONE], Wrap::Clamp).unwrap();
    /// // A ray at height 0.25 crossing the diagonal at (0.4, 0.4), from above the low side
    /// // into the high side's shell under its surface: only the seam wall stops it.
    /// let ray = Ray::new(DVec3::new(-1.0, 1.8, 0.25), DVec3::new(1.0, -1.0, 0.0)).unwrap();
    /// let closed = DisplacedSurface::new(mesh.clone(), field.clone(), 0.5, 1.0).unwrap();
    /// let hit = closed.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default());
    /// let hit = hit.unwrap();
    /// assert!(matches!(hit.part, TexelPart::Wall { .. }));
    /// assert!((hit.hit.t - 1.4 * 2f64.sqrt()).abs() < 1e-12);
    /// let open = DisplacedSurface::with_seam_rule(mesh, field, 0.5, 1.0, SeamRule::Open).unwrap();
    /// assert!(open.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default()).is_none());
    /// ```
    ///
    /// # Errors
    /// As [`DisplacedSurface::new`].
    pub fn with_seam_rule(
        mesh: BaseMesh<T>,
        field: HeightField,
        height_scale: T,
        tiling: T,
        rule: SeamRule,
    ) -> Result<Self, DisplacementError> {
        Self::with_midlevel(mesh, field, height_scale, tiling, rule, T::ZERO)
    }

    /// [`DisplacedSurface::with_seam_rule`] for a map whose height `midlevel` (in `[0, 1]`)
    /// stays on the base mesh: the surface lies at `(h - midlevel) * height_scale` along the
    /// directions, so the map pushes both in and out (Blender's and Cycles' midlevel,
    /// RenderMan's displacement centre; `0` pushes out only, `0.5` centres the shell on the
    /// mesh). The shell's floor, [`DisplacedSurface::mesh`], is the base mesh moved by
    /// `-midlevel` times its displacement directions, after the seams' welding, so that the
    /// two sides of a seam move by the same numbers and stay closed; everything else (prisms,
    /// TLAS, walks, seam walls) is built on that floor.
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, SeamRule, TraversalStats, Wrap};
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Ray;
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// // Every sample at height 0.25: with midlevel 0.5 the surface lies a quarter of the
    /// // height scale (2) below the mesh.
    /// let field = HeightField::new(4, 4, vec![16384; 16], Wrap::Repeat).unwrap();
    /// let surface =
    ///     DisplacedSurface::with_midlevel(mesh, field, 2.0, 1.0, SeamRule::Closed, 0.5).unwrap();
    /// let ray = Ray::new(DVec3::new(0.3, 0.6, 3.0), -DVec3::Z).unwrap();
    /// let hit = surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default());
    /// let depth = 3.0 - (16384.0 / 65535.0 - 0.5) * 2.0;
    /// assert!((hit.unwrap().hit.t - depth).abs() < 1e-12);
    /// ```
    ///
    /// # Errors
    /// As [`DisplacedSurface::new`], and a midlevel outside `[0, 1]` or NaN.
    pub fn with_midlevel(
        mesh: BaseMesh<T>,
        field: HeightField,
        height_scale: T,
        tiling: T,
        rule: SeamRule,
        midlevel: T,
    ) -> Result<Self, DisplacementError> {
        if !(midlevel >= T::ZERO && midlevel <= T::ONE) {
            return Err(DisplacementError::BadMidlevel(midlevel.to_f64()));
        }
        if !height_scale.is_finite() {
            return Err(DisplacementError::BadHeightScale(height_scale.to_f64()));
        }
        if !(tiling > T::ZERO && tiling.is_finite()) {
            return Err(DisplacementError::BadTiling(tiling.to_f64()));
        }
        let side = field.grid_side() as f64;
        // The tracers' square grid of `side` texels per unit: the tiling times the map's
        // share of it per axis (exactly the tiling on a square power-of-two map).
        let [scale_u, scale_v] = field.grid_scale();
        let uv_scale = if scale_u == 1.0 && scale_v == 1.0 {
            [tiling; 2]
        } else {
            [
                T::from_f64(tiling.to_f64() * scale_u),
                T::from_f64(tiling.to_f64() * scale_v),
            ]
        };
        let repeats = field.wrap() == crate::Wrap::Repeat;
        let seams = Seams::find(&mesh, tiling.to_f64(), repeats);
        let mut mesh = mesh;
        let welded = (rule == SeamRule::Closed && seams.welds_something())
            .then(|| seams.welded_normals::<T>(mesh.normals()));
        let normals = welded.as_deref().unwrap_or(mesh.normals());
        if welded.is_some() || midlevel != T::ZERO {
            let floor = shell_floor(mesh.positions(), normals, height_scale, midlevel);
            let normals = normals.to_vec();
            // Welded normals of finite normals are finite; a floor can overflow (a huge
            // height scale), which is the world range's error on a triangle using it.
            if mesh.set_pose(&floor, &normals).is_err() {
                let finite =
                    |p: &T::Vec3| p.x().is_finite() && p.y().is_finite() && p.z().is_finite();
                let triangle = (0..mesh.triangle_count())
                    .position(|i| {
                        mesh.triangle(i)
                            .iter()
                            .any(|&v| !finite(&floor[v as usize]))
                    })
                    .unwrap_or(0);
                return Err(DisplacementError::WorldOutOfRange { triangle });
            }
        }
        let prisms = PrismTlas::new(mesh, height_scale, uv_scale, side).map_err(|e| match e {
            SetupError::HeightScale(v) => DisplacementError::BadHeightScale(v),
            SetupError::Tiling(v) => DisplacementError::BadTiling(v),
            SetupError::UvOutOfRange(triangle) => DisplacementError::UvOutOfRange { triangle },
            SetupError::WorldOutOfRange(triangle) => {
                DisplacementError::WorldOutOfRange { triangle }
            }
            SetupError::RangeTooLarge(triangle, range) => {
                DisplacementError::TexelRangeTooLarge { triangle, range }
            }
        })?;
        let straight = AffinePatches::find(&prisms.mesh, height_scale, uv_scale, field.grid_side());
        Ok(Self {
            straight,
            straight_walk: true,
            midlevel,
            prisms,
            field,
            texel_size: T::ONE / T::from_f64(side),
            has_walls: rule == SeamRule::Closed && !seams.edges().is_empty(),
            seams,
            seam_rule: rule,
        })
    }

    /// The base mesh's seams (found whatever the rule).
    #[must_use]
    pub fn seams(&self) -> &Seams {
        &self.seams
    }

    /// How seams are treated.
    #[must_use]
    pub fn seam_rule(&self) -> SeamRule {
        self.seam_rule
    }

    /// The shell's floor: the base mesh with its welded directions, moved by `-midlevel`
    /// times them ([`DisplacedSurface::with_midlevel`]; the base mesh itself at midlevel 0).
    #[must_use]
    pub fn mesh(&self) -> &BaseMesh<T> {
        &self.prisms.mesh
    }

    /// The height that stays on the base mesh ([`DisplacedSurface::with_midlevel`]).
    #[must_use]
    pub fn midlevel(&self) -> T {
        self.midlevel
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
    /// let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Repeat).unwrap();
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
        let vertices = self.mesh().positions().len();
        let sizes_match = positions.len() == vertices && normals.len() == vertices;
        let welded =
            (self.seam_rule == SeamRule::Closed && self.seams.welds_something() && sizes_match)
                .then(|| self.seams.welded_normals::<T>(normals));
        let normals = welded.as_deref().unwrap_or(normals);
        let update = if self.midlevel != T::ZERO && sizes_match {
            let scale = self.prisms.height_scale;
            let floor = shell_floor(positions, normals, scale, self.midlevel);
            self.prisms.set_pose(&floor, normals, update)
        } else {
            self.prisms.set_pose(positions, normals, update)
        }?;
        // A pose may make prisms affine or curved: the patches follow it.
        self.straight = AffinePatches::find(
            &self.prisms.mesh,
            self.prisms.height_scale,
            self.prisms.uv_scale,
            self.field.grid_side(),
        );
        Ok(update)
    }

    /// Whether prisms whose three displacement directions are equal (grouped into patches of
    /// neighbours that share one affine map) are walked along the ray's straight line in texel space
    /// (the default), or every prism along its curve (for comparison: the same surface, hits
    /// within rounding).
    pub fn set_straight_walk(&mut self, on: bool) {
        self.straight_walk = on;
    }

    /// The base triangles walked along straight lines when [`DisplacedSurface::set_straight_walk`]
    /// is on: the affine prisms, but those with a uv seam, a non-manifold edge or an
    /// ill-conditioned frame (a direction nearly in the base plane).
    #[must_use]
    pub fn straight_triangles(&self) -> usize {
        self.straight.straight_triangles()
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
        self.field.memory_bytes() + self.prisms.memory_bytes() + self.straight.memory_bytes()
    }

    /// The side of one cell of the tracers' square texel grid, `1 / grid_side`
    /// ([`HeightField::grid_side`]), in the grid's own coordinates: texture coordinates times
    /// the tiling and [`HeightField::grid_scale`], divided by it, are grid coordinates. On a
    /// square power-of-two map these are the map's texels in uv (times the tiling); on any
    /// other map the texel of the map in uv is [`DisplacedSurface::texel_uv_size`].
    #[must_use]
    pub fn texel_size(&self) -> T {
        self.texel_size
    }

    /// The uv extent of one texel of the height map, per axis: `1 / (width * tiling)` and
    /// `1 / (height * tiling)`, what [`SurfaceHit::texel`] counts (texel `(i, j)` spans
    /// `[i, i + 1] x [j, j + 1]` times this).
    ///
    /// ```
    /// use nlrt_accel::glam::{DVec2, DVec3};
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, Wrap};
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// let field = HeightField::new(300, 200, vec![0; 300 * 200], Wrap::Clamp).unwrap();
    /// let surface = DisplacedSurface::new(mesh, field, 0.1, 2.0).unwrap();
    /// assert_eq!(surface.texel_uv_size(), [1.0 / 600.0, 1.0 / 400.0]);
    /// ```
    #[must_use]
    pub fn texel_uv_size(&self) -> [T; 2] {
        // uvs times `uv_scale` (the tiling times the map's share of the grid) times the grid
        // side are texel coordinates.
        let side = self.field.grid_side() as f64;
        self.prisms
            .uv_scale
            .map(|scale| T::from_f64(1.0 / (scale.to_f64() * side)))
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

    /// The texture-space geometry of texel `(x, y)`: its uv square `[u0, v0, u1, v1]` and
    /// its corner heights `[h00, h10, h01, h11]` (the two microtriangles, or a flat texel).
    #[must_use]
    pub fn texel_geometry(&self, x: i32, y: i32) -> ([T; 4], [T; 4]) {
        self.texel_geometry_in::<T>(x, y)
    }

    /// The plane of the microtriangle `part` of texel `(x, y)` (see [`plane_of`]), computed in
    /// `C` from the texel's corners in `T` (widened exactly where `C` is wider: the same
    /// microtriangles).
    pub(crate) fn texel_plane_in<C: Real>(
        &self,
        x: i32,
        y: i32,
        part: TexelPart,
    ) -> Option<TexturePlane<C>> {
        let (uv, h) = self.texel_geometry_in::<C>(x, y);
        plane_of(uv, h, part)
    }

    /// [`DisplacedSurface::texel_geometry`] in `C`: each value computed in `T`, then converted
    /// (exactly, from `f32` to `f64` or to itself).
    pub(crate) fn texel_geometry_in<C: Real>(&self, x: i32, y: i32) -> ([C; 4], [C; 4]) {
        let c = self.field.texel_corners(i64::from(x), i64::from(y));
        // In i64: the far side of texel i32::MAX is 2^31 (a public call may name any texel).
        let (x, y) = (i64::from(x), i64::from(y));
        let uv = [x, y, x + 1, y + 1].map(|i| self.coord_in::<C>(i));
        (uv, c.map(Self::height_in::<C>))
    }

    /// [`DisplacedSurface::height`] in `C`: the value in `T`, converted (computed in `C`
    /// directly where `C` is `T`: the same value without two conversions per sample).
    #[inline]
    fn height_in<C: Real>(s: u16) -> C {
        if C::MANTISSA_DIGITS == T::MANTISSA_DIGITS {
            C::from_i32(i32::from(s)) / C::from_i32(i32::from(HEIGHT_ONE))
        } else {
            C::from_f64(Self::height(s).to_f64())
        }
    }

    /// The texture coordinate of cell boundary `i` in `C`, as [`DisplacedSurface::height_in`].
    #[inline]
    fn coord_in<C: Real>(&self, i: i64) -> C {
        // |i| <= 2^31: exact in f64, and rounded once to C as an i32 would be.
        let boundary = C::from_f64(i as f64);
        if C::MANTISSA_DIGITS == T::MANTISSA_DIGITS {
            boundary * C::from_f64(self.texel_size.to_f64())
        } else {
            C::from_f64((T::from_f64(i as f64) * self.texel_size).to_f64())
        }
    }

    /// The nearest hit of `ray` on the displaced surface of triangle `tri` through the
    /// min-max pyramid (the BLAS): the ray's curve walked down the pyramid from the heights at
    /// which it is inside the prism, cut at each node's split lines, each piece clipped to
    /// its child's height bounds (see `traverse_curve_cells` in `cells.rs`), children in order
    /// of entry, pieces entered beyond the current nearest hit skipped, texels whose uv square
    /// misses the base triangle's uv triangle skipped (texel discard), and per texel
    /// the watertight piece search of [`DisplacedSurface::intersect_texel`], each plane's
    /// cubic solved only on the height interval of its piece.
    ///
    /// On an `f32` surface, a prism where Eq. 6 is ill-conditioned for the ray (the ray
    /// nearly parallel to its layers: [`NonlinearRay::condition`] above 64 at the height 0,
    /// 1/2 or 1) or where the curve may have a pole inside the shell is traced in `f64` from
    /// the same inputs, widened exactly, on the same texels
    /// ([`nlrt_shellmap::in_f64`]), and the hit rounded back: the `f32` curve's own error
    /// there would move hits by more than its rounding bounds see (counted in
    /// [`TraversalStats::f64_prisms`]).
    pub fn intersect_blas(
        &self,
        tri: usize,
        prism: &Prism<T>,
        ray: &NonlinearRay<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.search(
            ill_conditioned_in_narrow_type(ray),
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

    /// [`DisplacedSurface::intersect_blas`] computed in `C` (`T`, or `f64` for an
    /// ill-conditioned prism of an `f32` surface, on the same texels: their corners computed in
    /// `T` and converted) with a walk stack of `STACK_LEN` entries (tests use a tiny one to
    /// exercise the fallback).
    fn walk_blas<C: Real, const STACK_LEN: usize>(
        &self,
        excluded: Option<Exclusion>,
        tri: usize,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        [t_min, t_max]: [C; 2],
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<C>> {
        let mut best = None;
        let edges = BaseEdges::new(ray);
        let curve = TextureCurve::new(prism, ray);
        let widen = |v: T| C::from_f64(v.to_f64());
        let cells = CellSize {
            size: widen(self.texel_size),
            f32_lines: T::MANTISSA_DIGITS < C::MANTISSA_DIGITS,
        };
        walk_cells::<C, STACK_LEN>(
            self.prisms.roots(tri),
            prism,
            &curve,
            &edges,
            cells,
            t_min,
            t_max,
            stats,
            |level, x, y| {
                let [lo, hi] = self.field.texel_bounds(level, i64::from(x), i64::from(y));
                [Self::height_in::<C>(lo), Self::height_in::<C>(hi)]
            },
            |x, y, _, t_max, stats| {
                stats.texel_tests += 1;
                let (hit, part) = self.texel_hit(
                    prism,
                    ray,
                    (&edges, &curve, excluded),
                    [x, y],
                    [t_min, t_max],
                    &mut stats.undecided_in_f32,
                )?;
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
        let mut stats = TraversalStats::default();
        self.search(
            ill_conditioned_in_narrow_type(ray),
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

    /// [`DisplacedSurface::intersect_blas_brute_force`] computed in `C`.
    fn brute_force_in<C: Real>(
        &self,
        excluded: Option<Exclusion>,
        tri: usize,
        prism: &Prism<C>,
        ray: &NonlinearRay<C>,
        [t_min, t_max]: [C; 2],
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<C>> {
        let [x0, y0, x1, y1] = self.prisms.roots(tri).texels;
        let edges = BaseEdges::new(ray);
        let curve = TextureCurve::new(prism, ray);
        let mut best: Option<SurfaceHit<C>> = None;
        let mut t_max = t_max;
        for y in y0..=y1 {
            for x in x0..=x1 {
                if let Some((hit, part)) = self.texel_hit(
                    prism,
                    ray,
                    (&edges, &curve, excluded),
                    [x, y],
                    [t_min, t_max],
                    &mut stats.undecided_in_f32,
                ) {
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
    /// each prism: along the ray's straight line in texel space on the triangles of affine
    /// patches ([`DisplacedSurface::straight_triangles`], unless
    /// [`DisplacedSurface::set_straight_walk`] turned it off), along its curve elsewhere
    /// ([`DisplacedSurface::intersect_blas`]).
    pub fn intersect(
        &self,
        ray: &Ray<T>,
        t_min: T,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        self.walk_tlas(ray, [t_min, t_max], Query::Nearest, None, stats)
    }

    /// Whether `ray` meets the surface at some `t` in `[t_min, t_max]` (a shadow ray's
    /// query): as [`DisplacedSurface::intersect`], but the first prism that holds a hit ends
    /// the search, where the nearest hit would go on to the prisms whose boxes the ray
    /// enters before that hit.
    pub fn occluded(&self, ray: &Ray<T>, t_min: T, t_max: T, stats: &mut TraversalStats) -> bool {
        self.walk_tlas(ray, [t_min, t_max], Query::Any, None, stats)
            .is_some()
    }

    /// The TLAS walk of [`DisplacedSurface::intersect`], [`DisplacedSurface::occluded`] and
    /// their leaving forms (`origin`: the element the ray leaves).
    pub(crate) fn walk_tlas(
        &self,
        ray: &Ray<T>,
        [t_min, t_max]: [T; 2],
        query: Query,
        origin: Option<&Origin>,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        // Eq. 6's frame depends on the ray alone: set up once for all its prisms.
        let frame = ray.perpendiculars();
        let nearest_in = |tri: usize, prism: &Prism<T>, t_max: T, stats: &mut TraversalStats| {
            let excluded = origin.and_then(|o| o.excluded_in(self.mesh(), tri));
            if self.straight_walk
                && let Some((line, triangle)) = self.straight.line(tri, ray, t_min)
            {
                // An affine patch has no seam edge (a seam's two sides differ in uv): no wall.
                let roots = self.prisms.roots(tri);
                let found = walk_straight(
                    &self.field,
                    roots,
                    line?,
                    triangle,
                    [t_min, t_max],
                    excluded,
                    stats,
                )?;
                let mut hit = found.hit;
                let uv = prism.texture_uv(hit.alpha, hit.beta);
                (hit.u, hit.v) = (uv.x(), uv.y());
                return Some(SurfaceHit {
                    hit,
                    triangle: tri as u32,
                    texel: found.texel,
                    part: match found.part {
                        0 => TexelPart::Lower,
                        1 => TexelPart::Upper,
                        _ => TexelPart::Flat,
                    },
                });
            }
            let nl = NonlinearRay::with_perpendiculars(prism, ray, frame);
            // Eq. 6 sees the origin only through its offset across the ray, which is below the
            // prism box's size for a ray that entered the box, and the box lies within
            // `max_world_coordinate` (checked at construction): finite. A NaN curve would have
            // the walk visit every node (every comparison with NaN fails).
            debug_assert!(nl.is_finite(), "{nl:?} in {prism:?}");
            let hit = self.search(
                ill_conditioned_in_narrow_type(&nl),
                Search::Walk,
                excluded,
                tri,
                prism,
                &nl,
                t_min,
                t_max,
                stats,
            );
            self.nearer_wall_hit(tri, prism, &nl, [t_min, t_max], excluded, hit)
        };
        self.prisms
            .traverse(ray, t_min, t_max, |tri, prism, t_max| {
                if query.is_done(t_max) {
                    return None;
                }
                stats.prism_tests += 1;
                let hit = nearest_in(tri, prism, t_max, stats)?;
                Some((hit, query.range_after(hit.hit.t)))
            })
    }

    /// The nearest hit testing every texel of every triangle (no TLAS, no pyramid, no prism
    /// gate): the reference for tests.
    pub fn intersect_brute_force(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<SurfaceHit<T>> {
        self.brute_force(ray, [t_min, t_max], None)
    }

    /// [`DisplacedSurface::intersect_brute_force`] with the element `origin` excluded.
    pub(crate) fn brute_force(
        &self,
        ray: &Ray<T>,
        [t_min, t_max]: [T; 2],
        origin: Option<&Origin>,
    ) -> Option<SurfaceHit<T>> {
        self.prisms
            .intersect_brute_force(ray, t_max, |tri, prism, nl, t_max| {
                let excluded = origin.and_then(|o| o.excluded_in(self.mesh(), tri));
                let mut stats = TraversalStats::default();
                let hit = self.search(
                    ill_conditioned_in_narrow_type(nl),
                    Search::EveryCell,
                    excluded,
                    tri,
                    prism,
                    nl,
                    t_min,
                    t_max,
                    &mut stats,
                );
                let hit = self.nearer_wall_hit(tri, prism, nl, [t_min, t_max], excluded, hit)?;
                Some((hit, hit.hit.t))
            })
    }

    /// The world-space unit normal at a hit (Eq. 13), facing against the ray direction `dir`;
    /// `None` where the shell degenerates to a line or point.
    #[must_use]
    pub fn normal(&self, hit: &SurfaceHit<T>, dir: T::Vec3) -> Option<T::Vec3> {
        let (prism, abh) = self.element_plane(hit)?;
        let n = world_normal(&prism, &abh, hit.hit.alpha, hit.hit.beta, hit.hit.h);
        facing_unit::<T>(n, dir)
    }

    /// The prism of a hit and the plane of the element hit in its canonical coordinates
    /// (`None` for a degenerate microtriangle).
    pub(crate) fn element_plane(&self, hit: &SurfaceHit<T>) -> Option<(Prism<T>, [T; 4])> {
        let prism = self.prism(hit.triangle as usize);
        if let TexelPart::Wall { edge } = hit.part {
            return Some((prism, WALL_PLANES[usize::from(edge)].map(T::from_i32)));
        }
        let (uv, heights) = self.texel_geometry(hit.texel[0], hit.texel[1]);
        let plane = plane_of(uv, heights, hit.part)?;
        let abh = plane.canonical(&prism);
        Some((prism, abh))
    }
}

impl<T: Real> DisplacedSurface<T> {
    /// The prism boxes' union.
    #[must_use]
    pub fn bounds(&self) -> Aabb<T> {
        self.prisms.tlas.bounds()
    }
}

/// Condition number of Eq. 6 ([`NonlinearRay::condition`]) beyond which a prism of an `f32`
/// surface is traced in `f64`: there the `f32` curve's coefficients may err by `2^6` units of
/// roundoff (`2^-18` relative), which moves a hit of a ray nearly parallel to the prism's
/// layers along the ray by more than the judge allows (`1e-4` relative). The `f32` ghost hits
/// of the twisted torus lay at conditions 84, 2,158 and 8,354, and 99% of its hits at most
/// 19 (`nlrt watertight torus-twisted --rays 65536 --precision f32`); at 64 about 1% of the
/// fur's and the torus's prism tests are traced in `f64`, at no measurable cost, and at 32
/// twice as many, with no ghost left to remove.
const F64_CONDITION: f64 = 64.0;

/// Whether a prism's nonlinear ray in `T` is traced in `f64` instead: `T` is narrower and
/// Eq. 6's condition at the heights 0, 1/2 or 1 exceeds [`F64_CONDITION`] (or is not a
/// number, or the determinant vanishes there), or the curve's denominator `D(h)` has a root
/// in `[0, 1]`: near a pole inside the shell the curve's uv error bounds grow as `1 / |D|`, and
/// in `f32` they admitted every texel of a huge triangle near it (the slow unit `pole-sweep`:
/// 225M texel tests, 129 s, against 13 us in `f64`). The samples decide which precision
/// traces the prism, not any answer: either walk is watertight in its own arithmetic.
fn ill_conditioned_in_narrow_type<T: Real>(ray: &NonlinearRay<T>) -> bool {
    let limit = T::from_f64(F64_CONDITION);
    T::MANTISSA_DIGITS < f64::MANTISSA_DIGITS
        && (![T::ZERO, T::HALF, T::ONE]
            .into_iter()
            .all(|h| ray.condition_at_most(h, limit))
            || {
                // The range of `D` over [0, 1] (its ends and vertex) holds 0.
                let (lo, hi) = quadratic_range(&ray.d, T::ZERO, T::ONE);
                !(lo > T::ZERO || hi < T::ZERO)
            })
}

impl<T: Real> PrismSearch<T> for DisplacedSurface<T> {
    type Hit<C: Real> = SurfaceHit<C>;

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
    ) -> Option<SurfaceHit<C>> {
        match search {
            Search::Walk => {
                self.walk_blas::<C, CURVE_STACK>(excluded, tri, prism, ray, [t_min, t_max], stats)
            }
            Search::EveryCell => {
                self.brute_force_in(excluded, tri, prism, ray, [t_min, t_max], stats)
            }
        }
    }

    fn narrowed(hit: SurfaceHit<f64>) -> SurfaceHit<T> {
        SurfaceHit {
            hit: hit.hit.narrowed(),
            triangle: hit.triangle,
            texel: hit.texel,
            part: hit.part,
        }
    }
}

/// The plane of the microtriangle `part` of a texel with uv square `[u0, v0, u1, v1]` and
/// corner heights `[h00, h10, h01, h11]` (normal with `n_h > 0`); the flat plane `h = const`
/// whenever the texel is flat, whatever `part` says.
pub(crate) fn plane_of<C: Real>(
    [u0, v0, u1, v1]: [C; 4],
    [h00, h10, h01, h11]: [C; 4],
    part: TexelPart,
) -> Option<TexturePlane<C>> {
    let p = |u: C, v: C, h: C| C::Vec3::new(u, v, h);
    let flat = h00 == h10 && h00 == h01 && h00 == h11;
    match if flat { TexelPart::Flat } else { part } {
        TexelPart::Lower => {
            TexturePlane::through(&[p(u0, v0, h00), p(u1, v0, h10), p(u1, v1, h11)])
        }
        TexelPart::Upper => {
            TexturePlane::through(&[p(u0, v0, h00), p(u1, v1, h11), p(u0, v1, h01)])
        }
        TexelPart::Flat => Some(TexturePlane {
            normal: C::Vec3::new(C::ZERO, C::ZERO, C::ONE),
            k: -h00,
        }),
        TexelPart::Wall { .. } => None,
    }
}

/// The shell's floor under a base mesh: each position moved by `-midlevel` times its
/// displacement direction (`normal * height_scale`, the prism's direction as
/// [`BaseMesh::prism`] computes it), in one rounding per coordinate
/// ([`DisplacedSurface::with_midlevel`]; the pre-tessellated references build on the same
/// floor). Vertices equal in position and welded direction (the two sides of a seam) get the
/// same floor, bit for bit.
///
/// ```
/// use nlrt_poly::glam::DVec3;
/// let floor = nlrt_accel::shell_floor::<f64>(&[DVec3::ONE], &[DVec3::Z], 2.0, 0.25);
/// assert_eq!(floor, vec![DVec3::new(1.0, 1.0, 0.5)]);
/// ```
#[must_use]
pub fn shell_floor<T: Real>(
    positions: &[T::Vec3],
    normals: &[T::Vec3],
    height_scale: T,
    midlevel: T,
) -> alloc::vec::Vec<T::Vec3> {
    positions
        .iter()
        .zip(normals)
        .map(|(&p, &n)| {
            let d = n * height_scale;
            T::Vec3::new(
                (-midlevel).mul_add(d.x(), p.x()),
                (-midlevel).mul_add(d.y(), p.y()),
                (-midlevel).mul_add(d.z(), p.z()),
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{HeightField, Wrap};
    use alloc::vec;
    use alloc::vec::Vec;
    use nlrt_poly::glam::{DVec2, DVec3};

    /// `side^2` heights in `[0, 1)` from a linear congruential generator seeded by `state`.
    fn random_heights(side: usize, mut state: u64) -> Vec<f32> {
        (0..side * side)
            .map(|_| {
                state = state
                    .wrapping_mul(6_364_136_223_846_793_005)
                    .wrapping_add(1_442_695_040_888_963_407);
                (state >> 40) as f32 / (1u64 << 24) as f32
            })
            .collect()
    }

    /// A mesh of two unit squares: the first (x in [0, 1]) split along its diagonal by a uv
    /// seam (its halves take their uvs from different places of a clamped random map) and a
    /// normal seam (the halves' copies of the diagonal's ends tilt differently); the second (x
    /// in [2, 3]) with shared vertices and no seam.
    fn seamed_and_plain_squares() -> (BaseMesh<f64>, HeightField) {
        let mut positions = Vec::new();
        let (mut normals, mut uvs, mut triangles) = (Vec::new(), Vec::new(), Vec::new());
        let square = [DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
        let tilt = |x: f64, y: f64| DVec3::new(x, y, 1.0).normalize();
        // Seamed: (p0, p1, p2) and (p0, p2, p3) on their own vertices.
        for (k, (tri, shift, n)) in [
            ([0, 1, 2], DVec2::new(0.55, 0.1), tilt(0.2, -0.1)),
            ([0, 2, 3], DVec2::new(0.05, 0.5), tilt(-0.15, 0.2)),
        ]
        .into_iter()
        .enumerate()
        {
            for v in tri {
                let p = square[v];
                positions.push(p);
                normals.push(if v == 0 || v == 2 { n } else { DVec3::Z });
                uvs.push(DVec2::new(p.x, p.y) * 0.4 + shift);
            }
            let b = 3 * k as u32;
            triangles.push([b, b + 1, b + 2]);
        }
        // Plain: four shared vertices.
        let b = positions.len() as u32;
        for p in square {
            positions.push(p + DVec3::new(2.0, 0.0, 0.0));
            normals.push(tilt(p.x * 0.2 - 0.1, p.y * 0.1));
            uvs.push(DVec2::new(p.x, p.y) * 0.9 + DVec2::splat(0.05));
        }
        triangles.push([b, b + 1, b + 2]);
        triangles.push([b, b + 2, b + 3]);
        let mesh = BaseMesh::new(positions, normals, uvs, triangles).unwrap();
        let side = 16;
        let heights = random_heights(side, 0x2545_f491_4f6c_dd1d_u64);
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp).unwrap();
        (mesh, field)
    }

    /// Any texel can be asked for its geometry (the marching baseline's normal asks for the
    /// texel of a hit whose texture coordinate saturated): the far side of texel `i32::MAX`
    /// is `2^31` texels, not an overflow.
    #[test]
    fn texel_geometry_holds_for_every_texel() {
        let (mesh, field) = seamed_and_plain_squares();
        let surface = DisplacedSurface::new(mesh, field, 0.3, 1.0).unwrap();
        let size = surface.texel_size();
        let far = (1u64 << 31) as f64;
        let ([u0, v0, u1, v1], _) = surface.texel_geometry(i32::MAX, i32::MIN);
        assert_eq!(
            [u0, u1, v0, v1],
            [far - 1.0, far, -far, 1.0 - far].map(|c| c * size)
        );
    }

    /// A base triangle may span [`MAX_TEXEL_RANGE`] texels per axis and no more: one more
    /// texel of tiling and the set-up names the triangle and its range.
    #[test]
    fn a_triangle_wider_than_the_texel_range_limit_is_refused() {
        let square = |uv_side: f64| {
            let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
            let uv = p
                .iter()
                .map(|p| DVec2::new(p.x, 0.5 * p.y) * uv_side)
                .collect();
            BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap()
        };
        let field = HeightField::new(4, 4, vec![0; 16], Wrap::Repeat).unwrap();
        // 4 texels per unit of uv: a uv side of 2^14 spans exactly 2^16 texels along u.
        let limit = MAX_TEXEL_RANGE / 4.0;
        assert!(DisplacedSurface::<f64>::new(square(limit), field.clone(), 0.1, 1.0).is_ok());
        let wide = limit + 0.25;
        match DisplacedSurface::<f64>::new(square(wide), field, 0.1, 1.0) {
            Err(e @ DisplacementError::TexelRangeTooLarge { triangle: 0, range }) => {
                assert_eq!(range, [4.0 * wide, 2.0 * wide]);
                let message = alloc::format!("{e}");
                assert!(message.contains("65537 x 32768.5") && message.contains("subdivide"));
            }
            other => panic!("{other:?}"),
        }
    }

    /// Seam walls: the accelerated walk and testing every texel find the same nearest hits
    /// with them; rays through the seamed square's crack miss without the rule and hit with
    /// it; and every hit on the plain square is bit-identical with and without the rule.
    #[test]
    fn seam_walls_close_the_crack_and_change_nothing_elsewhere() {
        let (mesh, field) = seamed_and_plain_squares();
        let closed = DisplacedSurface::new(mesh.clone(), field.clone(), 0.3, 1.0).unwrap();
        let open = DisplacedSurface::with_seam_rule(mesh, field, 0.3, 1.0, SeamRule::Open).unwrap();
        assert_eq!(closed.seams().edges().len(), 1);
        assert!(closed.seams().edges()[0].uv_differs && closed.seams().edges()[0].normal_differs);
        // Welded: the seam's ends share one direction in the closed surface only.
        let n = closed.mesh().normals();
        assert!(
            n[0] == n[3] && n[2] == n[4] && open.mesh().normals()[0] != open.mesh().normals()[3]
        );
        let (mut walls, mut closed_cracks, mut plain) = (0, 0, 0);
        for i in 0..60 {
            for j in 0..60 {
                let (a, b) = (f64::from(i) / 59.0, f64::from(j) / 59.0);
                // Low grazing rays across the diagonal, and steep ones over both squares.
                let rays = [
                    Ray::new(
                        DVec3::new(-0.5 + 1.2 * a, 1.5, 0.02 + 0.3 * b),
                        DVec3::new(0.7, -1.0, -0.05),
                    ),
                    Ray::new(
                        DVec3::new(-0.2 + 3.4 * a, -0.2 + 1.4 * b, 1.0),
                        DVec3::new(0.3, 0.2, -1.0),
                    ),
                ];
                for ray in rays.into_iter().flatten() {
                    let mut stats = TraversalStats::default();
                    let c = closed.intersect(&ray, 0.0, f64::INFINITY, &mut stats);
                    let brute = closed.intersect_brute_force(&ray, 0.0, f64::INFINITY);
                    match (c, brute) {
                        (None, None) => {}
                        (Some(x), Some(y)) => {
                            assert!((x.hit.t - y.hit.t).abs() < 1e-12, "{x:?} {y:?}")
                        }
                        other => panic!("walk and brute force differ: {other:?}"),
                    }
                    let o = open.intersect(&ray, 0.0, f64::INFINITY, &mut stats);
                    if let Some(hit) = c
                        && matches!(hit.part, TexelPart::Wall { .. })
                    {
                        walls += 1;
                        closed_cracks +=
                            usize::from(o.is_none_or(|o| o.hit.t > hit.hit.t * (1.0 + 1e-6)));
                    }
                    if let Some(o) = o
                        && o.triangle >= 2
                    {
                        // The plain square: the same hit, bit for bit.
                        assert_eq!(c, Some(o));
                        plain += 1;
                    }
                }
            }
        }
        assert!(
            walls > 100 && closed_cracks > 100 && plain > 500,
            "{walls} {closed_cracks} {plain}"
        );
    }

    /// Midlevel: the surface is the one built at midlevel 0 on the floor (the welded mesh
    /// moved by `-midlevel` times its directions), hit for hit and bit for bit; the seam's two
    /// sides move together (the same floor vertices), the walk equals testing every texel,
    /// a pose is shifted like the rest pose, and midlevels outside `[0, 1]` are refused.
    #[test]
    fn a_midlevel_is_the_surface_on_the_moved_floor() {
        let (mesh, field) = seamed_and_plain_squares();
        let (scale, m) = (0.3, 0.5);
        let shifted = DisplacedSurface::with_midlevel(
            mesh.clone(),
            field.clone(),
            scale,
            1.0,
            SeamRule::Closed,
            m,
        )
        .unwrap();
        assert_eq!(shifted.midlevel(), m);
        let at_zero = DisplacedSurface::new(mesh.clone(), field.clone(), scale, 1.0).unwrap();
        let floor = shell_floor::<f64>(
            at_zero.mesh().positions(),
            at_zero.mesh().normals(),
            scale,
            m,
        );
        assert_eq!(shifted.mesh().positions(), floor.as_slice());
        assert!(
            floor[0] == floor[3] && floor[2] == floor[4],
            "the seam's sides move together"
        );
        let mut on_floor_mesh = at_zero.mesh().clone();
        on_floor_mesh
            .set_pose(&floor, at_zero.mesh().normals())
            .unwrap();
        let on_floor = DisplacedSurface::new(on_floor_mesh, field.clone(), scale, 1.0).unwrap();
        // The same surface after a pose: the rest pose given again.
        let mut posed = shifted.clone();
        posed
            .set_pose(mesh.positions(), mesh.normals(), crate::TlasUpdate::DEFAULT)
            .unwrap();
        let (mut hits, mut below_base) = (0, 0);
        for i in 0..40 {
            for j in 0..40 {
                let (a, b) = (f64::from(i) / 39.0, f64::from(j) / 39.0);
                let Some(ray) = Ray::new(
                    DVec3::new(-0.2 + 3.4 * a, -0.2 + 1.4 * b, 1.0),
                    DVec3::new(0.3, 0.2, -1.0),
                ) else {
                    continue;
                };
                let mut stats = TraversalStats::default();
                let hit = shifted.intersect(&ray, 0.0, f64::INFINITY, &mut stats);
                assert_eq!(
                    hit,
                    on_floor.intersect(&ray, 0.0, f64::INFINITY, &mut stats)
                );
                assert_eq!(hit, posed.intersect(&ray, 0.0, f64::INFINITY, &mut stats));
                let brute = shifted.intersect_brute_force(&ray, 0.0, f64::INFINITY);
                assert_eq!(hit.map(|h| h.hit.t), brute.map(|h| h.hit.t));
                if let Some(h) = hit {
                    hits += 1;
                    // Below the base mesh (z = 0 on the plain square, whose normals point up
                    // within 0.1 rad): the map pushes in under its midlevel.
                    below_base += usize::from(h.triangle >= 2 && ray.at(h.hit.t).z < -1e-3);
                }
            }
        }
        assert!(hits > 600 && below_base > 100, "{hits} {below_base}");
        for bad in [-0.25, 1.5, f64::NAN] {
            let e = DisplacedSurface::with_midlevel(
                mesh.clone(),
                field.clone(),
                scale,
                1.0,
                SeamRule::Closed,
                bad,
            )
            .unwrap_err();
            assert!(matches!(e, DisplacementError::BadMidlevel(_)), "{e:?}");
            assert!(alloc::format!("{e}").contains("[0, 1]"));
        }
    }

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
        let heights = random_heights(side, 0x9e37_79b9_7f4a_7c15_u64);
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Repeat).unwrap();
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
                let fell_back = surface.walk_blas::<f64, 2>(
                    None,
                    tri,
                    &prism,
                    &nl,
                    [0.0, f64::INFINITY],
                    &mut tiny,
                );
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
