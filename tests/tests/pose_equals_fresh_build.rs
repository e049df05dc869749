//! Animated base meshes: after `set_pose` (TLAS refitted, rebuilt, or by the automatic rule)
//! a surface returns exactly the hits of a surface built afresh on the posed mesh, for f32
//! and f64, displacement and shell mapping, over a sequence of poses that includes
//! degenerate ones (triangles collapsed to a line or a point, inverted prisms, zero normals),
//! where it must neither panic nor return a non-finite hit.

use nlrt_accel::{
    BaseMesh, DisplacedSurface, MeshError, ShellObject, ShellSurface, TlasUpdate, TraversalStats,
    Wrap,
};
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;
use nlrt_tests::geometry::{
    MapKind, SplitMix64, grid_mesh, height_map, random_object, ray_from_above,
};

const RAYS_PER_POSE: usize = 150;
const POSES: usize = 16;
/// An automatic rule tight enough to rebuild on some of these poses and refit on others (the
/// default rebuilds on none of them: a refitted tree over this small grid costs at most 1.2x
/// a fresh one), so that both of its branches are compared with fresh builds.
const TIGHT: TlasUpdate = TlasUpdate::Auto {
    max_cost_growth: 1.02,
};

/// Pose `k` of `POSES` of a mesh at rest: a travelling wave with a shear for most frames;
/// frame 5 squashes the mesh flat onto z = 0 (the bend's triangles degenerate towards
/// lines), frame 9 collapses every vertex to one point with zero normals, frame 11 folds
/// the mesh like an accordion (layers of triangles on top of each other), frame 13 turns
/// every normal inside out (inverted prisms).
fn pose<T: Real>(rest: &BaseMesh<T>, k: usize) -> (Vec<T::Vec3>, Vec<T::Vec3>) {
    let phase = k as f64 / POSES as f64 * std::f64::consts::TAU;
    let f = |v: T::Vec3| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()];
    let v = |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
    let positions = rest.positions().iter().map(|&p| f(p));
    let normals = rest.normals().iter().map(|&n| f(n));
    match k {
        5 => (
            positions.map(|[x, y, _]| v([x, y, 0.0])).collect(),
            normals.map(|_| v([0.0, 0.0, 1.0])).collect(),
        ),
        9 => (
            positions.map(|_| v([0.5, 0.5, 0.1])).collect(),
            normals.map(|_| v([0.0; 3])).collect(),
        ),
        11 => (
            // Folded like an accordion along x onto [0, 1/2] (six layers on top of each
            // other): a tree built at rest, which splits by x, now has children that overlap
            // wholly, while a fresh tree splits by y, so the automatic rule must rebuild.
            positions
                .map(|[x, y, z]| {
                    let f = (3.0 * x).fract();
                    v([f.min(1.0 - f), y, z + 0.05 * x])
                })
                .collect(),
            normals.map(v).collect(),
        ),
        13 => (
            positions.map(v).collect(),
            normals.map(|[x, y, z]| v([-x, -y, -z])).collect(),
        ),
        _ => (
            positions
                .map(|[x, y, z]| {
                    let lift = 0.2 * (phase + 3.0 * x).sin();
                    v([x + 0.3 * phase.sin() * z, y + 0.1 * phase.cos(), z + lift])
                })
                .collect(),
            // The wave's normal direction: the gradient of z - lift(x).
            normals
                .map(|[x, y, z]| {
                    let slope = 0.6 * (phase + 3.0 * x).cos();
                    v([x - slope * z, y, z])
                })
                .collect(),
        ),
    }
}

/// The update rules, each on its own surface, against a fresh build per pose: every
/// ray's hit distance is bit-identical (two prisms can report the same distance where they
/// share an edge, so the triangle may differ only then) and finite.
fn poses_agree<T: Real, S: Posable<Real = T>, H: Copy + std::fmt::Debug>(
    rest: &BaseMesh<T>,
    build: impl Fn(BaseMesh<T>) -> S,
    hit: impl Fn(&S, &Ray<T>) -> Option<H>,
    distance: impl Fn(&H) -> (T, u32),
) {
    let mut surfaces: Vec<(TlasUpdate, S)> = [
        TlasUpdate::Refit,
        TlasUpdate::Rebuild,
        TlasUpdate::DEFAULT,
        TIGHT,
    ]
    .into_iter()
    .map(|u| (u, build(rest.clone())))
    .collect();
    let mut rng = SplitMix64::new(0x905e);
    let (mut hits, mut tight_rebuilds) = (0usize, 0usize);
    for k in 0..POSES {
        let (positions, normals) = pose(rest, k);
        let mut posed = rest.clone();
        posed.set_pose(&positions, &normals).unwrap();
        let fresh = build(posed);
        for (update, surface) in &mut surfaces {
            let done = surface.set_pose(&positions, &normals, *update).unwrap();
            assert!(done.sah_cost.is_finite() && done.sah_cost_at_build.is_finite());
            tight_rebuilds += usize::from(done.rebuilt && *update == TIGHT);
            // Refit never fails here (every prism box stays finite); Rebuild always builds.
            match update {
                TlasUpdate::Refit => assert!(!done.rebuilt),
                TlasUpdate::Rebuild => assert!(done.rebuilt),
                TlasUpdate::Auto { .. } => {}
            }
        }
        for _ in 0..RAYS_PER_POSE {
            let (o, d) = ray_from_above(&mut rng, 0.2);
            let v =
                |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
            let ray = Ray::new(v(o), v(d)).unwrap();
            let want = hit(&fresh, &ray);
            if let Some(h) = &want {
                assert!(distance(h).0.is_finite(), "pose {k}: {h:?}");
                hits += 1;
            }
            for (update, surface) in &surfaces {
                let got = hit(surface, &ray);
                let same = match (&got, &want) {
                    (None, None) => true,
                    (Some(a), Some(b)) => {
                        distance(a).0.to_f64().to_bits() == distance(b).0.to_f64().to_bits()
                    }
                    _ => false,
                };
                assert!(
                    same,
                    "{} pose {k} ({update:?}): {got:?} vs fresh {want:?}",
                    T::NAME
                );
            }
        }
    }
    assert!(hits > POSES * RAYS_PER_POSE / 4, "{hits} hits");
    assert!(
        (1..POSES).contains(&tight_rebuilds),
        "the tight automatic rule rebuilt on {tight_rebuilds} of {POSES} poses: both of its \
         branches must be taken"
    );
}

/// What both surfaces offer for this test.
trait Posable {
    type Real: Real;
    fn set_pose(
        &mut self,
        p: &[<Self::Real as Real>::Vec3],
        n: &[<Self::Real as Real>::Vec3],
        u: TlasUpdate,
    ) -> Result<nlrt_accel::PoseUpdate, MeshError>;
}

impl<T: Real> Posable for DisplacedSurface<T> {
    type Real = T;
    fn set_pose(
        &mut self,
        p: &[T::Vec3],
        n: &[T::Vec3],
        u: TlasUpdate,
    ) -> Result<nlrt_accel::PoseUpdate, MeshError> {
        DisplacedSurface::set_pose(self, p, n, u)
    }
}

impl<T: Real> Posable for ShellSurface<T> {
    type Real = T;
    fn set_pose(
        &mut self,
        p: &[T::Vec3],
        n: &[T::Vec3],
        u: TlasUpdate,
    ) -> Result<nlrt_accel::PoseUpdate, MeshError> {
        ShellSurface::set_pose(self, p, n, u)
    }
}

fn displacement<T: Real>() {
    let rest = grid_mesh::<T>(6, 0.15, true);
    let field = height_map(32, MapKind::Random, Wrap::Repeat, 3);
    poses_agree(
        &rest,
        |mesh| DisplacedSurface::new(mesh, field.clone(), T::from_f64(0.1), T::ONE).unwrap(),
        |s, ray| s.intersect(ray, T::ZERO, T::INFINITY, &mut TraversalStats::default()),
        |h| (h.hit.t, h.triangle),
    );
}

fn shell<T: Real>() {
    let rest = grid_mesh::<T>(5, 0.15, true);
    let object = ShellObject::<T>::new(random_object::<T>(40, 11)).unwrap();
    poses_agree(
        &rest,
        |mesh| ShellSurface::new(mesh, object.clone(), T::from_f64(0.1), T::from_f64(2.0)).unwrap(),
        |s, ray| s.intersect(ray, T::ZERO, T::INFINITY, &mut TraversalStats::default()),
        |h| (h.hit.t, h.triangle),
    );
}

#[test]
fn displaced_f32_poses_equal_fresh_builds() {
    displacement::<f32>();
}

#[test]
fn displaced_f64_poses_equal_fresh_builds() {
    displacement::<f64>();
}

#[test]
fn shell_f32_poses_equal_fresh_builds() {
    shell::<f32>();
}

#[test]
fn shell_f64_poses_equal_fresh_builds() {
    shell::<f64>();
}

/// A rejected pose (wrong vertex count, NaN) is an error and leaves the surface as it was.
#[test]
fn bad_poses_are_rejected_and_change_nothing() {
    let rest = grid_mesh::<f64>(3, 0.1, false);
    let field = height_map(16, MapKind::Random, Wrap::Repeat, 1);
    let mut surface = DisplacedSurface::new(rest.clone(), field, 0.1, 1.0).unwrap();
    let n = rest.positions().len();
    let short = surface.set_pose(&rest.positions()[1..], rest.normals(), TlasUpdate::Refit);
    assert!(
        matches!(short, Err(MeshError::PoseVertexCount { vertices, positions, .. }) if vertices == n && positions == n - 1)
    );
    let mut nan = rest.positions().to_vec();
    nan[2].y = f64::NAN;
    let err = surface
        .set_pose(&nan, rest.normals(), TlasUpdate::DEFAULT)
        .unwrap_err();
    assert_eq!(
        err,
        MeshError::NotFinite {
            vertex: 2,
            attribute: "position"
        }
    );
    assert_eq!(surface.mesh().positions(), rest.positions());
}
