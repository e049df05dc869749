//! The surfaces' queries for rays that leave them (shadow and bounce rays started at the hit
//! point): [`DisplacedSurface::intersect_leaving`], [`ShellSurface::intersect_leaving`] and
//! their occlusion forms, over the exclusion of `crate::leaving`.

use nlrt_poly::{Real, Vector3};
use nlrt_shellmap::Ray;

use crate::displacement::DisplacedSurface;
use crate::leaving::{Element, Origin, TOUCH_RADIUS, Touch, texel_length, up_crossing};
use crate::shell::{ShellHit, ShellSurface};
use crate::stats::TraversalStats;
use crate::surface_hit::{SurfaceHit, TexelPart};
use crate::tlas::Query;

impl<T: Real> DisplacedSurface<T> {
    /// The nearest hit of a ray that leaves the surface where it was hit at `from` (a bounce
    /// ray): `ray` starts at `from`'s point as the caller computed it (the incoming ray at
    /// `from.hit.t`), with no offset, and `from`'s element (its microtriangle, flat texel or
    /// seam wall piece) is excluded by its id (`crate::leaving`), so that the ray cannot hit
    /// the surface it starts on whatever the rounding of its origin and its angle. Distances
    /// in `[0, t_max]`.
    ///
    /// ```
    /// use nlrt_accel::{BaseMesh, DisplacedSurface, HeightField, TraversalStats, Wrap};
    /// use nlrt_poly::glam::{DVec2, DVec3};
    /// use nlrt_shellmap::Ray;
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Repeat).unwrap();
    /// let surface = DisplacedSurface::new(mesh, field, 0.5, 1.0).unwrap();
    /// let stats = &mut TraversalStats::default();
    /// let down = Ray::new(DVec3::new(0.3, 0.6, 2.0), -DVec3::Z).unwrap();
    /// let hit = surface.intersect(&down, 0.0, f64::INFINITY, stats).unwrap();
    /// // A ray leaving the plane from the hit point, grazing: the plain query finds the
    /// // plane it starts on at once.
    /// let along = Ray::new(down.at(hit.hit.t), DVec3::new(1.0, 0.2, 0.01)).unwrap();
    /// assert!(surface.intersect(&along, 0.0, f64::INFINITY, stats).is_some());
    /// assert!(surface.intersect_leaving(&along, &hit, f64::INFINITY, stats).is_none());
    /// assert!(!surface.occluded_leaving(&along, &hit, f64::INFINITY, stats));
    /// ```
    pub fn intersect_leaving(
        &self,
        ray: &Ray<T>,
        from: &SurfaceHit<T>,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<SurfaceHit<T>> {
        let origin = self.origin(from, ray.dir);
        self.walk_tlas(ray, [T::ZERO, t_max], Query::Nearest, Some(&origin), stats)
    }

    /// Whether a ray leaving the surface at `from` meets it at a distance in `[0, t_max]` (a
    /// shadow ray): [`DisplacedSurface::intersect_leaving`] as an occlusion query.
    pub fn occluded_leaving(
        &self,
        ray: &Ray<T>,
        from: &SurfaceHit<T>,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> bool {
        let origin = self.origin(from, ray.dir);
        self.walk_tlas(ray, [T::ZERO, t_max], Query::Any, Some(&origin), stats)
            .is_some()
    }

    /// The distance (in units of the ray parameter) within which a ray leaving the surface
    /// at `from` in direction `dir` does not take a neighbouring microtriangle that it
    /// crosses towards the side it left to ([`DisplacedSurface::intersect_leaving`]: a touch
    /// at its origin, where the origin lies on their shared edge or corner or within its
    /// rounding of one), or the other prism of a seam meets the wall it leaves: 1/16 of a
    /// texel's world length at the origin. `None` where the element hit is degenerate.
    #[must_use]
    pub fn leaving_touch_distance(&self, from: &SurfaceHit<T>, dir: T::Vec3) -> Option<f64> {
        self.origin(from, dir).touch.map(|touch| touch.within)
    }

    /// [`DisplacedSurface::intersect_leaving`] testing every texel of every triangle (the
    /// reference for tests).
    #[must_use]
    pub fn intersect_leaving_brute_force(
        &self,
        ray: &Ray<T>,
        from: &SurfaceHit<T>,
        t_max: T,
    ) -> Option<SurfaceHit<T>> {
        self.brute_force(ray, [T::ZERO, t_max], Some(&self.origin(from, ray.dir)))
    }

    /// The element of `from`, as a ray leaving it in direction `dir` excludes it: on a
    /// microtriangle or flat texel with the side it leaves to and the ray parameter of a
    /// touch at the origin (`crate::leaving`).
    fn origin(&self, from: &SurfaceHit<T>, dir: T::Vec3) -> Origin {
        let plane = self.element_plane(from);
        let touch = plane.map(|(prism, abh)| {
            let point = [from.hit.alpha, from.hit.beta, from.hit.h];
            let texel = texel_length(&prism, from.hit.h, self.texel_size.to_f64());
            Touch {
                leaves_up: (!matches!(from.part, TexelPart::Wall { .. }))
                    .then(|| up_crossing(&prism, &abh, point, dir) >= T::ZERO),
                within: TOUCH_RADIUS * texel / dir.length().to_f64(),
            }
        });
        let seam = match from.part {
            TexelPart::Wall { edge } => self
                .seams
                .of_triangle(from.triangle as usize)
                .map(|walls| walls[usize::from(edge)]),
            _ => None,
        };
        Origin {
            triangle: from.triangle,
            element: Element {
                cell: from.texel,
                index: from.part.index(),
            },
            touch,
            seam,
        }
    }
}

impl<T: Real> ShellSurface<T> {
    /// The nearest hit of a ray that leaves the object where it was hit at `from` (a bounce
    /// ray): `ray` starts at `from`'s point as the caller computed it, with no offset, and
    /// `from`'s object triangle in its tile is excluded by its id (`crate::leaving`), so that
    /// the ray cannot hit the triangle it starts on. Distances in `[0, t_max]`.
    pub fn intersect_leaving(
        &self,
        ray: &Ray<T>,
        from: &ShellHit<T>,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> Option<ShellHit<T>> {
        let origin = from.origin();
        self.walk_tlas(ray, [T::ZERO, t_max], Query::Nearest, Some(&origin), stats)
    }

    /// Whether a ray leaving the object at `from` meets it at a distance in `[0, t_max]` (a
    /// shadow ray): [`ShellSurface::intersect_leaving`] as an occlusion query.
    pub fn occluded_leaving(
        &self,
        ray: &Ray<T>,
        from: &ShellHit<T>,
        t_max: T,
        stats: &mut TraversalStats,
    ) -> bool {
        let origin = from.origin();
        self.walk_tlas(ray, [T::ZERO, t_max], Query::Any, Some(&origin), stats)
            .is_some()
    }

    /// [`ShellSurface::intersect_leaving`] by brute force (the reference for tests).
    #[must_use]
    pub fn intersect_leaving_brute_force(
        &self,
        ray: &Ray<T>,
        from: &ShellHit<T>,
        t_max: T,
    ) -> Option<ShellHit<T>> {
        self.brute_force(ray, [T::ZERO, t_max], Some(&from.origin()))
    }
}

impl<T: Real> ShellHit<T> {
    /// The element hit, as a ray leaving it excludes it.
    #[must_use]
    pub(crate) fn origin(&self) -> Origin {
        Origin {
            triangle: self.triangle,
            element: Element {
                cell: self.tile,
                index: self.object_triangle,
            },
            touch: None,
            seam: None,
        }
    }
}
