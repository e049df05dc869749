//! The tracers behind [`Tracer`]: nonlinear ray tracing (displacement and shell mapping) and
//! each compared method of `nlrt-baselines`, set up from a [`Scene`] and traced in their
//! own precision (`f32` or `f64`). The pre-tessellated reference lives in `tessellate`,
//! geometry images in `geometry_image`, Embree in `embree_reference`; [`crate::trace::method::Method`]
//! names them all.

use crate::scene::material::Rng;
use crate::scene::scenes::{Content, Scene};
use crate::trace::tessellate::Tessellated;
use crate::trace::tracer::{TraceHit, Tracer, ray_in};
use nlrt_accel::{DisplacedSurface, HeightField, ShellSurface, TraversalStats};
use nlrt_baselines::{
    AffineTracing as _, ConeMap, ConeOptions, ConeTraced as _, ConeTracing, DistanceMap,
    MarchOptions, Marching as _, ProjectiveSurface, Rectification, TetrahedralShells as _,
    VertexQuadrics, VoxelMarching as _, VoxelObject,
};
use nlrt_poly::Real;
use nlrt_poly::glam::DVec3;

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
        // Scenes are checked by `Scene::check_precision` before they are built (built-in
        // scenes are valid by construction).
        let valid = "a scene checked by Scene::check_precision";
        match &scene.content {
            Content::Displacement(_) => Self::Displaced(scene.displaced_surface().expect(valid)),
            Content::Shell(_) => Self::Shell(scene.shell_surface().expect(valid)),
        }
    }

    /// Base triangles walked along straight lines ([`DisplacedSurface::straight_triangles`],
    /// [`ShellSurface::straight_triangles`]).
    #[must_use]
    pub fn straight_triangles(&self) -> usize {
        match self {
            Self::Displaced(s) => s.straight_triangles(),
            Self::Shell(s) => s.straight_triangles(),
        }
    }

    /// Whether affine patches are walked straight (the default) or every prism along its
    /// curve ([`DisplacedSurface::set_straight_walk`], [`ShellSurface::set_straight_walk`]).
    pub fn set_straight_walk(&mut self, on: bool) {
        match self {
            Self::Displaced(s) => s.set_straight_walk(on),
            Self::Shell(s) => s.set_straight_walk(on),
        }
    }
}

impl<T: Real> Nonlinear<T> {
    /// Moves the base mesh to `pose` (f64, converted to `T`) and updates the TLAS by
    /// `update` ([`DisplacedSurface::set_pose`], [`ShellSurface::set_pose`]).
    ///
    /// # Errors
    /// A pose with another vertex count, or a value not finite in `T`.
    pub fn set_pose(
        &mut self,
        pose: &crate::scene::motion::Pose,
        update: nlrt_accel::TlasUpdate,
    ) -> Result<nlrt_accel::PoseUpdate, String> {
        use nlrt_poly::Vector3;
        let v = |p: &DVec3| T::Vec3::new(T::from_f64(p.x), T::from_f64(p.y), T::from_f64(p.z));
        let positions: Vec<T::Vec3> = pose.positions.iter().map(v).collect();
        let normals: Vec<T::Vec3> = pose.normals.iter().map(v).collect();
        self.set_pose_in_precision(&positions, &normals, update)
    }

    /// [`Nonlinear::set_pose`] with the pose already in `T` (what `nlrt animate` times).
    ///
    /// # Errors
    /// As [`Nonlinear::set_pose`].
    pub fn set_pose_in_precision(
        &mut self,
        positions: &[T::Vec3],
        normals: &[T::Vec3],
        update: nlrt_accel::TlasUpdate,
    ) -> Result<nlrt_accel::PoseUpdate, String> {
        match self {
            Self::Displaced(s) => s.set_pose(positions, normals, update),
            Self::Shell(s) => s.set_pose(positions, normals, update),
        }
        .map_err(|e| format!("pose in {}: {e}", T::NAME))
    }

    /// The TLAS's SAH cost ([`nlrt_accel::Bvh4::sah_cost`]).
    #[must_use]
    pub fn tlas_sah_cost(&self) -> f64 {
        match self {
            Self::Displaced(s) => s.tlas().sah_cost(),
            Self::Shell(s) => s.tlas().sah_cost(),
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

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        let Some((ray, t_min, t_max)) = ray_in::<T>(origin, dir, t_min, t_max) else {
            return false;
        };
        let mut stats = TraversalStats::default();
        match self {
            Self::Displaced(s) => s.occluded(&ray, t_min, t_max, &mut stats),
            Self::Shell(s) => s.occluded(&ray, t_min, t_max, &mut stats),
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
        // The jitter is a hash of the ray, so the same ray always gets the same samples.
        let mut hash = Rng::stream(
            origin.x.to_bits()
                ^ dir.x.to_bits().rotate_left(21)
                ^ dir.y.to_bits().rotate_left(42)
                ^ dir.z.to_bits(),
        );
        let jitter = T::from_f64(hash.next_f64());
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
