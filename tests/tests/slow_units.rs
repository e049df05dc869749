//! The fuzzer's slow units (`fuzz/slow/<target>/`): inputs on which one ray once took seconds
//! to minutes. Nothing is timed; the nonlinear walk's node tests are counted against the bound
//! that makes its work linear in the nodes the ray's curve can reach: each node of the
//! triangle's texel range is visited at most once per stretch of the ray inside the prism (at
//! most 4, `BaseEdges::stretches`), and each visit tests at most its 4 children.

use nlrt_accel::TraversalStats;
use nlrt_tests::fuzz_input::displacement_case;
use std::path::PathBuf;

/// Nodes of the quadtree over a texel range `[x0, y0, x1, y1]` (inclusive), from the texels
/// up to the roots' level.
fn nodes_in_range(roots: nlrt_accel::RootNodes) -> u64 {
    let [x0, y0, x1, y1] = roots.texels.map(i64::from);
    (0..=roots.level)
        .map(|level| {
            let span = |a: i64, b: i64| ((b >> level) - (a >> level) + 1) as u64;
            span(x0, x1) * span(y0, y1)
        })
        .sum()
}

/// Runs the walk on every unit of `fuzz/slow/<dir>/`, decoded as the fuzz target of that
/// directory decodes it, and checks its node tests against the bound.
fn walk_is_bounded<T: nlrt_poly::Real>(dir: &str) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/slow")
        .join(dir);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("the slow units are committed") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable unit");
        let (surface, ray) = displacement_case::<T>(&data).expect("a slow unit sets up");
        let mut stats = TraversalStats::default();
        let _ = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
        let bound: u64 = (0..surface.mesh().triangle_count())
            .map(|tri| 4 * 4 * nodes_in_range(surface.roots(tri)))
            .sum();
        assert!(
            stats.box_tests as u64 <= bound && stats.fallbacks == 0,
            "{}: {stats:?}, bound {bound} node tests",
            path.display()
        );
        count += 1;
    }
    assert!(count > 0);
}

#[test]
fn slow_units_walk_a_bounded_number_of_nodes() {
    walk_is_bounded::<f64>("displacement_f64");
}

/// The f32 target's units: `affine-box-walk` is slow for the affine baseline only (the walk
/// rejects its ray at once); `long-column-miss` walks 39M nodes and tests 29M texels of a
/// 385 x 151,891 texel range (about 10 s in release).
#[test]
fn slow_units_walk_a_bounded_number_of_nodes_f32() {
    walk_is_bounded::<f32>("displacement_f32");
}
