//! Built-in scene variants made for one measurement (tagged `Tag::Variant` in the registry):
//! the ghost-hit and coarse tori, `fig9-displaced`, the uv-seam scenes and `dem-crop`.

use super::maps::*;
use super::paper::*;
use super::scene::*;
use crate::scene::material::Material;
use crate::scene::motion::{Deformation, Motion};
use nlrt_accel::{HeightField, SeamRule, Wrap};
use nlrt_poly::glam::{DVec2, DVec3};
use std::f64::consts::TAU;

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
pub(super) fn torus_variant(
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

/// A `side x side` map `noise` faded to exactly zero on its border: each sample times
/// `shape` of the window `sin(pi u) sin(pi v)` (clamped at 0), so that a clamped map leaves no
/// way under the surface through a mesh border on the uv square's edges.
fn faded_to_zero_border(noise: &[f32], side: usize, shape: impl Fn(f64) -> f64) -> Vec<f32> {
    let last = (side - 1) as f64;
    noise
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
                (f64::from(h) * shape(window)).max(0.0) as f32
            }
        })
        .collect()
}

/// Fig. 9's seven columns (regular; uv-degenerate to a line and to a point; prisms pinching
/// to a line and to a point; a triangle degenerate in world and uv; in world only) displaced by
/// an fBm map instead of shell-mapped by an object, for the watertightness measurement: the
/// map is clamped and fades to exactly zero on its border (a `sin(pi u) sin(pi v)` window), so
/// a ray can get under the surface of the pinched columns only through it.
#[must_use]
pub fn fig9_displaced(side: usize) -> Scene {
    let heights = faded_to_zero_border(&fbm_map(side, 4, 6, 23), side, |w| w);
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

/// A plateau meeting curved flanks, for the watertightness of straight and curved walks side
/// by side: a 32 x 32 quad grid over `[-1, 1]^2`, flat (`y = 0`, directions straight up) where
/// `|x|, |z| <= 1/2` and bending down beyond as `y = -(max(|x| - 1/2, 0)^2 + max(|z| - 1/2,
/// 0)^2)`, each vertex displaced along the surface's normal there. The plateau's 512 triangles
/// share one affine map and are walked along straight lines; the ring of triangles beyond its
/// rim (one vertex still straight up, the other tilted) and the flanks take the curved walk;
/// the two meet along the rim, where the fBm map is far from zero. The map is clamped and
/// fades to exactly zero on its border (as in [`fig9_displaced`]), so every ray that reaches
/// the base is judged. Positions on the grid are exact binary fractions.
#[must_use]
pub fn plateau(side: usize) -> Scene {
    const QUADS: usize = 32;
    let bend = |c: f64| (c.abs() - 0.5).max(0.0);
    let at = |u: f64, v: f64| {
        let (x, z) = (2.0 * u - 1.0, 2.0 * v - 1.0);
        let (bx, bz) = (bend(x), bend(z));
        let y = if bx == 0.0 && bz == 0.0 {
            0.0
        } else {
            -(bx * bx + bz * bz)
        };
        // The normal of `y = f(x, z)`: `(-df/dx, 1, -df/dz)`, straight up on the plateau and
        // its rim (where the derivatives are 0).
        let normal = if bx == 0.0 && bz == 0.0 {
            DVec3::Y
        } else {
            DVec3::new(2.0 * bx * x.signum(), 1.0, 2.0 * bz * z.signum()).normalize()
        };
        (DVec3::new(x, y, z), normal)
    };
    let (mut positions, mut normals, mut uvs, mut triangles) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for j in 0..=QUADS {
        for i in 0..=QUADS {
            let uv = DVec2::new(i as f64, j as f64) / QUADS as f64;
            let (p, n) = at(uv.x, uv.y);
            positions.push(p);
            normals.push(n);
            uvs.push(uv);
        }
    }
    let idx = |i: usize, j: usize| (j * (QUADS + 1) + i) as u32;
    for j in 0..QUADS {
        for i in 0..QUADS {
            // Wound as the mountain's quad: counter-clockwise seen from above.
            triangles.push([idx(i, j), idx(i + 1, j + 1), idx(i + 1, j)]);
            triangles.push([idx(i, j), idx(i, j + 1), idx(i + 1, j + 1)]);
        }
    }
    // The square root of the window: heights stay large up to near the border.
    let heights = faded_to_zero_border(&fbm_map(side, 4, 6, 29), side, f64::sqrt);
    Scene {
        name: "plateau",
        positions,
        normals,
        uvs,
        triangles,
        content: Content::Displacement(
            HeightField::from_unit_heights(side, side, &heights, Wrap::Clamp)
                .expect("power-of-two side"),
        ),
        height_scale: 0.15,
        tiling: 1.0,
        // Over a corner of the plateau, looking along its rim and down a flank.
        camera: Camera {
            eye: DVec3::new(1.3, 1.1, 1.5),
            target: DVec3::new(0.25, -0.1, 0.3),
            fov_degrees: 50.0,
        },
        sun: DVec3::new(0.5, 0.8, 0.3).normalize(),
        material: Material::Diffuse,
        motion: Motion::deform(Deformation::Wave),
        seam_rule: SeamRule::Closed,
        others: Vec::new(),
        midlevel: 0.0,
    }
}

/// A floor of shell-mapped tiles, the flat-based shell scene: the mountain's quad (2 base
/// triangles, one affine patch) holding the Cornell-box object of [`cornell`] tiled 16 x 16,
/// seen from the mountain's camera. Every ray is walked along its straight line through the
/// tiles (the shells' straight walk), where `cornell`'s sphere takes the curved walk.
#[must_use]
pub fn cornell_floor(n: usize) -> Scene {
    let mut scene = mountain(64);
    scene.name = "cornell-floor";
    scene.content = Content::Shell(cornell_object(n));
    scene.height_scale = 0.1;
    scene.tiling = 16.0;
    scene.motion = Motion::deform(Deformation::Squash);
    scene
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
        others: Vec::new(),
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
        others: Vec::new(),
        midlevel: 0.0,
    }
}
