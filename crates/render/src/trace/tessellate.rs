//! The pre-tessellated reference: every microtriangle (or instanced object triangle) clipped
//! to its base triangle in uv,
//! mapped to world space by Eq. 1 at its vertices, and put in a world-space BVH (the
//! approach the paper compares against, Table 2). It is a different surface from the
//! nonlinear one by design (flat world triangles instead of the curved images of flat
//! microtriangles); the report states their distance.

use crate::scene::scenes::{Content, Scene};
use nlrt_accel::{
    Aabb, Bvh4, EDGE_VERTICES, HEIGHT_ONE, HeightField, SeamRule, Seams, SlabRay, Wrap,
    ray_triangle,
};
use nlrt_poly::glam::{DVec2, DVec3};
use nlrt_shellmap::Prism;
use rayon::prelude::*;

/// World-space triangles of the tessellated displaced surface with their BVH.
pub struct Tessellated {
    triangles: Vec<[DVec3; 3]>,
    /// Base triangle of each triangle.
    base: Vec<u32>,
    bvh: Bvh4<f64>,
    /// Base triangles skipped because their uvs are degenerate (no inverse of Eq. 2-3).
    pub skipped_uv_degenerate: usize,
}

/// A vertex `(u, v, h)` in texel units.
type Uvh = [f64; 3];

/// Clips a convex polygon to the half-plane `n . (p - a) >= 0` in uv.
fn clip(poly: &[Uvh], a: DVec2, n: DVec2) -> Vec<Uvh> {
    let side = |p: &Uvh| n.dot(DVec2::new(p[0], p[1]) - a);
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (&poly[i], &poly[(i + 1) % poly.len()]);
        let (sp, sq) = (side(p), side(q));
        if sp >= 0.0 {
            out.push(*p);
        }
        if (sp >= 0.0) != (sq >= 0.0) {
            let t = sp / (sp - sq);
            out.push(core::array::from_fn(|k| p[k] + (q[k] - p[k]) * t));
        }
    }
    out
}

/// The seam walls of a displacement scene as world triangles: per seam edge, the region of
/// the shared side wall (Eq. 1 over the edge, welded `normals`) between the two sides' height
/// curves, cut where either side's curve bends (it crosses a texel edge or diagonal) and
/// where the two cross, each piece a quad of two triangles. Base triangle: the first side's.
fn seam_walls(
    scene: &Scene,
    seams: &Seams,
    (floor, normals): (&[DVec3], &[DVec3]),
    field: &HeightField,
) -> Vec<([DVec3; 3], u32)> {
    // Texels per unit of uv along u and v.
    let texels = DVec2::new(field.width() as f64, field.height() as f64) * scene.tiling;
    let mut out = Vec::new();
    for edge in seams.edges() {
        // Each side's edge ends in texel units, in the first side's order.
        let ends = |side: usize| {
            let s = edge.sides[side];
            let tri = scene.triangles[s.triangle as usize];
            let [i, j] = EDGE_VERTICES[s.edge as usize].map(|k| tri[k] as usize);
            let (i, j) = if side == 1 && edge.reversed {
                (j, i)
            } else {
                (i, j)
            };
            (i, j, scene.uvs[i] * texels, scene.uvs[j] * texels)
        };
        let (i, j, a0, a1) = ends(0);
        let (_, _, b0, b1) = ends(1);
        // Breakpoints: where either side's uv segment crosses a grid line or a diagonal.
        let mut cuts = vec![0.0, 1.0];
        for (p, q) in [(a0, a1), (b0, b1)] {
            let mut lines = |from: f64, to: f64| {
                let (lo, hi) = (from.min(to), from.max(to));
                if hi > lo {
                    let mut n = lo.ceil();
                    while n <= hi {
                        cuts.push((n - from) / (to - from));
                        n += 1.0;
                    }
                }
            };
            lines(p.x, q.x);
            lines(p.y, q.y);
            lines(p.x - p.y, q.x - q.y);
        }
        cuts.retain(|s| (0.0..=1.0).contains(s));
        cuts.sort_by(f64::total_cmp);
        cuts.dedup();
        let height = |p: DVec2, q: DVec2, s: f64| {
            let at = p + (q - p) * s;
            field.height_at(at.x, at.y).0
        };
        let (p0, p1) = (floor[i], floor[j]);
        let (n0, n1) = (
            normals[i] * scene.height_scale,
            normals[j] * scene.height_scale,
        );
        let world = |s: f64, h: f64| p0 + (p1 - p0) * s + (n0 + (n1 - n0) * s) * h;
        let base = edge.sides[0].triangle;
        let mut quad = |s0: f64, s1: f64| {
            let (ha0, ha1) = (height(a0, a1, s0), height(a0, a1, s1));
            let (hb0, hb1) = (height(b0, b1, s0), height(b0, b1, s1));
            let q = [
                world(s0, ha0),
                world(s1, ha1),
                world(s1, hb1),
                world(s0, hb0),
            ];
            for t in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                if (t[1] - t[0]).cross(t[2] - t[0]).length_squared() > 0.0 {
                    out.push((t, base));
                }
            }
        };
        for w in cuts.windows(2) {
            let (s0, s1) = (w[0], w[1]);
            let gap = |s: f64| height(a0, a1, s) - height(b0, b1, s);
            let (g0, g1) = (gap(s0), gap(s1));
            if g0 * g1 < 0.0 {
                // The curves cross inside: two pieces, each a triangle in effect.
                let sc = s0 + (s1 - s0) * g0 / (g0 - g1);
                quad(s0, sc);
                quad(sc, s1);
            } else {
                quad(s0, s1);
            }
        }
    }
    out
}

/// The seams a displacement scene closes as nonlinear tracing closes them
/// ([`nlrt_accel::SeamRule`]), the displacement directions (welded across them) and the
/// shell's floor (the base mesh at the midlevel's depth, moved after the welding): what the
/// pre-tessellated surfaces are built on.
pub(crate) fn displaced_floor(scene: &Scene) -> (Option<Seams>, Vec<DVec3>, Vec<DVec3>) {
    let seams = match (&scene.content, scene.seam_rule) {
        (Content::Displacement(field), SeamRule::Closed) => Some(Seams::find(
            &scene.mesh::<f64>(),
            scene.tiling,
            field.wrap() == Wrap::Repeat,
        )),
        _ => None,
    };
    let normals = seams.as_ref().map_or_else(
        || scene.normals.clone(),
        |s| s.welded_normals::<f64>(&scene.normals),
    );
    let floor = nlrt_accel::shell_floor::<f64>(
        &scene.positions,
        &normals,
        scene.height_scale,
        scene.midlevel,
    );
    (seams, normals, floor)
}

/// The point `q` (texel units) of base triangle `t` (its uvs in texel units, `det` their
/// orientation's determinant) mapped by Eq. 1 over the flat prism of floor points `p` and
/// scaled directions `n`: the map the pre-tessellated surfaces put their vertices through.
pub(crate) fn flat_world(
    t: &[DVec2; 3],
    det: f64,
    p: &[DVec3; 3],
    n: &[DVec3; 3],
    q: [f64; 3],
) -> DVec3 {
    let d = DVec2::new(q[0], q[1]) - t[0];
    let alpha = d.perp_dot(t[2] - t[0]) / det;
    let beta = (t[1] - t[0]).perp_dot(d) / det;
    let at = |k: usize| p[k] + n[k] * q[2];
    at(0) + (at(1) - at(0)) * alpha + (at(2) - at(0)) * beta
}

impl Tessellated {
    /// Tessellates `scene` (in parallel over texel rows).
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        Self::build(scene, false)
    }

    /// Tessellates `scene` through the curved shell mapping (Jeschke et al. 2007, sec. 3.2:
    /// [`Prism::curved_shell_point`] at the microtriangles' vertices): the reference of curved
    /// shell mapping, whole (also where it bends out of the prisms).
    #[must_use]
    pub fn curved(scene: &Scene) -> Self {
        Self::build(scene, true)
    }

    fn build(scene: &Scene, curved: bool) -> Self {
        // Cells: texels of the height map (per axis), or tiles of the object (in uv units
        // times tiling).
        let cells_per_tile = match &scene.content {
            Content::Displacement(field) => DVec2::new(field.width() as f64, field.height() as f64),
            Content::Shell(_) => DVec2::ONE,
        };
        let scale = scene.tiling * cells_per_tile;
        let (seams, normals, floor) = displaced_floor(scene);
        let (normals, floor) = (&normals, &floor);
        // (base triangle, texel row) jobs.
        let mut jobs = Vec::new();
        let mut skipped = 0;
        let mut bases = Vec::new();
        for (b, tri) in scene.triangles.iter().enumerate() {
            let t = tri.map(|v| scene.uvs[v as usize] * scale);
            let det = (t[1] - t[0]).perp_dot(t[2] - t[0]);
            let size = (t[1] - t[0])
                .length_squared()
                .max((t[2] - t[0]).length_squared());
            // Below this the inverse of Eq. 2-3 loses all digits: uv-degenerate.
            if !(det.abs() > 1e-12 * size) {
                skipped += 1;
                continue;
            }
            let lo = t[0].min(t[1]).min(t[2]).floor();
            let hi = t[0].max(t[1]).max(t[2]).floor();
            for y in lo.y as i64..=hi.y as i64 {
                jobs.push((b, y, lo.x as i64, hi.x as i64));
            }
            bases.push((b, t, det));
        }
        let base_of = |b: usize| bases.iter().find(|x| x.0 == b).copied();
        let (triangles, base): (Vec<[DVec3; 3]>, Vec<u32>) = jobs
            .par_iter()
            .flat_map_iter(|&(b, y, x0, x1)| {
                let (_, t, det) = base_of(b).expect("job of a kept triangle");
                let tri = scene.triangles[b];
                let (p, n) = (
                    tri.map(|v| floor[v as usize]),
                    tri.map(|v| normals[v as usize] * scene.height_scale),
                );
                let orient = det.signum();
                let edges: [(DVec2, DVec2); 3] = core::array::from_fn(|i| {
                    let (a, c) = (t[i], t[(i + 1) % 3]);
                    let e = c - a;
                    (a, DVec2::new(-e.y, e.x) * orient)
                });
                let world = move |q: &Uvh| {
                    if curved {
                        let d = DVec2::new(q[0], q[1]) - t[0];
                        let alpha = d.perp_dot(t[2] - t[0]) / det;
                        let beta = (t[1] - t[0]).perp_dot(d) / det;
                        return Prism::<f64>::new(p, n, [DVec2::ZERO; 3])
                            .curved_shell_point(alpha, beta, q[2]);
                    }
                    flat_world(&t, det, &p, &n, *q)
                };
                let mut out = Vec::new();
                for x in x0..=x1 {
                    let micro: Vec<[Uvh; 3]> = match &scene.content {
                        Content::Displacement(field) => {
                            let c = field.texel_corners(x, y);
                            let h = c.map(|s| f64::from(s) / f64::from(HEIGHT_ONE));
                            let (u0, v0) = (x as f64, y as f64);
                            let (u1, v1) = (u0 + 1.0, v0 + 1.0);
                            vec![
                                [[u0, v0, h[0]], [u1, v0, h[1]], [u1, v1, h[3]]],
                                [[u0, v0, h[0]], [u1, v1, h[3]], [u0, v1, h[2]]],
                            ]
                        }
                        Content::Shell(object) => object
                            .iter()
                            .map(|t| t.map(|p| [p.x + x as f64, p.y + y as f64, p.z]))
                            .collect(),
                    };
                    for m in micro {
                        let mut poly = m.to_vec();
                        for &(a, nrm) in &edges {
                            poly = clip(&poly, a, nrm);
                            if poly.len() < 3 {
                                break;
                            }
                        }
                        if poly.len() < 3 {
                            continue;
                        }
                        let w: Vec<DVec3> = poly.iter().map(world).collect();
                        for k in 1..w.len() - 1 {
                            out.push(([w[0], w[k], w[k + 1]], b as u32));
                        }
                    }
                }
                out
            })
            .unzip();
        let (mut triangles, mut base) = (triangles, base);
        if let (Some(seams), Content::Displacement(field)) = (&seams, &scene.content) {
            for (t, b) in seam_walls(scene, seams, (floor, normals), field) {
                triangles.push(t);
                base.push(b);
            }
        }
        let boxes: Vec<Aabb<f64>> = triangles
            .par_iter()
            .map(|t| Aabb::of_points(t.iter().copied()))
            .collect();
        let bvh = Bvh4::build(&boxes, 4);
        Self {
            triangles,
            base,
            bvh,
            skipped_uv_degenerate: skipped,
        }
    }

    /// The world-space triangles.
    #[must_use]
    pub fn triangles(&self) -> &[[DVec3; 3]] {
        &self.triangles
    }

    /// The base triangle of each triangle.
    #[must_use]
    pub fn base_triangles(&self) -> &[u32] {
        &self.base
    }

    /// Triangles.
    #[must_use]
    pub fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    /// Bytes of triangles, their base-triangle ids and BVH.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.triangles.len() * std::mem::size_of::<[DVec3; 3]>()
            + self.base.len() * std::mem::size_of::<u32>()
            + self.bvh.memory_bytes()
    }

    /// Nearest hit in `(t_min, t_max]`: distance, geometric normal facing the ray and base
    /// triangle.
    #[must_use]
    pub fn intersect(
        &self,
        origin: DVec3,
        dir: DVec3,
        t_min: f64,
        t_max: f64,
    ) -> Option<(f64, DVec3, u32)> {
        let slab = SlabRay::new(origin, dir);
        let mut best = None;
        self.bvh.traverse(&slab, t_min, t_max, |i, t_max| {
            let tri = &self.triangles[i as usize];
            let t = ray_triangle(tri, origin, dir).map(|h| h.0)?;
            if t > t_min && t < t_max {
                best = Some(i);
                Some(t)
            } else {
                None
            }
        });
        let i = best?;
        let tri = &self.triangles[i as usize];
        let t = ray_triangle(tri, origin, dir).map(|h| h.0)?;
        let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
        Some((
            t,
            if n.dot(dir) > 0.0 { -n } else { n },
            self.base[i as usize],
        ))
    }
}
