//! Shell mapping: TLAS + implicit quadtree over tiles + the object's BVH returns the first hit
//! that testing every object triangle in every tile of every base triangle returns.

use nlrt_accel::{BaseMesh, ShellObject, ShellSurface, TraversalStats};
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;
use nlrt_tests::geometry::{
    SplitMix64, assert_occlusion_agrees, grid_mesh, random_object, ray_from_above,
};

fn ray_count() -> usize {
    if std::env::var_os("NLRT_EXTENSIVE").is_some() {
        6000
    } else {
        300
    }
}

/// The base meshes: [`grid_mesh`] bent (every prism curved), flat (every prism affine,
/// walked straight), or flat with its last column of vertices' directions tilted (affine
/// prisms beside curved ones: straight and curved walks meet at open edges).
#[derive(Clone, Copy, PartialEq)]
enum Base {
    Bent,
    Flat,
    FlatBesideCurved,
}

fn base_mesh<T: Real>(base: Base, n: usize, degenerate: bool) -> BaseMesh<T> {
    match base {
        Base::Bent => grid_mesh::<T>(n, 0.15, degenerate),
        Base::Flat => grid_mesh::<T>(n, 0.0, degenerate),
        Base::FlatBesideCurved => {
            let flat = grid_mesh::<T>(n, 0.0, degenerate);
            let tilted = T::Vec3::new(T::from_f64(0.3), T::from_f64(0.1), T::ONE);
            let normals = flat
                .positions()
                .iter()
                .zip(flat.normals())
                .map(|(p, &n)| if p.x() == T::ONE { tilted } else { n })
                .collect();
            BaseMesh::new(
                flat.positions().to_vec(),
                normals,
                flat.uvs().to_vec(),
                (0..flat.triangle_count())
                    .map(|i| flat.triangle(i))
                    .collect(),
            )
            .unwrap()
        }
    }
}

fn compare<T: Real>(
    tiling: f64,
    (base, mesh_n): (Base, usize),
    degenerate: bool,
    object_size: usize,
    min_elevation: f64,
) {
    let seed = (tiling * 100.0) as u64 + mesh_n as u64;
    let object = ShellObject::<T>::new(random_object::<T>(object_size, seed)).unwrap();
    let surface = ShellSurface::new(
        base_mesh::<T>(base, mesh_n, degenerate),
        object,
        T::from_f64(0.1),
        T::from_f64(tiling),
    )
    .unwrap();
    let all = surface.mesh().triangle_count();
    match base {
        Base::Bent => assert_eq!(surface.straight_triangles(), 0),
        Base::Flat => assert_eq!(surface.straight_triangles(), all),
        Base::FlatBesideCurved => {
            let straight = surface.straight_triangles();
            assert!(straight > 0 && straight < all, "{straight} of {all}");
        }
    }
    let mut rng = SplitMix64::new(seed ^ 0xabc);
    // Same bound as the displacement test: ties between triangles sharing a point.
    let t_bound = T::from_f64(3.0) * T::EPSILON.sqrt();
    let (mut hits, mut mismatches, mut tests) = (0, 0, 0u64);
    for _ in 0..ray_count() {
        let (o, d) = ray_from_above(&mut rng, min_elevation);
        let v = |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let ray = Ray::new(v(o), v(d)).unwrap();
        let mut stats = TraversalStats::default();
        let fast = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        tests += u64::from(stats.texel_tests);
        // A straight-walked prism answers on its line, hit or miss: no prism of a flat base
        // is traced on the curved path (which an f32 surface runs in f64 arithmetic).
        if base == Base::Flat {
            assert_eq!(stats.f64_prisms, 0, "{o:?} {d:?}");
        }
        let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
        // The occlusion query: blocked where a hit exists, open before the nearest one.
        let blocked =
            |t_max| surface.occluded(&ray, T::ZERO, t_max, &mut TraversalStats::default());
        assert_occlusion_agrees(blocked, fast.map(|h| h.hit.t), &(o, d));
        let agree = match (fast, brute) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                hits += 1;
                a == b || (a.hit.t - b.hit.t).abs() <= t_bound
            }
            _ => false,
        };
        if !agree {
            mismatches += 1;
            eprintln!(
                "{}: mismatch {fast:?} vs {brute:?} for {o:?} {d:?}",
                T::NAME
            );
        }
    }
    eprintln!(
        "{} tiling {tiling} mesh {mesh_n} object {object_size}: {hits} hits of {} rays, {mismatches} mismatches, {tests} triangle tests",
        T::NAME,
        ray_count()
    );
    assert!(hits > ray_count() / 10, "the rays should often hit");
    assert_eq!(mismatches, 0);
}

macro_rules! shell_tests {
    ($($t:ident),*) => {$(
        mod $t {
            use super::*;

            #[test]
            fn tiled_4() {
                compare::<$t>(4.0, (Base::Bent, 2), false, 40, 0.3);
            }

            #[test]
            fn tiled_16_grazing() {
                compare::<$t>(16.0, (Base::Bent, 2), false, 12, 0.05);
            }

            #[test]
            fn uv_degenerate_base_triangles() {
                compare::<$t>(3.0, (Base::Bent, 3), true, 30, 0.3);
            }

            #[test]
            fn straight_tiled_4() {
                compare::<$t>(4.0, (Base::Flat, 2), false, 40, 0.3);
            }

            #[test]
            fn straight_tiled_16_grazing() {
                compare::<$t>(16.0, (Base::Flat, 2), false, 12, 0.05);
            }

            #[test]
            fn straight_beside_curved() {
                compare::<$t>(4.0, (Base::FlatBesideCurved, 4), false, 40, 0.3);
                compare::<$t>(16.0, (Base::FlatBesideCurved, 4), false, 30, 0.05);
            }
        }
    )*};
}

shell_tests!(f32, f64);
