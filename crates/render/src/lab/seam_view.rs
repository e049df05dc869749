//! A seam scene with and without the seam rule ([`nlrt_accel::SeamRule`]), side by side, with
//! the crack pixels marked: the report's picture of what the rule closes.

use crate::lab::watertight::LEAK_TOLERANCE;
use crate::scene::scenes::Scene;
use crate::trace::integrator::{Frame, RenderOptions, render};
use crate::trace::methods::Nonlinear;
use nlrt_accel::SeamRule;

/// The two renders (nonlinear tracing in f32) and where they differ.
pub struct SeamComparison {
    /// Width of one render.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// 8-bit sRGB, `2 * width` by `height`: with the rule on the left, without it on the
    /// right with the crack pixels in red.
    pub rgb: Vec<u8>,
    /// Pixels that hit the surface with the rule.
    pub hit_pixels: usize,
    /// Crack pixels: without the rule, the pixel's centre ray reaches the base mesh (from
    /// either side) before any hit, or misses (by more than [`LEAK_TOLERANCE`]): heights are
    /// `>= 0`, so the surface lies over the base and the ray went through a crack.
    pub crack_pixels: usize,
}

/// Whether a pixel whose centre ray crosses the base at `base` (NaN: never) and hits at
/// `depth` (NaN: misses) went through a crack.
fn is_crack(base: f64, depth: f64) -> bool {
    !base.is_nan() && (depth.is_nan() || depth > base * (1.0 + LEAK_TOLERANCE))
}

/// The nearest crossing of the base mesh by each pixel's centre ray (the renderer's primary
/// ray through the pixel centre), in f64; NaN where there is none.
fn base_crossings(scene: &Scene, width: usize, height: usize) -> Vec<f64> {
    use rayon::prelude::*;
    let triangles: Vec<[nlrt_poly::glam::DVec3; 3]> = scene
        .triangles
        .iter()
        .map(|t| t.map(|v| scene.positions[v as usize]))
        .collect();
    let aspect = width as f64 / height as f64;
    (0..width * height)
        .into_par_iter()
        .map(|k| {
            let (x, y) = ((k % width) as f64 + 0.5, (k / width) as f64 + 0.5);
            let dir = scene
                .camera
                .direction(x / width as f64, y / height as f64, aspect);
            triangles
                .iter()
                .filter_map(|t| nlrt_accel::ray_triangle::<f64>(t, scene.camera.eye, dir))
                .map(|(t, _, _)| t)
                .filter(|&t| t > 0.0)
                .fold(f64::NAN, f64::min)
        })
        .collect()
}

/// Renders `scene` with nonlinear tracing in f32 under both seam rules.
///
/// # Errors
/// A scene nonlinear tracing cannot build in f32.
pub fn compare(scene: &Scene, opts: &RenderOptions) -> Result<SeamComparison, String> {
    let frame = |rule: SeamRule| -> Result<Frame, String> {
        let mut scene = scene.clone();
        scene.seam_rule = rule;
        let tracer = Nonlinear::<f32>::Displaced(scene.displaced_surface::<f32>()?);
        Ok(render(&scene, &tracer, opts, &|_| {}))
    };
    let (closed, open) = (frame(SeamRule::Closed)?, frame(SeamRule::Open)?);
    let (width, height) = (closed.width, closed.height);
    let (left, right) = (closed.rgb8(), open.rgb8());
    let base = base_crossings(scene, width, height);
    let mut rgb = Vec::with_capacity(2 * left.len());
    let mut crack_pixels = 0;
    for y in 0..height {
        rgb.extend_from_slice(&left[3 * y * width..3 * (y + 1) * width]);
        for x in 0..width {
            let k = y * width + x;
            if is_crack(base[k], open.depth[k]) {
                crack_pixels += 1;
                rgb.extend_from_slice(&[255, 0, 0]);
            } else {
                rgb.extend_from_slice(&right[3 * k..3 * k + 3]);
            }
        }
    }
    Ok(SeamComparison {
        width,
        height,
        rgb,
        hit_pixels: closed.depth.iter().filter(|d| !d.is_nan()).count(),
        crack_pixels,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crack_is_a_ray_that_reaches_the_base_unhit() {
        assert!(is_crack(2.0, f64::NAN));
        assert!(is_crack(2.0, 2.5));
        assert!(!is_crack(2.0, 2.0 * (1.0 + LEAK_TOLERANCE / 2.0)));
        assert!(!is_crack(2.0, 1.5));
        // Beside the base (a silhouette), a miss is no crack.
        assert!(!is_crack(f64::NAN, f64::NAN));
    }

    /// The cube without the rule shows cracks along its edges; with it, none of its centre
    /// rays reaches the base unhit.
    #[test]
    fn the_seam_cube_cracks_open_without_the_rule_only() {
        let scene =
            crate::scene::scenes::builtin("seam-cube", crate::scene::scenes::Size::Small).unwrap();
        let opts = RenderOptions {
            width: 64,
            height: 48,
            spp: 1,
            bounces: 0,
        };
        let view = compare(&scene, &opts).unwrap();
        assert_eq!(view.rgb.len(), 2 * 64 * 48 * 3);
        assert!(
            view.hit_pixels > 800 && view.crack_pixels > 50,
            "{} {}",
            view.hit_pixels,
            view.crack_pixels
        );
        let closed = render(&scene, &Nonlinear::<f32>::new(&scene), &opts, &|_| {});
        let base = base_crossings(&scene, 64, 48);
        let cracks = (0..base.len())
            .filter(|&k| is_crack(base[k], closed.depth[k]))
            .count();
        assert_eq!(cracks, 0);
    }
}
