//! `nlrt edit`: the time from a local edit of the mountain's height map (a brush stroke of
//! `brush x brush` samples) to the next frame being traceable, per method:
//!
//! - nonlinear tracing and tessellation-free mapping share the min-max pyramid: a partial
//!   update of the nodes over the stroke ([`nlrt_accel::HeightField::update_region`]), against
//!   a full rebuild of the pyramid; the TLAS does not depend on the heights;
//! - the geometry image (Carr et al. 2006) is re-sampled and its pyramid rebuilt (timed over
//!   the whole map: the paper rebuilds it every frame);
//! - the pre-tessellated reference must re-tessellate and rebuild its BVH (timed as a full
//!   build at the same map size: the simplest correct answer; a refit of the stroke's
//!   triangles would be cheaper, and is not what users of a static BVH get).
//!
//! The partial update is verified: after all strokes, camera rays traced through the updated
//! surface and through one built from scratch from the same samples hit at the same distances.

use crate::lab::median;
use crate::scene::material::Rng;
use crate::scene::scenes::{self, Content, Scene, Size};
use crate::trace::methods::Nonlinear;
use crate::trace::tessellate::Tessellated;
use nlrt_accel::{DisplacedSurface, HeightField, TraversalStats};
use nlrt_poly::glam::DVec3;
use nlrt_shellmap::Ray;
use std::time::Instant;

/// Settings of `nlrt edit`.
#[derive(Clone, Copy, Debug)]
pub struct EditOptions {
    /// Map size of the mountain (small: 1024^2, paper: 4096^2).
    pub size: Size,
    /// Brush strokes timed (the median is reported).
    pub strokes: usize,
    /// Brush side in samples.
    pub brush: usize,
    /// Also time the pre-tessellated reference's rebuild (seconds at 1024^2, minutes and
    /// gigabytes at 4096^2).
    pub reference: bool,
}

impl Default for EditOptions {
    fn default() -> Self {
        Self {
            size: Size::Small,
            strokes: 200,
            brush: 64,
            reference: true,
        }
    }
}

/// What `nlrt edit` measured.
#[derive(Clone, Debug)]
pub struct EditReport {
    /// Map side in samples.
    pub side: usize,
    /// Brush side in samples.
    pub brush: usize,
    /// Strokes timed.
    pub strokes: usize,
    /// Median seconds of a partial pyramid update after one stroke.
    pub partial_seconds: f64,
    /// Largest seconds of a partial update.
    pub partial_max_seconds: f64,
    /// Median seconds of a full pyramid rebuild.
    pub rebuild_seconds: f64,
    /// Seconds of a full re-tessellation and BVH build (when measured).
    pub tessellated_seconds: Option<f64>,
    /// Seconds of re-sampling the geometry image and rebuilding its pyramid (f32).
    pub geometry_image_seconds: f64,
    /// Rays compared between the updated surface and one built from scratch.
    pub verified_rays: usize,
    /// Rays whose hit distance differs between them (0 when the update is right).
    pub verify_mismatches: usize,
}

/// One stroke: a raised (or lowered) cosine bump of `brush x brush` samples at `(x0, y0)`;
/// returns the edited sample range `[x0, y0, x1, y1)`.
fn stroke(field: &mut HeightField, brush: usize, rng: &mut Rng) -> [i64; 4] {
    let (width, height) = (field.width(), field.height());
    let brush = brush.min(width).min(height);
    // Uniform in 0..=side - brush (next_f64 < 1, so the product stays below the count).
    let x0 = (rng.next_f64() * (width - brush + 1) as f64) as usize;
    let y0 = (rng.next_f64() * (height - brush + 1) as f64) as usize;
    let amplitude = if rng.next_f64() < 0.5 {
        3000.0
    } else {
        -3000.0
    };
    let samples = field.samples_mut();
    for j in 0..brush {
        for i in 0..brush {
            let r = |k: usize| (k as f64 + 0.5) / brush as f64 * 2.0 - 1.0;
            let d = (r(i) * r(i) + r(j) * r(j)).sqrt().min(1.0);
            let bump = amplitude * 0.5 * (1.0 + (std::f64::consts::PI * d).cos());
            let s = &mut samples[(y0 + j) * width + x0 + i];
            *s = (f64::from(*s) + bump).clamp(0.0, f64::from(u16::MAX)) as u16;
        }
    }
    [
        x0 as i64,
        y0 as i64,
        (x0 + brush) as i64,
        (y0 + brush) as i64,
    ]
}

/// Runs the measurement on the built-in mountain.
///
/// # Errors
/// Zero strokes or a zero brush.
pub fn run(opts: &EditOptions) -> Result<EditReport, String> {
    if opts.strokes == 0 || opts.brush == 0 {
        return Err("edit: strokes and brush must be at least 1".into());
    }
    let scene = scenes::builtin("mountain", opts.size).ok_or("mountain scene missing")?;
    let Nonlinear::Displaced(mut surface) = Nonlinear::<f32>::new(&scene) else {
        return Err("mountain is not a displacement scene".into());
    };
    // The mountain's map is square.
    let side = surface.field().width();
    let mut rng = Rng::stream(0x5eed);
    let mut partial = Vec::with_capacity(opts.strokes);
    for _ in 0..opts.strokes {
        let [x0, y0, x1, y1] = stroke(surface.field_mut(), opts.brush, &mut rng);
        let start = Instant::now();
        surface.field_mut().update_region(x0, y0, x1, y1);
        partial.push(start.elapsed().as_secs_f64());
    }
    let partial_max_seconds = partial.iter().copied().fold(0.0, f64::max);
    let partial_seconds = median(partial).unwrap_or(f64::NAN);
    // Verify before the full rebuilds below overwrite the partially updated pyramid.
    let (verified_rays, verify_mismatches) = verify(&scene, &surface);
    let mut rebuilds = Vec::new();
    for _ in 0..5 {
        let mut field = surface.field().clone();
        let start = Instant::now();
        field.rebuild();
        rebuilds.push(start.elapsed().as_secs_f64());
    }
    let mut edited = scene.clone();
    edited.content = Content::Displacement(surface.field().clone());
    let start = Instant::now();
    let image = crate::trace::geometry_image::geometry_image::<f32>(&edited);
    let geometry_image_seconds = start.elapsed().as_secs_f64();
    drop(image);
    let tessellated_seconds = opts.reference.then(|| {
        let start = Instant::now();
        let t = Tessellated::new(&edited);
        let seconds = start.elapsed().as_secs_f64();
        drop(t);
        seconds
    });
    Ok(EditReport {
        side,
        brush: opts.brush.min(side),
        strokes: opts.strokes,
        partial_seconds,
        partial_max_seconds,
        rebuild_seconds: median(rebuilds).unwrap_or(f64::NAN),
        tessellated_seconds,
        geometry_image_seconds,
        verified_rays,
        verify_mismatches,
    })
}

/// Camera rays (a 128^2 grid) through `updated` and through a surface built from scratch from
/// its samples: how many, and how many hit at different distances.
fn verify(scene: &Scene, updated: &DisplacedSurface<f32>) -> (usize, usize) {
    let field = updated.field();
    let fresh_field = HeightField::new(
        field.width(),
        field.height(),
        field.samples().to_vec(),
        field.wrap(),
    )
    .expect("samples of a valid field");
    let fresh = DisplacedSurface::new(
        updated.mesh().clone(),
        fresh_field,
        scene.height_scale as f32,
        scene.tiling as f32,
    )
    .expect("same parameters as the updated surface");
    let n = 128;
    let mut mismatches = 0;
    for k in 0..n * n {
        let (x, y) = ((k % n) as f64 + 0.5, (k / n) as f64 + 0.5);
        let d: DVec3 = scene.camera.direction(x / n as f64, y / n as f64, 1.0);
        let Some(ray) = Ray::new(scene.camera.eye.as_vec3(), d.as_vec3()) else {
            continue;
        };
        let trace = |s: &DisplacedSurface<f32>| {
            s.intersect(&ray, 0.0, f32::INFINITY, &mut TraversalStats::default())
                .map(|h| h.hit.t.to_bits())
        };
        if trace(updated) != trace(&fresh) {
            mismatches += 1;
        }
    }
    (n * n, mismatches)
}

/// The report as a Markdown table.
#[must_use]
pub fn markdown(r: &EditReport) -> String {
    let ms = |s: f64| format!("{:.3} ms", s * 1e3);
    let mut md = format!(
        "Mountain, {side}^2 map, {brush}^2-sample brush strokes ({strokes} timed, median; one thread).\n\n\
         | method | what an edit costs | time to traceable |\n|---|---|---|\n\
         | nonlinear (f32/f64) | partial min-max update over the stroke | {} (max {}) |\n\
         | tessellation-free (f32/f64) | the same pyramid, the same update | {} |\n\
         | either, without partial updates | full pyramid rebuild | {} |\n\
         | ray marching, tetrahedra, projective (f32/f64) | nothing: they read the samples only | 0 |\n",
        ms(r.partial_seconds),
        ms(r.partial_max_seconds),
        ms(r.partial_seconds),
        ms(r.rebuild_seconds),
        side = r.side,
        brush = r.brush,
        strokes = r.strokes,
    );
    md.push_str(&format!(
        "| geometry image f32 | re-sampling and pyramid rebuild (whole map) | {} |\n",
        ms(r.geometry_image_seconds)
    ));
    match r.tessellated_seconds {
        Some(s) => md.push_str(&format!(
            "| pre-tessellated f64 | re-tessellation and BVH build | {} |\n",
            ms(s)
        )),
        None => md.push_str("| pre-tessellated f64 | re-tessellation and BVH build | not measured (`--no-reference`) |\n"),
    }
    md.push_str(&format!(
        "\nVerified: {} camera rays through the updated surface and a surface built from scratch \
         from the same samples; {} hit at different distances.\n",
        r.verified_rays, r.verify_mismatches
    ));
    md
}
