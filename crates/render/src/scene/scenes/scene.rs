//! The scene type: a base mesh, what fills its shell, the camera, light, material and motion,
//! and how each precision's surface is built from it.

use crate::scene::material::Material;
use crate::scene::motion::{Motion, Pose};
use nlrt_accel::{
    BaseMesh, DisplacedSurface, HeightField, SeamRule, ShellObject, ShellSurface, Wrap,
};
use nlrt_poly::glam::{DVec2, DVec3};

/// A displacement scene in f64 (converted per precision when built).
#[derive(Clone, Debug)]
pub struct Scene {
    /// Name (`mountain`, `cylinder`, `fur`).
    pub name: &'static str,
    /// Base mesh positions.
    pub positions: Vec<DVec3>,
    /// Base mesh normals (unit; the shell's thickness is `height_scale`).
    pub normals: Vec<DVec3>,
    /// Texture coordinates.
    pub uvs: Vec<DVec2>,
    /// Triangles.
    pub triangles: Vec<[u32; 3]>,
    /// What fills the shell.
    pub content: Content,
    /// World height of `h = 1` (the shell's thickness along unit normals).
    pub height_scale: f64,
    /// The map's height that stays on the base mesh (displacement; `0`: the map pushes out
    /// only, `0.5`: in and out alike; [`nlrt_accel::DisplacedSurface::with_midlevel`]).
    pub midlevel: f64,
    /// Repeats of the height map or object per unit of uv.
    pub tiling: f64,
    /// Camera.
    pub camera: Camera,
    /// Direction towards the sun (unit).
    pub sun: DVec3,
    /// The surface's material.
    pub material: Material,
    /// How the base mesh moves in `nlrt animate` (every built-in scene has a motion).
    pub motion: Motion,
    /// How uv and normal seams of the base mesh are treated by displacement methods and the
    /// pre-tessellated reference ([`SeamRule::Closed`] unless `--no-seam-fix`).
    pub seam_rule: SeamRule,
    /// The scene's second and later objects (a scene file of several `[[object]]` tables),
    /// each a one-object scene with this one's camera, sun, motion and seam rule and no
    /// `others` of its own; empty for every built-in scene. The fields above are the first
    /// object. Methods build each object's own tracer and trace them as one
    /// ([`crate::trace::objects::ObjectUnion`]); see [`Scene::objects`].
    pub others: Vec<Scene>,
}

/// What fills a scene's shell.
#[derive(Clone, Debug)]
pub enum Content {
    /// A height map (displacement mapping).
    Displacement(HeightField),
    /// An object in one unit tile of texture space, `(u, v, h)` in `[0, 1]^3` (shell mapping).
    Shell(Vec<[DVec3; 3]>),
}

impl Content {
    /// A one-line description.
    #[must_use]
    pub fn describe(&self) -> String {
        match self {
            Content::Displacement(f) if f.width() == f.height() => {
                format!("{}^2 height map", f.width())
            }
            Content::Displacement(f) => format!("{} x {} height map", f.width(), f.height()),
            Content::Shell(t) => format!("instanced object of {} triangles", t.len()),
        }
    }
}

/// A pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    /// Eye.
    pub eye: DVec3,
    /// Point looked at.
    pub target: DVec3,
    /// Vertical field of view, degrees.
    pub fov_degrees: f64,
}

impl Camera {
    /// The unit direction through image point `(x, y)` in `[0, 1]^2` (y down) for an image of
    /// aspect `width / height`.
    #[must_use]
    pub fn direction(&self, x: f64, y: f64, aspect: f64) -> DVec3 {
        let forward = (self.target - self.eye).normalize();
        let up_hint = if forward.y.abs() > 0.99 {
            DVec3::Z
        } else {
            DVec3::Y
        };
        let right = forward.cross(up_hint).normalize();
        let up = right.cross(forward);
        let half = (self.fov_degrees.to_radians() * 0.5).tan();
        (forward + right * ((2.0 * x - 1.0) * half * aspect) + up * ((1.0 - 2.0 * y) * half))
            .normalize()
    }
}

impl Scene {
    /// Every object of the scene, the first (this scene's own fields) first. Each is traced
    /// as a one-object scene: what is built from an object never looks at its `others`.
    pub fn objects(&self) -> impl Iterator<Item = &Scene> {
        core::iter::once(self).chain(self.others.iter())
    }

    /// How many objects the scene has (1 for every built-in scene).
    #[must_use]
    pub fn object_count(&self) -> usize {
        1 + self.others.len()
    }

    /// The object whose base triangles carry hit id `id` (ids run through the objects in
    /// order, [`crate::trace::objects::ObjectUnion`]) and the id within it; `None` past the last.
    #[must_use]
    pub fn object_of(&self, id: u32) -> Option<(&Scene, u32)> {
        let mut first = 0u64;
        for object in self.objects() {
            let count = object.triangles.len() as u64;
            if u64::from(id) < first + count {
                return Some((object, (u64::from(id) - first) as u32));
            }
            first += count;
        }
        None
    }

    /// The material at hit id `id` (the material of the object it belongs to).
    #[must_use]
    pub fn material_of(&self, id: u32) -> Material {
        self.object_of(id)
            .map_or(self.material, |(o, _)| o.material)
    }

    /// Sets the seam rule of every object.
    pub fn set_seam_rule(&mut self, rule: SeamRule) {
        self.seam_rule = rule;
        for other in &mut self.others {
            other.seam_rule = rule;
        }
    }

    /// Sets the motion of every object (a deformation moves each object's base mesh by the
    /// same function of world position).
    pub fn set_motion(&mut self, motion: Motion) {
        for other in &mut self.others {
            other.motion = motion.clone();
        }
        self.motion = motion;
    }

    /// Every object's content, one line (`"1024^2 height map"`, or the objects' joined by
    /// `" + "`).
    #[must_use]
    pub fn describe_content(&self) -> String {
        let parts: Vec<String> = self.objects().map(|o| o.content.describe()).collect();
        parts.join(" + ")
    }

    /// Base triangles over every object.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.objects().map(|o| o.triangles.len()).sum()
    }

    /// Why this scene cannot be set up for nonlinear tracing (and every method built on the
    /// same prisms) in precision `T`, or `Ok`: a mesh value, the height scale or the tiling
    /// that is finite in f64 but not in `T`, or texture coordinates that, times the tiling
    /// and the map's side, reach beyond [`nlrt_accel::MAX_TEXEL_COORDINATE`] texels. Scene
    /// files are checked in f64 when loaded and in f32 before an f32 method runs.
    ///
    /// # Errors
    /// The message names the value and the precision.
    pub fn check_precision<T: nlrt_poly::Real>(&self) -> Result<(), String> {
        for (k, object) in self.objects().enumerate() {
            match &object.content {
                Content::Displacement(_) => object.displaced_surface::<T>().map(|_| ()),
                Content::Shell(_) => object.shell_surface::<T>().map(|_| ()),
            }
            .map_err(|e| {
                if self.others.is_empty() {
                    e
                } else {
                    format!("object {}: {e}", k + 1)
                }
            })?;
        }
        Ok(())
    }

    /// The height scale and tiling in precision `T`, or which of them is finite in f64 but
    /// not in `T`.
    fn scale_and_tiling<T: nlrt_poly::Real>(&self) -> Result<(T, T), String> {
        let in_precision = |what: &str, v: f64| {
            let t = T::from_f64(v);
            if v.is_finite() && !t.is_finite() {
                Err(format!(
                    "{what} = {v:e} is finite but not representable in {} (use --precision f64)",
                    T::NAME
                ))
            } else {
                Ok(t)
            }
        };
        Ok((
            in_precision("height_scale", self.height_scale)?,
            in_precision("tiling", self.tiling)?,
        ))
    }

    /// The seams of a displacement scene's base mesh (`None` for shell mapping, which does
    /// not close them).
    #[must_use]
    pub fn seams(&self) -> Option<nlrt_accel::Seams> {
        let Content::Displacement(field) = &self.content else {
            return None;
        };
        let mesh = self.try_mesh::<f64>().ok()?;
        Some(nlrt_accel::Seams::find(
            &mesh,
            self.tiling,
            field.wrap() == Wrap::Repeat,
        ))
    }

    /// One line on the seams for progress output: `""` without seams, else their counts and
    /// whether they are closed (per object, for a scene of several).
    #[must_use]
    pub fn describe_seams(&self) -> String {
        if self.others.is_empty() {
            return self.describe_own_seams();
        }
        self.objects()
            .enumerate()
            .filter_map(|(k, object)| {
                let seams = object.describe_own_seams();
                (!seams.is_empty())
                    .then(|| format!(", object {}: {}", k + 1, seams.trim_start_matches(", ")))
            })
            .collect()
    }

    /// [`Scene::describe_seams`] of this object alone.
    fn describe_own_seams(&self) -> String {
        match self.seams() {
            Some(seams) if !seams.edges().is_empty() => format!(
                ", {} seam edges ({} uv, {} normal{}; {})",
                seams.edges().len(),
                seams.uv_seams(),
                seams.normal_seams(),
                if seams.unpaired() > 0 {
                    format!(", {} non-manifold left open", seams.unpaired())
                } else {
                    String::new()
                },
                match self.seam_rule {
                    SeamRule::Closed => "closed",
                    SeamRule::Open => "left open: --no-seam-fix",
                }
            ),
            _ => String::new(),
        }
    }

    /// The displaced surface of a displacement scene in precision `T` (what nonlinear
    /// tracing and every method on the same prisms build on).
    ///
    /// # Errors
    /// Not a displacement scene, or the reasons of [`Scene::check_precision`].
    pub fn displaced_surface<T: nlrt_poly::Real>(&self) -> Result<DisplacedSurface<T>, String> {
        let Content::Displacement(field) = &self.content else {
            return Err(format!("scene '{}' is not a displacement scene", self.name));
        };
        let (scale, tiling) = self.scale_and_tiling::<T>()?;
        let mesh = self
            .try_mesh::<T>()
            .map_err(|e| format!("base mesh in {}: {e}", T::NAME))?;
        DisplacedSurface::with_midlevel(
            mesh,
            field.clone(),
            scale,
            tiling,
            self.seam_rule,
            T::from_f64(self.midlevel),
        )
        .map_err(|e| {
            let hint = match e {
                nlrt_accel::DisplacementError::UvOutOfRange { .. } => {
                    " (texture coordinates x tiling x map side must stay within 2^22 texels)"
                }
                nlrt_accel::DisplacementError::WorldOutOfRange { .. } => world_range_hint::<T>(),
                _ => "",
            };
            format!("in {}: {e}{hint}", T::NAME)
        })
    }

    /// The shell-mapped surface of a shell scene in precision `T`.
    ///
    /// # Errors
    /// Not a shell scene, or the reasons of [`Scene::check_precision`].
    pub fn shell_surface<T: nlrt_poly::Real>(&self) -> Result<ShellSurface<T>, String> {
        use nlrt_poly::Vector3;
        let Content::Shell(object) = &self.content else {
            return Err(format!("scene '{}' is not a shell-mapped scene", self.name));
        };
        let (scale, tiling) = self.scale_and_tiling::<T>()?;
        let mesh = self
            .try_mesh::<T>()
            .map_err(|e| format!("base mesh in {}: {e}", T::NAME))?;
        let v = |p: &DVec3| T::Vec3::new(T::from_f64(p.x), T::from_f64(p.y), T::from_f64(p.z));
        let object = ShellObject::new(object.iter().map(|t| t.map(|p| v(&p))).collect())
            .map_err(|e| format!("object in {}: {e}", T::NAME))?;
        ShellSurface::new(mesh, object, scale, tiling).map_err(|e| {
            let hint = match e {
                nlrt_accel::ShellError::UvOutOfRange { .. } => {
                    " (texture coordinates x tiling must stay within 2^22 tiles)"
                }
                nlrt_accel::ShellError::WorldOutOfRange { .. } => world_range_hint::<T>(),
                _ => "",
            };
            format!("in {}: {e}{hint}", T::NAME)
        })
    }

    /// The pose of frame `frame` of `frames` by the scene's [`Motion`] (frame 0 of a
    /// deformation is the rest pose); `None` for a static scene.
    #[must_use]
    pub fn pose(&self, frame: usize, frames: usize) -> Option<Pose> {
        self.motion
            .pose(&self.positions, &self.normals, frame, frames)
    }

    /// This scene with its base mesh moved to `pose` (and no motion of its own): what a
    /// method without pose updates builds on, and a fresh build to compare a pose update
    /// with.
    ///
    /// # Errors
    /// A pose with another vertex count than the mesh.
    pub fn posed(&self, pose: &Pose) -> Result<Scene, String> {
        if pose.positions.len() != self.positions.len()
            || pose.normals.len() != self.positions.len()
        {
            return Err(format!(
                "a pose of '{}' needs {} positions and normals, not {} and {}",
                self.name,
                self.positions.len(),
                pose.positions.len(),
                pose.normals.len()
            ));
        }
        let mut scene = self.clone();
        scene.positions.clone_from(&pose.positions);
        scene.normals.clone_from(&pose.normals);
        scene.motion = Motion::Static;
        Ok(scene)
    }

    /// Every object moved to frame `frame` of `frames` by its motion (and no motion of its
    /// own): [`Scene::posed`] of each object's [`Scene::pose`].
    ///
    /// # Errors
    /// A static object, or a pose with another vertex count than its mesh.
    pub fn posed_at(&self, frame: usize, frames: usize) -> Result<Scene, String> {
        let posed = |object: &Scene| {
            let pose = object
                .pose(frame, frames)
                .ok_or_else(|| format!("scene '{}' has no motion", object.name))?;
            object.posed(&pose)
        };
        let mut scene = posed(self)?;
        scene.others = self.others.iter().map(posed).collect::<Result<_, _>>()?;
        Ok(scene)
    }

    /// The base mesh in precision `T`, or why it is invalid there.
    ///
    /// # Errors
    /// A non-finite value (in `T`) or a bad index.
    pub fn try_mesh<T: nlrt_poly::Real>(&self) -> Result<BaseMesh<T>, nlrt_accel::MeshError> {
        use nlrt_poly::{Vector2, Vector3};
        let v3 = |v: &DVec3| T::Vec3::new(T::from_f64(v.x), T::from_f64(v.y), T::from_f64(v.z));
        let v2 = |v: &DVec2| T::Vec2::new(T::from_f64(v.x), T::from_f64(v.y));
        BaseMesh::new(
            self.positions.iter().map(v3).collect(),
            self.normals.iter().map(v3).collect(),
            self.uvs.iter().map(v2).collect(),
            self.triangles.clone(),
        )
    }

    /// The base mesh in precision `T`.
    ///
    /// # Panics
    /// When [`Scene::check_precision`] fails for `T`: never for the built-in scenes (valid by
    /// construction), and never for a loaded scene file after the command's check.
    #[must_use]
    pub fn mesh<T: nlrt_poly::Real>(&self) -> BaseMesh<T> {
        self.try_mesh()
            .expect("scenes are checked by Scene::check_precision before they are built")
    }
}

/// What to do about a mesh beyond [`nlrt_shellmap::max_world_coordinate`] of precision `T`.
pub(super) fn world_range_hint<T: nlrt_poly::Real>() -> &'static str {
    if T::MANTISSA_DIGITS < f64::MANTISSA_DIGITS {
        " (scale the scene down, or use --precision f64)"
    } else {
        " (scale the scene down)"
    }
}
