//! The built-in scenes: procedural analogues of the paper's Table 2 displacement scenes
//! (nothing is downloaded). Each is a base mesh with normals and uvs, a height map, a height
//! scale, a tiling and a camera.

mod maps;
mod paper;
mod registry;
mod scene;
mod variants;

pub use maps::{fbm_map, spike_map};
pub use paper::{
    blob_object, cornell, cornell_object, cylinder, feather_object, feathers, fig9, fur, fur_cones,
    highpoly, mountain, scale_object, scales, torus_scene,
};
pub use registry::{BUILTIN, Builtin, MIN_MAP_SIDE, Size, Tag, builtin, is_builtin, names};
pub use scene::{Camera, Content, Scene};
pub use variants::{
    COARSE_TORI, CoarseTorus, coarse_torus, cornell_floor, dem_crop, fig9_displaced, ghost_torus,
    plateau, seam_cube, seam_sphere,
};

#[cfg(test)]
mod tests {
    use super::{BUILTIN, Content, MIN_MAP_SIDE, Size, Tag, builtin, names};

    /// The registry names each scene once, each is either in the report or a variant, and
    /// the shell tag matches what the shell scenes build.
    #[test]
    fn the_registry_names_each_scene_once_with_consistent_tags() {
        let mut all: Vec<&str> = BUILTIN.iter().map(|b| b.name).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), BUILTIN.len());
        for b in &BUILTIN {
            assert!(b.has(Tag::Report) != b.has(Tag::Variant), "{}", b.name);
        }
        assert_eq!(names(Tag::Report).len(), 9);
        for name in names(Tag::Shell) {
            let scene = builtin(name, Size::Small).unwrap();
            assert!(matches!(scene.content, Content::Shell(_)), "{name}");
        }
        for tag in [Tag::Ghost, Tag::Seam, Tag::Coarse, Tag::ReportJudged] {
            assert!(
                names(tag)
                    .iter()
                    .all(|n| names(Tag::Watertight).contains(n)),
                "{tag:?}"
            );
        }
    }

    /// `Size::MapSide` sets every map's side and leaves the rest at the paper's sizes; sides
    /// that are not powers of two in `[MIN_MAP_SIDE, 16384]` are refused with a message.
    #[test]
    fn a_map_side_sets_the_maps_and_nothing_else() {
        let size = Size::map_side(MIN_MAP_SIDE).unwrap();
        for name in ["mountain", "cylinder", "fur", "torus"] {
            let scene = builtin(name, size).unwrap();
            let Content::Displacement(field) = &scene.content else {
                panic!("{name} is a displacement scene")
            };
            assert_eq!([field.width(), field.height()], [MIN_MAP_SIDE; 2], "{name}");
        }
        let paper = builtin("cornell", Size::Paper).unwrap();
        let swept = builtin("cornell", size).unwrap();
        assert_eq!(swept.content.describe(), paper.content.describe());
        for bad in [0, 256, 1000, 32768] {
            let e = Size::map_side(bad).unwrap_err();
            assert!(
                e.contains(&bad.to_string()) && e.contains("power of two"),
                "{e}"
            );
        }
    }

    /// Midlevel 0.5: nonlinear tracing and the pre-tessellated reference (built on the same
    /// floor) hit at the same distances, in both precisions, and the surface is another one
    /// than at midlevel 0 (the map pushes in where it pushed out). On the mountain, whose
    /// prisms are affine, the reference's flat microtriangles are the surface itself, so f64
    /// agrees to its rounding.
    #[test]
    fn a_midlevel_moves_the_surface_and_every_method_with_it() {
        use crate::trace::methods::Nonlinear;
        use crate::trace::tessellate::Tessellated;
        use crate::trace::tracer::Tracer;
        let scene = builtin("mountain-midlevel", Size::Small).unwrap();
        let zero = builtin("mountain", Size::Small).unwrap();
        assert_eq!((scene.midlevel, zero.midlevel), (0.5, 0.0));
        let reference = Tessellated::new(&scene);
        let (nonlinear_32, nonlinear_64, at_zero) = (
            Nonlinear::<f32>::new(&scene),
            Nonlinear::<f64>::new(&scene),
            Nonlinear::<f64>::new(&zero),
        );
        let n = 48;
        let (mut hits, mut moved) = (0, 0);
        for k in 0..n * n {
            let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
            let dir = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
            let eye = scene.camera.eye;
            let trace = |t: &dyn Tracer| t.intersect(eye, dir, 0.0, f64::INFINITY).map(|h| h.t);
            let truth = trace(&reference);
            for (tracer, tolerance) in [(&nonlinear_64 as &dyn Tracer, 1e-9), (&nonlinear_32, 1e-4)]
            {
                match (truth, trace(tracer)) {
                    (Some(a), Some(b)) => {
                        assert!((a - b).abs() <= tolerance * a, "ray {k}: {a} vs {b}");
                    }
                    (a, b) => assert_eq!(a.is_some(), b.is_some(), "ray {k}: {a:?} vs {b:?}"),
                }
            }
            if let Some(t) = truth {
                hits += 1;
                if trace(&at_zero).is_none_or(|z| (z - t).abs() > 1e-6 * t) {
                    moved += 1;
                }
            }
        }
        assert!(hits > n * n / 4, "{hits}");
        assert!(moved > hits * 9 / 10, "{moved} of {hits}");
    }
}
