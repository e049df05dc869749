//! The fuzzer's slow units (`fuzz/slow/<target>/`): inputs on which one ray once took seconds
//! to minutes. Nothing is timed; the nonlinear walk's node tests are counted against the bound
//! that makes its work linear in the nodes the ray's curve can reach: each node of the
//! triangle's texel range is visited at most once per stretch of the ray inside the prism (at
//! most 4, `BaseEdges::stretches`), and each visit tests at most its 4 children.

use nlrt_accel::TraversalStats;
use nlrt_tests::fuzz_input::{
    affine_displacement_case, displacement_case, displacement_parts, shell_case,
};
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
/// bound. A unit that no longer sets up must be refused for its world coordinates or for its
/// texel range: the f32 units with a coordinate beyond `max_world_coordinate` (a normal of
/// 1.6e29), whose nonlinear ray was NaN, so that the walk could decide nothing and visited
/// every node (39M nodes, 10 s, on `long-column-miss`); and the units whose base triangle
/// spans more than `MAX_TEXEL_RANGE` texels (or tiles) on an axis, where one grazing ray
/// crossed up to a million texels (`long-row-*`, `pole-sweep`). `expected_refusals` names
/// the units that must be refused, so that a unit cannot slip out of the walk's bound by
/// being refused for another reason.
fn walk_is_bounded(dir: &str, expected_refusals: &[&str], walk: impl Fn(&[u8]) -> Walked) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/slow")
        .join(dir);
    let mut count = 0;
    for entry in std::fs::read_dir(&dir).expect("the slow units are committed") {
        let path = entry.expect("readable directory").path();
        let data = std::fs::read(&path).expect("readable unit");
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .expect("unit names are ASCII");
        match walk(&data) {
            Ok((stats, bound)) => {
                assert!(
                    stats.box_tests as u64 <= bound && stats.fallbacks == 0,
                    "{}: {stats:?}, bound {bound} node tests",
                    path.display()
                );
                assert!(!expected_refusals.contains(&name), "{name} was traced");
            }
            Err(e) => {
                assert!(expected_refusals.contains(&name), "{name} refused: {e}");
                assert!(
                    e.contains("beyond the largest this precision traces")
                        || (e.contains("per axis are traced") && e.contains("subdivide")),
                    "{}: {e}",
                    path.display()
                );
            }
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

/// The f64 target's units: `grazing-long-texel-row` and the three `long-row-*` refused for
/// their texel ranges; `affine-range-walk`, slow for the tessellation-free baseline only (a
/// 34,312^2 texel range; the nonlinear walk makes 17 node tests).
#[test]
fn slow_units_walk_a_bounded_number_of_nodes() {
    walk_is_bounded(
        "displacement_f64",
        &[
            "grazing-long-texel-row",
            "long-row-hit",
            "long-row-miss",
            "long-row-tiny-distance",
        ],
        displacement_walk::<f64>,
    );
}

/// The f32 target's units: `affine-box-walk` (slow for the affine baseline only) and
/// `pole-sweep` (below) refused at set-up for their texel ranges (1,566 x 399,362 and 76,329 x
/// 151,889 texels), `long-column-miss` for a normal beyond `max_world_coordinate`; and
/// `subnormal-hit-band`, traced: a prism traced in f64 over 9,398 x 2,700 texels whose one
/// ray (a hit at `t = 2.2e-44`) makes 29.9M node and 3.7M texel tests (4.4 s in release),
/// within the bound; `affine-range-walk` to `affine-range-walk-4`, slow for the
/// tessellation-free baseline only (7.7 s, 15.8 s, 55.6 s and 1.0 s; 28M, 68M, 415M and 8.9M
/// texel tests over ranges of 9,398^2, 12,659 x 12,658, 16,385 x 50,631 and 25,314 x 23,749
/// texels; the nonlinear walk rejects their rays in f64 at once).
#[test]
fn slow_units_walk_a_bounded_number_of_nodes_f32() {
    walk_is_bounded(
        "displacement_f32",
        &["affine-box-walk", "long-column-miss", "pole-sweep"],
        displacement_walk::<f32>,
    );
}

/// `pole-sweep`: a prism 2e9 units wide whose curve's denominator changes sign at `h =
/// 2.8e-4`, where the `f32` curve's uv error bounds, growing as `1 / |D|`, admitted every
/// texel near that height: 481M node tests and 225M texel tests (129 s in release) for no
/// hit. A prism whose curve has a pole inside the shell is traced in `f64`, which rejects the
/// ray at once. The unit's own tiling gives its triangle more texels than `MAX_TEXEL_RANGE`
/// (refused above); a quarter of it keeps the same prism and ray (the pole does not depend on
/// the map) within the limit.
#[test]
fn a_pole_inside_the_shell_is_walked_in_f64() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/slow/displacement_f32/pole-sweep");
    let data = std::fs::read(path).expect("the slow units are committed");
    let (mesh, field, tiling, ray) = displacement_parts::<f32>(&data).expect("a valid unit");
    let surface = nlrt_accel::DisplacedSurface::new(mesh, field, 1.0, tiling * 0.25)
        .expect("within the texel range limit");
    let mut stats = TraversalStats::default();
    let hit = surface.intersect(&ray, 0.0, f32::INFINITY, &mut stats);
    assert_eq!(stats.f64_prisms, 1, "{stats:?}");
    assert!(stats.box_tests < 1000, "{stats:?}");
    assert!(hit.is_none());
}

/// The shell target's units: `tile-walk`, refused at set-up (a position beyond
/// `max_world_coordinate`), where its NaN curve had the walk visit 39M nodes (3.1 s); and
/// `huge-tile-range`, a triangle over 65,000 x 65,000 tiles whose one ray makes 41M node and
/// box tests and 11M object-triangle tests (5 to 10 s in release): within
/// `MAX_TEXEL_RANGE`, so traced, and within the bound, which is linear in the tiles its
/// curve can reach (accepted: docs/testing.md).
#[test]
fn shell_slow_units_walk_a_bounded_number_of_nodes() {
    walk_is_bounded("shell_f32", &["tile-walk"], shell_walk::<f32>);
}

/// The straight walk on every displacement unit made affine (its triangle's first direction
/// at all three corners, as the fuzz targets also trace it): each node is expanded at most
/// once (the walk is nearest first along a line, each node pushed by its parent alone), and an
/// expansion tests its 4 children, so the child tests stay within 4 per node of the texel
/// range plus the roots; and the texels tested lie in the triangle's texel box padded by one
/// (the line is clipped to it: `straight-sliver`, a triangle 4e-24 texels wide and 9,152
/// long, tested 151M texels in 11 s when only its padded edges bounded the line). Units
/// refused at set-up are skipped (the same refusals as above).
#[test]
fn straight_walks_of_the_slow_units_are_bounded() {
    fn straight<T: nlrt_poly::Real>(dir: &str) -> usize {
        let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../fuzz/slow")
            .join(dir);
        let mut walked = 0;
        for entry in std::fs::read_dir(&dir).expect("the slow units are committed") {
            let path = entry.expect("readable directory").path();
            let data = std::fs::read(&path).expect("readable unit");
            let Ok((surface, ray)) = affine_displacement_case::<T>(&data) else {
                continue;
            };
            if surface.straight_triangles() == 0 {
                continue;
            }
            let mut stats = TraversalStats::default();
            let _ = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            let bound = 4 * nodes_in_range(surface.roots(0)) + 4;
            assert!(
                u64::from(stats.box_tests) <= bound,
                "{}: {stats:?}, bound {bound}",
                path.display()
            );
            let [x0, y0, x1, y1] = surface.roots(0).texels.map(i64::from);
            let texels = (x1 - x0 + 3) * (y1 - y0 + 3);
            assert!(
                i64::from(stats.texel_tests) <= texels,
                "{}: {stats:?}, {texels} texels in the padded box",
                path.display()
            );
            walked += 1;
        }
        walked
    }
    let walked = straight::<f32>("displacement_f32") + straight::<f64>("displacement_f64");
    assert!(walked > 0, "no unit made an affine prism");
}
