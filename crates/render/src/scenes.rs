//! The built-in scenes: procedural analogues of the paper's Table 2 displacement scenes
//! (nothing is downloaded). Each is a base mesh with normals and uvs, a height map, a height
//! scale, a tiling and a camera.

use crate::animation::{Deformation, Motion, Pose};
use crate::material::Material;
use nlrt_accel::{
    BaseMesh, DisplacedSurface, HeightField, SeamRule, ShellObject, ShellSurface, Wrap,
};
use nlrt_poly::glam::{DVec2, DVec3};
use rayon::prelude::*;
use std::f64::consts::TAU;

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

/// Names of the built-in scenes: displacement mapping (mountain, cylinder, fur) and shell
/// mapping (scales, cornell, fig9). `torus` is the watertightness scene of the paper's Fig. 8,
/// `fig9` its Fig. 9 (degenerate base meshes and prisms).
pub const SCENE_NAMES: [&str; 9] = [
    "mountain", "cylinder", "fur", "torus", "feathers", "scales", "cornell", "highpoly", "fig9",
];

/// Scenes whose rays `nlrt watertight` can decide (displacement scenes: closed meshes, or the
/// mountain's convex shell) and the report measures.
pub const WATERTIGHT_SCENES: [&str; 6] = [
    "torus",
    "fur",
    "mountain",
    "mountain-grazing",
    "fig9-displaced",
    "seam-cube",
];

/// The ghost-hit tori ([`ghost_torus`]): judged by `nlrt watertight`, not by the report
/// (their figures are in `docs/watertightness.md`).
pub const GHOST_SCENES: [&str; 3] = ["torus-spikes", "torus-tilted", "torus-twisted"];

/// The uv-seam scenes ([`seam_cube`], [`seam_sphere`]): base meshes whose atlas is cut, so
/// the two sides of each seam sample different texels.
pub const SEAM_SCENES: [&str; 2] = ["seam-cube", "seam-sphere"];

/// Built-in scene variants made for one measurement, not part of the default report's
/// renders: `mountain-grazing` (the mountain seen at grazing angles), `fur-cones` (the fur's
/// torus under broad cones, [`fur_cones`]), `fig9-displaced` (Fig.
/// 9's columns with a height map), the ghost-hit tori ([`ghost_torus`]) and the seam scenes
/// ([`SEAM_SCENES`]), the coarse tori ([`COARSE_TORI`]), `mountain-midlevel` and
/// `torus-midlevel` (the mountain and the torus with midlevel 0.5: the maps push in and out),
/// and `dem-crop` ([`dem_crop`]: a map neither square nor a power of two), for
/// `nlrt watertight`, and usable everywhere a scene is.
pub const VARIANT_NAMES: [&str; 20] = [
    "dem-crop",
    "mountain-midlevel",
    "torus-midlevel",
    COARSE_TORI[0].0,
    COARSE_TORI[1].0,
    COARSE_TORI[2].0,
    COARSE_TORI[3].0,
    COARSE_TORI[4].0,
    COARSE_TORI[5].0,
    COARSE_TORI[6].0,
    COARSE_TORI[7].0,
    COARSE_TORI[8].0,
    "mountain-grazing",
    "fur-cones",
    "fig9-displaced",
    "torus-spikes",
    "torus-tilted",
    "torus-twisted",
    "seam-cube",
    "seam-sphere",
];

/// Whether `name` is a built-in scene or variant.
#[must_use]
pub fn is_builtin(name: &str) -> bool {
    SCENE_NAMES.contains(&name) || VARIANT_NAMES.contains(&name)
}

/// Sizes of a built-in scene: the paper's, or reduced for quick runs, or the paper's with
/// every height map of a chosen side (a scale sweep).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Size {
    /// The paper's sizes (4096^2 maps; the fur's 256^2 spikes tiled 8 x 8).
    Paper,
    /// Maps a quarter of the side (the fur's 64^2), same meshes.
    Small,
    /// The paper's sizes, with every height map of this side (a power of two, at least
    /// [`MIN_MAP_SIDE`]: see [`Size::map_side`]); the same terrain or relief, sampled finer or
    /// coarser.
    MapSide(usize),
}

/// The smallest map side [`Size::map_side`] accepts: the fBm maps' coarsest noise period is
/// 4 lattice cells across the map, and the finest octave of 8 needs at least one sample per
/// cell of period `4 * 2^7 = 512`.
pub const MIN_MAP_SIDE: usize = 512;

impl Size {
    /// [`Size::MapSide`] after checking `side`: a power of two from [`MIN_MAP_SIDE`] to the
    /// scene files' largest map (16384).
    ///
    /// # Errors
    /// A side outside that range or not a power of two, with a message saying so.
    pub fn map_side(side: usize) -> Result<Self, String> {
        if side.is_power_of_two() && (MIN_MAP_SIDE..=16384).contains(&side) {
            Ok(Self::MapSide(side))
        } else {
            Err(format!(
                "map side {side} must be a power of two from {MIN_MAP_SIDE} to 16384"
            ))
        }
    }

    /// The side to use for a map whose paper size is `paper` and small size `small`.
    #[must_use]
    fn pick(self, paper: usize, small: usize) -> usize {
        match self {
            Self::Paper => paper,
            Self::Small => small,
            Self::MapSide(side) => side,
        }
    }

    /// An object resolution or other non-map size: the map side does not change it.
    #[must_use]
    fn detail(self, paper: usize, small: usize) -> usize {
        if self == Self::Small { small } else { paper }
    }
}

/// The built-in scene `name` at `size`; `None` for an unknown name.
#[must_use]
pub fn builtin(name: &str, size: Size) -> Option<Scene> {
    let map = |paper, small| size.pick(paper, small);
    match name {
        "mountain" => Some(mountain(map(4096, 1024))),
        "cylinder" => Some(cylinder(map(4096, 1024))),
        "fur" => Some(fur(map(256, 64))),
        "fur-cones" => Some(fur_cones(map(256, 64))),
        "torus" => Some(torus_scene(map(1024, 256))),
        "mountain-grazing" => {
            // The watertightness view of the mountain: just above the shell's top, over the
            // map's edge, looking across it about 4 degrees down.
            let mut m = mountain(map(4096, 1024));
            m.name = "mountain-grazing";
            m.camera.eye = DVec3::new(0.0, 0.4, 0.95);
            m.camera.target = DVec3::new(0.0, 0.25, -1.0);
            Some(m)
        }
        "mountain-midlevel" | "torus-midlevel" => {
            let mut scene = if name == "mountain-midlevel" {
                mountain(map(4096, 1024))
            } else {
                torus_scene(map(1024, 256))
            };
            scene.name = if name == "mountain-midlevel" {
                "mountain-midlevel"
            } else {
                "torus-midlevel"
            };
            scene.midlevel = 0.5;
            Some(scene)
        }
        "dem-crop" => Some(dem_crop(if size == Size::Small { 150 } else { 601 })),
        "scales" => Some(scales()),
        "fig9" => Some(fig9()),
        "fig9-displaced" => Some(fig9_displaced(map(1024, 256))),
        "torus-spikes" | "torus-tilted" | "torus-twisted" => ghost_torus(name, map(256, 64)),
        _ if name.starts_with("torus-coarse") => COARSE_TORI
            .iter()
            .find(|(n, _)| *n == name)
            .map(|&(n, shape)| coarse_torus(n, shape, map(256, 64))),
        "cornell" => Some(cornell(size.detail(15, 6))),
        "seam-cube" => Some(seam_cube(map(1024, 256))),
        "seam-sphere" => Some(seam_sphere(map(1024, 256))),
        "feathers" => Some(feathers()),
        "highpoly" => Some(highpoly(size.detail(270, 32))),
        _ => None,
    }
}

/// A hash of a lattice point to `[0, 1)`.
fn lattice(i: i64, j: i64, seed: u64) -> f64 {
    let mut z = (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (j as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ seed;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as f64 / u64::MAX as f64
}

/// Periodic value noise with period `period` lattice cells, smooth (quintic) interpolation.
fn value_noise(x: f64, y: f64, period: i64, seed: u64) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (i, j) = (fx as i64, fy as i64);
    let s = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (tx, ty) = (s(x - fx), s(y - fy));
    let at = |a: i64, b: i64| lattice(a.rem_euclid(period), b.rem_euclid(period), seed);
    let top = at(i, j) + (at(i + 1, j) - at(i, j)) * tx;
    let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * tx;
    top + (bottom - top) * ty
}

/// A tileable fBm height map (`octaves` of value noise, gain 0.5), normalised to `[0, 1]`.
#[must_use]
pub fn fbm_map(side: usize, base_period: i64, octaves: u32, seed: u64) -> Vec<f32> {
    let rows: Vec<Vec<f64>> = (0..side)
        .into_par_iter()
        .map(|j| {
            (0..side)
                .map(|i| {
                    let (mut sum, mut amp, mut period) = (0.0, 1.0, base_period);
                    for o in 0..octaves {
                        let scale = period as f64 / side as f64;
                        sum += amp
                            * value_noise(
                                i as f64 * scale,
                                j as f64 * scale,
                                period,
                                seed + u64::from(o),
                            );
                        amp *= 0.5;
                        period *= 2;
                    }
                    sum
                })
                .collect()
        })
        .collect();
    let (lo, hi) = rows
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    rows.iter()
        .flatten()
        .map(|&v| ((v - lo) / span) as f32)
        .collect()
}

/// A spike map for fur: a cone of radius `radius` texels around a jittered centre in each
/// cell of `cells x cells`, heights 1 at the tip.
#[must_use]
pub fn spike_map(side: usize, cells: usize, radius: f64, seed: u64) -> Vec<f32> {
    let cell = side as f64 / cells as f64;
    let centres: Vec<(f64, f64)> = (0..cells * cells)
        .map(|k| {
            let (i, j) = ((k % cells) as i64, (k / cells) as i64);
            (
                (i as f64 + 0.25 + 0.5 * lattice(i, j, seed)) * cell,
                (j as f64 + 0.25 + 0.5 * lattice(i, j, seed + 1)) * cell,
            )
        })
        .collect();
    (0..side * side)
        .map(|k| {
            let (x, y) = ((k % side) as f64, (k / side) as f64);
            let (ci, cj) = ((x / cell) as usize, (y / cell) as usize);
            let (cx, cy) = centres[cj.min(cells - 1) * cells + ci.min(cells - 1)];
            let d = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
            (1.0 - d / radius).max(0.0) as f32
        })
        .collect()
}

fn field(side: usize, heights: &[f32]) -> HeightField {
    HeightField::from_unit_heights(side, side, heights, Wrap::Repeat).expect("power-of-two side")
}

/// A terrain as a DEM export gives it: `width x (width * 383 / 601)` samples (601 x 383 at the
/// paper's size, neither square nor a power of two on either side), cropped from the
/// mountain's fBm terrain with no resampling, clamped at its edges (a terrain does not
/// repeat), on a quad of the same aspect seen from the mountain's camera.
#[must_use]
pub fn dem_crop(width: usize) -> Scene {
    let height = (width * 383 / 601).max(2);
    let side = width.next_power_of_two();
    let terrain = fbm_map(side, 4, 8, 11);
    let (x0, y0) = ((side - width) / 3, (side - height) / 2);
    let heights: Vec<f32> = (0..width * height)
        .map(|k| terrain[(y0 + k / width) * side + x0 + k % width])
        .collect();
    let map = HeightField::from_unit_heights(width, height, &heights, Wrap::Clamp)
        .expect("a size within the limits");
    // The mountain's quad, camera and light (its own map, small, is replaced).
    let mut scene = mountain(64);
    let aspect = height as f64 / width as f64;
    for p in &mut scene.positions {
        p.z *= aspect;
    }
    scene.name = "dem-crop";
    scene.content = Content::Displacement(map);
    scene
}

/// (a) Mountain: 2 base triangles, an fBm map.
#[must_use]
pub fn mountain(side: usize) -> Scene {
    let p = [
        DVec3::new(-1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, -1.0),
        DVec3::new(1.0, 0.0, 1.0),
        DVec3::new(-1.0, 0.0, 1.0),
    ];
    let uvs = p
        .iter()
        .map(|p| DVec2::new((p.x + 1.0) * 0.5, (p.z + 1.0) * 0.5))
        .collect();
    Scene {
        name: "mountain",
        positions: p.to_vec(),
        normals: vec![DVec3::Y; 4],
        uvs,
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        content: Content::Displacement(field(side, &fbm_map(side, 4, 8, 11))),
        height_scale: 0.3,
        tiling: 1.0,
        camera: Camera {
            eye: DVec3::new(0.0, 2.0, 2.4),
            target: DVec3::new(0.0, 0.05, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.5, 0.7, 0.3).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Wave),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// A grid surface `(i, j) -> (position, normal, uv)` over `n_u x n_v` quads.
fn grid(
    n_u: usize,
    n_v: usize,
    at: impl Fn(f64, f64) -> (DVec3, DVec3),
) -> (Vec<DVec3>, Vec<DVec3>, Vec<DVec2>, Vec<[u32; 3]>) {
    let (mut p, mut n, mut uv, mut tris) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    // Seams get duplicated vertices (u = 1 next to u = 0), so uvs are continuous per triangle;
    // their positions and normals are computed at u = 0 (and v = 0 where `at` is periodic in
    // v, detected by equal results at 0 and 1 up to rounding), so the two sides of a seam are
    // bit-identical and the shell has no crack there.
    let periodic_v = {
        let (a, b) = (at(0.3, 0.0).0, at(0.3, 1.0).0);
        (a - b).length() < 1e-9
    };
    for j in 0..=n_v {
        for i in 0..=n_u {
            let (u, v) = (i as f64 / n_u as f64, j as f64 / n_v as f64);
            let (pu, pv) = (
                if i == n_u { 0.0 } else { u },
                if j == n_v && periodic_v { 0.0 } else { v },
            );
            let (pos, nor) = at(pu, pv);
            p.push(pos);
            n.push(nor);
            uv.push(DVec2::new(u, v));
        }
    }
    let idx = |i: usize, j: usize| (j * (n_u + 1) + i) as u32;
    for j in 0..n_v {
        for i in 0..n_u {
            tris.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
            tris.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
        }
    }
    (p, n, uv, tris)
}

/// (b) Cylinder: 512 base triangles (16 around x 16 along), an fBm map wrapped around it.
#[must_use]
pub fn cylinder(side: usize) -> Scene {
    let (positions, normals, uvs, triangles) = grid(16, 16, |u, v| {
        let a = TAU * u;
        let n = DVec3::new(a.cos(), 0.0, a.sin());
        (n * 0.6 + DVec3::Y * (v * 2.0 - 1.0), n)
    });
    Scene {
        name: "cylinder",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(field(side, &fbm_map(side, 8, 9, 23))),
        height_scale: 0.12,
        tiling: 1.0,
        camera: Camera {
            eye: DVec3::new(0.0, 0.6, 3.2),
            target: DVec3::ZERO,
            fov_degrees: 45.0,
        },
        sun: DVec3::new(-0.4, 0.6, 0.7).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Bend),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// (c) Torus fur, the kind the paper measured: 8,192 base triangles (64 x 64 quads) under
/// thin hairs, one cone of radius 1.5 texels (at every map size) per 4 x 4 texels, so each
/// hair is a few texels wide and, at the fur's height scale, 9 (small) to 37 (paper size)
/// times taller than wide; their microtriangles are long and steep, with world boxes far
/// larger than their area (what makes the paper's pre-tessellated fur slow).
#[must_use]
pub fn fur(side: usize) -> Scene {
    // A hair's radius in texels: below 2 texels a cone is a single peak of samples.
    const HAIR_RADIUS: f64 = 1.5;
    let mut scene = fur_cones(side);
    scene.name = "fur";
    scene.content = Content::Displacement(field(side, &spike_map(side, side / 4, HAIR_RADIUS, 5)));
    scene
}

/// The torus of [`fur`] under broad, overlapping cones (radius `side / 24` texels on a grid
/// of `side / 8`, tiled 8 x 8): spikes about as wide as tall, whose microtriangles are not
/// long and thin, so pre-tessellation handles them as well as a mountain.
#[must_use]
pub fn fur_cones(side: usize) -> Scene {
    let (positions, normals, uvs, triangles) = torus(64, 1.0, 0.35);
    Scene {
        name: "fur-cones",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(field(
            side,
            &spike_map(side, side / 8, side as f64 / 24.0, 5),
        )),
        height_scale: 0.12,
        tiling: 8.0,
        camera: Camera {
            eye: DVec3::new(0.0, 1.9, 2.4),
            target: DVec3::new(0.0, -0.1, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.3, 0.8, 0.5).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Breathe),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

impl Scene {
    /// Why this scene cannot be set up for nonlinear tracing (and every method built on the
    /// same prisms) in precision `T`, or `Ok`: a mesh value, the height scale or the tiling
    /// that is finite in f64 but not in `T`, or texture coordinates that, times the tiling
    /// and the map's side, reach beyond [`nlrt_accel::MAX_TEXEL_COORDINATE`] texels. Scene
    /// files are checked in f64 when loaded and in f32 before an f32 method runs.
    ///
    /// # Errors
    /// The message names the value and the precision.
    pub fn check_precision<T: nlrt_poly::Real>(&self) -> Result<(), String> {
        match &self.content {
            Content::Displacement(_) => self.displaced_surface::<T>().map(|_| ()),
            Content::Shell(_) => self.shell_surface::<T>().map(|_| ()),
        }
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
    /// whether they are closed.
    #[must_use]
    pub fn describe_seams(&self) -> String {
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

/// A torus of `n x n` quads: positions, unit normals, uvs, triangles.
fn torus(
    n: usize,
    r_major: f64,
    r_minor: f64,
) -> (Vec<DVec3>, Vec<DVec3>, Vec<DVec2>, Vec<[u32; 3]>) {
    grid(n, n, |u, v| {
        let (a, b) = (TAU * u, TAU * v);
        let centre = DVec3::new(a.cos(), 0.0, a.sin()) * r_major;
        let n = DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
        (centre + n * r_minor, n)
    })
}

/// A `n x n` grid of the surface `f(s, t)` as triangles.
fn patch(n: usize, f: impl Fn(f64, f64) -> DVec3) -> Vec<[DVec3; 3]> {
    let mut out = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let p = |a: usize, b: usize| f(a as f64 / n as f64, b as f64 / n as f64);
            out.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
            out.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
        }
    }
    out
}

/// A scale (shingle): a curved plate rising from the tile's lower edge to its upper edge
/// and overlapping the next row, like fish or reptile scales (8 x 8 quads, 128 triangles).
/// It spans the whole tile, so that the scales close: neighbours in a row meet along the tile
/// boundary at the height of their low sides (`h = 0.15`), and each row's high edge stands
/// over the next row's low one. (With a margin between tiles, a view along a tile boundary
/// looked through the gaps on the torus's near and far sides: a see-through line.)
#[must_use]
pub fn scale_object() -> Vec<[DVec3; 3]> {
    patch(8, |s, t| {
        let (u, v) = (s, t);
        // sin(pi) is 1.2e-16, not 0: the two sides of a scale are at the same height exactly.
        let across = if s == 0.0 || s == 1.0 {
            0.0
        } else {
            (std::f64::consts::PI * s).sin()
        };
        DVec3::new(u, v, (0.15 + 0.8 * t * across).min(1.0))
    })
}

/// A shell-mapped torus of `n x n` quads (`2 n^2` base triangles) seen from above at an
/// angle: the base of the scales, feathers and high-poly scenes.
fn shell_torus(
    name: &'static str,
    n: usize,
    object: Vec<[DVec3; 3]>,
    height_scale: f64,
    tiling: f64,
    material: Material,
) -> Scene {
    let (positions, normals, uvs, triangles) = torus(n, 1.0, 0.4);
    Scene {
        name,
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Shell(object),
        height_scale,
        tiling,
        camera: Camera {
            eye: DVec3::new(0.0, 1.8, 2.2),
            target: DVec3::new(0.0, -0.1, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.3, 0.8, 0.5).normalize(),
        material,
        motion: Motion::deform(Deformation::Breathe),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// (e) Scales: a torus of 2,048 base triangles with a glossy scale object tiled 16 x 16.
#[must_use]
pub fn scales() -> Scene {
    shell_torus("scales", 32, scale_object(), 0.06, 16.0, Material::GLOSSY)
}

/// A Cornell-box-like object in the unit tile: floor, back, left and right walls and two
/// blocks, the walls `n x n` grids and the block faces `n/2 x n/2` (`n = 15`: 2,780 triangles).
#[must_use]
pub fn cornell_object(n: usize) -> Vec<[DVec3; 3]> {
    let mut t = Vec::new();
    let (lo, hi) = (0.05, 0.95);
    let lerp = |a: f64, b: f64, s: f64| a + (b - a) * s;
    // Floor (h = lo), back wall (v = hi), left (u = lo) and right (u = hi) walls.
    t.extend(patch(n, |s, r| {
        DVec3::new(lerp(lo, hi, s), lerp(lo, hi, r), lo)
    }));
    t.extend(patch(n, |s, r| {
        DVec3::new(lerp(lo, hi, s), hi, lerp(lo, hi, r))
    }));
    t.extend(patch(n, |s, r| {
        DVec3::new(lo, lerp(lo, hi, s), lerp(lo, hi, r))
    }));
    t.extend(patch(n, |s, r| {
        DVec3::new(hi, lerp(lo, hi, s), lerp(lo, hi, r))
    }));
    // Two blocks: tops and four sides each (a tall and a short one).
    for (x0, y0, w, height) in [(0.2, 0.5, 0.25, 0.7), (0.55, 0.2, 0.25, 0.35)] {
        let (x1, y1, z1) = (x0 + w, y0 + w, lo + height);
        let m = (n / 2).max(1);
        t.extend(patch(m, |s, r| {
            DVec3::new(lerp(x0, x1, s), lerp(y0, y1, r), z1)
        }));
        t.extend(patch(m, |s, r| {
            DVec3::new(lerp(x0, x1, s), y0, lerp(lo, z1, r))
        }));
        t.extend(patch(m, |s, r| {
            DVec3::new(lerp(x0, x1, s), y1, lerp(lo, z1, r))
        }));
        t.extend(patch(m, |s, r| {
            DVec3::new(x0, lerp(y0, y1, s), lerp(lo, z1, r))
        }));
        t.extend(patch(m, |s, r| {
            DVec3::new(x1, lerp(y0, y1, s), lerp(lo, z1, r))
        }));
    }
    t
}

/// (g) Cornell: a UV sphere of 722 base triangles (19 x 19 quads; the rows at the poles are
/// world-degenerate there) with a Cornell-box-like object tiled 16 x 16. Each tile holds its
/// own box, inset by 0.05 tile from the tile's sides: the gaps between boxes are meant, and a
/// view along a tile boundary (the default camera's centre column, along the meridians at the
/// front and back of the sphere) looks through the gaps on both sides of the sphere to the
/// background, as the pre-tessellated reference does.
#[must_use]
pub fn cornell(n: usize) -> Scene {
    let (positions, normals, uvs, triangles) = grid(19, 19, |u, v| {
        // The poles exactly (`cos(pi / 2)` is 6e-17, not 0): every vertex of a pole row's
        // pole is then one point, and the pole triangles are exactly degenerate rather than
        // slivers 1e-16 of their length wide.
        if v == 0.0 || v == 1.0 {
            let n = DVec3::new(0.0, 2.0 * v - 1.0, 0.0);
            return (n, n);
        }
        let (a, b) = (TAU * u, std::f64::consts::PI * (v - 0.5));
        let n = DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
        (n, n)
    });
    Scene {
        name: "cornell",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Shell(cornell_object(n)),
        height_scale: 0.1,
        tiling: 16.0,
        camera: Camera {
            eye: DVec3::new(0.0, 0.9, 2.6),
            target: DVec3::ZERO,
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.4, 0.7, 0.6).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Squash),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// Fig. 8's test object: a torus of 8,192 base triangles with an fBm map tiled 2 x 2
/// (periodic, so the map is continuous across the torus's uv seams), seen from a grazing
/// angle where leaks through single-precision tracing show.
#[must_use]
pub fn torus_scene(side: usize) -> Scene {
    let (positions, normals, uvs, triangles) = torus(64, 1.0, 0.4);
    Scene {
        name: "torus",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(field(side, &fbm_map(side, 8, 7, 37))),
        height_scale: 0.1,
        tiling: 2.0,
        camera: Camera {
            eye: DVec3::new(0.0, 0.9, 2.8),
            target: DVec3::new(0.0, -0.1, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.3, 0.8, 0.5).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Breathe),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// The classes of base mesh on which hits in front of the true surface ("ghost hits") are
/// hunted (`nlrt watertight`): prisms that self-intersect, strongly sheared prisms, and
/// twisted texture coordinates, each on a closed torus (so every ray reaching the base is
/// judged for leaks too). `torus-spikes`: a coarse torus (12 x 12 quads, tube radius 0.4)
/// whose height scale 0.5 exceeds the tube radius, so the prisms on the inner side cross the
/// axis and intersect each other, under single-texel spikes (one sample at full height in 8 of
/// each 64 texels, the rest 0). `torus-tilted`: vertex normals tilted by up to 45 degrees at
/// random (the same at a seam's duplicated vertices, so the surface stays closed), so
/// neighbouring prisms shear against each other, under a 0 / full-height checkerboard.
/// `torus-twisted`: texture coordinates twisted by two turns of the tube around the ring
/// (whole tiles at the seam), an fBm map and a height scale 0.6, 1.5 times the tube radius.
#[must_use]
pub fn ghost_torus(kind: &str, side: usize) -> Option<Scene> {
    let (name, n, height_scale, heights): (&'static str, usize, f64, Vec<f32>) = match kind {
        "torus-spikes" => (
            "torus-spikes",
            12,
            0.5,
            (0..side * side)
                .map(|k| {
                    let (i, j) = ((k % side) as i64, (k / side) as i64);
                    f32::from(lattice(i, j, 71) < 1.0 / 8.0)
                })
                .collect(),
        ),
        "torus-tilted" => (
            "torus-tilted",
            32,
            0.15,
            (0..side * side)
                .map(|k| f32::from((k % side + k / side) % 2 == 1))
                .collect(),
        ),
        "torus-twisted" => ("torus-twisted", 32, 0.6, fbm_map(side, 4, 6, 53)),
        _ => return None,
    };
    let (positions, mut normals, mut uvs, triangles) = torus(n, 1.0, 0.4);
    if kind == "torus-tilted" {
        // A random tilt per vertex position: a unit vector perpendicular to the normal, by
        // an angle up to 45 degrees.
        for (normal, p) in normals.iter_mut().zip(&positions) {
            let key = |x: f64, salt: u64| {
                lattice(
                    x.to_bits() as i64,
                    salt as i64,
                    p.y.to_bits() ^ p.z.to_bits(),
                )
            };
            let (angle, turn) = (key(p.x, 1) * std::f64::consts::FRAC_PI_4, key(p.x, 2) * TAU);
            let side_a = normal.any_orthonormal_vector();
            let side_b = normal.cross(side_a);
            let across = side_a * turn.cos() + side_b * turn.sin();
            *normal = (*normal * angle.cos() + across * angle.sin()).normalize();
        }
    }
    if kind == "torus-twisted" {
        for uv in &mut uvs {
            uv.y += 2.0 * uv.x;
        }
    }
    Some(torus_variant(
        name,
        (positions, normals, uvs, triangles),
        field(side, &heights),
        height_scale,
    ))
}

/// The torus scene's camera, light and material over another base mesh, map and height
/// scale (tiling 1): the tori made for one measurement.
fn torus_variant(
    name: &'static str,
    (positions, normals, uvs, triangles): (Vec<DVec3>, Vec<DVec3>, Vec<DVec2>, Vec<[u32; 3]>),
    map: HeightField,
    height_scale: f64,
) -> Scene {
    let mut scene = torus_scene(map.width());
    scene.name = name;
    scene.positions = positions;
    scene.normals = normals;
    scene.uvs = uvs;
    scene.triangles = triangles;
    scene.content = Content::Displacement(map);
    scene.height_scale = height_scale;
    scene.tiling = 1.0;
    scene
}

/// The shape of a coarse torus ([`coarse_torus`]): the family that `docs/watertightness.md`
/// ("Coarse prisms and horizontal microtriangles") sweeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoarseTorus {
    /// Quads around the ring.
    pub n_ring: usize,
    /// Quads around the tube.
    pub n_tube: usize,
    /// The shell's height scale (the tube's radius is 0.4).
    pub height_scale: f64,
    /// Whether the map carries the single-texel spikes beside its half-height step.
    pub spikes: bool,
}

/// The coarse tori by name: base meshes from 6 x 4 to 48 x 32 quads, shells from 0.01 to 0.6
/// high, with and without spikes. The coarsest and thinnest leaked most in f32 before the
/// horizontal-microtriangle rule (docs/watertightness.md); each is judged at 1M rays there.
pub const COARSE_TORI: [(&str, CoarseTorus); 9] = {
    const fn shape(n_ring: usize, n_tube: usize, height_scale: f64, spikes: bool) -> CoarseTorus {
        CoarseTorus {
            n_ring,
            n_tube,
            height_scale,
            spikes,
        }
    }
    [
        ("torus-coarse", shape(6, 4, 0.6, true)),
        ("torus-coarse-6x4-h0.2", shape(6, 4, 0.2, true)),
        ("torus-coarse-6x4-h0.2-step", shape(6, 4, 0.2, false)),
        ("torus-coarse-6x4-h0.05", shape(6, 4, 0.05, true)),
        ("torus-coarse-6x4-h0.01", shape(6, 4, 0.01, true)),
        ("torus-coarse-12x8", shape(12, 8, 0.6, true)),
        ("torus-coarse-12x8-h0.2", shape(12, 8, 0.2, true)),
        ("torus-coarse-24x16", shape(24, 16, 0.6, true)),
        ("torus-coarse-48x32", shape(48, 32, 0.6, true)),
    ]
};

/// A coarse, strongly bent torus: `n_ring x n_tube` quads (tens of base triangles, where the
/// built-in tori have thousands), so each prism's three directions differ by 60-90 degrees;
/// a shell of `height_scale` (above the tube's radius 0.4, the inner ring's prisms overlap);
/// a map of isolated full-height single-texel spikes (one in 35 texels; left out when
/// `spikes` is false) beside a half-height step over half the map. Its plateau texels beside a
/// spike hold a horizontal microtriangle at the texel's lowest height, which f32 once lost to
/// rounding.
#[must_use]
pub fn coarse_torus(name: &'static str, shape: CoarseTorus, side: usize) -> Scene {
    let CoarseTorus {
        n_ring,
        n_tube,
        height_scale,
        spikes,
    } = shape;
    let (positions, normals, uvs, triangles) = grid(n_ring, n_tube, |u, v| {
        let (a, b) = (TAU * u, TAU * v);
        let centre = DVec3::new(a.cos(), 0.0, a.sin());
        let n = DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
        (centre + n * 0.4, n)
    });
    let heights: Vec<f32> = (0..side * side)
        .map(|k| {
            let (i, j) = (k % side, k / side);
            if spikes && i % 5 == 2 && j % 7 == 3 {
                1.0
            } else if i >= side / 2 {
                0.5
            } else {
                0.0
            }
        })
        .collect();
    let mut scene = torus_variant(
        name,
        (positions, normals, uvs, triangles),
        field(side, &heights),
        height_scale,
    );
    scene.camera = Camera {
        eye: DVec3::new(0.0, 2.2, 2.6),
        target: DVec3::ZERO,
        fov_degrees: 45.0,
    };
    scene
}

/// Fig. 9: a Cornell-box object instanced once in the shell of a two-triangle rectangle, in
/// seven columns: (1) regular; (2) one base triangle degenerate to a line in uv, (3) to a
/// point in uv; (4) normals that make the prisms degenerate to a line at `h = 1`, (5) to a
/// point; (6) one triangle degenerate to a line in world and uv space (it must disappear);
/// (7) one triangle degenerate to a line in world space only.
#[must_use]
pub fn fig9() -> Scene {
    let height = 0.5;
    let (mut positions, mut normals, mut uvs, mut triangles) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for column in 0..7 {
        let x0 = column as f64 * 1.25 - 3.75;
        let corner = |x: f64, z: f64| DVec3::new(x0 + x, 0.0, z - 0.5);
        let mut p = [
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
            corner(0.0, 1.0),
        ];
        let mut uv = [
            DVec2::new(0.0, 0.0),
            DVec2::new(1.0, 0.0),
            DVec2::new(1.0, 1.0),
            DVec2::new(0.0, 1.0),
        ];
        let mut n = [DVec3::Y; 4];
        match column {
            1 => uv[3] = DVec2::new(0.5, 0.5), // triangle (0, 2, 3): a line in uv
            2 => {
                // triangle (0, 2, 3): a point in uv (its own vertices)
                uv = [DVec2::splat(0.5); 4];
                uv[1] = DVec2::new(1.0, 0.0);
            }
            3 => {
                // S_i(1) on the line x = centre, y = height: the prisms pinch to a line.
                for i in 0..4 {
                    n[i] = (DVec3::new(x0 + 0.5, height, p[i].z) - p[i]) / height;
                }
            }
            4 => {
                // S_i(1) all at one point: the prisms pinch to a point.
                for i in 0..4 {
                    n[i] = (DVec3::new(x0 + 0.5, height, 0.0) - p[i]) / height;
                }
            }
            5 => {
                // Triangle (0, 2, 3) a line in world and uv: vertex 3 on the diagonal.
                p[3] = corner(0.5, 0.5);
                uv[3] = DVec2::new(0.5, 0.5);
            }
            6 => p[3] = corner(0.5, 0.5), // a line in world only
            _ => {}
        }
        // Column 2's point-degenerate triangle gets its own vertices so the other keeps uvs.
        let base = positions.len() as u32;
        positions.extend(p);
        normals.extend(n);
        uvs.extend(uv);
        if column == 2 {
            positions.extend([p[0], p[1], p[2]]);
            normals.extend([n[0], n[1], n[2]]);
            uvs.extend([
                DVec2::new(0.0, 0.0),
                DVec2::new(1.0, 0.0),
                DVec2::new(1.0, 1.0),
            ]);
            triangles.push([base + 4, base + 5, base + 6]);
        } else {
            triangles.push([base, base + 1, base + 2]);
        }
        triangles.push([base, base + 2, base + 3]);
    }
    Scene {
        name: "fig9",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Shell(cornell_object(8)),
        height_scale: height,
        tiling: 1.0,
        camera: Camera {
            eye: DVec3::new(0.5, 3.0, 3.9),
            target: DVec3::new(0.5, 0.0, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.3, 0.8, 0.5).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Twist),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// Fig. 9's seven columns (regular; uv-degenerate to a line and to a point; prisms pinching
/// to a line and to a point; a triangle degenerate in world and uv; in world only) displaced by
/// an fBm map instead of shell-mapped by an object, for the watertightness measurement: the
/// map is clamped and fades to exactly zero on its border (a `sin(pi u) sin(pi v)` window), so
/// a ray can get under the surface of the pinched columns only through it.
#[must_use]
pub fn fig9_displaced(side: usize) -> Scene {
    let noise = fbm_map(side, 4, 6, 23);
    let last = (side - 1) as f64;
    let heights: Vec<f32> = noise
        .iter()
        .enumerate()
        .map(|(k, &h)| {
            let (i, j) = ((k % side) as f64, (k / side) as f64);
            let window =
                (std::f64::consts::PI * i / last).sin() * (std::f64::consts::PI * j / last).sin();
            // sin(pi) is 1.2e-16, not 0: the border is set to zero exactly.
            let on_border = i == 0.0 || j == 0.0 || i == last || j == last;
            if on_border {
                0.0
            } else {
                (f64::from(h) * window).max(0.0) as f32
            }
        })
        .collect();
    let mut scene = fig9();
    scene.name = "fig9-displaced";
    scene.content = Content::Displacement(
        HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp)
            .expect("power-of-two side"),
    );
    scene.height_scale = 0.4;
    // All seven columns in a square view (the watertightness grid is square).
    scene.camera = Camera {
        eye: DVec3::new(0.5, 5.0, 7.0),
        target: DVec3::new(0.5, 0.0, 0.0),
        fov_degrees: 60.0,
    };
    scene
}

/// A feather in the unit tile: a shaft rising along v, and `barbs` pairs of barbs, each a
/// thin strip of two quads sweeping out and up from the shaft and drooping at its tip
/// (`8 barbs + 2` triangles).
#[must_use]
pub fn feather_object(barbs: usize) -> Vec<[DVec3; 3]> {
    let shaft_h = |v: f64| 0.15 + 0.6 * v;
    let mut out = Vec::new();
    let p = |u: f64, v: f64, h: f64| DVec3::new(u, v, h.clamp(0.0, 1.0));
    // Shaft: a narrow strip.
    let (a, b) = (p(0.49, 0.03, shaft_h(0.03)), p(0.51, 0.03, shaft_h(0.03)));
    let (c, d) = (p(0.51, 0.97, shaft_h(0.97)), p(0.49, 0.97, shaft_h(0.97)));
    out.push([a, b, c]);
    out.push([a, c, d]);
    let width = 0.75 / barbs as f64;
    for k in 0..barbs {
        let v0 = 0.08 + 0.78 * k as f64 / barbs as f64;
        let length = 0.46 * (1.0 - 0.5 * (k as f64 / barbs as f64 - 0.3).abs());
        for side in [-1.0, 1.0] {
            // Centre line of the barb at parameter s in [0, 1]: out, forward and up, drooping.
            let at = |s: f64, dv: f64| {
                let u = 0.5 + side * length * s;
                let v = v0 + 0.1 * s + dv;
                p(u, v.min(0.99), shaft_h(v0) + 0.15 * s - 0.25 * s * s)
            };
            for (s0, s1) in [(0.0, 0.5), (0.5, 1.0)] {
                let taper = |s: f64| width * (1.0 - 0.6 * s);
                out.push([at(s0, 0.0), at(s1, 0.0), at(s1, taper(s1))]);
                out.push([at(s0, 0.0), at(s1, taper(s1)), at(s0, taper(s0))]);
            }
        }
    }
    out
}

/// (d) Feathers: a torus of 2,048 base triangles with a feather object (98 triangles) tiled
/// 64 x 128 (tiling 64, the torus's v running over two units of uv).
#[must_use]
pub fn feathers() -> Scene {
    let mut scene = shell_torus(
        "feathers",
        32,
        feather_object(12),
        0.08,
        64.0,
        Material::Diffuse,
    );
    for uv in &mut scene.uvs {
        uv.y *= 2.0;
    }
    scene
}

/// A closed, bumpy blob in the unit tile: a sphere of `n x n` quads (`2 n^2` triangles:
/// 145,800 for `n = 270`) whose radius ripples with the angles, the high-polygon instanced
/// object of Table 2 (h). Closed exactly: the seam meridian (`s = 1`) is the first one
/// (`s = 0`) and each pole is one point, so every edge there is shared bit for bit (`sin(2 pi)`
/// and `sin(pi)` are not 0 in floating point: evaluated as they come, the copies differ by
/// 1e-16, the object's shared edges there are not recognised as shared, and the pole's fan
/// keeps zero-area slivers between them).
#[must_use]
pub fn blob_object(n: usize) -> Vec<[DVec3; 3]> {
    let point = |s: f64, t: f64| {
        let centre = DVec3::new(0.5, 0.5, 0.5);
        let base = 0.36;
        if t == 0.0 || t == 1.0 {
            return centre + DVec3::new(0.0, 0.0, if t == 0.0 { base } else { -base });
        }
        let s = if s == 1.0 { 0.0 } else { s };
        let (theta, phi) = (TAU * s, std::f64::consts::PI * t);
        let r = base + 0.06 * (7.0 * theta).sin() * (5.0 * phi).sin();
        let dir = DVec3::new(theta.cos() * phi.sin(), theta.sin() * phi.sin(), phi.cos());
        centre + dir * r
    };
    patch(n, point)
        .into_iter()
        .filter(|t| (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0)
        .collect()
}

/// (h) High-polygon object: a torus of 512 base triangles with a bumpy blob tiled 16 x 16
/// (`2 n^2` triangles per instance, minus the zero-area ones at the poles). The blobs are
/// separate objects with gaps between them, meant: the default camera's centre column, in the
/// plane of a tile boundary at the torus's front and back, sees the background through them.
#[must_use]
pub fn highpoly(n: usize) -> Scene {
    shell_torus(
        "highpoly",
        16,
        blob_object(n),
        0.12,
        16.0,
        Material::Diffuse,
    )
}

/// A non-periodic fBm map (clamped at the border) for the seam scenes: the cells of an atlas
/// hold unrelated relief, so the heights on the two sides of a seam differ.
fn atlas_map(side: usize, seed: u64) -> HeightField {
    HeightField::from_unit_heights(side, side, &fbm_map(side, 8, 6, seed), Wrap::Clamp)
        .expect("power-of-two side")
}

/// A cube as a user's asset has it: 6 faces of 4 x 4 quads, each face its own island of a
/// 3 x 2 uv atlas (with margins), and normals split at the cube's edges (each face keeps its
/// own). Every edge of the cube is a uv seam and a normal seam; a clamped fBm map makes the
/// heights on its two sides differ. Positions are exact binary fractions, so the faces' copies
/// of an edge's vertices are bit-identical.
#[must_use]
pub fn seam_cube(side: usize) -> Scene {
    const QUADS: usize = 4;
    // The margin of each atlas island, as a share of its cell.
    const MARGIN: f64 = 1.0 / 16.0;
    let faces: [(DVec3, DVec3, DVec3); 6] = [
        (DVec3::X, DVec3::NEG_Z, DVec3::Y),
        (DVec3::NEG_X, DVec3::Z, DVec3::Y),
        (DVec3::Y, DVec3::X, DVec3::NEG_Z),
        (DVec3::NEG_Y, DVec3::X, DVec3::Z),
        (DVec3::Z, DVec3::X, DVec3::Y),
        (DVec3::NEG_Z, DVec3::NEG_X, DVec3::Y),
    ];
    let (mut positions, mut normals, mut uvs, mut triangles) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for (f, &(n, u, v)) in faces.iter().enumerate() {
        let base = positions.len() as u32;
        let cell = DVec2::new((f % 3) as f64, (f / 3) as f64);
        for j in 0..=QUADS {
            for i in 0..=QUADS {
                let (a, b) = (i as f64 / QUADS as f64, j as f64 / QUADS as f64);
                positions.push(n + u * (2.0 * a - 1.0) + v * (2.0 * b - 1.0));
                normals.push(n);
                let local = DVec2::splat(MARGIN) + DVec2::new(a, b) * (1.0 - 2.0 * MARGIN);
                uvs.push((cell + local) / DVec2::new(3.0, 2.0));
            }
        }
        let idx = |i: usize, j: usize| base + (j * (QUADS + 1) + i) as u32;
        for j in 0..QUADS {
            for i in 0..QUADS {
                triangles.push([idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)]);
                triangles.push([idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]);
            }
        }
    }
    Scene {
        name: "seam-cube",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(atlas_map(side, 71)),
        height_scale: 0.25,
        tiling: 1.0,
        camera: Camera {
            eye: DVec3::new(2.9, 2.3, 3.4),
            target: DVec3::new(0.0, 0.1, 0.0),
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.5, 0.8, 0.3).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Squash),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// A uv-sphere (24 x 12 quads) under a clamped fBm map: the `u = 0 / u = 1` meridian is a uv
/// seam whose sides sample opposite borders of the map, and the poles are seams too (each
/// pole triangle has its own pole vertex, at its own `u`). The pole rows' other triangles
/// have zero world area (no surface). Positions are computed once per ring and at the poles
/// exactly, so the copies of a seam's vertices are bit-identical.
#[must_use]
pub fn seam_sphere(side: usize) -> Scene {
    let (positions, normals, uvs, triangles) = grid(24, 12, |u, v| {
        let n = if v == 0.0 {
            DVec3::NEG_Y
        } else if v == 1.0 {
            DVec3::Y
        } else {
            let (a, b) = (TAU * u, std::f64::consts::PI * (v - 0.5));
            DVec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos())
        };
        (n, n)
    });
    Scene {
        name: "seam-sphere",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(atlas_map(side, 73)),
        height_scale: 0.15,
        tiling: 1.0,
        camera: Camera {
            // Facing the meridian seam (u = 0 lies towards +x), from above the equator so a
            // pole shows too.
            eye: DVec3::new(3.0, 1.6, -0.6),
            target: DVec3::ZERO,
            fov_degrees: 45.0,
        },
        sun: DVec3::new(0.6, 0.7, -0.2).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Breathe),
        seam_rule: SeamRule::Closed,
        midlevel: 0.0,
    }
}

/// What to do about a mesh beyond [`nlrt_shellmap::max_world_coordinate`] of precision `T`.
fn world_range_hint<T: nlrt_poly::Real>() -> &'static str {
    if T::MANTISSA_DIGITS < f64::MANTISSA_DIGITS {
        " (scale the scene down, or use --precision f64)"
    } else {
        " (scale the scene down)"
    }
}

#[cfg(test)]
mod tests {
    use super::{Content, MIN_MAP_SIDE, Size, builtin};

    /// `Size::MapSide` sets every map's side and leaves the rest at the paper's sizes; sides
    /// that are not powers of two in `[MIN_MAP_SIDE, 16384]` are refused with a message.
    #[test]
    fn a_map_side_sets_the_maps_and_nothing_else() {
        let size = Size::map_side(MIN_MAP_SIDE).unwrap();
        for name in ["mountain", "cylinder", "fur", "torus"] {
            let scene = builtin(name, size).unwrap();
            let Content::Displacement(field) = &scene.content else {
                panic!("{name} is a displacement scene")
            };
            assert_eq!([field.width(), field.height()], [MIN_MAP_SIDE; 2], "{name}");
        }
        let paper = builtin("cornell", Size::Paper).unwrap();
        let swept = builtin("cornell", size).unwrap();
        assert_eq!(swept.content.describe(), paper.content.describe());
        for bad in [0, 256, 1000, 32768] {
            let e = Size::map_side(bad).unwrap_err();
            assert!(
                e.contains(&bad.to_string()) && e.contains("power of two"),
                "{e}"
            );
        }
    }

    /// Midlevel 0.5: nonlinear tracing and the pre-tessellated reference (built on the same
    /// floor) hit at the same distances, in both precisions, and the surface is another one
    /// than at midlevel 0 (the map pushes in where it pushed out). On the mountain, whose
    /// prisms are affine, the reference's flat microtriangles are the surface itself, so f64
    /// agrees to its rounding.
    #[test]
    fn a_midlevel_moves_the_surface_and_every_method_with_it() {
        use crate::tessellate::Tessellated;
        use crate::tracer::Tracer;
        use crate::tracers::Nonlinear;
        let scene = builtin("mountain-midlevel", Size::Small).unwrap();
        let zero = builtin("mountain", Size::Small).unwrap();
        assert_eq!((scene.midlevel, zero.midlevel), (0.5, 0.0));
        let reference = Tessellated::new(&scene);
        let (nonlinear_32, nonlinear_64, at_zero) = (
            Nonlinear::<f32>::new(&scene),
            Nonlinear::<f64>::new(&scene),
            Nonlinear::<f64>::new(&zero),
        );
        let n = 48;
        let (mut hits, mut moved) = (0, 0);
        for k in 0..n * n {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let dir = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
            let eye = scene.camera.eye;
            let trace = |t: &dyn Tracer| t.intersect(eye, dir, 0.0, f64::INFINITY).map(|h| h.t);
            let truth = trace(&reference);
            for (tracer, tolerance) in [(&nonlinear_64 as &dyn Tracer, 1e-9), (&nonlinear_32, 1e-4)]
            {
                match (truth, trace(tracer)) {
                    (Some(a), Some(b)) => {
                        assert!((a - b).abs() <= tolerance * a, "ray {k}: {a} vs {b}");
                    }
                    (a, b) => assert_eq!(a.is_some(), b.is_some(), "ray {k}: {a:?} vs {b:?}"),
                }
            }
            if let Some(t) = truth {
                hits += 1;
                if trace(&at_zero).is_none_or(|z| (z - t).abs() > 1e-6 * t) {
                    moved += 1;
                }
            }
        }
        assert!(hits > n * n / 4, "{hits}");
        assert!(moved > hits * 9 / 10, "{moved} of {hits}");
    }
}
