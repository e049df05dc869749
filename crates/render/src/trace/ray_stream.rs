//! A recorded ray stream: every ray one render cast (primary, shadow, bounce), in the
//! render's order, replayed into any tracer so that methods are timed on the same rays. A
//! render's secondary rays depend on where its method hit, so timing each method's own render
//! compares different rays; replaying one stream does not.
//!
//! ```
//! use nlrt_render::trace::integrator::{RenderOptions, render_recording};
//! use nlrt_render::trace::ray_stream::{RayKind, replay};
//! use nlrt_render::scene::scenes::{Size, builtin};
//! use nlrt_render::trace::methods::Nonlinear;
//!
//! let scene = builtin("torus", Size::Small).unwrap();
//! let tracer = Nonlinear::<f32>::new(&scene);
//! let opts = RenderOptions { width: 16, height: 12, spp: 1, bounces: 1 };
//! let (frame, stream) = render_recording(&scene, &tracer, &opts);
//! assert_eq!(stream.len() as u64, frame.all_rays);
//! // The same rays into the f64 tracer: its hits on the primary rays.
//! let f64_tracer = Nonlinear::<f64>::new(&scene);
//! let primary = replay(&f64_tracer, &stream, Some(RayKind::Primary));
//! assert_eq!(primary.rays, frame.primary_rays);
//! ```

use crate::trace::tracer::Tracer;
use nlrt_poly::glam::DVec3;
use rayon::prelude::*;

/// What a ray of a render was for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayKind {
    /// From the camera.
    Primary,
    /// From a hit towards the sun.
    Shadow,
    /// From a hit in a sampled direction.
    Bounce,
}

/// One ray of a stream: origin, direction and kind (distance range `[0, inf)`, as the
/// renderer casts every ray).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StreamRay {
    /// Origin.
    pub origin: DVec3,
    /// Direction (not necessarily unit).
    pub dir: DVec3,
    /// What it was for.
    pub kind: RayKind,
}

/// The rays of one render, in the order each pixel row cast them, rows in image order.
#[derive(Clone, Debug, Default)]
pub struct RayStream {
    pub(crate) rays: Vec<StreamRay>,
}

impl RayStream {
    /// Rays in the stream.
    #[must_use]
    pub fn len(&self) -> usize {
        self.rays.len()
    }

    /// Whether the stream holds no ray.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// The rays.
    #[must_use]
    pub fn rays(&self) -> &[StreamRay] {
        &self.rays
    }

    /// Rays of `kind`.
    #[must_use]
    pub fn count(&self, kind: RayKind) -> u64 {
        self.rays.iter().filter(|r| r.kind == kind).count() as u64
    }
}

/// A replay of a stream into one tracer.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Replay {
    /// Rays traced.
    pub rays: u64,
    /// Rays that hit.
    pub hits: u64,
    /// Wall-clock seconds.
    pub seconds: f64,
}

impl Replay {
    /// Million rays per second.
    #[must_use]
    pub fn mrays(&self) -> f64 {
        self.rays as f64 / self.seconds / 1e6
    }
}

/// Rays per parallel work item: consecutive rays of a stream (a run of neighbouring pixels'
/// rays) stay together as in the render, which hands each thread whole rows.
const CHUNK: usize = 256;

/// Traces the rays of `stream` (only those of `kind`, when given) with `tracer` on the current
/// rayon pool, in chunks of consecutive rays; times the tracing alone.
#[must_use]
pub fn replay(tracer: &dyn Tracer, stream: &RayStream, kind: Option<RayKind>) -> Replay {
    // Only a subset is copied (before the clock starts); every ray is traced in place.
    let subset: Vec<StreamRay>;
    let rays: &[StreamRay] = match kind {
        Some(k) => {
            subset = stream
                .rays
                .iter()
                .copied()
                .filter(|r| r.kind == k)
                .collect();
            &subset
        }
        None => &stream.rays,
    };
    let start = std::time::Instant::now();
    let hits: u64 = rays
        .par_chunks(CHUNK)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|r| match r.kind {
                    // As the render asks them: a shadow ray only whether it is blocked.
                    RayKind::Shadow => tracer.occluded(r.origin, r.dir, 0.0, f64::INFINITY),
                    _ => tracer
                        .intersect(r.origin, r.dir, 0.0, f64::INFINITY)
                        .is_some(),
                })
                .count() as u64
        })
        .sum();
    Replay {
        rays: rays.len() as u64,
        hits,
        seconds: start.elapsed().as_secs_f64(),
    }
}
