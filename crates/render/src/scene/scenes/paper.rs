//! The paper's scenes (Table 2 analogues, Fig. 8 and 9; `fur-cones`, on whose torus the fur is
//! built) and the base meshes they are built on.

use super::maps::*;
use super::scene::*;
use crate::scene::material::Material;
use crate::scene::motion::{Deformation, Motion};
use nlrt_accel::SeamRule;
use nlrt_poly::glam::{DVec2, DVec3};
use std::f64::consts::TAU;

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
        others: Vec::new(),
        midlevel: 0.0,
    }
}

/// A grid surface `(i, j) -> (position, normal, uv)` over `n_u x n_v` quads.
pub(super) fn grid(
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
        others: Vec::new(),
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

/// A torus of `n x n` quads: positions, unit normals, uvs, triangles.
pub(super) fn torus(
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
pub(super) fn patch(n: usize, f: impl Fn(f64, f64) -> DVec3) -> Vec<[DVec3; 3]> {
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
pub(super) fn shell_torus(
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
        others: Vec::new(),
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
        others: Vec::new(),
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
        others: Vec::new(),
        midlevel: 0.0,
    }
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
        others: Vec::new(),
        midlevel: 0.0,
    }
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
        others: Vec::new(),
        midlevel: 0.0,
    }
}
