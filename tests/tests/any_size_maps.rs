//! Height maps of any width x height are traced as they are: over the texels a map covers, a
//! surface on a `W x H` map hits exactly where the same surface hits on the map padded by hand
//! to the square power of two `P` (every padded sample read by the map's own wrap rule, the
//! mesh's uvs scaled by `W / P` and `H / P` so each texel stays where it was), bit for bit, on
//! curved prisms and on affine ones (the straight walk), in `f32` and `f64`; and both equal
//! testing every texel, as does the map tiled 2.5 times (repeated: the walk's nodes then
//! straddle the tile's edges). Sizes are picked at random (proptest), most of them neither square nor a
//! power of two.

use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::Ray;
use nlrt_tests::geometry::{SplitMix64, grid_mesh, ray_from_above};
use proptest::prelude::*;

/// Rays per case; `NLRT_EXTENSIVE=1` multiplies by 10.
fn ray_count() -> usize {
    if std::env::var_os("NLRT_EXTENSIVE").is_some() {
        1500
    } else {
        150
    }
}

/// A `width x height` map of random samples, and the same map padded to `P x P` (`P` the
/// map's grid side), each padded sample read from the map by its wrap rule.
fn map_and_padded(
    width: usize,
    height: usize,
    wrap: Wrap,
    seed: u64,
) -> (HeightField, HeightField) {
    let mut rng = SplitMix64::new(seed);
    let samples = (0..width * height)
        .map(|_| (rng.next_u64() >> 48) as u16)
        .collect();
    let map = HeightField::new(width, height, samples, wrap).expect("a valid size");
    let p = map.grid_side();
    let padded: Vec<u16> = (0..p * p)
        .map(|k| map.sample((k % p) as i64, (k / p) as i64))
        .collect();
    (
        map,
        HeightField::new(p, p, padded, wrap).expect("a power of two"),
    )
}

/// `mesh` with its uvs scaled per axis by `scale` (in `T`, as the surface scales them).
fn scaled_uvs<T: Real>(mesh: &BaseMesh<T>, scale: [f64; 2]) -> BaseMesh<T> {
    let s = scale.map(T::from_f64);
    let uvs = mesh
        .uvs()
        .iter()
        .map(|uv| T::Vec2::new(uv.x() * s[0], uv.y() * s[1]))
        .collect();
    let triangles = (0..mesh.triangle_count())
        .map(|i| mesh.triangle(i))
        .collect();
    BaseMesh::new(
        mesh.positions().to_vec(),
        mesh.normals().to_vec(),
        uvs,
        triangles,
    )
    .expect("the same mesh")
}

/// Hits that differ between the map and its padded copy, and between the map's walk and
/// testing every texel (beyond ties at shared edges), and the hits seen.
fn compare<T: Real>(
    width: usize,
    height: usize,
    wrap: Wrap,
    bend: f64,
    seed: u64,
) -> (usize, usize, usize) {
    let (map, padded) = map_and_padded(width, height, wrap, seed);
    let mesh = grid_mesh::<T>(3, bend, false);
    let padded_mesh = scaled_uvs(&mesh, map.grid_scale());
    let scale = T::from_f64(0.1);
    let tiled = (wrap == Wrap::Repeat).then(|| {
        DisplacedSurface::new(mesh.clone(), map.clone(), scale, T::from_f64(2.5))
            .expect("a valid surface")
    });
    let on_map = DisplacedSurface::new(mesh, map, scale, T::ONE).expect("a valid surface");
    let on_padded =
        DisplacedSurface::new(padded_mesh, padded, scale, T::ONE).expect("a valid surface");
    let t_bound = T::from_f64(3.0) * T::EPSILON.sqrt();
    let mut rng = SplitMix64::new(seed ^ 0x5eed);
    let (mut differ, mut brute_differ, mut hits) = (0, 0, 0);
    for _ in 0..ray_count() {
        let (o, d) = ray_from_above(&mut rng, 0.25);
        let v = |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let ray = Ray::new(v(o), v(d)).expect("a unit direction");
        let mut stats = TraversalStats::default();
        let a = on_map.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        let b = on_padded.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        if a != b {
            differ += 1;
            eprintln!("{width} x {height} {wrap:?} bend {bend}: {a:?} vs padded {b:?}");
        }
        let agree = |s: &DisplacedSurface<T>, walk: Option<nlrt_accel::SurfaceHit<T>>| match (
            walk,
            s.intersect_brute_force(&ray, T::ZERO, T::INFINITY),
        ) {
            (None, None) => true,
            (Some(x), Some(y)) => x.hit.t == y.hit.t || (x.hit.t - y.hit.t).abs() <= t_bound,
            _ => false,
        };
        brute_differ += usize::from(!agree(&on_map, a));
        if let Some(tiled) = &tiled {
            let walk = tiled.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            if !agree(tiled, walk) {
                brute_differ += 1;
                eprintln!(
                    "{width} x {height} tiled, bend {bend}: the walk differs from every texel"
                );
            }
        }
        hits += usize::from(a.is_some());
    }
    (differ, brute_differ, hits)
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: if std::env::var_os("NLRT_EXTENSIVE").is_some() {
            256
        } else {
            12
        },
        ..ProptestConfig::default()
    }
}

macro_rules! any_size_tests {
    ($($t:ident),*) => {$(
        mod $t {
            use super::*;

            proptest! {
                #![proptest_config(config())]

                /// A random size from 2 x 2 to 90 x 90, both wraps, curved (bent grid) and
                /// affine (flat grid, walked straight) prisms.
                #[test]
                fn any_size_equals_its_padded_copy(
                    width in 2usize..=90,
                    height in 2usize..=90,
                    clamp in any::<bool>(),
                    flat in any::<bool>(),
                    seed in any::<u64>(),
                ) {
                    let wrap = if clamp { Wrap::Clamp } else { Wrap::Repeat };
                    let bend = if flat { 0.0 } else { 0.15 };
                    let (differ, brute_differ, hits) = compare::<$t>(width, height, wrap, bend, seed);
                    prop_assert_eq!(differ, 0);
                    prop_assert_eq!(brute_differ, 0);
                    prop_assert!(hits > ray_count() / 4, "{} hits", hits);
                }
            }

            /// Sizes at the edges of the pyramid's rounding: one more and one less than a power
            /// of two, a single texel row, prime sides.
            #[test]
            fn sizes_beside_powers_of_two() {
                for (w, h) in [(2, 2), (3, 2), (2, 65), (33, 31), (64, 63), (65, 17), (97, 89)] {
                    for wrap in [Wrap::Repeat, Wrap::Clamp] {
                        for bend in [0.0, 0.15] {
                            let (differ, brute_differ, hits) = compare::<$t>(w, h, wrap, bend, (w * 131 + h) as u64);
                            assert_eq!((differ, brute_differ), (0, 0), "{w} x {h} {wrap:?} bend {bend}");
                            assert!(hits > ray_count() / 4, "{w} x {h}: {hits} hits");
                        }
                    }
                }
            }
        }
    )*};
}

any_size_tests!(f32, f64);
