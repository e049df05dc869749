//! The fuzzer's slow units (`fuzz/slow/<target>/`): inputs on which one ray once took seconds
//! to minutes. Nothing is timed; the nonlinear walk's node tests are counted against the bound
//! that makes its work linear in the nodes the ray's curve can reach: each node of the
//! triangle's texel range is visited at most once per stretch of the ray inside the prism (at
//! most 4, `BaseEdges::stretches`), and each visit tests at most its 4 children.

use nlrt_accel::TraversalStats;
use nlrt_tests::fuzz_input::{displacement_case, shell_case};
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

/// What a unit's set-up and walk came to: the walk's counters and their bound, or the
/// set-up's error.
type Walked = Result<(TraversalStats, u64), String>;

/// Runs `walk` on every unit of `fuzz/slow/<dir>/` and checks its node tests against the
/// bound. A unit that no longer sets up must be refused for its world coordinates: the f32
/// units with a coordinate beyond `max_world_coordinate` (a normal of 1.6e29), whose
/// nonlinear ray was NaN, so that the walk could decide nothing and visited every node (39M
/// nodes, 10 s, on `long-column-miss`).
fn walk_is_bounded(dir: &str, walk: impl Fn(&[u8]) -> Walked) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/slow")
        .join(dir);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("the slow units are committed") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable unit");
        match walk(&data) {
            Ok((stats, bound)) => assert!(
                stats.box_tests as u64 <= bound && stats.fallbacks == 0,
                "{}: {stats:?}, bound {bound} node tests",
                path.display()
            ),
            Err(e) => assert!(
                e.contains("beyond the largest this precision traces"),
                "{}: {e}",
                path.display()
            ),
        }
        count += 1;
    }
    assert!(count > 0);
}

/// The walk's counters on one unit and their bound: 16 node tests per node of each base
/// triangle's cell range (the displacement and shell surfaces share the walk).
fn counted(
    triangles: usize,
    roots: impl Fn(usize) -> nlrt_accel::RootNodes,
    intersect: impl FnOnce(&mut TraversalStats),
) -> Walked {
    let mut stats = TraversalStats::default();
    intersect(&mut stats);
    let bound = (0..triangles)
        .map(|tri| 4 * 4 * nodes_in_range(roots(tri)))
        .sum();
    Ok((stats, bound))
}

/// [`walk_is_bounded`] for a displacement target's units.
fn displacement_walk<T: nlrt_poly::Real>(data: &[u8]) -> Walked {
    let (surface, ray) = displacement_case::<T>(data)?;
    counted(
        surface.mesh().triangle_count(),
        |tri| surface.roots(tri),
        |stats| {
            let _ = surface.intersect(&ray, T::ZERO, T::INFINITY, stats);
        },
    )
}

/// [`walk_is_bounded`] for a shell target's units: the same walk over tiles.
fn shell_walk<T: nlrt_poly::Real>(data: &[u8]) -> Walked {
    let (surface, ray) = shell_case::<T>(data)?;
    counted(
        surface.mesh().triangle_count(),
        |tri| surface.roots(tri),
        |stats| {
            let _ = surface.intersect(&ray, T::ZERO, T::INFINITY, stats);
        },
    )
}

#[test]
fn slow_units_walk_a_bounded_number_of_nodes() {
    walk_is_bounded("displacement_f64", displacement_walk::<f64>);
}

/// The f32 target's units: `affine-box-walk` is slow for the affine baseline only (the walk
/// rejects its ray at once); `long-column-miss` is refused at set-up (a normal beyond
/// `max_world_coordinate`); `pole-sweep` below.
#[test]
fn slow_units_walk_a_bounded_number_of_nodes_f32() {
    walk_is_bounded("displacement_f32", displacement_walk::<f32>);
}

/// `pole-sweep`: a prism 2e9 units wide whose curve's denominator changes sign at `h =
/// 2.8e-4`, where the `f32` curve's uv error bounds, growing as `1 / |D|`, admitted every
/// texel near that height: 481M node tests and 225M texel tests (129 s in release) for no
/// hit. A prism whose curve has a pole inside the shell is traced in `f64`, which rejects the
/// ray at once.
#[test]
fn a_pole_inside_the_shell_is_walked_in_f64() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/slow/displacement_f32/pole-sweep");
    let data = std::fs::read(path).expect("the slow units are committed");
    let (surface, ray) = displacement_case::<f32>(&data).expect("the unit sets up");
    let mut stats = TraversalStats::default();
    let hit = surface.intersect(&ray, 0.0, f32::INFINITY, &mut stats);
    assert_eq!(stats.f64_prisms, 1, "{stats:?}");
    assert!(stats.box_tests < 1000, "{stats:?}");
    assert!(hit.is_none());
}

/// The shell target's units: `tile-walk`, refused at set-up (a position beyond
/// `max_world_coordinate`), where its NaN curve had the walk visit 39M nodes (3.1 s); and
/// `huge-tile-range`, a triangle over 65,000 x 65,000 tiles whose one ray makes 41M node and
/// box tests and 11M object-triangle tests (9.9 s in release, more than 300 s while `f32`
/// shells traced in `f32` arithmetic): within the bound, not yet under the 10 ms.
#[test]
fn shell_slow_units_walk_a_bounded_number_of_nodes() {
    walk_is_bounded("shell_f32", shell_walk::<f32>);
}
