//! The methods a scene can be rendered with, behind one interface, and the renderer: a
//! pinhole camera and a small path tracer (diffuse surfaces, a sun with next-event
//! estimation and shadow rays, a sky, a configurable bounce count), so incoherent secondary
//! rays are measured as in the paper. Rays are generated and shaded in f64; only the
//! intersection runs in the method's precision.

use crate::resample::GeometryImageTracer;
use crate::scenes::{Content, Scene};
use crate::tessellate::Tessellated;
use nlrt_accel::{DisplacedSurface, HeightField, ShellObject, ShellSurface, TraversalStats};
use nlrt_baselines::{
    AffineTracing as _, ConeMap, ConeOptions, ConeTraced as _, ConeTracing, DistanceMap,
    MarchOptions, Marching as _, ProjectiveSurface, Rectification, TetrahedralShells as _,
    VertexQuadrics, VoxelMarching as _, VoxelObject,
};
use nlrt_poly::glam::DVec3;
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;
use rayon::prelude::*;
use std::fmt;
use std::sync::atomic::{AtomicU64, Ordering};

/// A way of intersecting rays with a scene's displaced surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// Nonlinear ray tracing in single precision.
    NonlinearF32,
    /// Nonlinear ray tracing in double precision.
    NonlinearF64,
    /// Tessellation-free displacement mapping (Thonat et al. 2021: world-space node boxes by
    /// affine arithmetic, flat world microtriangles) in single precision; displacement only.
    AffineF32,
    /// Tessellation-free displacement mapping in double precision; displacement only.
    AffineF64,
    /// Geometry-image ray tracing (Carr et al. 2006: the displaced surface re-sampled on the
    /// texel grid, a min-max pyramid of world boxes walked by hit/miss links) in single
    /// precision; height fields on one uv chart only.
    GeometryImageF32,
    /// Geometry-image ray tracing in double precision.
    GeometryImageF64,
    /// Smooth shell mapping by ray marching (Jeschke et al. 2007: canonical-space sampling
    /// with image-space error correction, 2 samples per texel, binary-search refinement) in
    /// single precision; instanced objects are voxelised in their tile (its 3D textures).
    MarchingF32,
    /// Smooth shell mapping by ray marching in double precision.
    MarchingF64,
    /// Ray marching with the 3D distance map of Jeschke et al. 2007, sec. 4.4 (empty-space
    /// jumps of up to 31 cells; cells of at most 256 per axis and 32 height layers, or per
    /// voxel of an instanced object) in single precision.
    DistanceMapF32,
    /// Ray marching with the distance map in double precision.
    DistanceMapF64,
    /// Tetrahedral shells (Porumbescu et al. 2005: each prism split into three tetrahedra with
    /// consistent diagonals, a piecewise-linear map, sampled like marching) in single
    /// precision; height fields only.
    TetrahedraF32,
    /// Tetrahedral shells in double precision.
    TetrahedraF64,
    /// Projective displacement mapping (parallel offset prisms, world-space samples projected
    /// linearly to texture space, jittered first sample, no bottom-level structure) in single
    /// precision; height fields only.
    ProjectiveF32,
    /// Projective displacement mapping in double precision.
    ProjectiveF64,
    /// Cone tracing with silhouettes (Ouazzani Chahdi et al. 2021: conservative cone map,
    /// per-vertex quadrics, viewing-ray rectification, per prism) in single precision; height
    /// fields only.
    ConeRayF32,
    /// Cone tracing with viewing-ray rectification in double precision.
    ConeRayF64,
    /// Cone tracing with cone rectification (the paper's second correction) in single
    /// precision; height fields only.
    ConeConeF32,
    /// Cone tracing with cone rectification in double precision.
    ConeConeF64,
    /// Curved shell mapping (Jeschke et al. 2007, sec. 3.2 and 4.5: Coons patches over the
    /// vertex normals, height compression `w / 2 + 1 / 4`, heights by the interpolation of
    /// its Eq. 2, marched like [`Method::MarchingF32`]) in single precision; height fields
    /// only. A different surface: compared with [`Method::TessellatedCurved`].
    CurvedF32,
    /// Curved shell mapping in double precision.
    CurvedF64,
    /// The pre-tessellated microtriangles traced by Embree 3 (single precision): what users pick
    /// today. Only with the `embree` feature.
    EmbreeF32,
    /// Pre-tessellated microtriangles in a world-space BVH (f64): the reference.
    Tessellated,
    /// The curved shell mapping's surface pre-tessellated (microtriangle vertices through the
    /// curved mapping, f64): the reference of [`Method::CurvedF32`] and [`Method::CurvedF64`].
    TessellatedCurved,
}

impl Method {
    /// All methods, references last.
    pub const ALL: [Method; 23] = [
        Method::NonlinearF32,
        Method::NonlinearF64,
        Method::AffineF32,
        Method::AffineF64,
        Method::GeometryImageF32,
        Method::GeometryImageF64,
        Method::MarchingF32,
        Method::MarchingF64,
        Method::DistanceMapF32,
        Method::DistanceMapF64,
        Method::TetrahedraF32,
        Method::TetrahedraF64,
        Method::ProjectiveF32,
        Method::ProjectiveF64,
        Method::ConeRayF32,
        Method::ConeRayF64,
        Method::ConeConeF32,
        Method::ConeConeF64,
        Method::CurvedF32,
        Method::CurvedF64,
        Method::EmbreeF32,
        Method::Tessellated,
        Method::TessellatedCurved,
    ];

    /// Short name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::NonlinearF32 => "nonlinear f32",
            Method::NonlinearF64 => "nonlinear f64",
            Method::AffineF32 => "tessellation-free f32",
            Method::AffineF64 => "tessellation-free f64",
            Method::GeometryImageF32 => "geometry image f32",
            Method::GeometryImageF64 => "geometry image f64",
            Method::MarchingF32 => "ray marching f32",
            Method::MarchingF64 => "ray marching f64",
            Method::DistanceMapF32 => "marching + distance map f32",
            Method::DistanceMapF64 => "marching + distance map f64",
            Method::TetrahedraF32 => "tetrahedra f32",
            Method::TetrahedraF64 => "tetrahedra f64",
            Method::ProjectiveF32 => "projective f32",
            Method::ProjectiveF64 => "projective f64",
            Method::ConeRayF32 => "cone tracing (ray rect.) f32",
            Method::ConeRayF64 => "cone tracing (ray rect.) f64",
            Method::ConeConeF32 => "cone tracing (cone rect.) f32",
            Method::ConeConeF64 => "cone tracing (cone rect.) f64",
            Method::CurvedF32 => "curved shell f32",
            Method::CurvedF64 => "curved shell f64",
            Method::EmbreeF32 => "Embree 3 pre-tessellated f32",
            Method::Tessellated => "pre-tessellated f64",
            Method::TessellatedCurved => "pre-tessellated curved f64",
        }
    }

    /// File-name friendly name.
    #[must_use]
    pub fn slug(self) -> &'static str {
        match self {
            Method::NonlinearF32 => "nonlinear-f32",
            Method::NonlinearF64 => "nonlinear-f64",
            Method::AffineF32 => "tessellation-free-f32",
            Method::AffineF64 => "tessellation-free-f64",
            Method::GeometryImageF32 => "geometry-image-f32",
            Method::GeometryImageF64 => "geometry-image-f64",
            Method::MarchingF32 => "marching-f32",
            Method::MarchingF64 => "marching-f64",
            Method::DistanceMapF32 => "distance-map-f32",
            Method::DistanceMapF64 => "distance-map-f64",
            Method::TetrahedraF32 => "tetrahedra-f32",
            Method::TetrahedraF64 => "tetrahedra-f64",
            Method::ProjectiveF32 => "projective-f32",
            Method::ProjectiveF64 => "projective-f64",
            Method::ConeRayF32 => "cone-ray-f32",
            Method::ConeRayF64 => "cone-ray-f64",
            Method::ConeConeF32 => "cone-cone-f32",
            Method::ConeConeF64 => "cone-cone-f64",
            Method::CurvedF32 => "curved-f32",
            Method::CurvedF64 => "curved-f64",
            Method::EmbreeF32 => "embree-f32",
            Method::Tessellated => "tessellated-f64",
            Method::TessellatedCurved => "tessellated-curved-f64",
        }
    }

    /// The reference its error is measured against: the pre-tessellated surface it renders.
    #[must_use]
    pub fn reference(self) -> Method {
        match self {
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => {
                Method::TessellatedCurved
            }
            _ => Method::Tessellated,
        }
    }

    /// Whether this is a pre-tessellated reference.
    #[must_use]
    pub fn is_reference(self) -> bool {
        matches!(self, Method::Tessellated | Method::TessellatedCurved)
    }

    /// The f64 run of the same surface, whose difference is this method's precision error
    /// alone (nonlinear f64; curved shell f64 for the curved methods).
    #[must_use]
    pub fn f64_partner(self) -> Method {
        match self {
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => Method::CurvedF64,
            _ => Method::NonlinearF64,
        }
    }

    /// The method named `slug` (as [`Method::slug`] writes it).
    #[must_use]
    pub fn from_slug(slug: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.slug() == slug)
    }

    /// Whether the method can render `scene` (tessellation-free mapping handles height
    /// fields only, not instanced objects; geometry images also need one uv chart over the
    /// unit square with a power-of-two tiled map).
    #[must_use]
    pub fn supports(self, scene: &Scene) -> bool {
        self.unsupported_reason(scene).is_none()
    }

    /// Why the method cannot render `scene`, or `None` when it can.
    #[must_use]
    pub fn unsupported_reason(self, scene: &Scene) -> Option<&'static str> {
        match self {
            Method::AffineF32 | Method::AffineF64 => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "tessellation-free mapping renders height fields, not instanced objects",
                )
            }
            Method::GeometryImageF32 | Method::GeometryImageF64 => {
                crate::resample::unsupported_reason(scene)
            }
            Method::MarchingF32
            | Method::MarchingF64
            | Method::DistanceMapF32
            | Method::DistanceMapF64 => None,
            Method::ProjectiveF32 | Method::ProjectiveF64 => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "projective displacement mapping renders height fields, not instanced objects",
                )
            }
            Method::TetrahedraF32 | Method::TetrahedraF64 => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "tetrahedral shells are implemented for height fields, not instanced objects",
                )
            }
            Method::ConeRayF32 | Method::ConeRayF64 | Method::ConeConeF32 | Method::ConeConeF64 => {
                (!matches!(scene.content, Content::Displacement(_)))
                    .then_some("cone tracing renders height fields, not instanced objects")
            }
            Method::EmbreeF32 => {
                if cfg!(feature = "embree") {
                    None
                } else {
                    Some(
                        "built without the `embree` feature (install libembree-dev, then \
                         `cargo run --release --features embree`)",
                    )
                }
            }
            Method::CurvedF32 | Method::CurvedF64 | Method::TessellatedCurved => {
                (!matches!(scene.content, Content::Displacement(_))).then_some(
                    "curved shell mapping is implemented for height fields, not instanced objects",
                )
            }
            Method::NonlinearF32 | Method::NonlinearF64 | Method::Tessellated => None,
        }
    }

    /// Builds the method's acceleration data for `scene`; `None` when it does not support it.
    #[must_use]
    pub fn build(self, scene: &Scene) -> Option<Box<dyn Tracer>> {
        if !self.supports(scene) {
            return None;
        }
        Some(match self {
            Method::NonlinearF32 => Box::new(Nonlinear::<f32>::new(scene)),
            Method::NonlinearF64 => Box::new(Nonlinear::<f64>::new(scene)),
            Method::AffineF32 => Box::new(TessellationFree::<f32>::new(scene)?),
            Method::AffineF64 => Box::new(TessellationFree::<f64>::new(scene)?),
            Method::GeometryImageF32 => Box::new(GeometryImageTracer::<f32>::new(scene)?),
            Method::GeometryImageF64 => Box::new(GeometryImageTracer::<f64>::new(scene)?),
            Method::MarchingF32
            | Method::MarchingF64
            | Method::DistanceMapF32
            | Method::DistanceMapF64
                if matches!(scene.content, Content::Shell(_)) =>
            {
                let jumps = matches!(self, Method::DistanceMapF32 | Method::DistanceMapF64);
                if self.name().ends_with("f32") {
                    Box::new(VolumeMarching::<f32>::new(scene, jumps)?)
                } else {
                    Box::new(VolumeMarching::<f64>::new(scene, jumps)?)
                }
            }
            Method::MarchingF32 => Box::new(Marching::<f32>::new(scene)?),
            Method::MarchingF64 => Box::new(Marching::<f64>::new(scene)?),
            Method::DistanceMapF32 => Box::new(Marching::<f32>::distance_map(scene)?),
            Method::DistanceMapF64 => Box::new(Marching::<f64>::distance_map(scene)?),
            Method::TetrahedraF32 => Box::new(Marching::<f32>::tetrahedra(scene)?),
            Method::TetrahedraF64 => Box::new(Marching::<f64>::tetrahedra(scene)?),
            Method::ProjectiveF32 => Box::new(Projective::<f32>::new(scene)?),
            Method::ProjectiveF64 => Box::new(Projective::<f64>::new(scene)?),
            Method::ConeRayF32 => Box::new(ConeTracer::<f32>::new(scene, Rectification::Ray)?),
            Method::ConeRayF64 => Box::new(ConeTracer::<f64>::new(scene, Rectification::Ray)?),
            Method::ConeConeF32 => Box::new(ConeTracer::<f32>::new(scene, Rectification::Cone)?),
            Method::ConeConeF64 => Box::new(ConeTracer::<f64>::new(scene, Rectification::Cone)?),
            Method::CurvedF32 => Box::new(Marching::<f32>::curved(scene)?),
            Method::CurvedF64 => Box::new(Marching::<f64>::curved(scene)?),
            #[cfg(feature = "embree")]
            Method::EmbreeF32 => Box::new(crate::embree_reference::EmbreeTessellated::new(scene)?),
            #[cfg(not(feature = "embree"))]
            Method::EmbreeF32 => return None,
            Method::Tessellated => Box::new(Tessellated::new(scene)),
            Method::TessellatedCurved => Box::new(Tessellated::curved(scene)),
        })
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A hit as the renderer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    /// Distance along the ray.
    pub t: f64,
    /// Unit normal facing against the ray.
    pub normal: DVec3,
    /// Base triangle hit (the hit-id AOV).
    pub id: u32,
}

impl TraceHit {
    /// A hit found in precision `T`: distance, unit normal facing against the ray, base
    /// triangle.
    #[must_use]
    pub(crate) fn from_precision<T: Real>(t: T, normal: T::Vec3, id: u32) -> Self {
        Self {
            t: t.to_f64(),
            normal: to_dvec3::<T>(normal),
            id,
        }
    }
}

/// A renderer ray (f64) in precision `T` with its distance range (an infinite `t_max` stays
/// infinite); `None` for a zero or non-finite direction.
pub(crate) fn ray_in<T: Real>(
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<(Ray<T>, T, T)> {
    let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
    let t_max = if t_max.is_finite() {
        T::from_f64(t_max)
    } else {
        T::INFINITY
    };
    Some((Ray::new(v(origin), v(dir))?, T::from_f64(t_min), t_max))
}

/// A vector of precision `T` in f64.
pub(crate) fn to_dvec3<T: Real>(v: T::Vec3) -> DVec3 {
    DVec3::new(v.x().to_f64(), v.y().to_f64(), v.z().to_f64())
}

/// Intersection of a ray with the scene.
pub trait Tracer: Sync {
    /// Nearest hit with distance in `(t_min, t_max]`.
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit>;
    /// Bytes of acceleration data.
    fn memory_bytes(&self) -> usize;
}

/// Nonlinear ray tracing in precision `T`: a displaced surface or a shell-mapped object.
pub enum Nonlinear<T: Real> {
    /// Displacement mapping.
    Displaced(DisplacedSurface<T>),
    /// Shell mapping of an instanced object.
    Shell(ShellSurface<T>),
}

impl<T: Real> Nonlinear<T> {
    /// Builds the acceleration data of `scene`.
    ///
    /// # Panics
    /// Never for valid scenes (built-in scenes are).
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let (scale, tiling) = (T::from_f64(scene.height_scale), T::from_f64(scene.tiling));
        match &scene.content {
            Content::Displacement(field) => Self::Displaced(
                DisplacedSurface::new(scene.mesh::<T>(), field.clone(), scale, tiling)
                    .expect("valid scene"),
            ),
            Content::Shell(object) => {
                let v =
                    |p: &DVec3| T::Vec3::new(T::from_f64(p.x), T::from_f64(p.y), T::from_f64(p.z));
                let object = ShellObject::new(
                    object
                        .iter()
                        .map(|t| [v(&t[0]), v(&t[1]), v(&t[2])])
                        .collect(),
                )
                .expect("valid object");
                Self::Shell(
                    ShellSurface::new(scene.mesh::<T>(), object, scale, tiling)
                        .expect("valid scene"),
                )
            }
        }
    }
}

impl<T: Real> Tracer for Nonlinear<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut stats = TraversalStats::default();
        let (t, n, id) = match self {
            Self::Displaced(s) => {
                let hit = s.intersect(&ray, t_min, t_max, &mut stats)?;
                (hit.hit.t, s.normal(&hit, ray.dir)?, hit.triangle)
            }
            Self::Shell(s) => {
                let hit = s.intersect(&ray, t_min, t_max, &mut stats)?;
                (hit.hit.t, s.normal(&hit, ray.dir)?, hit.triangle)
            }
        };
        Some(TraceHit::from_precision::<T>(t, n, id))
    }

    fn memory_bytes(&self) -> usize {
        match self {
            Self::Displaced(s) => s.memory_bytes(),
            Self::Shell(s) => s.memory_bytes(),
        }
    }
}

/// Tessellation-free displacement mapping (Thonat et al. 2021) in precision `T`, on the same
/// acceleration data as nonlinear tracing ([`DisplacedSurface::intersect_affine`]).
pub struct TessellationFree<T: Real>(DisplacedSurface<T>);

impl<T: Real> TessellationFree<T> {
    /// Builds the surface; `None` for scenes that are not height fields.
    #[must_use]
    pub fn new(scene: &Scene) -> Option<Self> {
        match Nonlinear::<T>::new(scene) {
            Nonlinear::Displaced(s) => Some(Self(s)),
            Nonlinear::Shell(_) => None,
        }
    }
}

impl<T: Real> Tracer for TessellationFree<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut stats = TraversalStats::default();
        let hit = self.0.intersect_affine(&ray, t_min, t_max, &mut stats)?;
        let n = hit.facing_normal(ray.dir)?;
        Some(TraceHit::from_precision::<T>(hit.t, n, hit.triangle))
    }

    fn memory_bytes(&self) -> usize {
        self.0.memory_bytes()
    }
}

/// Sampling methods in precision `T` on the same prisms and height field: smooth shell
/// mapping by ray marching (Jeschke et al. 2007, [`DisplacedSurface::intersect_marching`]) or
/// tetrahedral shells ([`DisplacedSurface::intersect_tetrahedra`]).
pub struct Marching<T: Real> {
    surface: DisplacedSurface<T>,
    opts: MarchOptions,
    shell: SampledShell,
}

/// The distance map the marchers use: 32 height layers, at most 256 cells per axis (sec. 4.4
/// used 128^3 for its textures; our maps are wider than tall).
#[must_use]
pub fn distance_map_of(field: &HeightField) -> DistanceMap {
    DistanceMap::new(field, 32, 256)
}

/// The shell a [`Marching`] tracer samples.
#[derive(Clone, Debug)]
enum SampledShell {
    /// Smooth shell mapping (Jeschke et al. 2007, sec. 3.1).
    Smooth,
    /// Smooth shell mapping with distance-map jumps (sec. 4.4).
    DistanceMap(DistanceMap),
    /// Three tetrahedra per prism (piecewise-linear map).
    Tetrahedra,
    /// Curved shell mapping (Jeschke et al. 2007, sec. 3.2).
    Curved,
}

impl<T: Real> Marching<T> {
    /// Ray marching; `None` for scenes that are not height fields.
    #[must_use]
    pub fn new(scene: &Scene) -> Option<Self> {
        match Nonlinear::<T>::new(scene) {
            Nonlinear::Displaced(surface) => Some(Self {
                surface,
                opts: MarchOptions::default(),
                shell: SampledShell::Smooth,
            }),
            Nonlinear::Shell(_) => None,
        }
    }

    /// Tetrahedral shells; `None` for scenes that are not height fields.
    #[must_use]
    pub fn tetrahedra(scene: &Scene) -> Option<Self> {
        Self::new(scene).map(|m| Self {
            shell: SampledShell::Tetrahedra,
            ..m
        })
    }

    /// Ray marching with the distance map [`distance_map_of`]; `None` for scenes that are not
    /// height fields.
    #[must_use]
    pub fn distance_map(scene: &Scene) -> Option<Self> {
        let Content::Displacement(field) = &scene.content else {
            return None;
        };
        let map = distance_map_of(field);
        Self::new(scene).map(|m| Self {
            shell: SampledShell::DistanceMap(map),
            ..m
        })
    }

    /// Curved shell mapping; `None` for scenes that are not height fields.
    #[must_use]
    pub fn curved(scene: &Scene) -> Option<Self> {
        Self::new(scene).map(|m| Self {
            shell: SampledShell::Curved,
            ..m
        })
    }
}

impl<T: Real> Tracer for Marching<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut stats = TraversalStats::default();
        let (s, opts) = (&self.surface, &self.opts);
        let hit = match &self.shell {
            SampledShell::Smooth => s.intersect_marching(&ray, t_min, t_max, opts, &mut stats)?,
            SampledShell::DistanceMap(map) => {
                s.intersect_sphere_traced(&ray, t_min, t_max, map, opts, &mut stats)?
            }
            SampledShell::Tetrahedra => {
                s.intersect_tetrahedra(&ray, t_min, t_max, opts, &mut stats)?
            }
            SampledShell::Curved => {
                s.intersect_curved_marching(&ray, t_min, t_max, opts, &mut stats)?
            }
        };
        let n = match &self.shell {
            SampledShell::Curved => s.curved_normal(&hit, ray.dir)?,
            _ => s.normal(&hit, ray.dir)?,
        };
        Some(TraceHit::from_precision::<T>(hit.hit.t, n, hit.triangle))
    }

    fn memory_bytes(&self) -> usize {
        self.surface.memory_bytes()
            + match &self.shell {
                SampledShell::DistanceMap(map) => map.memory_bytes(),
                _ => 0,
            }
    }
}

/// Ray marching through a voxelised instanced object in precision `T`
/// ([`ShellSurface::intersect_marching`]): Jeschke et al.'s method for volumetric content,
/// with or without the voxels' distance map.
pub struct VolumeMarching<T: Real> {
    surface: ShellSurface<T>,
    voxels: VoxelObject,
    opts: MarchOptions,
    jumps: bool,
}

/// Voxels per axis of the object's tile (the paper's 3D textures: 128^3).
pub const VOXEL_RESOLUTION: usize = 128;

impl<T: Real> VolumeMarching<T> {
    /// Voxelises the scene's object; `None` for scenes that are not shell-mapped.
    #[must_use]
    pub fn new(scene: &Scene, jumps: bool) -> Option<Self> {
        let Nonlinear::Shell(surface) = Nonlinear::<T>::new(scene) else {
            return None;
        };
        let voxels = VoxelObject::new(surface.object(), VOXEL_RESOLUTION);
        Some(Self {
            surface,
            voxels,
            opts: MarchOptions::default(),
            jumps,
        })
    }
}

impl<T: Real> Tracer for VolumeMarching<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut stats = TraversalStats::default();
        let (s, voxels, opts) = (&self.surface, &self.voxels, &self.opts);
        let hit = if self.jumps {
            s.intersect_sphere_traced(&ray, t_min, t_max, voxels, opts, &mut stats)?
        } else {
            s.intersect_marching(&ray, t_min, t_max, voxels, opts, &mut stats)?
        };
        let n = self.surface.normal(&hit, ray.dir)?;
        Some(TraceHit::from_precision::<T>(hit.hit.t, n, hit.triangle))
    }

    fn memory_bytes(&self) -> usize {
        self.surface.memory_bytes() + self.voxels.memory_bytes()
    }
}

/// Cone tracing with silhouettes in precision `T` ([`DisplacedSurface::intersect_cone_traced`]).
pub struct ConeTracer<T: Real> {
    surface: DisplacedSurface<T>,
    cone: ConeTracing<T>,
}

impl<T: Real> ConeTracer<T> {
    /// Builds the cone map (rows in parallel) and the quadrics; `None` for scenes that are not
    /// height fields.
    #[must_use]
    pub fn new(scene: &Scene, rectification: Rectification) -> Option<Self> {
        Self::with_quadrics(scene, rectification, true)
    }

    /// [`ConeTracer::new`], or with flat quadrics when `silhouettes` is false: the original
    /// cone tracing, whose silhouettes the paper corrects (for comparison).
    #[must_use]
    pub fn with_quadrics(
        scene: &Scene,
        rectification: Rectification,
        silhouettes: bool,
    ) -> Option<Self> {
        let Nonlinear::Displaced(surface) = Nonlinear::<T>::new(scene) else {
            return None;
        };
        let cones = {
            use rayon::prelude::*;
            let builder = ConeMap::builder(surface.field());
            let mut ratio = vec![0.0f32; builder.len()];
            ratio
                .par_chunks_mut(builder.row_len())
                .enumerate()
                .for_each(|(j, row)| builder.fill_row(j, row));
            builder.finish(ratio)
        };
        let quadrics = if silhouettes {
            VertexQuadrics::new(surface.mesh())
        } else {
            VertexQuadrics::flat(surface.mesh().positions().len())
        };
        let options = ConeOptions {
            rectification,
            ..ConeOptions::default()
        };
        Some(Self {
            surface,
            cone: ConeTracing {
                cones,
                quadrics,
                options,
            },
        })
    }
}

impl<T: Real> Tracer for ConeTracer<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut stats = TraversalStats::default();
        let hit = self
            .surface
            .intersect_cone_traced(&ray, t_min, t_max, &self.cone, &mut stats)?;
        let n = self.surface.normal(&hit, ray.dir)?;
        Some(TraceHit::from_precision::<T>(hit.hit.t, n, hit.triangle))
    }

    fn memory_bytes(&self) -> usize {
        self.surface.memory_bytes() + self.cone.memory_bytes()
    }
}

/// Projective displacement mapping in precision `T` ([`ProjectiveSurface`]); the first
/// sample of each ray is jittered by a hash of the ray (thin-feature sampling).
pub struct Projective<T: Real> {
    surface: ProjectiveSurface<T>,
    opts: MarchOptions,
}

impl<T: Real> Projective<T> {
    /// Builds the parallel prisms; `None` for scenes that are not height fields.
    #[must_use]
    pub fn new(scene: &Scene) -> Option<Self> {
        let Content::Displacement(field) = &scene.content else {
            return None;
        };
        let surface = ProjectiveSurface::new(
            &scene.mesh::<T>(),
            field.clone(),
            T::from_f64(scene.height_scale),
            T::from_f64(scene.tiling),
        )
        .ok()?;
        Some(Self {
            surface,
            opts: MarchOptions::default(),
        })
    }
}

impl<T: Real> Tracer for Projective<T> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (ray, t_min, t_max) = ray_in::<T>(origin, dir, t_min, t_max)?;
        let mut hash = Rng(origin.x.to_bits()
            ^ dir.x.to_bits().rotate_left(21)
            ^ dir.y.to_bits().rotate_left(42)
            ^ dir.z.to_bits());
        let jitter = T::from_f64(hash.next());
        let mut stats = TraversalStats::default();
        let hit = self
            .surface
            .intersect(&ray, t_min, t_max, jitter, &self.opts, &mut stats)?;
        let n = self.surface.surface().normal(&hit, ray.dir)?;
        Some(TraceHit::from_precision::<T>(hit.hit.t, n, hit.triangle))
    }

    fn memory_bytes(&self) -> usize {
        self.surface.memory_bytes()
    }
}

impl Tracer for Tessellated {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        let (t, normal, id) = Tessellated::intersect(self, origin, dir, t_min, t_max)?;
        Some(TraceHit { t, normal, id })
    }

    fn memory_bytes(&self) -> usize {
        Tessellated::memory_bytes(self)
    }
}

/// Render settings.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel (the first through the pixel centre, for the depth AOV).
    pub spp: usize,
    /// Diffuse bounces after the primary hit (each with a shadow ray).
    pub bounces: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 320,
            height: 240,
            spp: 1,
            bounces: 1,
        }
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Linear RGB per pixel.
    pub color: Vec<[f32; 3]>,
    /// Distance of the centre sample's primary hit (NaN: no hit).
    pub depth: Vec<f64>,
    /// Unit normal of the centre sample's primary hit, facing the camera (zero: no hit).
    pub normal: Vec<[f32; 3]>,
    /// Base triangle of the centre sample's primary hit ([`u32::MAX`]: no hit).
    pub hit_id: Vec<u32>,
    /// Primary rays cast.
    pub primary_rays: u64,
    /// All rays cast (primary, shadow, bounce).
    pub all_rays: u64,
    /// Wall-clock seconds of the render.
    pub seconds: f64,
}

/// Offset of secondary ray origins along the normal, relative to the scene's size: f32 hit
/// points carry a relative error of about 2^-24 times the conditioning of the hit (below
/// ~100 except at grazing angles), so about 1e-5 of the scene; 1e-4 leaves a factor 10 and
/// stays well below the finest displacement detail (a texel of a 4096^2 map on a 2-unit
/// mesh is 5e-4).
const SECONDARY_OFFSET: f64 = 1e-4;

/// The renderer's random numbers (SplitMix64, one stream per pixel).
pub struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn sky(dir: DVec3) -> DVec3 {
    let t = (dir.y * 0.5 + 0.5).clamp(0.0, 1.0);
    DVec3::new(0.55, 0.6, 0.7) * (1.0 - t) + DVec3::new(0.35, 0.5, 0.9) * t
}

/// A surface's reflectance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Material {
    /// Lambertian, albedo 0.5.
    Diffuse,
    /// A normalised Phong lobe (specular reflectance 0.5, the given exponent) around the
    /// mirror direction: the glossy material, whose bounce rays stay coherent around the
    /// reflection instead of spreading over the hemisphere.
    Glossy {
        /// Phong exponent (sharper for larger).
        exponent: f64,
    },
}

/// Reflectance of both materials.
const ALBEDO: f64 = 0.5;

impl Material {
    /// The glossy material of the built-in scenes and of scene files (`material = "glossy"`).
    pub const GLOSSY: Material = Material::Glossy { exponent: 40.0 };

    /// `pi` times the BRDF for light arriving from `light` seen along `dir` (towards the
    /// surface) at normal `n`.
    #[must_use]
    pub fn brdf_times_pi(self, n: DVec3, dir: DVec3, light: DVec3) -> f64 {
        match self {
            Material::Diffuse => ALBEDO,
            Material::Glossy { exponent } => {
                let mirror = dir - n * (2.0 * dir.dot(n));
                let c = mirror.dot(light).max(0.0);
                ALBEDO * (exponent + 2.0) * 0.5 * c.powf(exponent)
            }
        }
    }

    /// A bounce direction and the path weight (BRDF times cosine over the pdf); `None` when
    /// the sampled direction goes below the surface (the path ends).
    pub fn sample(self, n: DVec3, dir: DVec3, rng: &mut Rng) -> Option<(DVec3, f64)> {
        match self {
            Material::Diffuse => Some((cosine_direction(n, rng), ALBEDO)),
            Material::Glossy { exponent } => {
                let mirror = (dir - n * (2.0 * dir.dot(n))).normalize();
                // Phong lobe sampling: pdf (e + 1) / (2 pi) cos^e around the mirror direction.
                let (r1, r2) = (rng.next(), rng.next());
                let cos_a = r2.powf(1.0 / (exponent + 1.0));
                let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
                let phi = std::f64::consts::TAU * r1;
                let next = frame_around(mirror, phi.cos() * sin_a, phi.sin() * sin_a, cos_a);
                let cos = next.dot(n);
                (cos > 0.0).then(|| (next, ALBEDO * (exponent + 2.0) / (exponent + 1.0) * cos))
            }
        }
    }
}

/// `x t + y b + z n` for an orthonormal frame `(t, b, n)` around the unit vector `n`.
fn frame_around(n: DVec3, x: f64, y: f64, z: f64) -> DVec3 {
    let helper = if n.x.abs() > 0.9 { DVec3::Y } else { DVec3::X };
    let t = n.cross(helper).normalize();
    let b = n.cross(t);
    (t * x + b * y + n * z).normalize()
}

/// Cosine-weighted direction around `n`.
fn cosine_direction(n: DVec3, rng: &mut Rng) -> DVec3 {
    let (r1, r2) = (rng.next(), rng.next());
    let phi = std::f64::consts::TAU * r1;
    let r = r2.sqrt();
    frame_around(n, r * phi.cos(), r * phi.sin(), (1.0 - r2).sqrt())
}

/// Renders `scene` with `tracer`; `progress` is called with the number of rows finished.
pub fn render(
    scene: &Scene,
    tracer: &dyn Tracer,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Frame {
    let (w, h) = (opts.width, opts.height);
    let aspect = w as f64 / h as f64;
    let extent = {
        let lo = scene
            .positions
            .iter()
            .fold(DVec3::INFINITY, |a, &p| a.min(p));
        let hi = scene
            .positions
            .iter()
            .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
        (hi - lo).length().max(1e-9)
    };
    let offset = SECONDARY_OFFSET * extent;
    let sun_radiance = DVec3::new(1.15, 1.05, 0.95);
    let primary = AtomicU64::new(0);
    let all = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let start = std::time::Instant::now();
    type Row = (Vec<[f32; 3]>, Vec<f64>, Vec<([f32; 3], u32)>);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut colors = Vec::with_capacity(w);
            let mut depths = Vec::with_capacity(w);
            let mut aovs = Vec::with_capacity(w);
            let (mut n_primary, mut n_all) = (0u64, 0u64);
            for x in 0..w {
                let mut rng = Rng(((y * w + x) as u64) << 20);
                let mut sum = DVec3::ZERO;
                let mut depth = f64::NAN;
                let mut aov = ([0.0f32; 3], u32::MAX);
                for s in 0..opts.spp.max(1) {
                    let (jx, jy) = if s == 0 {
                        (0.5, 0.5)
                    } else {
                        (rng.next(), rng.next())
                    };
                    let dir = scene.camera.direction(
                        (x as f64 + jx) / w as f64,
                        (y as f64 + jy) / h as f64,
                        aspect,
                    );
                    let mut origin = scene.camera.eye;
                    let mut dir = dir;
                    let mut throughput = DVec3::ONE;
                    n_primary += 1;
                    for bounce in 0..=opts.bounces {
                        n_all += 1;
                        let Some(hit) = tracer.intersect(origin, dir, 0.0, f64::INFINITY) else {
                            sum += throughput * sky(dir);
                            break;
                        };
                        let n = hit.normal;
                        if s == 0 && bounce == 0 {
                            depth = hit.t;
                            aov = ([n.x as f32, n.y as f32, n.z as f32], hit.id);
                        }
                        let p = origin + dir * hit.t + n * offset;
                        // Next-event estimation towards the sun: BRDF times the sun's
                        // irradiance (pi * sun_radiance, so that a white diffuse surface facing
                        // it reflects sun_radiance) times the cosine.
                        let cos = n.dot(scene.sun);
                        if cos > 0.0 {
                            n_all += 1;
                            if tracer.intersect(p, scene.sun, 0.0, f64::INFINITY).is_none() {
                                let brdf_pi = scene.material.brdf_times_pi(n, dir, scene.sun);
                                sum += throughput * sun_radiance * (brdf_pi * cos);
                            }
                        }
                        if bounce == opts.bounces {
                            break;
                        }
                        let Some((next, weight)) = scene.material.sample(n, dir, &mut rng) else {
                            break;
                        };
                        throughput *= weight;
                        origin = p;
                        dir = next;
                    }
                }
                let c = sum / opts.spp.max(1) as f64;
                colors.push([c.x as f32, c.y as f32, c.z as f32]);
                depths.push(depth);
                aovs.push(aov);
            }
            primary.fetch_add(n_primary, Ordering::Relaxed);
            all.fetch_add(n_all, Ordering::Relaxed);
            progress(rows_done.fetch_add(1, Ordering::Relaxed) as usize + 1);
            (colors, depths, aovs)
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let mut color = Vec::with_capacity(w * h);
    let mut depth = Vec::with_capacity(w * h);
    let (mut normal, mut hit_id) = (Vec::with_capacity(w * h), Vec::with_capacity(w * h));
    for (c, d, a) in rows {
        color.extend(c);
        depth.extend(d);
        for (n, id) in a {
            normal.push(n);
            hit_id.push(id);
        }
    }
    Frame {
        width: w,
        height: h,
        color,
        depth,
        normal,
        hit_id,
        primary_rays: primary.into_inner(),
        all_rays: all.into_inner(),
        seconds,
    }
}

/// 8-bit sRGB of a linear value (clamped).
#[must_use]
pub fn to_srgb8(v: f32) -> u8 {
    let v = v.clamp(0.0, 1.0);
    let s = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes RGB8 pixels as a PNG.
///
/// # Errors
/// When the file cannot be written.
pub fn write_png(
    path: &std::path::Path,
    width: usize,
    height: usize,
    rgb: &[u8],
) -> std::io::Result<()> {
    let file = std::fs::File::create(path)?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width as u32, height as u32);
    encoder.set_color(png::ColorType::Rgb);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(std::io::Error::other)?;
    writer
        .write_image_data(rgb)
        .map_err(std::io::Error::other)?;
    writer.finish().map_err(std::io::Error::other)
}

impl Frame {
    /// The frame as 8-bit sRGB.
    #[must_use]
    pub fn rgb8(&self) -> Vec<u8> {
        self.color.iter().flat_map(|c| c.map(to_srgb8)).collect()
    }
}

impl Frame {
    /// Writes the centre samples' AOVs as a 32-bit float OpenEXR file: `Z` (hit distance, NaN
    /// where the ray missed), `N.X`, `N.Y`, `N.Z` (unit normal facing the camera, zero on a
    /// miss) and `id` (base triangle, as an unsigned integer channel; 2^32 - 1 on a miss).
    ///
    /// # Errors
    /// When the file cannot be written.
    pub fn write_aovs_exr(&self, path: &std::path::Path) -> Result<(), String> {
        use exr::prelude::*;
        let w = self.width;
        let channels = SpecificChannels::build()
            .with_channel("Z")
            .with_channel("N.X")
            .with_channel("N.Y")
            .with_channel("N.Z")
            .with_channel("id")
            .with_pixel_fn(|p: Vec2<usize>| {
                let i = p.y() * w + p.x();
                let n = self.normal[i];
                (self.depth[i] as f32, n[0], n[1], n[2], self.hit_id[i])
            });
        Image::from_channels((self.width, self.height), channels)
            .write()
            .to_file(path)
            .map_err(|e| format!("cannot write {}: {e}", path.display()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The BRDF used for next-event estimation and the sampling used for bounces must describe
    /// the same material, or images are biased: their directional albedos (the integral of
    /// BRDF times cosine over the hemisphere) agree, estimated independently: by uniform
    /// hemisphere sampling of `brdf_times_pi`, and by the mean bounce weight of `sample`.
    #[test]
    fn sampling_and_brdf_agree_on_the_albedo() {
        let n = DVec3::new(0.2, 0.9, -0.1).normalize();
        for material in [Material::Diffuse, Material::GLOSSY] {
            for incidence in [0.0f64, 0.5, 1.2] {
                // A direction towards the surface at `incidence` from the normal.
                let t = n.cross(DVec3::X).normalize();
                let dir = -(n * incidence.cos() + t * incidence.sin());
                let mut rng = Rng(7);
                let count = 400_000;
                let mut by_sampling = 0.0;
                let mut by_brdf = 0.0;
                for _ in 0..count {
                    if let Some((_, w)) = material.sample(n, dir, &mut rng) {
                        by_sampling += w;
                    }
                    // Uniform hemisphere: pdf 1 / (2 pi); BRDF = brdf_times_pi / pi.
                    let (r1, r2) = (rng.next(), rng.next());
                    let z = r1;
                    let s = (1.0 - z * z).sqrt();
                    let phi = std::f64::consts::TAU * r2;
                    let l = frame_around(n, s * phi.cos(), s * phi.sin(), z);
                    by_brdf += material.brdf_times_pi(n, dir, l) * z * 2.0;
                }
                let (a, b) = (by_sampling / count as f64, by_brdf / count as f64);
                // Monte Carlo: a few standard errors of the noisier (uniform) estimate.
                assert!(
                    (a - b).abs() < 0.02,
                    "{material:?} at {incidence}: {a} vs {b}"
                );
                assert!(a <= ALBEDO + 0.01, "{material:?}: energy {a}");
            }
        }
    }
}
