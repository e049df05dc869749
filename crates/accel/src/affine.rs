//! Straight rays in affine prisms.
//!
//! Where a base triangle's three displacement directions are equal (a flat terrain, a facade,
//! every flat part of a mesh with one shared normal), the shell map
//! `P(alpha, beta, h) = B(alpha, beta) + h N` is affine, and so is the map from texel space
//! `(x, y, h)` (texture coordinates times the map's side, heights in `[0, 1]`) to the world.
//! A ray is a straight line there, every microtriangle a flat triangle with integer texel
//! corners, and the min-max pyramid is walked as maximum-mipmap height-field tracers walk it
//! (Tevs et al. 2008): a node's four children are slabs in `x` and `y`, the line's heights at
//! a child's entry and exit bound its heights inside, and texels are decided by a watertight
//! ray-triangle test (Woop, Benthin and Wald 2013) instead of the curved path's quadratics and
//! cubics.
//!
//! Watertightness has three parts.
//! - Inside a texel grid: a texel corner is transformed into the test's sheared frame by one
//!   function of the corner alone, and each edge function is a difference of two products of
//!   those numbers, so the two microtriangles that share an edge compute exactly negated
//!   values for it: a ray cannot pass between them.
//! - The walk never loses a texel the test would hit: node boxes are padded by a bound on the
//!   test's rounding (the walk's paddings, set per prism from the line's reach).
//! - Between base triangles: triangles whose affine maps agree are grouped into a patch traced
//!   in one frame, so all of them see the same line, bit for bit, and the same hit points; a
//!   hit belongs to the triangles whose texel-space edges it lies on or inside, each edge's
//!   function computed from its two corners in one canonical order (the same number in both
//!   triangles that share it). Where a patch meets another patch (a crease) or a triangle on
//!   the curved path (a bent direction), the two sides see different lines or a line and a
//!   curve: there each side owns, beyond the shared edge, the hits within a bound on its own
//!   hit point's error (the walk's window; the curved path's edge windows do the same), so
//!   that a hit on either side is owned by that side whatever the other decides. A triangle
//!   with a uv seam or an edge of more than two triangles keeps the curved path (its seam
//!   walls are the curved path's).

mod patches;
mod walk;

pub(crate) use patches::AffinePatches;
pub(crate) use walk::{Walk, walk_straight, walk_straight_tiles};

#[cfg(test)]
mod tests {
    use crate::test_util::unit_randoms;
    use crate::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
    use alloc::vec::Vec;
    use nlrt_poly::{Real, Vector2, Vector3};
    use nlrt_shellmap::Ray;

    /// A planar grid of `k x k` quads (alternating diagonals, so that base edges cross texel
    /// diagonals), in the plane `[origin, e1, e2]` (through `origin`, spanned by `e1`, `e2`),
    /// with uvs an affine function of the grid (`[turn, scale]`: rotated by `turn` radians,
    /// scaled by `scale`; shifted by `shift`) and one displacement direction `n` for every
    /// vertex.
    fn grid<T: Real>(
        k: usize,
        [origin, e1, e2]: [[f64; 3]; 3],
        n: [f64; 3],
        [turn, scale]: [f64; 2],
        shift: [f64; 2],
    ) -> BaseMesh<T> {
        let v3 =
            |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        let (mut positions, mut uvs) = (Vec::new(), Vec::new());
        for j in 0..=k {
            for i in 0..=k {
                let (a, b) = (i as f64 / k as f64, j as f64 / k as f64);
                positions.push(v3(core::array::from_fn(|c| {
                    origin[c] + a * e1[c] + b * e2[c]
                })));
                let (c, s) = (turn.cos(), turn.sin());
                uvs.push(T::Vec2::new(
                    T::from_f64(scale * (c * a - s * b) + shift[0]),
                    T::from_f64(scale * (s * a + c * b) + shift[1]),
                ));
            }
        }
        let mut triangles = Vec::new();
        let at = |i: usize, j: usize| (j * (k + 1) + i) as u32;
        for j in 0..k {
            for i in 0..k {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                if (i + j) % 2 == 0 {
                    triangles.extend([[a, b, c], [a, c, d]]);
                } else {
                    triangles.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        let normals = alloc::vec![v3(n); positions.len()];
        BaseMesh::new(positions, normals, uvs, triangles).expect("a valid grid")
    }

    fn random_field(side: usize, seed: u64) -> HeightField {
        let mut r = unit_randoms(seed);
        let samples = (0..side * side).map(|_| (r() * 65535.0) as u16).collect();
        HeightField::new(side, side, samples, Wrap::Repeat).expect("a valid map")
    }

    /// The base meshes the straight walk is tested on.
    #[derive(Clone, Copy, Debug, PartialEq)]
    enum Shape {
        /// A tilted, sheared 3 x 3 grid whose base edges cross texel diagonals: one patch.
        Flat,
        /// A tilted, sheared 4 x 4 grid folded along its middle column line, the directions
        /// bent at its last column of vertices: two patches meeting at a crease (16 and 8
        /// triangles), the second beside 8 curved triangles.
        Mixed,
        /// `Flat` with each interior vertex's uv moved by up to a fifth of a grid cell at
        /// random: a plane whose triangles' affine maps all differ, so each is a patch of its
        /// own and every interior edge is open.
        Jittered,
    }

    impl Shape {
        /// Triangles walked straight.
        fn straight_triangles(self) -> usize {
            match self {
                Shape::Flat | Shape::Jittered => 18,
                Shape::Mixed => 24,
            }
        }
    }

    /// The mesh of `shape`.
    fn tilted_mesh<T: Real>(shape: Shape) -> BaseMesh<T> {
        let frame = [[0.3, -0.2, 0.1], [1.7, 0.2, -0.1], [-0.1, 0.3, 1.6]];
        let n = [0.25, 1.0, 0.1];
        let uv = ([0.4, 1.3], [0.2, -0.7]);
        match shape {
            Shape::Flat => grid::<T>(3, frame, n, uv.0, uv.1),
            Shape::Jittered => {
                let flat = grid::<T>(3, frame, n, uv.0, uv.1);
                let mut r = unit_randoms(29);
                let cell = 1.3 / 3.0;
                let uvs = flat
                    .uvs()
                    .iter()
                    .enumerate()
                    .map(|(v, &uv)| {
                        let (i, j) = (v % 4, v / 4);
                        let interior = (1..3).contains(&i) && (1..3).contains(&j);
                        let (du, dv) = if interior {
                            (
                                0.2 * cell * (2.0 * r() - 1.0),
                                0.2 * cell * (2.0 * r() - 1.0),
                            )
                        } else {
                            (0.0, 0.0)
                        };
                        T::Vec2::new(
                            T::from_f64(uv.x().to_f64() + du),
                            T::from_f64(uv.y().to_f64() + dv),
                        )
                    })
                    .collect();
                BaseMesh::new(
                    flat.positions().to_vec(),
                    flat.normals().to_vec(),
                    uvs,
                    (0..flat.triangle_count())
                        .map(|i| flat.triangle(i))
                        .collect(),
                )
                .expect("a valid grid")
            }
            Shape::Mixed => {
                let k = 4;
                let flat = grid::<T>(k, frame, n, uv.0, uv.1);
                let v3 = |a: [f64; 3]| {
                    T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]))
                };
                // Vertex `(i, j)` is number `j (k + 1) + i`; positions recomputed in f64 so
                // that each side of the fold is planar to the rounding of `T`.
                let positions = (0..(k + 1) * (k + 1))
                    .map(|v| {
                        let (a, b) = (
                            (v % (k + 1)) as f64 / k as f64,
                            (v / (k + 1)) as f64 / k as f64,
                        );
                        let fold = 0.4 * (a - 0.5).max(0.0);
                        v3(core::array::from_fn(|c| {
                            frame[0][c] + a * frame[1][c] + b * frame[2][c] + fold * n[c]
                        }))
                    })
                    .collect();
                let normals = (0..(k + 1) * (k + 1))
                    .map(|v| {
                        if v % (k + 1) == k {
                            v3([0.55, 1.0, 0.3])
                        } else {
                            v3(n)
                        }
                    })
                    .collect();
                BaseMesh::new(
                    positions,
                    normals,
                    flat.uvs().to_vec(),
                    (0..flat.triangle_count())
                        .map(|i| flat.triangle(i))
                        .collect(),
                )
                .expect("a valid grid")
            }
        }
    }

    /// A tilted grid over a random map, displaced along a direction off its normal.
    fn tilted_surface<T: Real>(seed: u64, shape: Shape) -> DisplacedSurface<T> {
        DisplacedSurface::new(
            tilted_mesh::<T>(shape),
            random_field(16, seed),
            T::from_f64(0.6),
            T::ONE,
        )
        .expect("a valid surface")
    }

    /// `mesh` widened to `f64`, exactly.
    fn widened<T: Real>(mesh: &BaseMesh<T>) -> BaseMesh<f64> {
        BaseMesh::new(
            mesh.positions().iter().map(|p| p.to_dvec3()).collect(),
            mesh.normals().iter().map(|p| p.to_dvec3()).collect(),
            mesh.uvs().iter().map(|p| p.to_dvec2()).collect(),
            (0..mesh.triangle_count())
                .map(|i| mesh.triangle(i))
                .collect(),
        )
        .expect("a valid mesh stays valid")
    }

    /// The straight walk in `T` finds the hits of the curved walk in `f64` on the same mesh
    /// (widened exactly) on rays from every direction at a tilted, sheared grid whose base
    /// edges cross texel diagonals (`shape`): the same hit or miss on every ray, distances
    /// within `T`'s rounding, the same microtriangle but where a hit lies within rounding of
    /// an edge; and brute force in `T` (every texel of every triangle, the curved test)
    /// agrees on whether the ray hits. Returns how many rays the curved walk in `T` answers
    /// otherwise than `f64` (hit or miss, or a distance off by more than the tolerance).
    fn straight_walk_matches_f64<T: Real>(shape: Shape, t_tolerance: f64) -> usize {
        let mut surface = tilted_surface::<T>(7, shape);
        let wide = widened(surface.mesh());
        let mut reference =
            DisplacedSurface::new(wide, random_field(16, 7), 0.6, 1.0).expect("a valid surface");
        reference.set_straight_walk(false);
        assert_eq!(surface.straight_triangles(), shape.straight_triangles());
        let mut r = unit_randoms(11);
        let (mut hits, mut same_part, mut curved_off) = (0, 0, 0);
        for _ in 0..3000 {
            // Aim at a point of the shell from a random direction.
            let target = [0.3 + r() * 1.6, -0.2 + r() * 1.0, 0.1 + r() * 1.5];
            let d = loop {
                let d = [r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0];
                let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                if l > 0.1 && l <= 1.0 {
                    break d.map(|c| c / l);
                }
            };
            let o = core::array::from_fn::<f64, 3, _>(|c| target[c] - 3.0 * d[c]);
            let v =
                |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
            let ray = Ray::new(v(o), v(d)).expect("a valid ray");
            let (wide_o, wide_d) = (Vector3::to_dvec3(ray.origin), Vector3::to_dvec3(ray.dir));
            let wide_ray: Ray<f64> = Ray::new(wide_o, wide_d).expect("a valid ray");
            let mut stats = TraversalStats::default();
            surface.set_straight_walk(true);
            let straight = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            surface.set_straight_walk(false);
            let curved = surface.intersect(&ray, T::ZERO, T::INFINITY, &mut stats);
            let truth = reference.intersect(&wide_ray, 0.0, f64::INFINITY, &mut stats);
            let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
            surface.set_straight_walk(true);
            assert_eq!(
                surface.occluded(&ray, T::ZERO, T::INFINITY, &mut stats),
                straight.is_some(),
                "{ray:?}"
            );
            if let Some(s) = straight {
                let half = s.hit.t / T::TWO;
                assert!(
                    !surface.occluded(&ray, T::ZERO, half, &mut stats),
                    "{ray:?}"
                );
            }
            assert_eq!(
                straight.is_some(),
                truth.is_some(),
                "{ray:?}: {straight:?} vs {truth:?}"
            );
            assert_eq!(straight.is_some(), brute.is_some(), "{ray:?}");
            let close = |a: Option<T>, b: Option<f64>| match (a, b) {
                (Some(a), Some(b)) => (a.to_f64() - b).abs() <= t_tolerance * b,
                (None, None) => true,
                _ => false,
            };
            curved_off += usize::from(!close(curved.map(|c| c.hit.t), truth.map(|c| c.hit.t)));
            if let (Some(s), Some(c)) = (straight, truth) {
                hits += 1;
                assert!(
                    close(Some(s.hit.t), Some(c.hit.t)),
                    "{s:?} vs {c:?}: {ray:?}"
                );
                same_part += usize::from(s.texel == c.texel && s.triangle == c.triangle);
                let (ps, pc) = (s.hit.u.to_f64(), c.hit.u);
                assert!((ps - pc).abs() < 1e-3, "u {ps} vs {pc}");
            }
        }
        assert!(hits > 1000, "{hits} hits: the rays test the surface");
        // A hit within rounding of a texel or triangle edge may be reported on either side.
        assert!(same_part * 100 >= hits * 99, "{same_part} of {hits}");
        curved_off
    }

    #[test]
    fn straight_walk_matches_f64_in_f32() {
        // The curved walk in f32 differs from f64 on one of these rays (a nearer hit where
        // f64 has none: docs/watertightness.md, "Straight rays in affine prisms"); the
        // straight walk on none.
        let curved_off = straight_walk_matches_f64::<f32>(Shape::Flat, 1e-4);
        assert!(curved_off <= 1, "{curved_off}");
    }

    #[test]
    fn straight_walk_matches_f64_in_f64() {
        assert_eq!(straight_walk_matches_f64::<f64>(Shape::Flat, 1e-10), 0);
    }

    #[test]
    fn straight_patches_of_one_triangle_match_f64() {
        // Every triangle its own patch: each has an open edge (its diagonal at least).
        let mesh = tilted_mesh::<f64>(Shape::Jittered);
        let patches = super::AffinePatches::find(&mesh, 0.6, [1.0, 1.0], 16);
        let open = patches
            .triangles()
            .iter()
            .flatten()
            .filter(|t| t.has_open_edge())
            .count();
        assert_eq!(open, 18);
        let curved_off = straight_walk_matches_f64::<f32>(Shape::Jittered, 1e-4);
        assert!(curved_off <= 1, "{curved_off}");
        assert_eq!(straight_walk_matches_f64::<f64>(Shape::Jittered, 1e-10), 0);
    }

    #[test]
    fn straight_beside_curved_matches_f64_in_f32() {
        let curved_off = straight_walk_matches_f64::<f32>(Shape::Mixed, 1e-4);
        assert!(curved_off <= 1, "{curved_off}");
    }

    #[test]
    fn straight_beside_curved_matches_f64_in_f64() {
        assert_eq!(straight_walk_matches_f64::<f64>(Shape::Mixed, 1e-10), 0);
    }

    /// Rays aimed at points exactly on the base edges between triangles (and on texel
    /// corners there), from above and at a slant: every one hits, in f32 and f64, on one
    /// patch (`Shape::Flat`) and where patches meet each other and curved triangles
    /// (`Shape::Mixed`).
    fn base_edges_do_not_leak<T: Real>(shape: Shape) {
        let surface = tilted_surface::<T>(3, shape);
        let mesh = surface.mesh();
        let mut r = unit_randoms(5);
        let mut rays = 0;
        for tri in (0..mesh.triangle_count()).map(|i| mesh.triangle(i)) {
            for k in 0..3 {
                let (a, b) = (tri[k] as usize, tri[(k + 1) % 3] as usize);
                for _ in 0..40 {
                    let s = r();
                    let p = |v: T::Vec3| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()];
                    let (pa, pb) = (p(mesh.positions()[a]), p(mesh.positions()[b]));
                    // A point on the edge, raised into the shell along the direction.
                    let lift = 0.6 * r();
                    let n = p(mesh.normals()[a]);
                    let target: [f64; 3] =
                        core::array::from_fn(|c| pa[c] + s * (pb[c] - pa[c]) + lift * n[c]);
                    // From the side the directions point to: down through the shell's top.
                    let tilt = [r() - 0.5, r() - 0.5, r() - 0.5];
                    let d: [f64; 3] = core::array::from_fn(|c| -n[c] + 0.5 * tilt[c]);
                    let o: [f64; 3] = core::array::from_fn(|c| target[c] - 4.0 * d[c]);
                    let v = |a: [f64; 3]| {
                        T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]))
                    };
                    let ray = Ray::new(v(o), v(d)).expect("a valid ray");
                    let hit = surface.intersect(
                        &ray,
                        T::ZERO,
                        T::INFINITY,
                        &mut TraversalStats::default(),
                    );
                    // Inside the mesh's interior the ray must meet the surface (it enters the
                    // shell's top and reaches the base); at the border it may pass beside.
                    let brute = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY);
                    if brute.is_some() {
                        rays += 1;
                        assert!(hit.is_some(), "{ray:?} leaked");
                    }
                }
            }
        }
        assert!(rays > 1500, "{rays}");
    }

    #[test]
    fn base_edges_do_not_leak_f32() {
        base_edges_do_not_leak::<f32>(Shape::Flat);
        base_edges_do_not_leak::<f32>(Shape::Mixed);
        base_edges_do_not_leak::<f32>(Shape::Jittered);
    }

    #[test]
    fn base_edges_do_not_leak_f64() {
        base_edges_do_not_leak::<f64>(Shape::Flat);
        base_edges_do_not_leak::<f64>(Shape::Mixed);
        base_edges_do_not_leak::<f64>(Shape::Jittered);
    }

    /// Rays aimed from every side at surface points on the open edges of `Shape::Mixed` (the
    /// crease between its two patches and the line where the second meets the curved
    /// triangles), where the two sides decide ownership on different lines or curves: the
    /// walk hits wherever brute force does, no farther. Returns the rays aimed.
    fn open_edges_do_not_leak<T: Real>() -> usize {
        let surface = tilted_surface::<T>(5, Shape::Mixed);
        let mesh = surface.mesh();
        let mut r = unit_randoms(17);
        let p = |v: T::Vec3| [v.x().to_f64(), v.y().to_f64(), v.z().to_f64()];
        let v = |a: [f64; 3]| T::Vec3::new(T::from_f64(a[0]), T::from_f64(a[1]), T::from_f64(a[2]));
        // Vertices `(i, j)` of the 4 x 4 grid: the open edges lie on the column lines i = 2
        // (the crease) and i = 3 (beside the curved column).
        let column = |vertex: u32| vertex as usize % 5;
        let mut edges = Vec::new();
        for tri in (0..mesh.triangle_count()).map(|i| mesh.triangle(i)) {
            for k in 0..3 {
                let (a, b) = (tri[k], tri[(k + 1) % 3]);
                if a < b && column(a) == column(b) && (column(a) == 2 || column(a) == 3) {
                    edges.push((a as usize, b as usize));
                }
            }
        }
        edges.sort_unstable();
        edges.dedup();
        assert_eq!(edges.len(), 8, "four edges on each line");
        let (mut aimed, mut leaks) = (0, 0);
        for (a, b) in edges {
            let (pa, pb) = (p(mesh.positions()[a]), p(mesh.positions()[b]));
            let n = p(mesh.normals()[a]);
            for _ in 0..150 {
                // The surface point above the edge point: brute force straight down the
                // direction from above the shell.
                let s = r();
                let on_edge: [f64; 3] = core::array::from_fn(|c| pa[c] + s * (pb[c] - pa[c]));
                let from: [f64; 3] = core::array::from_fn(|c| on_edge[c] + 2.0 * n[c]);
                let down = Ray::new(v(from), v(n.map(|c| -c))).expect("a valid ray");
                let Some(top) = surface.intersect_brute_force(&down, T::ZERO, T::INFINITY) else {
                    continue;
                };
                let t = top.hit.t.to_f64();
                let target: [f64; 3] = core::array::from_fn(|c| from[c] - t * n[c]);
                for _ in 0..8 {
                    // From the side the directions point to, at every slant.
                    let d = loop {
                        let d = [r() * 2.0 - 1.0, r() * 2.0 - 1.0, r() * 2.0 - 1.0];
                        let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                        let down = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
                        if l > 0.1 && l <= 1.0 && down < -0.05 * l {
                            break d.map(|c| c / l);
                        }
                    };
                    let o: [f64; 3] = core::array::from_fn(|c| target[c] - 3.0 * d[c]);
                    let ray = Ray::new(v(o), v(d)).expect("a valid ray");
                    let Some(brute) = surface.intersect_brute_force(&ray, T::ZERO, T::INFINITY)
                    else {
                        continue;
                    };
                    aimed += 1;
                    let hit = surface.intersect(
                        &ray,
                        T::ZERO,
                        T::INFINITY,
                        &mut TraversalStats::default(),
                    );
                    let through = hit.is_none_or(|h| {
                        h.hit.t.to_f64() > brute.hit.t.to_f64() * (1.0 + 1e-3) + 1e-3
                    });
                    leaks += usize::from(through);
                }
            }
        }
        assert_eq!(leaks, 0, "of {aimed} rays");
        aimed
    }

    #[test]
    fn open_edges_do_not_leak_f32() {
        assert!(open_edges_do_not_leak::<f32>() > 5000);
    }

    #[test]
    fn open_edges_do_not_leak_f64() {
        assert!(open_edges_do_not_leak::<f64>() > 5000);
    }

    /// Which triangles are walked straight and which of their edges are open: a flat grid
    /// all, one patch, no open edge; a grid whose directions differ in one vertex: every
    /// triangle but those touching it, the ring around it open; a grid folded along a
    /// column line: all, two patches, open along the fold; a grid with a uv seam along a
    /// column line: all but the triangles on the seam (their walls are the curved path's); a
    /// flat grid beside a curved one in the same mesh: the flat one only.
    #[test]
    fn affine_patches_are_the_flat_parts_of_the_mesh() {
        use super::AffinePatches;
        use nlrt_poly::glam::{DVec2, DVec3};
        const K: usize = 4;
        let flat = grid::<f64>(
            K,
            [[0.0; 3], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [0.0, 0.0, 1.0],
            [0.0, 1.0],
            [0.0; 2],
        );
        let triangles = || {
            (0..flat.triangle_count())
                .map(|i| flat.triangle(i))
                .collect::<Vec<_>>()
        };
        let remesh = |positions: Vec<DVec3>, normals: Vec<DVec3>, uvs: Vec<DVec2>, tris| {
            BaseMesh::new(positions, normals, uvs, tris).expect("valid")
        };
        // (straight triangles, straight triangles with an open edge).
        let patches = |m: &BaseMesh<f64>| {
            let p = AffinePatches::find(m, 0.2, [1.0, 1.0], 8);
            let open = p
                .triangles()
                .iter()
                .flatten()
                .filter(|t| t.has_open_edge())
                .count();
            (p.straight_triangles(), open)
        };
        let all = flat.triangle_count();
        assert_eq!(patches(&flat), (all, 0));

        let centre = (K / 2 * (K + 1) + K / 2) as u32;
        let mut normals = flat.normals().to_vec();
        normals[centre as usize] = DVec3::new(0.0, 0.1, 1.0);
        let bent = remesh(
            flat.positions().to_vec(),
            normals,
            flat.uvs().to_vec(),
            triangles(),
        );
        let touching = triangles().iter().filter(|t| t.contains(&centre)).count();
        let (straight, open) = patches(&bent);
        assert_eq!(straight, all - touching);
        assert!(open > 0 && open < straight, "{open} of {straight}");

        let mut positions = flat.positions().to_vec();
        for p in positions.iter_mut().filter(|p| p.x > 0.5) {
            p.z += 0.5 * (p.x - 0.5);
        }
        let folded = remesh(
            positions,
            flat.normals().to_vec(),
            flat.uvs().to_vec(),
            triangles(),
        );
        // The fold's two sides each have one column of triangles along it (2 K in all).
        assert_eq!(patches(&folded), (all, 2 * K));

        // A uv seam along the middle column line: its vertices duplicated, the right side's
        // uvs shifted by half a unit.
        let (mut positions, mut normals, mut uvs) = (
            flat.positions().to_vec(),
            flat.normals().to_vec(),
            flat.uvs().to_vec(),
        );
        let mut copy = alloc::vec![u32::MAX; positions.len()];
        for v in 0..positions.len() {
            if positions[v].x == 0.5 {
                copy[v] = positions.len() as u32;
                positions.push(positions[v]);
                normals.push(normals[v]);
                uvs.push(uvs[v] + DVec2::new(0.5, 0.0));
            }
        }
        let mut shifted = uvs.clone();
        for (v, uv) in shifted.iter_mut().enumerate() {
            if positions[v].x > 0.5 {
                *uv += DVec2::new(0.5, 0.0);
            }
        }
        let seamed_triangles = triangles()
            .into_iter()
            .map(|t| {
                let right = t.iter().any(|&v| flat.positions()[v as usize].x > 0.5);
                t.map(|v| {
                    if right && copy[v as usize] != u32::MAX {
                        copy[v as usize]
                    } else {
                        v
                    }
                })
            })
            .collect();
        let seamed = remesh(positions, normals, shifted, seamed_triangles);
        // One triangle of each quad beside the seam has an edge on it: 2 K of them.
        let (straight, _) = patches(&seamed);
        assert_eq!(straight, all - 2 * K);

        // Two copies side by side, the second with its own vertices and bent directions.
        let mut positions = flat.positions().to_vec();
        let mut normals = flat.normals().to_vec();
        let mut uvs = flat.uvs().to_vec();
        let mut both_triangles = triangles();
        let base = positions.len() as u32;
        positions.extend(
            flat.positions()
                .iter()
                .map(|p| *p + DVec3::new(3.0, 0.0, 0.0)),
        );
        normals.extend(
            flat.positions()
                .iter()
                .map(|p| DVec3::new(p.x * 0.2, 0.0, 1.0)),
        );
        uvs.extend(flat.uvs().iter().copied());
        both_triangles.extend(triangles().iter().map(|t| t.map(|v| v + base)));
        let both = remesh(positions, normals, uvs, both_triangles);
        assert_eq!(patches(&both), (all, 0));
    }
}
