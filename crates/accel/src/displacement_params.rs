//! A displaced surface's parameters by name ([`Displacement`]) and the constructor that
//! takes them.

use nlrt_poly::Real;

use crate::displacement::{DisplacedSurface, DisplacementError};
use crate::heightfield::HeightField;
use crate::mesh::BaseMesh;
use crate::seam::SeamRule;

/// How a height map displaces a base mesh: the named form of the arguments of
/// [`DisplacedSurface::with_midlevel`], for [`DisplacedSurface::with_displacement`]. Start
/// from [`Displacement::new`] (a height scale; tiling 1, midlevel 0, seams closed) and change
/// what differs.
///
/// ```
/// use nlrt_accel::{Displacement, SeamRule};
/// let d = Displacement { tiling: 4.0, midlevel: 0.5, ..Displacement::new(0.1f64) };
/// assert_eq!((d.height_scale, d.seam_rule), (0.1, SeamRule::Closed));
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Displacement<T> {
    /// The world length of a height of 1 (samples of 65535) along the mesh's normals.
    pub height_scale: T,
    /// How many times the map repeats per unit of uv, along u and v alike.
    pub tiling: T,
    /// The height in `[0, 1]` that stays on the base mesh (0: the map only pushes out).
    pub midlevel: T,
    /// How uv and normal seams are treated ([`SeamRule::Closed`]: crack-free).
    pub seam_rule: SeamRule,
}

impl<T: Real> Displacement<T> {
    /// `height_scale`, with a tiling of 1, midlevel 0 and closed seams.
    #[must_use]
    pub fn new(height_scale: T) -> Self {
        Self {
            height_scale,
            tiling: T::ONE,
            midlevel: T::ZERO,
            seam_rule: SeamRule::Closed,
        }
    }
}

impl<T: Real> DisplacedSurface<T> {
    /// The surface `displacement` describes: [`DisplacedSurface::with_midlevel`] with named
    /// arguments.
    ///
    /// ```
    /// use nlrt_accel::glam::{DVec2, DVec3};
    /// use nlrt_accel::{BaseMesh, Displacement, DisplacedSurface, HeightField, Ray, Wrap};
    /// let p = vec![DVec3::ZERO, DVec3::X, DVec3::new(1.0, 1.0, 0.0), DVec3::Y];
    /// let uv = p.iter().map(|p| DVec2::new(p.x, p.y)).collect();
    /// let mesh = BaseMesh::new(p, vec![DVec3::Z; 4], uv, vec![[0, 1, 2], [0, 2, 3]]).unwrap();
    /// let field = HeightField::new(4, 4, vec![u16::MAX; 16], Wrap::Clamp).unwrap();
    /// let push_in_and_out = Displacement { midlevel: 0.5, ..Displacement::new(2.0) };
    /// let surface = DisplacedSurface::with_displacement(mesh, field, push_in_and_out).unwrap();
    /// let ray = Ray::new(DVec3::new(0.3, 0.6, 3.0), -DVec3::Z).unwrap();
    /// assert_eq!(surface.nearest_hit(&ray, 0.0, f64::INFINITY).unwrap().t(), 2.0);
    /// ```
    ///
    /// # Errors
    /// As [`DisplacedSurface::with_midlevel`].
    pub fn with_displacement(
        mesh: BaseMesh<T>,
        field: HeightField,
        displacement: Displacement<T>,
    ) -> Result<Self, DisplacementError> {
        let Displacement {
            height_scale,
            tiling,
            midlevel,
            seam_rule,
        } = displacement;
        Self::with_midlevel(mesh, field, height_scale, tiling, seam_rule, midlevel)
    }
}
