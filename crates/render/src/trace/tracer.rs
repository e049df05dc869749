//! The interface every method is traced through: a ray in f64 in, the nearest hit out
//! ([`Tracer`]), with the conversions of a renderer ray into a method's precision.

use nlrt_poly::glam::DVec3;
use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;

/// A hit as the renderer sees it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraceHit {
    /// Distance along the ray.
    pub t: f64,
    /// Unit normal facing against the ray.
    pub normal: DVec3,
    /// Base triangle hit (the hit-id AOV).
    pub id: u32,
}

impl TraceHit {
    /// A hit found in precision `T`: distance, unit normal facing against the ray, base
    /// triangle.
    #[must_use]
    pub(crate) fn from_precision<T: Real>(t: T, normal: T::Vec3, id: u32) -> Self {
        Self {
            t: t.to_f64(),
            normal: normal.to_dvec3(),
            id,
        }
    }
}

/// A renderer ray (f64) in precision `T` with its distance range (an infinite `t_max` stays
/// infinite); `None` for a zero or non-finite direction.
pub(crate) fn ray_in<T: Real>(
    origin: DVec3,
    dir: DVec3,
    t_min: f64,
    t_max: f64,
) -> Option<(Ray<T>, T, T)> {
    let v = |a: DVec3| T::Vec3::new(T::from_f64(a.x), T::from_f64(a.y), T::from_f64(a.z));
    let t_max = if t_max.is_finite() {
        T::from_f64(t_max)
    } else {
        T::INFINITY
    };
    Some((Ray::new(v(origin), v(dir))?, T::from_f64(t_min), t_max))
}

/// Intersection of a ray with the scene.
pub trait Tracer: Sync {
    /// Nearest hit with distance in `(t_min, t_max]`.
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit>;
    /// Bytes of acceleration data.
    fn memory_bytes(&self) -> usize;
    /// Whether the ray meets the scene at some distance in `(t_min, t_max]` (a shadow ray's
    /// query). The default asks [`Tracer::intersect`]; a method may stop at the first hit it
    /// finds.
    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        self.intersect(origin, dir, t_min, t_max).is_some()
    }
}

impl<Tr: Tracer + ?Sized> Tracer for &Tr {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        (**self).intersect(origin, dir, t_min, t_max)
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        (**self).occluded(origin, dir, t_min, t_max)
    }

    fn memory_bytes(&self) -> usize {
        (**self).memory_bytes()
    }
}

impl<Tr: Tracer + ?Sized> Tracer for Box<Tr> {
    fn intersect(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> Option<TraceHit> {
        (**self).intersect(origin, dir, t_min, t_max)
    }

    fn occluded(&self, origin: DVec3, dir: DVec3, t_min: f64, t_max: f64) -> bool {
        (**self).occluded(origin, dir, t_min, t_max)
    }

    fn memory_bytes(&self) -> usize {
        (**self).memory_bytes()
    }
}
