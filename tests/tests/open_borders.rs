//! Open sheets seen from below their borders: a ray that comes in under the edge of a
//! displaced sheet over an open mesh border (through the prism's side wall, below the sheet)
//! and goes down through the base has met no surface, even where a texel's corner lies on the
//! base. Over a flat base the straight walk is exact about the ray's line (a watertight
//! ray-triangle test per microtriangle), so the curved walk (the straight walk turned off) must
//! agree with it: the same rays hit, at the same distances. Rays from outside every border,
//! from grazing to steep, some above the sheet; maps with plateaus at zero, spikes and noise;
//! f32 and f64.

use nlrt_accel::{DisplacedSurface, TraversalStats, Wrap};
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;
use nlrt_tests::geometry::{MapKind, SplitMix64, grid_mesh, height_map};

/// The height scale of the sheets.
const HEIGHT_SCALE: f64 = 0.2;

/// Rays per configuration; `NLRT_EXTENSIVE=1` multiplies by 20.
fn ray_count() -> usize {
    if std::env::var_os("NLRT_EXTENSIVE").is_some() {
        40_000
    } else {
        2_000
    }
}

/// Rays from outside a border of the unit square (any of the four), descending towards a
/// point of the base within a quarter of the square of that border, entering at heights from
/// the base to twice the sheet's top: how many the curved walk answers otherwise than the
/// straight walk (a hit against a miss, or distances apart by more than 1e-4 relative), and
/// how many hit.
fn disagreements<T: Real>(surface: &DisplacedSurface<T>, seed: u64) -> (usize, usize) {
    let mut rng = SplitMix64::new(seed);
    let mut curved = surface.clone();
    curved.set_straight_walk(false);
    let (mut differ, mut hits) = (0, 0);
    for _ in 0..ray_count() {
        let side = (rng.next_u64() % 4) as usize;
        let (along, depth) = (rng.unit(), 0.25 * rng.unit());
        let (target, outward) = match side {
            0 => ([depth, along], [-1.0, 0.0]),
            1 => ([1.0 - depth, along], [1.0, 0.0]),
            2 => ([along, depth], [0.0, -1.0]),
            _ => ([along, 1.0 - depth], [0.0, 1.0]),
        };
        let elevation = 0.02 + 0.58 * rng.unit();
        let sideways = (rng.unit() - 0.5) * 0.8;
        let horizontal = [
            outward[0] - sideways * outward[1],
            outward[1] + sideways * outward[0],
        ];
        let run = depth + 0.05 + 0.5 * rng.unit();
        let origin = [
            target[0] + horizontal[0] * run,
            target[1] + horizontal[1] * run,
            run * elevation.tan(),
        ];
        let v = |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let dir = [target[0] - origin[0], target[1] - origin[1], -origin[2]];
        let Some(ray) = Ray::new(v(origin), v(dir)) else {
            continue;
        };
        let mut stats = TraversalStats::default();
        let a = curved.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        let b = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        hits += usize::from(b.is_some());
        let agree = match (a, b) {
            (None, None) => true,
            (Some(a), Some(b)) => {
                let (ta, tb) = (a.hit.t.to_f64(), b.hit.t.to_f64());
                (ta - tb).abs() <= 1e-4 * tb.abs().max(1e-3)
            }
            _ => false,
        };
        differ += usize::from(!agree);
    }
    (differ, hits)
}

fn open_sheets<T: Real>() {
    let mut failures = Vec::new();
    let mut all_hits = 0;
    let cases = [
        (8, MapKind::Plateaus, Wrap::Clamp, 1.0),
        (16, MapKind::Plateaus, Wrap::Repeat, 2.0),
        (8, MapKind::Spikes, Wrap::Clamp, 1.0),
        (16, MapKind::Random, Wrap::Clamp, 1.0),
        (16, MapKind::Random, Wrap::Repeat, 3.0),
    ];
    for (k, (side, kind, wrap, tiling)) in cases.into_iter().enumerate() {
        let surface = DisplacedSurface::new(
            grid_mesh::<T>(3, 0.0, false),
            height_map(side, kind, wrap, 7 + k as u64),
            T::from_f64(HEIGHT_SCALE),
            T::from_f64(tiling),
        )
        .unwrap();
        assert_eq!(
            surface.straight_triangles(),
            18,
            "the flat square walks straight"
        );
        let (differ, hits) = disagreements(&surface, k as u64);
        all_hits += hits;
        if differ > 0 {
            failures.push(format!(
                "{side}^2 {kind:?} {wrap:?} tiling {tiling}: {differ} of {} rays ({hits} hits)",
                ray_count()
            ));
        }
    }
    // Some rays pass above the sheet and hit it: the comparison sees hits, not only misses.
    assert!(all_hits * 10 > ray_count(), "{all_hits} hits");
    assert!(
        failures.is_empty(),
        "the curved walk differs from the straight walk:\n{}",
        failures.join("\n")
    );
}

#[test]
fn rays_under_an_open_border_agree_with_the_straight_walk_in_f32() {
    open_sheets::<f32>();
}

#[test]
fn rays_under_an_open_border_agree_with_the_straight_walk_in_f64() {
    open_sheets::<f64>();
}
