//! Rays that leave a surface where a primary ray hit it (shadow and bounce rays), started at
//! the hit point with no offset and their origin's element excluded by its id
//! (`intersect_leaving`, `occluded_leaving`).
//!
//! - On a height field over a flat base, a ray leaving the surface steeper than its steepest
//!   microtriangle stays above it: it must miss, whatever the rounding of its origin. Without
//!   the exclusion most such rays hit their own microtriangle at once (counted, asserted).
//! - The accelerated leaving query equals the one testing every element, and the occlusion
//!   query agrees with it, on curved and straight walks, displaced and shell-mapped.

use nlrt_accel::{
    BaseMesh, DisplacedSurface, HeightField, ShellObject, ShellSurface, TraversalStats, Wrap,
};
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::Ray;
use nlrt_tests::geometry::{
    MapKind, SplitMix64, assert_occlusion_agrees, grid_mesh, height_map, random_object,
    ray_from_above,
};

/// Primary rays per configuration (each sends several leaving rays); `NLRT_EXTENSIVE=1`
/// multiplies by 20.
fn ray_count() -> usize {
    if std::env::var_os("NLRT_EXTENSIVE").is_some() {
        6000
    } else {
        300
    }
}

/// Leaving rays per primary hit.
const LEAVING_PER_HIT: usize = 4;

/// The height scale of every surface here.
const HEIGHT_SCALE: f64 = 0.1;

/// The steepest slope (rise over horizontal run) of the microtriangles of `field` on the flat
/// unit square with uvs `(x, y)` tiled `tiling` times and heights scaled by `HEIGHT_SCALE`:
/// the lower microtriangle of texel `(x, y)` rises `h10 - h00` along u and `h11 - h10` along
/// v per texel, the upper one `h11 - h01` and `h01 - h00`.
fn steepest_slope(field: &HeightField, tiling: f64) -> f64 {
    let side = field.width() as i64;
    let texel = 1.0 / (side as f64 * tiling);
    let h = |i: i64, j: i64| f64::from(field.sample(i, j)) / 65535.0;
    let mut steepest: f64 = 0.0;
    for y in 0..side {
        for x in 0..side {
            let (h00, h10, h01, h11) = (h(x, y), h(x + 1, y), h(x, y + 1), h(x + 1, y + 1));
            for (du, dv) in [(h10 - h00, h11 - h10), (h11 - h01, h01 - h00)] {
                steepest = steepest.max(du.hypot(dv));
            }
        }
    }
    steepest * HEIGHT_SCALE / texel
}

/// A direction at elevation `elevation` above the xy plane and azimuth `azimuth`.
fn direction(elevation: f64, azimuth: f64) -> [f64; 3] {
    [
        elevation.cos() * azimuth.cos(),
        elevation.cos() * azimuth.sin(),
        elevation.sin(),
    ]
}

fn vec3<T: Real>(a: [f64; 3]) -> T::Vec3 {
    T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]))
}

#[derive(Default, Debug)]
struct Tally {
    leaving: usize,
    /// Leaving rays that hit (must be none over a flat base).
    hits: usize,
    mismatches: usize,
    /// Leaving rays whose nearest hit beyond a thousandth of a texel differs from the plain
    /// query's there (other than on the origin's own element).
    dropped: usize,
    /// Leaving rays that the plain query, from the same origin, sees hit something.
    hits_without_exclusion: usize,
    /// Leaving rays whose walk met a decision `f32` cannot make (not compared with testing
    /// every texel).
    undecided: usize,
}

/// Rays leaving a displaced surface over the unit square (flat, or bent when `bend` is not
/// 0); over the flat one they leave steeper than the steepest microtriangle.
fn displaced<T: Real>(
    kind: MapKind,
    side: usize,
    tiling: f64,
    bend: f64,
    straight: bool,
    on_edges: bool,
) -> Tally {
    let seed = side as u64 * 7 + tiling as u64;
    let field = height_map(side, kind, Wrap::Repeat, seed);
    let steepest = steepest_slope(&field, tiling);
    let mesh = grid_mesh::<T>(2, bend, false);
    let mut surface =
        DisplacedSurface::new(mesh, field, T::from_f64(HEIGHT_SCALE), T::from_f64(tiling)).unwrap();
    // Primary hits from the straight walk wherever it applies (the flat base): the curved
    // walk reports a point of the floor for a ray that passes under the sheet's open border
    // (`docs/testing.md`), and no leaving ray from there can be held to the must-miss rule.
    let primary = surface.clone();
    surface.set_straight_walk(straight);
    let flat = bend == 0.0;
    assert_eq!(
        surface.straight_triangles() > 0,
        flat,
        "a flat base is walked straight"
    );
    let mut rng = SplitMix64::new(seed ^ 0x1eaf);
    let mut tally = Tally::default();
    let t_bound = T::from_f64(3.0) * T::EPSILON.sqrt();
    let near = T::from_f64(1e-3 / (side as f64 * tiling));
    for k in 0..ray_count() {
        let (o, d) = if on_edges && k % 2 == 0 {
            // Straight down onto a texel corner, a texel edge or a diagonal, where the hit
            // point lies on several microtriangles.
            let cells = side as f64 * tiling;
            let (i, j) = ((rng.unit() * cells) as u32, (rng.unit() * cells) as u32);
            let (fx, fy) = match k / 2 % 4 {
                0 => (0.0, 0.0),
                1 => (0.0, rng.unit()),
                2 => (rng.unit(), 0.0),
                _ => {
                    let f = rng.unit();
                    (f, f)
                }
            };
            let at = |c: u32, f: f64| T::from_f64((f64::from(c) + f) / cells).to_f64();
            ([at(i, fx), at(j, fy), 1.0], [0.0, 0.0, -1.0])
        } else {
            ray_from_above(&mut rng, 0.2)
        };
        let ray = Ray::new(vec3::<T>(o), vec3::<T>(d)).unwrap();
        let mut stats = TraversalStats::default();
        let Some(hit) = primary.intersect(&ray, T::ZERO, T::INFINITY, &mut stats) else {
            continue;
        };
        let origin = ray.at(hit.hit.t);
        let normal = surface.normal(&hit, ray.dir).unwrap();
        for _ in 0..LEAVING_PER_HIT {
            let azimuth = 2.0 * std::f64::consts::PI * rng.unit();
            let dir = if flat {
                // Steeper than every microtriangle, down to a hundredth of a radian above
                // the steepest (grazing it where the origin lies on it).
                let lowest = steepest.atan() + 0.01;
                let elevation = lowest + (std::f64::consts::FRAC_PI_2 - lowest) * rng.unit();
                vec3::<T>(direction(elevation, azimuth))
            } else {
                // Anywhere in the hemisphere the normal faces, down to grazing.
                let d = vec3::<T>(direction(
                    (2.0 * rng.unit() - 1.0) * std::f64::consts::FRAC_PI_2,
                    azimuth,
                ));
                if d.dot(normal) < T::ZERO { -d } else { d }
            };
            let Some(leave) = Ray::new(origin, dir) else {
                continue;
            };
            tally.leaving += 1;
            let mut stats = TraversalStats::default();
            let fast = surface.intersect_leaving(&leave, &hit, T::INFINITY, &mut stats);
            let brute = surface.intersect_leaving_brute_force(&leave, &hit, T::INFINITY);
            let blocked = |t_max| {
                surface.occluded_leaving(&leave, &hit, t_max, &mut TraversalStats::default())
            };
            assert_occlusion_agrees(blocked, fast.map(|h| h.hit.t), &(origin, dir));
            if surface
                .intersect(&leave, T::ZERO, T::INFINITY, &mut TraversalStats::default())
                .is_some()
            {
                tally.hits_without_exclusion += 1;
            }
            // Beyond a thousandth of a texel the leaving query drops no hit but the origin's
            // own element's and a neighbour's touch at the origin (within the library's
            // `leaving_touch_distance`): the plain query from there on finds the same
            // nearest hit.
            if fast.is_none_or(|f| f.hit.t >= near) {
                let plain =
                    surface.intersect(&leave, near, T::INFINITY, &mut TraversalStats::default());
                let touch = surface.leaving_touch_distance(&hit, dir).unwrap_or(0.0);
                let own = plain.is_some_and(|p| {
                    (p.triangle == hit.triangle && p.texel == hit.texel && p.part == hit.part)
                        || p.hit.t.to_f64() <= touch
                });
                let same = match (fast, plain) {
                    (None, None) => true,
                    (Some(a), Some(b)) => a == b || (a.hit.t - b.hit.t).abs() <= t_bound,
                    _ => false,
                };
                if !same && !own {
                    tally.dropped += 1;
                    eprintln!(
                        "{}: leaving {fast:?}, plain beyond {near:?} {plain:?}, from {hit:?}: {origin:?} {dir:?}",
                        T::NAME
                    );
                }
            }
            if let Some(f) = fast {
                tally.hits += 1;
                assert!(
                    f.triangle != hit.triangle || f.texel != hit.texel || f.part != hit.part,
                    "{}: hit its own element {f:?} leaving {hit:?}",
                    T::NAME
                );
                if flat {
                    eprintln!(
                        "{}: hit {f:?} leaving {hit:?} steeper than every slope: {origin:?} {dir:?}",
                        T::NAME
                    );
                }
            }
            // A walk that met a decision `f32` cannot make traced that prism in `f64`, where
            // testing every texel stays in `f32`: counted, not compared.
            if stats.undecided_in_f32 > 0 {
                tally.undecided += 1;
                continue;
            }
            let agree = match (fast, brute) {
                (None, None) => true,
                (Some(a), Some(b)) => a == b || (a.hit.t - b.hit.t).abs() <= t_bound,
                _ => false,
            };
            if !agree {
                tally.mismatches += 1;
                eprintln!(
                    "{}: mismatch {fast:?} vs {brute:?} leaving {hit:?}: {origin:?} {dir:?}",
                    T::NAME
                );
            }
        }
    }
    eprintln!(
        "{} {kind:?} {side} x{tiling} bend {bend} straight {straight}: {tally:?}",
        T::NAME
    );
    assert!(
        tally.leaving > ray_count(),
        "most primary rays hit: {tally:?}"
    );
    assert_eq!(tally.mismatches, 0, "{tally:?}");
    assert_eq!(tally.dropped, 0, "{tally:?}");
    // Decisions `f32` cannot make are rare on random rays (at most 1%); rays through texel
    // edges and corners are where they lie (the f64 retrace decides them), and every such
    // ray's answer is still held to the must-miss rule above.
    if !on_edges {
        assert!(tally.undecided * 100 <= tally.leaving, "{tally:?}");
    }
    if flat {
        assert_eq!(tally.hits, 0, "{tally:?}");
    }
    tally
}

/// Rays leaving a shell-mapped object in every direction of the hemisphere its normal faces.
fn shell<T: Real>(bend: f64, tiling: f64, object_size: usize) {
    let seed = object_size as u64 + tiling as u64;
    let object = ShellObject::<T>::new(random_object::<T>(object_size, seed)).unwrap();
    let mesh: BaseMesh<T> = grid_mesh::<T>(2, bend, false);
    let surface =
        ShellSurface::new(mesh, object, T::from_f64(HEIGHT_SCALE), T::from_f64(tiling)).unwrap();
    let mut rng = SplitMix64::new(seed ^ 0x5e11);
    let t_bound = T::from_f64(3.0) * T::EPSILON.sqrt();
    let (mut leaving, mut hits, mut mismatches, mut back_blocked) = (0, 0, 0, 0);
    for _ in 0..ray_count() {
        let (o, d) = ray_from_above(&mut rng, 0.2);
        let ray = Ray::new(vec3::<T>(o), vec3::<T>(d)).unwrap();
        let mut stats = TraversalStats::default();
        let Some(hit) = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats) else {
            continue;
        };
        let origin = ray.at(hit.hit.t);
        // Back along the primary ray, open up to its origin (it found nothing nearer).
        let back = Ray::new(origin, -ray.dir).unwrap();
        let before_eye = hit.hit.t * T::from_f64(0.999);
        let blocked =
            surface.intersect_leaving(&back, &hit, before_eye, &mut TraversalStats::default());
        if blocked.is_some() {
            back_blocked += 1;
            eprintln!("{}: back from {hit:?} blocked by {blocked:?}", T::NAME);
        }
        let normal = surface.normal(&hit, ray.dir).unwrap();
        for _ in 0..LEAVING_PER_HIT {
            let azimuth = 2.0 * std::f64::consts::PI * rng.unit();
            let d = vec3::<T>(direction(
                (2.0 * rng.unit() - 1.0) * std::f64::consts::FRAC_PI_2,
                azimuth,
            ));
            let dir = if d.dot(normal) < T::ZERO { -d } else { d };
            let Some(leave) = Ray::new(origin, dir) else {
                continue;
            };
            leaving += 1;
            let fast = surface.intersect_leaving(
                &leave,
                &hit,
                T::INFINITY,
                &mut TraversalStats::default(),
            );
            let brute = surface.intersect_leaving_brute_force(&leave, &hit, T::INFINITY);
            let blocked = |t_max| {
                surface.occluded_leaving(&leave, &hit, t_max, &mut TraversalStats::default())
            };
            assert_occlusion_agrees(blocked, fast.map(|h| h.hit.t), &(origin, dir));
            if let Some(f) = fast {
                hits += 1;
                assert!(
                    f.triangle != hit.triangle
                        || f.tile != hit.tile
                        || f.object_triangle != hit.object_triangle,
                    "{}: hit its own triangle {f:?} leaving {hit:?}",
                    T::NAME
                );
            }
            let agree = match (fast, brute) {
                (None, None) => true,
                (Some(a), Some(b)) => a == b || (a.hit.t - b.hit.t).abs() <= t_bound,
                _ => false,
            };
            if !agree {
                mismatches += 1;
                eprintln!(
                    "{}: mismatch {fast:?} vs {brute:?} leaving {hit:?}: {origin:?} {dir:?}",
                    T::NAME
                );
            }
        }
    }
    eprintln!(
        "{} shell bend {bend} x{tiling} object {object_size}: {leaving} leaving rays, {hits} hits, {mismatches} mismatches, {back_blocked} blocked back along the primary ray",
        T::NAME
    );
    assert_eq!(back_blocked, 0);
    assert!(leaving > ray_count(), "most primary rays hit");
    assert!(hits > 0, "some leaving rays meet another triangle");
    assert_eq!(mismatches, 0);
}

/// The unit square of [`grid_mesh`] (flat, `n x n` quads) with a uv seam down its middle:
/// the right half's vertices are its own, their uvs shifted, so its texels are not the left
/// half's and the seam is closed by a wall where the two sides' heights differ.
fn seamed_mesh<T: Real>(n: usize) -> BaseMesh<T> {
    let flat = grid_mesh::<T>(n, 0.0, false);
    let (mut positions, mut normals, mut uvs) = (
        flat.positions().to_vec(),
        flat.normals().to_vec(),
        flat.uvs().to_vec(),
    );
    let half = T::from_f64(0.5);
    let shift = T::Vec2::new(T::from_f64(0.375), T::from_f64(0.25));
    let mut copies = std::collections::HashMap::new();
    let triangles = (0..flat.triangle_count())
        .map(|t| {
            let tri = flat.triangle(t);
            let right = tri.iter().all(|&i| positions[i as usize].x() >= half);
            tri.map(|i| {
                if !right {
                    return i;
                }
                *copies.entry(i).or_insert_with(|| {
                    let k = i as usize;
                    positions.push(positions[k]);
                    normals.push(normals[k]);
                    uvs.push(uvs[k] + shift);
                    (positions.len() - 1) as u32
                })
            })
        })
        .collect();
    BaseMesh::new(positions, normals, uvs, triangles).unwrap()
}

/// A ray leaving a hit back along the primary ray that found it is open up to the primary
/// ray's origin: that ray found nothing nearer. Whatever the origin's rounding, the element
/// it lies on and the neighbours it touches there are not hit.
fn back_along_the_primary<T: Real>(surface: &DisplacedSurface<T>, label: &str) {
    let mut rng = SplitMix64::new(0xbac4);
    let (mut hits, mut walls) = (0, 0);
    for k in 0..ray_count() {
        let (o, d) = if k % 2 == 0 {
            ray_from_above(&mut rng, 0.1)
        } else {
            // Low, across the middle of the square (the seamed mesh's seam, where its walls
            // stand), at a point within the shell's heights.
            let target = [0.5, rng.unit(), HEIGHT_SCALE * rng.unit()];
            let side = if rng.unit() < 0.5 { 1.0 } else { -1.0 };
            let d = direction(-(0.05 + 0.3 * rng.unit()), side * 0.3 * (rng.unit() - 0.5));
            let d = [side * d[0], d[1], d[2]];
            let o = core::array::from_fn(|i| target[i] - 2.0 * d[i]);
            (o, d)
        };
        let ray = Ray::new(vec3::<T>(o), vec3::<T>(d)).unwrap();
        let Some(hit) =
            surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default())
        else {
            continue;
        };
        hits += 1;
        walls += usize::from(matches!(hit.part, nlrt_accel::TexelPart::Wall { .. }));
        let back = Ray::new(ray.at(hit.hit.t), -ray.dir).unwrap();
        let before_eye = hit.hit.t * T::from_f64(0.999);
        let stats = &mut TraversalStats::default();
        let blocked = surface.intersect_leaving(&back, &hit, before_eye, stats);
        assert!(
            blocked.is_none(),
            "{} {label}: back along {o:?} {d:?} from {hit:?}: {blocked:?}",
            T::NAME
        );
        assert!(!surface.occluded_leaving(&back, &hit, before_eye, stats));
    }
    eprintln!("{} {label}: {hits} hits, {walls} on seam walls", T::NAME);
    assert!(hits > ray_count() / 2, "most rays hit");
}

macro_rules! leaving_tests {
    ($($t:ident),*) => {$(
        mod $t {
            use super::*;

            #[test]
            fn steeper_than_every_slope_misses_on_the_straight_walk() {
                for kind in [MapKind::Random, MapKind::Spikes, MapKind::Plateaus] {
                    let tally = displaced::<$t>(kind, 32, 1.0, 0.0, true, false);
                    // Without the exclusion, rays leave from a rounded origin into the
                    // microtriangle they lie on.
                    assert!(tally.hits_without_exclusion > 0, "{tally:?}");
                }
            }

            #[test]
            fn leaving_from_texel_edges_and_corners() {
                for straight in [true, false] {
                    for kind in [MapKind::Random, MapKind::Plateaus] {
                        let _ = displaced::<$t>(kind, 32, 1.0, 0.0, straight, true);
                    }
                }
            }

            #[test]
            fn steeper_than_every_slope_misses_on_the_curved_walk() {
                for kind in [MapKind::Random, MapKind::Spikes, MapKind::Plateaus] {
                    let _ = displaced::<$t>(kind, 32, 1.0, 0.0, false, false);
                }
            }

            #[test]
            fn leaving_a_bent_surface_equals_every_texel() {
                for kind in [MapKind::Random, MapKind::Spikes] {
                    let tally = displaced::<$t>(kind, 32, 2.0, 0.15, true, false);
                    assert!(tally.hits > 0, "some rays meet the surface again: {tally:?}");
                }
            }

            #[test]
            fn back_along_the_primary_ray_is_open() {
                let seed = 7;
                for kind in [MapKind::Random, MapKind::Spikes, MapKind::Plateaus] {
                    for (label, mesh, straight) in [
                        ("flat, straight walk", grid_mesh::<$t>(2, 0.0, false), true),
                        ("flat, curved walk", grid_mesh::<$t>(2, 0.0, false), false),
                        ("bent", grid_mesh::<$t>(2, 0.15, false), true),
                        ("seamed", seamed_mesh::<$t>(2), true),
                    ] {
                        let field = height_map(32, kind, Wrap::Repeat, seed);
                        let mut surface =
                            DisplacedSurface::new(mesh, field, HEIGHT_SCALE as $t, 1.0).unwrap();
                        surface.set_straight_walk(straight);
                        back_along_the_primary(&surface, &format!("{kind:?} {label}"));
                    }
                }
            }

            #[test]
            fn leaving_a_shell_equals_every_triangle() {
                shell::<$t>(0.15, 4.0, 40);
                shell::<$t>(0.0, 4.0, 40);
            }
        }
    )*};
}

leaving_tests!(f32, f64);
