//! `nlrt watertight`: leaks of the floating-point tracer, decided by exact arithmetic.
//!
//! A ray leaks when, in exact arithmetic, it reaches a base triangle from the side its
//! normals point to, having entered the shell from outside, yet the tracer reports no hit
//! before that point. Heights are `>= 0`, so the displaced surface (or, for shell mapping, a
//! closed object layer... see below) lies on or above the base: a ray from outside that
//! reaches the base must have crossed it. The base crossing is computed with GMP rationals
//! ([`nlrt_oracle::crossing`]) on exactly the values the tracer sees (its precision's mesh and
//! ray), so the verdict does not depend on floating point. Where a piece of the mesh has
//! boundary edges (the mountain, Fig. 9's columns) a ray could enter under the surface through
//! a side wall, so it must also cross a top cap from outside before the base (the shell is
//! then a convex slab, so the ray stays inside it), unless the height map is zero all along
//! those edges (Fig. 9's displaced columns: a clamped map with a zero border), which leaves
//! no way under the surface but through it; closed meshes (tori) have no other way in. Rays
//! reaching a piece of mesh with a uv or normal seam are not judged: the surface itself is
//! cracked there (Fig. 9's point-degenerate column has one by construction).
//!
//! This finds misses and hits beyond the base; a hit that is too far but still above the base
//! is not detected by it (a lower bound on leaks). The other direction, hits in front of the
//! true surface, is judged per hit by the MPFR oracle ([`GhostCount`], nonlinear tracing).
//! `NLRT_SHOW_LEAKS=1` prints each leak and each hit the oracle does not confirm.
//! A shell-mapped object need not cover the base: shell scenes are judged by rays aimed at
//! points of the object instead (see the `shell` submodule), for nonlinear tracing.

use crate::scene::scenes::{Content, Scene};
use crate::trace::method::{Kind, Method, Precision};
use crate::trace::methods::Nonlinear;
use nlrt_accel::{Aabb, Bvh4, SlabRay, TraversalStats, Wrap};
use nlrt_baselines::{AffineTracing as _, MarchOptions, Marching as _, TetrahedralShells as _};
use nlrt_oracle::crossing::ray_triangle;
use nlrt_poly::glam::{DVec2, DVec3};
use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::Ray;
use rayon::prelude::*;

mod judge;
mod shell;

use judge::{HitJudgement, TrueSurface, shell_point_on_ray, vertex_neighbours};

/// A hit farther than the exact base crossing by more than this relative amount counts as a
/// leak. Distances of a correct hit carry a relative error of a few ulps times the hit's
/// conditioning (measured p99 ~ 4e-7 for f32 in the report); at the base (height 0) the true
/// hit is the crossing itself. 1e-4 is 250x that, and below the smallest displacement
/// feature relative to the viewing distance (a texel of the maps here is ~ 1e-3 of it).
pub const LEAK_TOLERANCE: f64 = 1e-4;

/// The methods whose leaks are measured, in report order.
pub const METHODS: [Method; 10] = [
    Method::NONLINEAR_F32,
    Method::NONLINEAR_F64,
    Method::TESSELLATION_FREE_F32,
    Method::TESSELLATION_FREE_F64,
    Method::MARCHING_F32,
    Method::MARCHING_F64,
    Method::DISTANCE_MAP_F32,
    Method::DISTANCE_MAP_F64,
    Method::TETRAHEDRA_F32,
    Method::TETRAHEDRA_F64,
];

/// The outcome for one ray.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayVerdict {
    /// The ray does not reach a base triangle from outside: no claim.
    NotDecided,
    /// Reaches the base and the tracer hit no farther than the crossing.
    Hit,
    /// Reaches the base (of this base triangle) and the tracer missed or hit beyond the
    /// crossing.
    Leak(u32),
}

/// Leak counts of one precision on one scene.
#[derive(Clone, Debug)]
pub struct LeakReport {
    /// The tracing method measured.
    pub method: Method,
    /// Rays cast.
    pub rays: usize,
    /// Rays that reach a base triangle from outside (decided by the oracle).
    pub decided: usize,
    /// Leaks among them.
    pub leaks: usize,
    /// RayVerdict per pixel (row-major), for the leak image.
    pub verdicts: Vec<RayVerdict>,
    /// Hit distances against the oracle (nonlinear tracing only).
    pub distance_error: Option<DistanceError>,
    /// Every hit judged against the oracle (nonlinear tracing only: the other methods trace
    /// other surfaces, flat world triangles or samples).
    pub ghosts: Option<GhostCount>,
    /// Seconds.
    pub seconds: f64,
    /// Where the leaks reach the base: per base triangle and its nearest edge, most first.
    pub leak_edges: Vec<LeakEdge>,
}

/// Leaks that reach the base near one edge of one base triangle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeakEdge {
    /// The base triangle.
    pub triangle: u32,
    /// Its edge nearest the crossings ([`nlrt_accel::EDGE_VERTICES`]: 0 `alpha = 0`, 1
    /// `beta = 0`, 2 `alpha + beta = 1`).
    pub edge: u8,
    /// Whether that edge is a seam of the mesh.
    pub seam: bool,
    /// Leaks there.
    pub leaks: usize,
}

/// The oracle's input for texture-space triangle `tri` in `prism` on `ray`: the tracer's values,
/// widened exactly to f64.
fn oracle_scene<T: Real>(
    prism: &nlrt_shellmap::Prism<T>,
    ray: &Ray<T>,
    tri: [[f64; 3]; 3],
) -> nlrt_oracle::shell::ShellScene {
    nlrt_oracle::shell::ShellScene {
        p: prism.p.map(to_f64::<T>),
        n: prism.n.map(to_f64::<T>),
        uv: prism.uv.map(|t| [t.x().to_f64(), t.y().to_f64()]),
        origin: to_f64::<T>(ray.origin),
        dir: to_f64::<T>(ray.dir),
        tri,
    }
}

/// One more leak at `edge` of base `triangle` in `places`.
fn count_leak(places: &mut Vec<LeakEdge>, triangle: u32, edge: u8, seam: bool) {
    match places
        .iter_mut()
        .find(|e| e.triangle == triangle && e.edge == edge)
    {
        Some(e) => e.leaks += 1,
        None => places.push(LeakEdge {
            triangle,
            edge,
            seam,
            leaks: 1,
        }),
    }
}

/// The edge of base triangle `tri` nearest the ray's base crossing at `t` (by barycentric
/// coordinates, in f64), and whether it is a seam.
fn nearest_edge<T: Real>(
    surface: &nlrt_accel::DisplacedSurface<T>,
    ray: &Ray<T>,
    t: f64,
    tri: usize,
) -> (u8, bool) {
    let prism = surface.prism(tri);
    let [p0, p1, p2] = prism.p.map(|p| DVec3::from(to_f64::<T>(p)));
    let point = DVec3::from(to_f64::<T>(ray.origin)) + DVec3::from(to_f64::<T>(ray.dir)) * t;
    let (e1, e2, d) = (p1 - p0, p2 - p0, point - p0);
    let normal = e1.cross(e2);
    let area = normal.length_squared();
    let (alpha, beta) = if area > 0.0 {
        (
            d.cross(e2).dot(normal) / area,
            e1.cross(d).dot(normal) / area,
        )
    } else {
        (0.0, 0.0)
    };
    let distances = [alpha, beta, 1.0 - alpha - beta];
    let edge = (0..3)
        .min_by(|&a, &b| distances[a].total_cmp(&distances[b]))
        .unwrap_or(0);
    let seam = surface
        .seams()
        .of_triangle(tri)
        .is_some_and(|walls| walls[edge] != nlrt_accel::NO_SEAM);
    (edge as u8, seam)
}

/// Relative error of hit distances against the oracle: for a sample of the rays that hit, the
/// true nearest hit (512-bit MPFR, [`nlrt_oracle::shell::true_microtriangle_hit`]) on the
/// microtriangles of the hit texel and its eight neighbours in the same prism, exactly as the
/// tracer has them (its precision's prism, ray, texel corners and heights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceError {
    /// Hits compared.
    pub samples: usize,
    /// Hits for which the oracle found no surface in that neighbourhood (the true hit lies in
    /// another prism, or there is none), and seam-wall hits (no microtriangle's; judged as
    /// ghosts or not instead); left out of the percentiles.
    pub unverified: usize,
    /// Median of `|t - t_true| / t_true`.
    pub median: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

/// Every reported hit of a grid judged against the oracle's true hits on the microtriangles
/// around it (the hit texel and its 8 neighbours, in the neighbouring prisms too when the hit
/// lies on a base edge; 512-bit MPFR on exactly the tracer's values). A hit is confirmed when
/// a true hit lies within [`LEAK_TOLERANCE`] (relative) of its distance. Otherwise it is too
/// far when a nearer true hit is there (the tracer passed the surface); when the nearest true
/// hit there is farther or absent, it is grazing if the point the tracer reports lies on the
/// true surface within the tolerance times its distance, in world space (the exact ray
/// passes that close to the surface without touching it, at a silhouette: conservative
/// rounding, which is what keeps the tracer from leaking, turns such a near miss into a hit)
/// and a ghost if not (a surface reported where there is none).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct GhostCount {
    /// Hits judged (every ray of the grid that hit).
    pub hits: usize,
    /// Hits where the true surface is not: in front of it, or where it has none.
    pub ghosts: usize,
    /// Near misses reported as hits, on the true surface within the tolerance.
    pub grazing: usize,
    /// Hits beyond a nearer true hit of the same neighbourhood.
    pub too_far: usize,
    /// Grid cells (row-major) of the ghost hits, for the leak image.
    pub ghost_cells: Vec<u32>,
}

/// Hits sampled for [`DistanceError`] (each costs 18 oracle solves, ~1 ms).
pub const DISTANCE_SAMPLES: usize = 1024;

impl LeakReport {
    /// Leak rate among decided rays.
    #[must_use]
    pub fn rate(&self) -> f64 {
        self.leaks as f64 / self.decided.max(1) as f64
    }

    /// 95% Wilson score interval of the leak rate (sound also at 0 leaks).
    #[must_use]
    pub fn wilson_95(&self) -> (f64, f64) {
        let n = self.decided.max(1) as f64;
        let p = self.rate();
        let z = 1.959_963_984_540_054f64;
        let den = 1.0 + z * z / n;
        let centre = (p + z * z / (2.0 * n)) / den;
        let half = z * ((p * (1.0 - p) / n) + z * z / (4.0 * n * n)).sqrt() / den;
        let lo = if self.leaks == 0 {
            0.0
        } else {
            (centre - half).max(0.0)
        };
        (lo, (centre + half).min(1.0))
    }
}

/// How a ray reaching a base triangle from the front is judged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Criterion {
    /// Reaching the base from outside proves a crossing of the surface.
    Base,
    /// The ray must also have crossed a top cap from outside before the base.
    TopCapFirst,
    /// No verdict: the triangle has zero world area, so no surface (rays do not cross it).
    NoSurface,
    /// No verdict: the triangle's piece of surface has a non-manifold seam (an edge of more
    /// than two triangles that disagree on uvs or normals there), which no rule closes.
    Seam,
}

/// Per base triangle, the [`Criterion`] for rays reaching it. Triangles sharing an edge (same
/// positions, uvs and normals at both ends) form a piece whose surface is continuous. A piece
/// without boundary edges (closed, like the tori) gets [`Criterion::Base`]: a ray from outside
/// cannot get under the surface but through it. So does a piece whose boundary edges all lie
/// where the height map is zero (along the uv square's border of a clamped map whose border
/// samples are all 0, as in `fig9-displaced`): a ray entering through a side wall enters at or
/// above the surface, and the difference between its height and the surface's changes sign (or
/// touches zero) before the base. Other open pieces (the mountain) get
/// [`Criterion::TopCapFirst`] (the shell is then a convex slab, the ray stays in it); pieces
/// with a seam get [`Criterion::Seam`]. Triangles of zero world area have no surface (as in
/// the paper) and their edges bound their neighbours.
fn criteria(scene: &Scene) -> Vec<Criterion> {
    use std::collections::HashMap;
    let key = |p: DVec3| (p.x.to_bits(), p.y.to_bits(), p.z.to_bits());
    // Per edge (by positions): its triangles, with the uvs and normals at its two ends in a
    // canonical order.
    type Ends = [(DVec2, DVec3); 2];
    let mut edges: HashMap<_, Vec<(usize, usize, Ends)>> = HashMap::new();
    for (i, t) in scene.triangles.iter().enumerate() {
        for k in 0..3 {
            let (va, vb) = (t[k] as usize, t[(k + 1) % 3] as usize);
            let (a, b) = (key(scene.positions[va]), key(scene.positions[vb]));
            let attributes = |v: usize| (scene.uvs[v] * scene.tiling, scene.normals[v]);
            let (edge, ends) = if a < b {
                ((a, b), [attributes(va), attributes(vb)])
            } else {
                ((b, a), [attributes(vb), attributes(va)])
            };
            edges.entry(edge).or_default().push((i, k, ends));
        }
    }
    // Two triangles agree on an edge when their normals are equal at both ends and their
    // tiled uvs are equal, or (with a repeating map) differ by one whole number of tiles at
    // both ends (the torus's u = 0 / u = 1 wrap).
    let repeats = match &scene.content {
        Content::Displacement(field) => field.wrap() == Wrap::Repeat,
        Content::Shell(_) => true,
    };
    let agree = |a: &Ends, b: &Ends| {
        let offset = a[0].0 - b[0].0;
        let whole = offset == offset.round() && (repeats || offset == DVec2::ZERO);
        a[0].1 == b[0].1 && a[1].1 == b[1].1 && whole && a[1].0 - b[1].0 == offset
    };
    // A triangle of zero world area has no surface (Ogaki 2023, Fig. 9: "it disappears as
    // expected as rays and the prism do not intersect"): it joins nothing, and the edges its
    // neighbours share with it are their boundary edges.
    let flat: Vec<bool> = scene
        .triangles
        .iter()
        .map(|t| {
            nlrt_oracle::crossing::has_zero_area(t.map(|v| scene.positions[v as usize].to_array()))
        })
        .collect();
    for users in edges.values_mut() {
        users.retain(|u| !flat[u.0]);
    }
    // Pieces: triangles joined by edges they agree on, by union-find.
    let mut parent: Vec<usize> = (0..scene.triangles.len()).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // An edge shared by exactly two triangles joins them even where they disagree (a seam):
    // the surface is closed there by the seam rule (`nlrt_accel::SeamRule::Closed`), and with
    // the rule off, the cracks are what the criterion measures.
    for users in edges.values() {
        for w in users.windows(2) {
            if users.len() == 2 || agree(&w[0].2, &w[1].2) {
                let (a, b) = (root(&mut parent, w[0].0), root(&mut parent, w[1].0));
                parent[a] = b;
            }
        }
    }
    let zero_border = match &scene.content {
        Content::Displacement(field) => {
            let (w, h) = (field.width() as i64, field.height() as i64);
            field.wrap() == Wrap::Clamp
                && (0..w).all(|i| field.sample(i, 0) == 0 && field.sample(i, h - 1) == 0)
                && (0..h).all(|j| field.sample(0, j) == 0 && field.sample(w - 1, j) == 0)
        }
        Content::Shell(_) => false,
    };
    let on_zero_border = |tri: usize, k: usize| {
        let t = scene.triangles[tri];
        let (a, b) = (
            scene.uvs[t[k] as usize] * scene.tiling,
            scene.uvs[t[(k + 1) % 3] as usize] * scene.tiling,
        );
        let line = |x: f64, y: f64| (x == 0.0 && y == 0.0) || (x == 1.0 && y == 1.0);
        zero_border && (line(a.x, b.x) || line(a.y, b.y))
    };
    let mut piece = vec![Criterion::Base; scene.triangles.len()];
    for users in edges.values() {
        let seam = users.len() > 2 && users.windows(2).any(|w| !agree(&w[0].2, &w[1].2));
        for &(tri, k, _) in users {
            let r = root(&mut parent, tri);
            if seam {
                piece[r] = Criterion::Seam;
            } else if users.len() == 1 && !on_zero_border(tri, k) && piece[r] == Criterion::Base {
                piece[r] = Criterion::TopCapFirst;
            }
        }
    }
    (0..scene.triangles.len())
        .map(|i| {
            if flat[i] {
                Criterion::NoSurface
            } else {
                piece[root(&mut parent, i)]
            }
        })
        .collect()
}

/// A float pre-filter for the exact test: `false` only when the f64 barycentric coordinates
/// are clearly outside (by 1e-6, some 10^9 ulps of the well-conditioned f64 computation) or
/// the crossing is clearly behind; near-parallel rays go to the exact test.
fn may_cross(o: [f64; 3], d: [f64; 3], tri: &[[f64; 3]; 3]) -> bool {
    let (o, d) = (DVec3::from(o), DVec3::from(d));
    let [a, b, c] = tri.map(DVec3::from);
    let (e1, e2) = (b - a, c - a);
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-12 * e1.length() * e2.length() {
        return true;
    }
    let s = o - a;
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = d.dot(q) / det;
    let t = e2.dot(q) / det;
    const SLACK: f64 = 1e-6;
    u >= -SLACK && v >= -SLACK && u + v <= 1.0 + SLACK && t > -SLACK * (1.0 + t.abs())
}

/// A prism's base and top triangles (f64, exactly the tracer's values) and the sign that
/// orients the base's geometric normal like the vertex normals.
type Caps = ([[f64; 3]; 3], [[f64; 3]; 3], f64);

fn to_f64<T: Real>(v: T::Vec3) -> [f64; 3] {
    [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()]
}

/// Runs `rays_side x rays_side` camera rays (pixel centres) through `scene` with `method`
/// (nonlinear tracing or tessellation-free mapping, in either precision); every hit of
/// nonlinear tracing is judged for ghosts.
///
/// # Errors
/// A scene that is not a displacement scene, or the pre-tessellated reference (its f64
/// triangles are not the surface the oracle's criterion is stated for).
pub fn measure(scene: &Scene, rays_side: usize, method: Method) -> Result<LeakReport, String> {
    let mut reports = measure_all(scene, rays_side, &[method], JudgedHits::Every)?;
    Ok(reports.remove(0))
}

/// [`measure`] for several methods, in their order, with nonlinear tracing's hits judged for
/// ghosts as `judged_hits` says. The rays and which of them are judged depend on the scene and
/// the precision only, so they are decided once per precision (each precision's first
/// report's `seconds` includes that).
///
/// # Errors
/// As [`measure`], for the first method that cannot be judged.
pub fn measure_all(
    scene: &Scene,
    rays_side: usize,
    methods: &[Method],
    judged_hits: JudgedHits,
) -> Result<Vec<LeakReport>, String> {
    measure_all_at_frame(scene, None, rays_side, methods, judged_hits)
}

/// [`measure_all`] on frame `frame.0` of `frame.1` of the scene's motion (`None`: the scene
/// as it is). Nonlinear tracing is judged as `nlrt animate` runs it: built on the rest pose,
/// then moved frame by frame to the judged one by pose updates ([`TlasUpdate::DEFAULT`]);
/// the rays are decided on the posed mesh.
///
/// # Errors
/// As [`measure_all`], and a static scene or a pose not finite in a method's precision.
///
/// [`TlasUpdate::DEFAULT`]: nlrt_accel::TlasUpdate::DEFAULT
pub fn measure_all_at_frame(
    scene: &Scene,
    frame: Option<(usize, usize)>,
    rays_side: usize,
    methods: &[Method],
    judged_hits: JudgedHits,
) -> Result<Vec<LeakReport>, String> {
    for &method in methods {
        judged_precision(method)?;
        if matches!(scene.content, Content::Shell(_))
            && !matches!(method, Method::NONLINEAR_F32 | Method::NONLINEAR_F64)
        {
            return Err(format!(
                "{method}: scene '{}' is shell-mapped; its watertightness is measured for \
                 nonlinear tracing (the other judged methods displace a height field)",
                scene.name
            ));
        }
    }
    let in_f32: Vec<Method> = methods
        .iter()
        .copied()
        .filter(|&m| judged_precision(m) == Ok(Precision::F32))
        .collect();
    let in_f64: Vec<Method> = methods
        .iter()
        .copied()
        .filter(|&m| judged_precision(m) == Ok(Precision::F64))
        .collect();
    let mut f32_reports = if in_f32.is_empty() {
        Vec::new()
    } else {
        measure_in::<f32>(scene, frame, rays_side, &in_f32, judged_hits)?
    }
    .into_iter();
    let mut f64_reports = if in_f64.is_empty() {
        Vec::new()
    } else {
        measure_in::<f64>(scene, frame, rays_side, &in_f64, judged_hits)?
    }
    .into_iter();
    Ok(methods
        .iter()
        .filter_map(|&m| match judged_precision(m) {
            Ok(Precision::F32) => f32_reports.next(),
            _ => f64_reports.next(),
        })
        .collect())
}

/// The precision `method` is judged in, or why it is not judged.
fn judged_precision(method: Method) -> Result<Precision, String> {
    match method.kind() {
        Kind::Nonlinear
        | Kind::TessellationFree
        | Kind::Marching
        | Kind::DistanceMap
        | Kind::Tetrahedra => Ok(method.precision()),
        _ => Err(format!(
            "{method}: watertightness is measured for nonlinear and tessellation-free tracing \
             and the smooth and tetrahedral shells (the references and geometry images are \
             other surfaces: flat triangles through re-sampled points, which need not lie above \
             the base near its edges; projective mapping displaces over other prisms; the \
             curved shell bends out of the prisms where they are thin for their curvature; cone \
             tracing gives up a prism where the quadric says the ray left the relief)"
        )),
    }
}

/// Which rays of the `n x n` grid are judged, and where: per grid cell, the exact distance
/// of the base crossing and its base triangle, or `None` for a ray the criterion cannot
/// decide. It depends on the scene and the precision only, so the methods of one precision
/// share it (the exact GMP crossings are most of a measurement's time).
fn decide<T: Real>(
    scene: &Scene,
    surface: &nlrt_accel::DisplacedSurface<T>,
    n: usize,
) -> Vec<Option<(f64, usize)>> {
    let criteria = criteria(scene);
    // Base and top-cap triangles exactly as the tracer's prisms have them.
    let mesh = surface.mesh();
    let caps: Vec<Caps> = (0..mesh.triangle_count())
        .map(|i| {
            let prism = surface.prism(i);
            let base = prism.p.map(to_f64::<T>);
            let top = [0, 1, 2].map(|k| to_f64::<T>(prism.p[k] + prism.n[k]));
            // Orientation: the side the (scaled) normals point to.
            let (a, b, c) = (
                DVec3::from(base[0]),
                DVec3::from(base[1]),
                DVec3::from(base[2]),
            );
            let normal_sum = prism
                .n
                .iter()
                .fold(DVec3::ZERO, |s, &n| s + DVec3::from(to_f64::<T>(n)));
            let orient = (b - a).cross(c - a).dot(normal_sum).signum();
            (base, top, orient)
        })
        .collect();
    let boxes: Vec<Aabb<f64>> = caps
        .iter()
        .map(|(b, t, _)| Aabb::of_points(b.iter().chain(t.iter()).map(|&p| DVec3::from(p))))
        .collect();
    let bvh = Bvh4::build(&boxes, 1);
    (0..n * n)
        .into_par_iter()
        .map(|k| {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let d = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
            let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
            let ray = Ray::<T>::new(v(scene.camera.eye), v(d))?;
            let (o, dir) = (to_f64::<T>(ray.origin), to_f64::<T>(ray.dir));
            // Nearest exact base crossing, and the nearest front top-cap crossing.
            let slab = SlabRay::new(DVec3::from(o), DVec3::from(dir));
            let mut base: Option<(f64, bool, usize)> = None;
            let mut top: Option<f64> = None;
            bvh.traverse(&slab, 0.0, f64::INFINITY, |i, _| {
                let (b, t, orient) = &caps[i as usize];
                if may_cross(o, dir, b)
                    && let Some(c) = ray_triangle(o, dir, *b)
                {
                    let front = c.from_front == (*orient > 0.0);
                    if base.is_none_or(|(bt, _, _)| c.t < bt) {
                        base = Some((c.t, front, i as usize));
                    }
                }
                if may_cross(o, dir, t)
                    && let Some(c) = ray_triangle(o, dir, *t)
                    && c.from_front == (*orient > 0.0)
                    && top.is_none_or(|tt| c.t < tt)
                {
                    top = Some(c.t);
                }
                None // visit every candidate
            });
            let Some((t_base, true, base_triangle)) = base else {
                return None;
            };
            let decided = match criteria[base_triangle] {
                Criterion::Base => true,
                Criterion::TopCapFirst => top.is_some_and(|t| t <= t_base),
                Criterion::Seam | Criterion::NoSurface => false,
            };
            if !decided {
                return None;
            }
            Some((t_base, base_triangle))
        })
        .collect()
}

fn measure_in<T: Real>(
    rest: &Scene,
    frame: Option<(usize, usize)>,
    rays_side: usize,
    methods: &[Method],
    judged_hits: JudgedHits,
) -> Result<Vec<LeakReport>, String> {
    let mut start = std::time::Instant::now();
    let mut tracer = Nonlinear::<T>::new(rest);
    let posed_scene;
    let scene = match frame {
        None => rest,
        Some((k, frames)) => {
            let pose_of = |j: usize| {
                rest.pose(j, frames)
                    .ok_or_else(|| format!("scene '{}' has no motion", rest.name))
            };
            for j in 0..=k {
                tracer.set_pose(&pose_of(j)?, nlrt_accel::TlasUpdate::DEFAULT)?;
            }
            posed_scene = rest.posed(&pose_of(k)?)?;
            posed_scene.check_precision::<T>()?;
            &posed_scene
        }
    };
    let n = rays_side;
    let surface = match &tracer {
        Nonlinear::Displaced(surface) => surface,
        Nonlinear::Shell(surface) => {
            return Ok(methods
                .iter()
                .map(|&method| {
                    let report = shell::measure(scene, surface, n * n, method, judged_hits, start);
                    start = std::time::Instant::now();
                    report
                })
                .collect());
        }
    };
    let decisions = decide(scene, surface, n);
    let mut reports = Vec::with_capacity(methods.len());
    for &method in methods {
        let affine = matches!(
            method,
            Method::TESSELLATION_FREE_F32 | Method::TESSELLATION_FREE_F64
        );
        let marching = matches!(method, Method::MARCHING_F32 | Method::MARCHING_F64);
        let tetrahedra = matches!(method, Method::TETRAHEDRA_F32 | Method::TETRAHEDRA_F64);
        let map = matches!(method, Method::DISTANCE_MAP_F32 | Method::DISTANCE_MAP_F64)
            .then(|| crate::trace::methods::distance_map_of(surface.field()));
        let verdicts: Vec<RayVerdict> = (0..n * n)
            .into_par_iter()
            .map(|k| {
                let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
                let Some((t_base, base_triangle)) = decisions[k] else {
                    return RayVerdict::NotDecided;
                };
                let Some(ray) = grid_ray::<T>(scene, n, k) else {
                    return RayVerdict::NotDecided;
                };
            let mut stats = TraversalStats::default();
            let hit = if tetrahedra {
                surface
                    .intersect_tetrahedra(
                        &ray,
                        T::ZERO,
                        T::INFINITY,
                        &MarchOptions::default(),
                        &mut stats,
                    )
                    .map(|h| (h.hit.t, h.triangle, h.texel, h.part, h.hit.h))
            } else if let Some(map) = &map {
                surface
                    .intersect_sphere_traced(
                        &ray,
                        T::ZERO,
                        T::INFINITY,
                        map,
                        &MarchOptions::default(),
                        &mut stats,
                    )
                    .map(|h| (h.hit.t, h.triangle, h.texel, h.part, h.hit.h))
            } else if marching {
                surface
                    .intersect_marching(&ray, T::ZERO, T::INFINITY, &MarchOptions::default(), &mut stats)
                    .map(|h| (h.hit.t, h.triangle, h.texel, h.part, h.hit.h))
            } else if affine {
                surface
                    .intersect_affine(&ray, T::ZERO, T::INFINITY, &mut stats)
                    .map(|h| (h.t, h.triangle, h.texel, h.part, T::NAN))
            } else {
                surface
                    .intersect(&ray, T::ZERO, T::INFINITY, &mut stats)
                    .map(|h| (h.hit.t, h.triangle, h.texel, h.part, h.hit.h))
            };
            match hit {
                Some(h) if h.0.to_f64() <= t_base * (1.0 + LEAK_TOLERANCE) => RayVerdict::Hit,
                _ => {
                    if std::env::var_os("NLRT_SHOW_LEAKS").is_some() {
                        let (edge, seam) = nearest_edge(surface, &ray, t_base, base_triangle);
                        eprintln!(
                            "{method} leak at pixel ({x}, {y}): base triangle {base_triangle} crossed at t = {t_base} nearest its edge {edge}{}, tracer {:?}",
                            if seam { " (a seam)" } else { "" },
                            hit.map(|h| (h.0.to_f64(), h.1, h.2, h.3, h.4.to_f64()))
                        );
                    }
                    RayVerdict::Leak(base_triangle as u32)
                }
            }
        })
        .collect();
        let decided = verdicts
            .iter()
            .filter(|v| **v != RayVerdict::NotDecided)
            .count();
        let mut leak_edges: Vec<LeakEdge> = Vec::new();
        for (k, v) in verdicts.iter().enumerate() {
            let (RayVerdict::Leak(triangle), Some((t_base, _)), Some(ray)) =
                (v, decisions[k], grid_ray::<T>(scene, n, k))
            else {
                continue;
            };
            let (edge, seam) = nearest_edge(surface, &ray, t_base, *triangle as usize);
            count_leak(&mut leak_edges, *triangle, edge, seam);
        }
        leak_edges.sort_by(|a, b| b.leaks.cmp(&a.leaks).then(a.triangle.cmp(&b.triangle)));
        let leaks = verdicts
            .iter()
            .filter(|v| matches!(v, RayVerdict::Leak(_)))
            .count();
        let nonlinear = !(affine || marching || tetrahedra || map.is_some());
        let truth = nonlinear.then(|| (TrueSurface::new(surface), grid_hits(scene, surface, n)));
        let distance_error = truth
            .as_ref()
            .map(|(t, hits)| distance_error(hits, t, judged_hits.distance_samples()));
        let ghosts = truth
            .as_ref()
            .map(|(t, hits)| ghost_count(hits, t, n, judged_hits));
        reports.push(LeakReport {
            leak_edges,
            method,
            distance_error,
            ghosts,
            rays: n * n,
            decided,
            leaks,
            verdicts,
            seconds: start.elapsed().as_secs_f64(),
        });
        start = std::time::Instant::now();
    }
    Ok(reports)
}

/// The ray of grid cell `k` of an `n x n` grid, in precision `T`.
fn grid_ray<T: Real>(scene: &Scene, n: usize, k: usize) -> Option<Ray<T>> {
    let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
    let d = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
    let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
    Ray::new(v(scene.camera.eye), v(d))
}

/// Which hits of a grid the oracle judges for [`GhostCount`] and for the [`DistanceError`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JudgedHits {
    /// Every hit (`nlrt watertight`; about 0.3 ms of one core per hit), and
    /// [`DISTANCE_SAMPLES`] hits for the [`DistanceError`].
    Every,
    /// About `ghosts` hits for ghosts and `distances` for the [`DistanceError`], each evenly
    /// spaced over the hits in grid order (the report, which must stay within its minutes).
    Spaced {
        /// Hits judged for ghosts.
        ghosts: usize,
        /// Hits whose distance is compared with the oracle's (about 18 oracle solves each,
        /// several times a ghost judgement, which usually settles at the hit texel).
        distances: usize,
    },
}

impl JudgedHits {
    /// Hits sampled for the [`DistanceError`].
    fn distance_samples(self) -> usize {
        match self {
            JudgedHits::Every => DISTANCE_SAMPLES,
            JudgedHits::Spaced { distances, .. } => distances,
        }
    }
}

/// The stride that takes about `count` (at least one) evenly spaced items of `len`.
fn spacing(len: usize, count: usize) -> usize {
    len.div_ceil(count.max(1)).max(1)
}

/// A grid ray that hit: its cell (row-major), the ray and the nonlinear tracer's hit.
type GridHit<T> = (usize, Ray<T>, nlrt_accel::SurfaceHit<T>);

/// The hits of nonlinear tracing on the `n x n` grid, in grid order (traced once for both
/// the ghost count and the distance errors).
fn grid_hits<T: Real>(
    scene: &Scene,
    surface: &nlrt_accel::DisplacedSurface<T>,
    n: usize,
) -> Vec<GridHit<T>> {
    (0..n * n)
        .into_par_iter()
        .filter_map(|k| {
            let ray = grid_ray::<T>(scene, n, k)?;
            let hit =
                surface.intersect(&ray, T::ZERO, T::INFINITY, &mut TraversalStats::default())?;
            Some((k, ray, hit))
        })
        .collect()
}

/// The `hits` judged by the oracle ([`GhostCount`]).
fn ghost_count<T: Real>(
    hits: &[GridHit<T>],
    truth: &TrueSurface<'_, T>,
    n: usize,
    which: JudgedHits,
) -> GhostCount {
    let stride = match which {
        JudgedHits::Every => 1,
        JudgedHits::Spaced { ghosts, .. } => spacing(hits.len(), ghosts),
    };
    let judged: Vec<(u32, HitJudgement)> = hits
        .par_iter()
        .step_by(stride)
        .map(|&(k, ray, hit)| {
            let t = hit.hit.t.to_f64();
            let verdict = truth.judge(&ray, &hit);
            if verdict != HitJudgement::Confirmed && std::env::var_os("NLRT_SHOW_LEAKS").is_some() {
                eprintln!(
                    "{} {verdict:?} at grid cell ({}, {}): t = {t}, triangle {}, texel {:?} ({:?}, alpha {}, beta {}, h {}), true hit near it {:?}",
                    T::NAME,
                    k % n,
                    k / n,
                    hit.triangle,
                    hit.texel,
                    hit.part,
                    hit.hit.alpha,
                    hit.hit.beta,
                    hit.hit.h,
                    truth.hit_around(&ray, hit.triangle as usize, hit.texel, 0.0)
                );
            }
            (k as u32, verdict)
        })
        .collect();
    GhostCount {
        hits: judged.len(),
        ghosts: judged.iter().filter(|j| j.1 == HitJudgement::Ghost).count(),
        grazing: judged
            .iter()
            .filter(|j| j.1 == HitJudgement::Grazing)
            .count(),
        too_far: judged
            .iter()
            .filter(|j| j.1 == HitJudgement::TooFar)
            .count(),
        ghost_cells: judged
            .iter()
            .filter(|j| j.1 == HitJudgement::Ghost)
            .map(|j| j.0)
            .collect(),
    }
}

/// [`DistanceError`] over about `samples` evenly spaced `hits`.
fn distance_error<T: Real>(
    hits: &[GridHit<T>],
    truth: &TrueSurface<'_, T>,
    samples: usize,
) -> DistanceError {
    let stride = spacing(hits.len(), samples);
    let errors: Vec<Option<f64>> = hits
        .par_iter()
        .step_by(stride)
        .map(|(_, ray, hit)| {
            // A seam-wall hit is no microtriangle's: the ghost judgement checks it
            // (`TrueSurface::on_wall`); here it counts as unverified.
            if matches!(hit.part, nlrt_accel::TexelPart::Wall { .. }) {
                return None;
            }
            let t = hit.hit.t.to_f64();
            truth
                .hit_around(ray, hit.triangle as usize, hit.texel, 0.0)
                .map(|truth| (t - truth).abs() / truth.abs().max(f64::MIN_POSITIVE))
        })
        .collect();
    let mut verified: Vec<f64> = errors.iter().flatten().copied().collect();
    verified.sort_by(f64::total_cmp);
    let q = |p: f64| {
        verified
            .get(((verified.len().max(1) - 1) as f64 * p).round() as usize)
            .copied()
            .unwrap_or(f64::NAN)
    };
    DistanceError {
        samples: errors.len(),
        unverified: errors.iter().filter(|e| e.is_none()).count(),
        median: q(0.5),
        p99: q(0.99),
        max: q(1.0),
    }
}

impl LeakReport {
    /// The base triangles leaks reached, with their counts, by triangle.
    #[must_use]
    pub fn leaks_by_triangle(&self) -> Vec<(u32, usize)> {
        let mut counts = std::collections::BTreeMap::new();
        for v in &self.verdicts {
            if let RayVerdict::Leak(t) = v {
                *counts.entry(*t).or_insert(0) += 1;
            }
        }
        counts.into_iter().collect()
    }
}

/// A leak image like the paper's Fig. 8: decided rays grey, leaks red, ghost hits yellow,
/// undecided black.
#[must_use]
pub fn leak_image(report: &LeakReport) -> Vec<u8> {
    let mut rgb: Vec<u8> = report
        .verdicts
        .iter()
        .flat_map(|v| match v {
            RayVerdict::NotDecided => [0, 0, 0],
            RayVerdict::Hit => [150, 150, 150],
            RayVerdict::Leak(_) => [255, 0, 0],
        })
        .collect();
    for &cell in report.ghosts.iter().flat_map(|g| &g.ghost_cells) {
        let i = 3 * cell as usize;
        rgb[i..i + 3].copy_from_slice(&[255, 220, 0]);
    }
    rgb
}

#[cfg(test)]
mod tests {
    use super::judge::distance_to_surface;
    use super::*;
    use crate::scene::scenes::{Size, builtin};

    /// A built-in displacement scene at small size and its `f32` surface.
    fn small_f32_displaced(name: &str) -> (Scene, nlrt_accel::DisplacedSurface<f32>) {
        let scene = builtin(name, Size::Small).expect("built-in");
        let Nonlinear::Displaced(surface) = Nonlinear::<f32>::new(&scene) else {
            unreachable!("{name} is a displacement scene")
        };
        (scene, surface)
    }

    /// The coarse tori (6 x 4 to 48 x 32 quads, shells 0.01 to 0.6 high, a plateau beside
    /// spikes): no ray leaks and no hit is a ghost in f32 on a 96^2 grid. Their plateau texels
    /// beside a spike hold a horizontal microtriangle at the texel's lowest height, whose
    /// plane's root lies at the end of the heights searched; the piece search lost it to the
    /// coefficients' rounding in f32 (54 of 28,910 decided rays of `torus-coarse` leaked on a
    /// 256^2 grid, 108 of the thinnest shell's) until such a part was decided by the curve's
    /// point at its height.
    #[test]
    fn the_coarse_tori_do_not_leak_in_f32() {
        let method = crate::trace::method::Method::ALL
            .into_iter()
            .find(|m| m.slug() == "nonlinear-f32")
            .expect("a method");
        for (name, _) in crate::scene::scenes::COARSE_TORI {
            let scene = builtin(name, Size::Small).expect("built-in");
            let report = measure(&scene, 96, method).expect("judged");
            assert!(report.decided > 3000, "{name}: {}", report.decided);
            assert_eq!(report.leaks, 0, "{name}: {:?}", report.leak_edges);
            assert_eq!(report.ghosts.map(|g| g.ghosts), Some(0), "{name}");
        }
    }

    /// The judge confirms the tracer's hits, and calls the same hits moved 1% nearer ghosts
    /// and 1% farther too far (the surface is not there; a nearer one is).
    #[test]
    fn the_oracle_judges_moved_hits() {
        let scene = crate::scene::scenes::torus_scene(64);
        let tracer = Nonlinear::<f64>::new(&scene);
        let Nonlinear::Displaced(surface) = &tracer else {
            unreachable!("displacement scene")
        };
        let truth = TrueSurface::new(surface);
        let n = 16;
        let mut judged = 0;
        for k in 0..n * n {
            let Some(ray) = grid_ray::<f64>(&scene, n, k) else {
                continue;
            };
            let Some(hit) =
                surface.intersect(&ray, 0.0, f64::INFINITY, &mut TraversalStats::default())
            else {
                continue;
            };
            assert_eq!(truth.judge(&ray, &hit), HitJudgement::Confirmed, "{hit:?}");
            let moved = |factor: f64| {
                let mut h = hit;
                h.hit.t *= factor;
                h
            };
            assert_eq!(truth.judge(&ray, &moved(0.99)), HitJudgement::Ghost);
            assert_eq!(truth.judge(&ray, &moved(1.01)), HitJudgement::TooFar);
            judged += 1;
        }
        assert!(judged > 50, "{judged}");
    }

    /// Rays of the twisted torus (`nlrt watertight torus-twisted --rays 65536`, grid cells of
    /// 256 x 256) nearly parallel to their prism's layers, where Eq. 6's condition is 2,158
    /// to 86,345: traced in `f32` they gave two ghost hits (one where the exact ray meets no
    /// microtriangle near it, one 9e-4 relative in front of the true surface) and one hit
    /// 3.4e-3 too far; their prisms are now traced in `f64` from the same inputs: the first
    /// ray misses, the other two hits are confirmed.
    #[test]
    fn ill_conditioned_f32_prisms_are_traced_in_f64() {
        let (scene, surface) = small_f32_displaced("torus-twisted");
        let truth = TrueSurface::new(&surface);
        let n = 256;
        let mut hits = 0;
        for (x, y) in [(17, 9), (29, 38), (40, 41)] {
            let ray = grid_ray::<f32>(&scene, n, y * n + x).expect("a camera ray");
            let mut stats = TraversalStats::default();
            let hit = surface.intersect(&ray, 0.0, f32::INFINITY, &mut stats);
            assert!(stats.f64_prisms > 0, "cell ({x}, {y}): {stats:?}");
            if let Some(hit) = hit {
                assert_eq!(
                    truth.judge(&ray, &hit),
                    HitJudgement::Confirmed,
                    "cell ({x}, {y}): {hit:?}"
                );
            }
            hits += usize::from(hit.is_some());
        }
        assert_eq!(hits, 2);
    }

    /// A ray of the torus (`nlrt watertight torus --rays 1000000`, pixel (598, 874)) that
    /// meets the surface where a texel's diagonal crosses the base edge between triangles
    /// 7580 and 7581: the texel test of each prism, in `f32`, saw the diagonal on the other
    /// side of the edge crossing than its neighbour did, and each left its root in the
    /// edge's window to the other as lying beyond doubt across the edge (decided in `f64`),
    /// where the other searched the other microtriangle's plane: a leak. Roots between the
    /// edge crossing and a diagonal crossing within the edge's window are kept.
    #[test]
    fn a_ray_through_a_diagonal_at_a_base_edge_hits_in_f32() {
        let (scene, surface) = small_f32_displaced("torus");
        let truth = TrueSurface::new(&surface);
        let n = 1000;
        let ray = grid_ray::<f32>(&scene, n, 874 * n + 598).expect("a camera ray");
        let hit = surface
            .intersect(&ray, 0.0, f32::INFINITY, &mut TraversalStats::default())
            .expect("the ray hits");
        // The ray reaches base triangle 7452 at t = 1.83 from outside: the hit lies before.
        assert!(hit.hit.t < 1.83, "{hit:?}");
        assert_eq!(truth.judge(&ray, &hit), HitJudgement::Confirmed, "{hit:?}");
    }

    /// A ray of the paper-size fur (`nlrt watertight fur --scene-size paper --rays 65536`,
    /// grid cell (118, 105)) that passes beside a hair: the exact ray meets no microtriangle
    /// near it, and the `f32` tracer reports a hit on the hair's wall, where conservative
    /// rounding counts the near miss as a hit. The reported point lies 1.1e-2 units of height
    /// above the surface at its texture coordinates (far beyond the tolerance: a wall that
    /// rises a unit within a texel or two) but 4.6e-6 of the distance from the wall, within a
    /// tenth of the tolerance: grazing, not a ghost.
    #[test]
    fn a_near_miss_beside_a_hair_is_grazing() {
        let scene = builtin("fur", Size::Paper).expect("built-in");
        let Nonlinear::Displaced(surface) = Nonlinear::<f32>::new(&scene) else {
            unreachable!("fur is a displacement scene")
        };
        let truth = TrueSurface::new(&surface);
        let n = 256;
        let ray = grid_ray::<f32>(&scene, n, 105 * n + 118).expect("a camera ray");
        let hit = surface
            .intersect(&ray, 0.0, f32::INFINITY, &mut TraversalStats::default())
            .expect("the f32 tracer reports a hit");
        let triangle = hit.triangle as usize;
        assert_eq!(
            truth.hit_around(&ray, triangle, hit.texel, 0.0),
            None,
            "{hit:?}"
        );
        let prism = surface.prism(triangle);
        let (a, b, h) = (
            f64::from(hit.hit.alpha),
            f64::from(hit.hit.beta),
            f64::from(hit.hit.h),
        );
        let side = surface.field().grid_side() as f64;
        let uv = |k: usize| DVec2::new(prism.uv[k].x().into(), prism.uv[k].y().into()) * side;
        let at = uv(0) * (1.0 - a - b) + uv(1) * a + uv(2) * b;
        let (surface_height, _) = surface.field().height_at(at.x, at.y);
        assert!(
            (h - surface_height).abs() > LEAK_TOLERANCE,
            "{h} {surface_height}"
        );
        let t = f64::from(hit.hit.t);
        let distance = distance_to_surface(&prism, surface.field(), a, b, h);
        assert!(distance < 0.1 * LEAK_TOLERANCE * t, "{distance}");
        assert_eq!(truth.judge(&ray, &hit), HitJudgement::Grazing, "{hit:?}");
    }

    /// The search's bound beside a wall of known distance: a map that rises from height 0
    /// to 1 across one column of texels, over a base triangle whose world coordinates are
    /// its texel coordinates and whose normals are +z (one unit of height, one world unit),
    /// so the wall is a 45-degree plane; points off the wall's middle along its normal, at
    /// distances from 1e-6 to 0.1: the bound is never below the true distance (every point
    /// it evaluates is on the surface; 1e-15 for the rounding of the point's coordinates)
    /// and reaches it within 1e-12.
    #[test]
    fn the_distance_to_the_surface_is_found_beside_a_wall() {
        use nlrt_accel::{HEIGHT_ONE, HeightField, Wrap};
        // Columns 0-1 of samples at 0, 2-3 at 1: the texels of column 1 rise as h = x - 1
        // over x in [1, 2] (texel units).
        let samples = (0..16)
            .map(|i| if i % 4 >= 2 { HEIGHT_ONE } else { 0 })
            .collect();
        let field = HeightField::new(4, 4, samples, Wrap::Clamp).expect("a valid map");
        let prism = nlrt_shellmap::Prism::<f64>::new(
            [
                DVec3::ZERO,
                DVec3::new(4.0, 0.0, 0.0),
                DVec3::new(0.0, 4.0, 0.0),
            ]
            .map(Into::into),
            [DVec3::Z; 3].map(Into::into),
            [DVec2::ZERO, DVec2::X, DVec2::Y].map(Into::into),
        );
        let normal = DVec3::new(-1.0, 0.0, 1.0).normalize();
        for distance in [1e-6, 1e-4, 1e-2, 0.1] {
            let p = DVec3::new(1.5, 0.5, 0.5) + normal * distance;
            let found = distance_to_surface(&prism, &field, p.x / 4.0, p.y / 4.0, p.z);
            assert!(
                found >= distance - 1e-15 && found <= distance + 1e-12,
                "{distance}: {found}"
            );
        }
    }

    #[test]
    fn criteria_follow_the_mesh_and_the_map() {
        let all = |name: &str| criteria(&builtin(name, Size::Small).unwrap());
        // Closed (the u = 0 / u = 1 wrap of a repeating map is not a seam).
        assert!(all("torus").iter().all(|c| *c == Criterion::Base));
        // Closed across its seams: every edge of the cube is one.
        assert!(all("seam-cube").iter().all(|c| *c == Criterion::Base));
        // Open, with heights on the boundary.
        assert!(all("mountain").iter().all(|c| *c == Criterion::TopCapFirst));
        let fig9 = all("fig9-displaced");
        use Criterion::{Base, NoSurface, TopCapFirst};
        assert_eq!(
            fig9,
            [
                Base,
                Base, // regular: boundary on the zero border
                TopCapFirst,
                TopCapFirst, // a triangle's uvs on the diagonal: interior heights
                TopCapFirst,
                TopCapFirst, // a seam to point-degenerate uvs: joined, open where they are
                Base,
                Base, // pinched to a line
                Base,
                Base, // pinched to a point
                TopCapFirst,
                NoSurface, // a line in world and uv: its neighbour's diagonal is open
                TopCapFirst,
                NoSurface, // a line in world only: the same
            ]
        );
    }
}
