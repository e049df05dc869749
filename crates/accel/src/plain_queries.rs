//! The queries without counters: [`TraversalStats`] is kept by every walk, but a renderer
//! rarely reads it.

use nlrt_poly::Real;
use nlrt_shellmap::Ray;

use crate::displacement::DisplacedSurface;
use crate::shell::{ShellHit, ShellSurface};
use crate::stats::TraversalStats;
use crate::surface_hit::SurfaceHit;

impl<T: Real> DisplacedSurface<T> {
    /// The nearest hit with `t` in `[t_min, t_max]`, without counters: as
    /// [`DisplacedSurface::intersect`], whose [`TraversalStats`] a renderer rarely reads.
    ///
    /// ```
    /// use nlrt_accel::glam::{DVec2, DVec3};
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, Ray, Wrap};
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Clamp).unwrap();
    /// let surface = DisplacedSurface::new(mesh, field, 0.5, 1.0).unwrap();
    /// let ray = Ray::new(DVec3::new(0.3, 0.6, 2.0), -DVec3::Z).unwrap();
    /// let hit = surface.nearest_hit(&ray, 0.0, f64::INFINITY).unwrap();
    /// assert_eq!(hit.position(&ray), DVec3::new(0.3, 0.6, 0.5));
    /// assert!(surface.any_hit(&ray, 0.0, 2.0) && !surface.any_hit(&ray, 0.0, 1.0));
    /// ```
    #[must_use]
    pub fn nearest_hit(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<SurfaceHit<T>> {
        self.intersect(ray, t_min, t_max, &mut TraversalStats::default())
    }

    /// Whether `ray` meets the surface at some `t` in `[t_min, t_max]`, without counters: as
    /// [`DisplacedSurface::occluded`].
    #[must_use]
    pub fn any_hit(&self, ray: &Ray<T>, t_min: T, t_max: T) -> bool {
        self.occluded(ray, t_min, t_max, &mut TraversalStats::default())
    }
}

impl<T: Real> ShellSurface<T> {
    /// The nearest hit with `t` in `[t_min, t_max]`, without counters: as
    /// [`ShellSurface::intersect`].
    #[must_use]
    pub fn nearest_hit(&self, ray: &Ray<T>, t_min: T, t_max: T) -> Option<ShellHit<T>> {
        self.intersect(ray, t_min, t_max, &mut TraversalStats::default())
    }

    /// Whether `ray` meets the object at some `t` in `[t_min, t_max]`, without counters: as
    /// [`ShellSurface::occluded`].
    #[must_use]
    pub fn any_hit(&self, ray: &Ray<T>, t_min: T, t_max: T) -> bool {
        self.occluded(ray, t_min, t_max, &mut TraversalStats::default())
    }
}
