//! The renderer: a pinhole camera and a small path tracer (diffuse and glossy surfaces, a sun
//! with next-event estimation and shadow rays, a sky, a configurable bounce count), so
//! incoherent secondary rays are measured as in the paper. Rays are generated and shaded in
//! f64; only the intersection runs in the method's precision, behind [`Tracer`].

use crate::scene::material::Rng;
use crate::scene::scenes::Scene;
use crate::trace::ray_stream::{RayKind, RayStream, StreamRay};
use crate::trace::tracer::Tracer;
use nlrt_poly::glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Render settings.
#[derive(Clone, Copy, Debug)]
pub struct RenderOptions {
    /// Width in pixels.
    pub width: usize,
    /// Height in pixels.
    pub height: usize,
    /// Samples per pixel (the first through the pixel centre, for the depth AOV).
    pub spp: usize,
    /// Diffuse bounces after the primary hit (each with a shadow ray).
    pub bounces: usize,
}

impl Default for RenderOptions {
    fn default() -> Self {
        Self {
            width: 320,
            height: 240,
            spp: 1,
            bounces: 1,
        }
    }
}

/// A rendered frame.
#[derive(Clone, Debug)]
pub struct Frame {
    /// Width.
    pub width: usize,
    /// Height.
    pub height: usize,
    /// Linear RGB per pixel.
    pub color: Vec<[f32; 3]>,
    /// Distance of the centre sample's primary hit (NaN: no hit).
    pub depth: Vec<f64>,
    /// Unit normal of the centre sample's primary hit, facing the camera (zero: no hit).
    pub normal: Vec<[f32; 3]>,
    /// Base triangle of the centre sample's primary hit ([`u32::MAX`]: no hit).
    pub hit_id: Vec<u32>,
    /// Primary rays cast.
    pub primary_rays: u64,
    /// All rays cast (primary, shadow, bounce).
    pub all_rays: u64,
    /// Wall-clock seconds of the render.
    pub seconds: f64,
}

/// Offset of secondary ray origins along the normal, relative to the scene's size (the
/// renderer's rule for every method; `nlrt_accel`'s `intersect_leaving` needs none): f32 hit
/// points carry a relative error of about 2^-24 times the conditioning of the hit (below
/// ~100 except at grazing angles), so about 1e-5 of the scene; 1e-4 leaves a factor 10 and
/// stays well below the finest displacement detail (a texel of a 4096^2 map on a 2-unit
/// mesh is 5e-4).
pub const SECONDARY_OFFSET: f64 = 1e-4;

/// The distance the renderer moves a secondary ray's origin along the hit's normal:
/// [`SECONDARY_OFFSET`] times the length of the scene's bounding box diagonal.
#[must_use]
pub fn secondary_offset(scene: &Scene) -> f64 {
    let lo = scene
        .positions
        .iter()
        .fold(DVec3::INFINITY, |a, &p| a.min(p));
    let hi = scene
        .positions
        .iter()
        .fold(DVec3::NEG_INFINITY, |a, &p| a.max(p));
    SECONDARY_OFFSET * (hi - lo).length().max(1e-9)
}

fn sky(dir: DVec3) -> DVec3 {
    let t = (dir.y * 0.5 + 0.5).clamp(0.0, 1.0);
    DVec3::new(0.55, 0.6, 0.7) * (1.0 - t) + DVec3::new(0.35, 0.5, 0.9) * t
}

/// Renders `scene` with `tracer`; `progress` is called with the number of rows finished.
pub fn render(
    scene: &Scene,
    tracer: &dyn Tracer,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Frame {
    render_with(scene, tracer, opts, progress, false).0
}

/// [`render`], also recording every ray it casts (for [`crate::trace::ray_stream::replay`]); the
/// frame's time includes the recording.
#[must_use]
pub fn render_recording(
    scene: &Scene,
    tracer: &dyn Tracer,
    opts: &RenderOptions,
) -> (Frame, RayStream) {
    render_with(scene, tracer, opts, &|_| {}, true)
}

fn render_with(
    scene: &Scene,
    tracer: &dyn Tracer,
    opts: &RenderOptions,
    progress: &(dyn Fn(usize) + Sync),
    record: bool,
) -> (Frame, RayStream) {
    let (w, h) = (opts.width, opts.height);
    let aspect = w as f64 / h as f64;
    let offset = secondary_offset(scene);
    let sun_radiance = DVec3::new(1.15, 1.05, 0.95);
    let primary = AtomicU64::new(0);
    let all = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let start = std::time::Instant::now();
    type Row = (
        Vec<[f32; 3]>,
        Vec<f64>,
        Vec<([f32; 3], u32)>,
        Vec<StreamRay>,
    );
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut colors = Vec::with_capacity(w);
            let mut depths = Vec::with_capacity(w);
            let mut aovs = Vec::with_capacity(w);
            let mut recorded = Vec::new();
            let mut cast = |origin: DVec3, dir: DVec3, kind: RayKind| {
                if record {
                    recorded.push(StreamRay { origin, dir, kind });
                }
            };
            let (mut n_primary, mut n_all) = (0u64, 0u64);
            for x in 0..w {
                let mut rng = Rng::stream((y * w + x) as u64);
                let mut sum = DVec3::ZERO;
                let mut depth = f64::NAN;
                let mut aov = ([0.0f32; 3], u32::MAX);
                for s in 0..opts.spp.max(1) {
                    let (jx, jy) = if s == 0 {
                        (0.5, 0.5)
                    } else {
                        (rng.next_f64(), rng.next_f64())
                    };
                    let dir = scene.camera.direction(
                        (x as f64 + jx) / w as f64,
                        (y as f64 + jy) / h as f64,
                        aspect,
                    );
                    let mut origin = scene.camera.eye;
                    let mut dir = dir;
                    let mut throughput = DVec3::ONE;
                    n_primary += 1;
                    for bounce in 0..=opts.bounces {
                        n_all += 1;
                        let kind = if bounce == 0 {
                            RayKind::Primary
                        } else {
                            RayKind::Bounce
                        };
                        cast(origin, dir, kind);
                        let Some(hit) = tracer.intersect(origin, dir, 0.0, f64::INFINITY) else {
                            sum += throughput * sky(dir);
                            break;
                        };
                        let n = hit.normal;
                        let material = scene.material_of(hit.id);
                        if s == 0 && bounce == 0 {
                            depth = hit.t;
                            aov = ([n.x as f32, n.y as f32, n.z as f32], hit.id);
                        }
                        let p = origin + dir * hit.t + n * offset;
                        // Next-event estimation towards the sun: BRDF times the sun's
                        // irradiance (pi * sun_radiance, so that a white diffuse surface facing
                        // it reflects sun_radiance) times the cosine.
                        let cos = n.dot(scene.sun);
                        if cos > 0.0 {
                            n_all += 1;
                            // A shadow ray asks only whether anything is in the way.
                            cast(p, scene.sun, RayKind::Shadow);
                            if !tracer.occluded(p, scene.sun, 0.0, f64::INFINITY) {
                                let brdf_pi = material.brdf_times_pi(n, dir, scene.sun);
                                sum += throughput * sun_radiance * (brdf_pi * cos);
                            }
                        }
                        if bounce == opts.bounces {
                            break;
                        }
                        let Some((next, weight)) = material.sample(n, dir, &mut rng) else {
                            break;
                        };
                        throughput *= weight;
                        origin = p;
                        dir = next;
                    }
                }
                let c = sum / opts.spp.max(1) as f64;
                colors.push([c.x as f32, c.y as f32, c.z as f32]);
                depths.push(depth);
                aovs.push(aov);
            }
            primary.fetch_add(n_primary, Ordering::Relaxed);
            all.fetch_add(n_all, Ordering::Relaxed);
            progress(rows_done.fetch_add(1, Ordering::Relaxed) as usize + 1);
            (colors, depths, aovs, recorded)
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let mut color = Vec::with_capacity(w * h);
    let mut depth = Vec::with_capacity(w * h);
    let (mut normal, mut hit_id) = (Vec::with_capacity(w * h), Vec::with_capacity(w * h));
    let mut stream = RayStream::default();
    for (c, d, a, r) in rows {
        stream.rays.extend(r);
        color.extend(c);
        depth.extend(d);
        for (n, id) in a {
            normal.push(n);
            hit_id.push(id);
        }
    }
    let frame = Frame {
        width: w,
        height: h,
        color,
        depth,
        normal,
        hit_id,
        primary_rays: primary.into_inner(),
        all_rays: all.into_inner(),
        seconds,
    };
    (frame, stream)
}
