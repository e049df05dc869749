//! Scene files: a TOML file naming an OBJ base mesh (uvs required, normals computed when
//! absent) and either a PNG height map (displacement mapping) or an OBJ object in the unit
//! tile (shell mapping), with height scale, tiling, camera and sun. Paths are relative to the
//! TOML file. Every error names the file (and the line, where the format has one).
//!
//! ```toml
//! [mesh]
//! obj = "base.obj"
//! material = "diffuse"        # optional: "diffuse" (default) or "glossy"
//! [displacement]
//! height_map = "height.png"   # grayscale PNG (8 or 16 bits), EXR (channel Y, else R, else
//!                             # the only one) or grayscale TIFF (integers or floats, a DEM
//!                             # export); any width x height from 2 x 2, traced as it is
//!                             # (no resampling)
//! height_scale = 0.1
//! tiling = 1.0                # optional, default 1
//! midlevel = 0.0              # optional: the height that stays on the mesh, in [0, 1]
//!                             # (0: the map pushes out only; 0.5: in and out alike)
//! normalize = false           # optional: map an EXR's or TIFF's range onto [0, 1] (a DEM
//!                             # in metres); without it their heights must lie in [0, 1]
//! [camera]
//! eye = [0.0, 1.0, 3.0]
//! target = [0.0, 0.0, 0.0]
//! fov_degrees = 45.0          # optional
//! sun = [0.3, 0.8, 0.5]       # optional
//! ```
//!
//! For shell mapping, `[shell]` with `object = "object.obj"` (vertices `(x, y, z)` read as
//! `(u, v, h)` in `[0, 1]^3`), `height_scale` and `tiling` replaces `[displacement]`.
//!
//! An optional `[animation]` section makes the base mesh move in `nlrt animate`, by one of:
//!
//! ```toml
//! [animation]
//! frames = ["walk_000.obj", "walk_001.obj"]  # poses: the base mesh's vertices, triangles
//!                                            # and uvs, moved (normals computed if absent)
//! # or
//! deformation = "bend"   # wave, bend, twist, breathe, squash (of the base mesh, y up)
//! amplitude = 1.0        # optional
//! ```

use crate::scene::map_file::{MapLimit, load_height_map};
use crate::scene::material::Material;
use crate::scene::motion::{Deformation, Motion, Pose};
use crate::scene::scenes::{Camera, Content, Scene};
use nlrt_accel::{HeightField, Wrap};
use nlrt_poly::glam::{DVec2, DVec3};
use serde::Deserialize;
use std::path::{Path, PathBuf};

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    mesh: Option<MeshSection>,
    displacement: Option<DisplacementSection>,
    shell: Option<ShellSection>,
    object: Option<Vec<ObjectSection>>,
    camera: CameraSection,
    animation: Option<AnimationSection>,
}

/// One `[[object]]` table: a base mesh placed in the scene, and what fills its shell.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectSection {
    obj: PathBuf,
    #[serde(default)]
    material: MaterialName,
    #[serde(default)]
    translate: [f64; 3],
    #[serde(default = "one")]
    scale: f64,
    displacement: Option<DisplacementSection>,
    shell: Option<ShellSection>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AnimationSection {
    frames: Option<Vec<PathBuf>>,
    deformation: Option<String>,
    amplitude: Option<f64>,
}

/// The most pose files an `[animation]` may name: each is a full copy of the base mesh in
/// memory, and 10,000 frames is over five minutes at 30 frames per second.
pub const MAX_POSE_FILES: usize = 10_000;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshSection {
    obj: PathBuf,
    #[serde(default)]
    material: MaterialName,
}

#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum MaterialName {
    #[default]
    Diffuse,
    Glossy,
}

/// How the height map continues past its border: `repeat` (tiled, the default) or `clamp`
/// (edge samples extended: a map that is not periodic, as a uv atlas's).
#[derive(Deserialize, Default, Clone, Copy)]
#[serde(rename_all = "lowercase")]
enum WrapName {
    #[default]
    Repeat,
    Clamp,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DisplacementSection {
    height_map: PathBuf,
    height_scale: f64,
    #[serde(default = "one")]
    tiling: f64,
    #[serde(default)]
    wrap: WrapName,
    #[serde(default)]
    midlevel: f64,
    #[serde(default)]
    normalize: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ShellSection {
    object: PathBuf,
    height_scale: f64,
    #[serde(default = "one")]
    tiling: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraSection {
    eye: [f64; 3],
    target: [f64; 3],
    #[serde(default = "default_fov")]
    fov_degrees: f64,
    #[serde(default = "default_sun")]
    sun: [f64; 3],
}

fn one() -> f64 {
    1.0
}
fn default_fov() -> f64 {
    45.0
}
fn default_sun() -> [f64; 3] {
    [0.3, 0.8, 0.5]
}

/// Where a scene file's text and the files it names come from, and how large a height map
/// may be.
pub struct Source<'a> {
    /// The bytes of a file, given its path (the scene file's own, or one it names joined to
    /// the scene file's directory), or the message saying why it cannot be read.
    pub read: &'a dyn Fn(&Path) -> Result<Vec<u8>, String>,
    /// The largest height-map side accepted, checked from the map's header before its
    /// samples are allocated ([`MAX_MAP_SIDE`] for files).
    pub max_map_side: usize,
}

/// A built-in scene by name ([`crate::scene::scenes::builtin`] at `size`), or the scene file at
/// `name` when it ends in `.toml` (its maps at their own size).
///
/// # Errors
/// An unknown name (the message lists the built-in scenes), or the reasons of [`load`].
pub fn builtin_or_file(name: &str, size: crate::scene::scenes::Size) -> Result<Scene, String> {
    if name.ends_with(".toml") {
        return load(Path::new(name));
    }
    let known = crate::scene::scenes::is_builtin(name);
    crate::scene::scenes::builtin(name, size).filter(|_| known).ok_or_else(|| {
        format!(
            "unknown scene '{name}' (built-in scenes: {}; variants: {}; or a scene file *.toml)",
            crate::scene::scenes::names(crate::scene::scenes::Tag::Report).join(", "),
            crate::scene::scenes::names(crate::scene::scenes::Tag::Variant).join(", ")
        )
    })
}

/// Loads a scene file.
///
/// # Errors
/// A message naming the file (and line) for: an unreadable file, TOML syntax, an unknown key,
/// a bad value, a missing section; a malformed OBJ, an OBJ without texture coordinates, NaN or
/// infinite vertices, triangles degenerate in both world and uv space; a height map that is
/// not a grayscale 8/16-bit PNG or an EXR of heights in [0, 1], or of a side below 2 or above the largest; an object outside the
/// unit tile.
pub fn load(path: &Path) -> Result<Scene, String> {
    let read = |p: &Path| std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()));
    load_from(
        path,
        &Source {
            read: &read,
            max_map_side: MAX_MAP_SIDE,
        },
    )
}

/// [`load`] with the scene file and the files it names read from `source` (the fuzz target
/// feeds them from memory).
///
/// # Errors
/// As [`load`].
pub fn load_from(path: &Path, source: &Source<'_>) -> Result<Scene, String> {
    let bytes = (source.read)(path)?;
    let text = std::str::from_utf8(&bytes)
        .map_err(|e| format!("{}: not UTF-8 text: {e}", path.display()))?;
    let file: File = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| format!(" line {}", text[..s.start].matches('\n').count() + 1))
            .unwrap_or_default();
        format!("{}{line}: {}", path.display(), e.message())
    })?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let in_file = |m: String| format!("{}: {m}", path.display());
    let several = file.object.is_some();
    let sections = match (file.mesh, file.object) {
        (Some(mesh), None) => vec![ObjectSection {
            obj: mesh.obj,
            material: mesh.material,
            translate: [0.0; 3],
            scale: 1.0,
            displacement: file.displacement,
            shell: file.shell,
        }],
        (None, Some(objects)) => {
            if file.displacement.is_some() || file.shell.is_some() {
                return Err(in_file(
                    "with [[object]] tables, each object has its own [object.displacement] or [object.shell]; a top-level [displacement] or [shell] belongs to a [mesh]".into(),
                ));
            }
            if objects.is_empty() || objects.len() > MAX_OBJECTS {
                return Err(in_file(format!(
                    "{} [[object]] tables; between 1 and {MAX_OBJECTS} are accepted",
                    objects.len()
                )));
            }
            objects
        }
        (Some(_), Some(_)) => {
            return Err(in_file(
                "give either one [mesh] or [[object]] tables, not both".into(),
            ));
        }
        (None, None) => {
            return Err(in_file(
                "a [mesh] section or [[object]] tables are required".into(),
            ));
        }
    };
    let mut limit = MapLimit {
        side: source.max_map_side,
        samples: source.max_map_side.saturating_mul(source.max_map_side),
    };
    let mut objects = Vec::with_capacity(sections.len());
    let label = path.display().to_string();
    let mut triangles = 0u64;
    for (k, section) in sections.into_iter().enumerate() {
        let object = load_object(&label, dir, source, &mut limit, section);
        // Every message begins with a file's path: the scene file's, for an object's.
        let object = object.map_err(|e| {
            if several {
                format!("{label}: object {}: {e}", k + 1)
            } else {
                e
            }
        })?;
        // Hit ids run through every object's base triangles (`ObjectUnion`): they must fit
        // in 32 bits together, as one mesh's indices do.
        triangles += object.triangles.len() as u64;
        if triangles > u64::from(u32::MAX) {
            return Err(in_file(format!(
                "the objects up to object {} hold more than 2^32 - 1 base triangles together; hit ids need fewer",
                k + 1
            )));
        }
        objects.push(object);
    }
    let check = |what: &str, v: f64, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(in_file(format!("{what} = {v} is out of range")))
        }
    };
    let c = &file.camera;
    let finite = |v: [f64; 3]| v.iter().all(|x| x.is_finite());
    if !(finite(c.eye) && finite(c.target) && finite(c.sun)) {
        return Err(format!(
            "{}: camera eye, target and sun must be finite numbers",
            path.display()
        ));
    }
    // The view direction must itself be finite and normalisable: eye and target far apart
    // at opposite ends of f64's range overflow, and targets a subnormal distance from the
    // eye underflow to a zero direction; either would make every camera ray NaN.
    let view = DVec3::from(c.target) - DVec3::from(c.eye);
    if !(view.is_finite() && view.normalize_or_zero() != DVec3::ZERO) {
        return Err(format!(
            "{}: camera target - eye = {view} is not a usable view direction (it must be finite and non-zero, with a length that neither overflows nor underflows)",
            path.display()
        ));
    }
    check(
        "fov_degrees",
        c.fov_degrees,
        c.fov_degrees > 0.0 && c.fov_degrees < 180.0,
    )?;
    // Scaled by its largest component first, so a direction like [1e300, 1e300, 1e300],
    // whose length overflows, still normalises.
    let sun = DVec3::from(c.sun);
    let largest = sun.abs().max_element();
    if largest == 0.0 {
        return Err(format!(
            "{}: sun direction {sun} is zero: it has no direction",
            path.display()
        ));
    }
    let sun = (sun / largest).normalize();
    let camera = Camera {
        eye: DVec3::from(c.eye),
        target: DVec3::from(c.target),
        fov_degrees: c.fov_degrees,
    };
    let mut scenes = Vec::with_capacity(objects.len());
    for object in objects {
        scenes.push(Scene {
            name: "file",
            positions: object.positions,
            normals: object.normals,
            uvs: object.uvs,
            triangles: object.triangles,
            content: object.content,
            height_scale: object.height_scale,
            tiling: object.tiling,
            camera,
            sun,
            material: object.material,
            motion: Motion::Static,
            seam_rule: nlrt_accel::SeamRule::Closed,
            midlevel: object.midlevel,
            others: Vec::new(),
        });
    }
    let mut scene = scenes.remove(0);
    scene.others = scenes;
    if let Some(a) = &file.animation {
        if a.frames.is_some() && !scene.others.is_empty() {
            return Err(in_file(
                "[animation] frames are poses of one base mesh; a file of several objects moves them by a deformation".into(),
            ));
        }
        let rest = (
            scene.positions.as_slice(),
            scene.uvs.as_slice(),
            scene.triangles.as_slice(),
        );
        let motion = load_motion(path, a, dir, source, rest)?;
        scene.set_motion(motion);
    }
    // Mesh values, height scale and tiling as the tracers will see them in f64 (f32 is
    // checked when an f32 method is asked for).
    scene
        .check_precision::<f64>()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(scene)
}

type ObjData = (Vec<DVec3>, Vec<DVec3>, Vec<DVec2>, Vec<[u32; 3]>);

/// The most `[[object]]` tables a scene file may have: a ray tests every object's root box in
/// turn ([`crate::trace::objects::ObjectUnion`]), so a ray that misses them all costs one box
/// test per object; 256 of them are of the order of one ray's walk through one surface (tens
/// to hundreds of child tests per ray, docs/measurements.md), past which a tree over the
/// objects would be the tool.
pub const MAX_OBJECTS: usize = 256;

/// One object of a scene file, loaded and placed.
struct ObjectData {
    positions: Vec<DVec3>,
    normals: Vec<DVec3>,
    uvs: Vec<DVec2>,
    triangles: Vec<[u32; 3]>,
    content: Content,
    height_scale: f64,
    tiling: f64,
    midlevel: f64,
    material: Material,
}

/// Loads an object's mesh and map or tile object and places it by its `translate` and
/// `scale` (the whole object, its height scale too, as an instance transform would); `label`
/// (the scene file) starts the messages about its values; `limit` is what its height map may take, less what it took after.
fn load_object(
    label: &str,
    dir: &Path,
    source: &Source<'_>,
    limit: &mut MapLimit,
    section: ObjectSection,
) -> Result<ObjectData, String> {
    let check = |what: &str, v: f64, ok: bool| {
        if ok {
            Ok(())
        } else {
            Err(format!("{label}: {what} = {v} is out of range"))
        }
    };
    check(
        "scale",
        section.scale,
        section.scale.is_finite() && section.scale > 0.0,
    )?;
    if !section.translate.iter().all(|x| x.is_finite()) {
        return Err(format!(
            "{label}: translate = {:?} must be finite numbers",
            section.translate
        ));
    }
    let (mut positions, normals, uvs, triangles) = load_obj(&dir.join(&section.obj), source, true)?;
    let (content, height_scale, tiling, midlevel) = match (section.displacement, section.shell) {
        (Some(d), None) => {
            check(
                "height_scale",
                d.height_scale,
                d.height_scale.is_finite() && d.height_scale > 0.0,
            )?;
            check(
                "tiling",
                d.tiling,
                d.tiling.is_finite() && d.tiling > 0.0 && d.tiling <= 1e6,
            )?;
            check("midlevel", d.midlevel, (0.0..=1.0).contains(&d.midlevel))?;
            let map_path = dir.join(&d.height_map);
            let bytes = (source.read)(&map_path)?;
            let mut field = load_height_map(&map_path, &bytes, *limit, d.normalize)?;
            limit.samples -= field.width() * field.height();
            if let WrapName::Clamp = d.wrap {
                // The samples were valid under one wrap, so they are under the other.
                field = HeightField::new(
                    field.width(),
                    field.height(),
                    field.samples().to_vec(),
                    Wrap::Clamp,
                )
                .map_err(|e| format!("{label}: {e}"))?;
            }
            (
                Content::Displacement(field),
                d.height_scale,
                d.tiling,
                d.midlevel,
            )
        }
        (None, Some(s)) => {
            check(
                "height_scale",
                s.height_scale,
                s.height_scale.is_finite() && s.height_scale > 0.0,
            )?;
            check(
                "tiling",
                s.tiling,
                s.tiling.is_finite() && s.tiling > 0.0 && s.tiling <= 1e6,
            )?;
            let object_path = dir.join(&s.object);
            let (p, _, _, t) = load_obj(&object_path, source, false)?;
            let object: Vec<[DVec3; 3]> = t.iter().map(|t| t.map(|i| p[i as usize])).collect();
            if let Some(bad) = object
                .iter()
                .flatten()
                .find(|v| !(v.min_element() >= 0.0 && v.max_element() <= 1.0))
            {
                return Err(format!(
                    "{}: object vertex {bad} is outside the unit tile [0, 1]^3 (objects are given as (u, v, h))",
                    object_path.display()
                ));
            }
            (Content::Shell(object), s.height_scale, s.tiling, 0.0)
        }
        _ => {
            return Err(format!(
                "{label}: exactly one of [displacement] and [shell] is required"
            ));
        }
    };
    let (scale, translate) = (section.scale, DVec3::from(section.translate));
    if scale != 1.0 || translate != DVec3::ZERO {
        for p in &mut positions {
            *p = *p * scale + translate;
        }
    }
    let height_scale = height_scale * scale;
    // Placed values must stay finite (the mesh itself is checked with the scene).
    check(
        "height_scale x scale",
        height_scale,
        height_scale.is_finite(),
    )?;
    Ok(ObjectData {
        positions,
        normals,
        uvs,
        triangles,
        content,
        height_scale,
        tiling,
        midlevel,
        material: match section.material {
            MaterialName::Diffuse => Material::Diffuse,
            MaterialName::Glossy => Material::GLOSSY,
        },
    })
}

/// The motion of an `[animation]` section; `rest` is the base mesh's positions, uvs and
/// triangles, which every pose file must match (but for its positions and normals).
fn load_motion(
    path: &Path,
    a: &AnimationSection,
    dir: &Path,
    source: &Source<'_>,
    rest: (&[DVec3], &[DVec2], &[[u32; 3]]),
) -> Result<Motion, String> {
    let err = |m: String| format!("{}: [animation] {m}", path.display());
    match (&a.frames, &a.deformation) {
        (Some(frames), None) => {
            if a.amplitude.is_some() {
                return Err(err(
                    "amplitude belongs to a deformation, not to frames".into()
                ));
            }
            if frames.is_empty() || frames.len() > MAX_POSE_FILES {
                return Err(err(format!(
                    "frames names {} files; between 1 and {MAX_POSE_FILES} are accepted",
                    frames.len()
                )));
            }
            let mut poses = Vec::with_capacity(frames.len());
            for f in frames {
                let frame_path = dir.join(f);
                let (p, n, uv, t) = load_obj(&frame_path, source, true)?;
                let what = if p.len() != rest.0.len() {
                    Some(format!(
                        "{} vertices, the base mesh {}",
                        p.len(),
                        rest.0.len()
                    ))
                } else if t.as_slice() != rest.2 {
                    Some("other triangles than the base mesh".into())
                } else if uv.as_slice() != rest.1 {
                    Some("other texture coordinates than the base mesh".into())
                } else {
                    None
                };
                if let Some(what) = what {
                    return Err(format!(
                        "{}: a pose must have the base mesh's vertices, triangles and uvs; it has {what}",
                        frame_path.display()
                    ));
                }
                poses.push(Pose {
                    positions: p,
                    normals: n,
                });
            }
            Ok(Motion::Frames(poses.into()))
        }
        (None, Some(name)) => {
            let deformation = Deformation::from_name(name).map_err(err)?;
            let amplitude = a.amplitude.unwrap_or(1.0);
            // Beyond 10 every deformation folds the mesh through itself many times over: not
            // an animation anyone means.
            if !(amplitude.is_finite() && amplitude.abs() <= 10.0) {
                return Err(err(format!(
                    "amplitude = {amplitude} is out of range (|amplitude| <= 10)"
                )));
            }
            Ok(Motion::Deform {
                deformation,
                amplitude,
            })
        }
        _ => Err(err("give exactly one of frames and deformation".into())),
    }
}

/// Checks every index of the OBJ's faces and lines (`f`, `l`) before the bytes go to `tobj`,
/// which turns an index beyond the elements defined into an arithmetic overflow (a panic in
/// debug builds, a wrapped index in release: `f 1/1 4/4 3/-3` with two `vt`): each index must
/// be an integer other than 0, a positive one at most the number of elements of its kind in
/// the file, a negative (relative) one at most the number defined before its line.
/// Lines are read as `tobj` reads them (split at `\n`, keyword the first word); a line that
/// is not UTF-8 is left to `tobj`, which refuses the file.
fn check_face_indices(bytes: &[u8]) -> Result<(), String> {
    const KINDS: [&str; 3] = ["vertex", "texture coordinate (vt)", "normal (vn)"];
    let lines = || bytes.split(|&b| b == b'\n').map(core::str::from_utf8);
    let count = |keyword: &str| {
        lines()
            .filter(|l| l.is_ok_and(|l| l.split_whitespace().next() == Some(keyword)))
            .count()
    };
    let total = [count("v"), count("vt"), count("vn")];
    let mut defined = [0usize; 3];
    for (number, line) in lines().enumerate() {
        let Ok(line) = line else { continue };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => defined[0] += 1,
            Some("vt") => defined[1] += 1,
            Some("vn") => defined[2] += 1,
            Some("f" | "l") => {
                for word in words {
                    for (kind, part) in word.split('/').take(3).enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        // What tobj does not parse as an index it refuses itself.
                        let Ok(index) = part.parse::<i64>() else {
                            continue;
                        };
                        let limit = if index < 0 {
                            defined[kind]
                        } else {
                            total[kind]
                        };
                        if index == 0 || index.unsigned_abs() > limit as u64 {
                            return Err(format!(
                                "line {}: {} index {index} is out of range ({limit} defined{}; indices start at 1, negative ones count back from the last defined)",
                                number + 1,
                                KINDS[kind],
                                if index < 0 { " before this line" } else { "" },
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    Ok(())
}

/// An OBJ as one mesh (all models merged). With `base`, texture coordinates are required and
/// normals computed (area-weighted) when absent.
fn load_obj(path: &Path, source: &Source<'_>, base: bool) -> Result<ObjData, String> {
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ..Default::default()
    };
    let bytes = (source.read)(path)?;
    check_face_indices(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
    // Material libraries are not read: the scene file gives the material.
    let (models, _) =
        tobj::load_obj_buf(&mut bytes.as_slice(), &options, |_| Ok(Default::default()))
            .map_err(|e| format!("{}: {e}", path.display()))?;
    let (mut p, mut n, mut uv, mut t) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for m in &models {
        let mesh = &m.mesh;
        let base_index = p.len() as u32;
        let count = mesh.positions.len() / 3;
        if base && mesh.texcoords.len() != 2 * count {
            return Err(format!(
                "{}: model '{}' has no texture coordinates (vt); a base mesh needs uvs",
                path.display(),
                m.name
            ));
        }
        for i in 0..count {
            let v = DVec3::new(
                f64::from(mesh.positions[3 * i]),
                f64::from(mesh.positions[3 * i + 1]),
                f64::from(mesh.positions[3 * i + 2]),
            );
            if !v.is_finite() {
                return Err(format!(
                    "{}: vertex {} is NaN or infinite",
                    path.display(),
                    p.len() + 1
                ));
            }
            p.push(v);
            if base {
                uv.push(DVec2::new(
                    f64::from(mesh.texcoords[2 * i]),
                    f64::from(mesh.texcoords[2 * i + 1]),
                ));
            }
            if mesh.normals.len() == 3 * count {
                let normal = DVec3::new(
                    f64::from(mesh.normals[3 * i]),
                    f64::from(mesh.normals[3 * i + 1]),
                    f64::from(mesh.normals[3 * i + 2]),
                );
                if !normal.is_finite() {
                    return Err(format!(
                        "{}: vertex normal {normal} is not finite",
                        path.display()
                    ));
                }
                n.push(normal);
            }
        }
        for tri in mesh.indices.chunks_exact(3) {
            t.push([
                tri[0] + base_index,
                tri[1] + base_index,
                tri[2] + base_index,
            ]);
        }
    }
    if t.is_empty() {
        return Err(format!("{}: no triangles", path.display()));
    }
    if base {
        for (k, tri) in t.iter().enumerate() {
            let [a, b, c] = tri.map(|i| i as usize);
            let world = (p[b] - p[a]).cross(p[c] - p[a]).length_squared();
            let tex = (uv[b] - uv[a]).perp_dot(uv[c] - uv[a]);
            if world == 0.0 && tex == 0.0 {
                return Err(format!(
                    "{}: triangle {} has zero area in both world and uv space",
                    path.display(),
                    k + 1
                ));
            }
        }
        if n.len() != p.len() {
            n = vec![DVec3::ZERO; p.len()];
            for tri in &t {
                let [a, b, c] = tri.map(|i| i as usize);
                let face = (p[b] - p[a]).cross(p[c] - p[a]);
                for v in [a, b, c] {
                    n[v] += face;
                }
            }
        }
        for v in &mut n {
            *v = v.normalize_or_zero();
        }
    }
    Ok((p, n, uv, t))
}

/// The largest height-map side a scene file may have: 16384^2 16-bit samples are 512 MiB
/// (and the decoder's buffer as much again, or 1 GiB for a 32-bit EXR channel), four times
/// the paper's largest map side (4096) and within this project's 24 GiB machines. Checked
/// from the file's header, before anything is allocated.
pub const MAX_MAP_SIDE: usize = 16_384;

/// Writes `scene` as a scene file `<dir>/<name>.toml` with its OBJ base mesh and its PNG
/// height map (16-bit) or OBJ object, loadable by [`load`]. Positions, normals and uvs are
/// written with 9 significant digits (OBJ is text; `tobj` reads them as f32).
///
/// # Errors
/// When a file cannot be written.
pub fn export(scene: &Scene, dir: &Path) -> Result<PathBuf, String> {
    export_as(scene, scene.name, dir)
}

/// [`export`] with the files named after `name` (`<name>.toml`, `<name>.obj`, ...; with
/// several objects, `<name>-<k>.obj`, ... per object `k` from 1, written as `[[object]]`
/// tables with their placement applied).
///
/// # Errors
/// As [`export`].
pub fn export_as(scene: &Scene, name: &str, dir: &Path) -> Result<PathBuf, String> {
    let io = |path: &Path, e: std::io::Error| format!("{}: {e}", path.display());
    std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
    let several = !scene.others.is_empty();
    let mut objects = String::new();
    for (k, object) in scene.objects().enumerate() {
        let stem = if several {
            format!("{name}-{}", k + 1)
        } else {
            name.to_string()
        };
        let (mesh, content) = export_object(object, &stem, dir)?;
        if several {
            objects += &format!("[[object]]\n{mesh}[object.{content}\n");
        } else {
            objects += &format!("[mesh]\n{mesh}\n[{content}");
        }
    }
    let c = &scene.camera;
    let animation = match &scene.motion {
        Motion::Deform {
            deformation,
            amplitude,
        } => format!(
            "\n[animation]\ndeformation = \"{}\"\namplitude = {amplitude}\n",
            deformation.name()
        ),
        // Poses read from files are not written back; a static scene has none.
        Motion::Frames(_) | Motion::Static => String::new(),
    };
    let toml = format!(
        "# The scene '{name}', exported by `nlrt export`.\n\n{objects}{animation}\n[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, {}]\nfov_degrees = {}\nsun = [{}, {}, {}]\n",
        c.eye.x,
        c.eye.y,
        c.eye.z,
        c.target.x,
        c.target.y,
        c.target.z,
        c.fov_degrees,
        scene.sun.x,
        scene.sun.y,
        scene.sun.z
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, toml).map_err(|e| io(&path, e))?;
    Ok(path)
}

/// Writes one object's base mesh (`<stem>.obj`) and map (`<stem>-height.png`) or tile object
/// (`<stem>-object.obj`); returns its mesh keys (`obj`, `material`) and its content table
/// without the opening bracket (`displacement]\n...` or `shell]\n...`).
fn export_object(object: &Scene, stem: &str, dir: &Path) -> Result<(String, String), String> {
    use std::fmt::Write as _;
    let scene = object;
    let io = |path: &Path, e: std::io::Error| format!("{}: {e}", path.display());
    let mut obj = String::from("# exported by nlrt\n");
    for p in &scene.positions {
        let _ = writeln!(obj, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
    }
    for t in &scene.uvs {
        let _ = writeln!(obj, "vt {:.9} {:.9}", t.x, t.y);
    }
    for n in &scene.normals {
        let _ = writeln!(obj, "vn {:.9} {:.9} {:.9}", n.x, n.y, n.z);
    }
    for t in &scene.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        let _ = writeln!(obj, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}");
    }
    let mesh_path = dir.join(format!("{stem}.obj"));
    std::fs::write(&mesh_path, obj).map_err(|e| io(&mesh_path, e))?;
    let content = match &scene.content {
        Content::Displacement(field) => {
            let path = dir.join(format!("{stem}-height.png"));
            let file = std::fs::File::create(&path).map_err(|e| io(&path, e))?;
            let (width, height) = (field.width() as u32, field.height() as u32);
            let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
            encoder.set_color(png::ColorType::Grayscale);
            encoder.set_depth(png::BitDepth::Sixteen);
            let bytes: Vec<u8> = field
                .samples()
                .iter()
                .flat_map(|s| s.to_be_bytes())
                .collect();
            encoder
                .write_header()
                .and_then(|mut w| w.write_image_data(&bytes))
                .map_err(|e| format!("{}: {e}", path.display()))?;
            format!(
                "displacement]\nheight_map = \"{stem}-height.png\"\nheight_scale = {}\ntiling = {}\nmidlevel = {}\n{}",
                scene.height_scale,
                scene.tiling,
                scene.midlevel,
                if field.wrap() == Wrap::Clamp {
                    "wrap = \"clamp\"\n"
                } else {
                    ""
                }
            )
        }
        Content::Shell(object) => {
            let path = dir.join(format!("{stem}-object.obj"));
            let mut text = String::from("# (u, v, h) in the unit tile, exported by nlrt\n");
            for t in object {
                for p in t {
                    let _ = writeln!(text, "v {:.9} {:.9} {:.9}", p.x, p.y, p.z);
                }
            }
            for k in 0..object.len() {
                let _ = writeln!(text, "f {} {} {}", 3 * k + 1, 3 * k + 2, 3 * k + 3);
            }
            std::fs::write(&path, text).map_err(|e| io(&path, e))?;
            format!(
                "shell]\nobject = \"{stem}-object.obj\"\nheight_scale = {}\ntiling = {}\n",
                scene.height_scale, scene.tiling
            )
        }
    };
    let material = match scene.material {
        Material::Diffuse => "",
        Material::Glossy { .. } => "material = \"glossy\"\n",
    };
    Ok((format!("obj = \"{stem}.obj\"\n{material}"), content))
}
