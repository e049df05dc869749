//! A hit on a displaced surface: where it lies and which element of which texel it is.

use nlrt_poly::Real;
use nlrt_shellmap::{Hit, Ray};

#[cfg(doc)]
use crate::seam::SeamRule;

/// Which part of a texel was hit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TexelPart {
    /// The microtriangle `(x, y), (x + 1, y), (x + 1, y + 1)`.
    Lower,
    /// The microtriangle `(x, y), (x + 1, y + 1), (x, y + 1)`.
    Upper,
    /// The whole texel, flat (all four corners at one height; sec. 5.4).
    Flat,
    /// The seam wall on base edge `edge` ([`crate::EDGE_VERTICES`]) of the hit's triangle,
    /// between the two sides' heights ([`SeamRule::Closed`]); `texel` is the texel of this
    /// side at the hit.
    Wall {
        /// The base edge.
        edge: u8,
    },
}

impl TexelPart {
    /// The part's index among the texel's elements (`crate::leaving`): the two
    /// microtriangles, the flat texel, the seam walls of the three base edges.
    #[must_use]
    pub(crate) fn index(self) -> u32 {
        match self {
            Self::Lower => 0,
            Self::Upper => 1,
            Self::Flat => 2,
            Self::Wall { edge } => 3 + u32::from(edge),
        }
    }
}

/// A hit on a displaced surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit<T: Real> {
    /// The hit in the prism's coordinates.
    pub hit: Hit<T>,
    /// Base triangle.
    pub triangle: u32,
    /// Texel (in the infinite, tiled grid).
    pub texel: [i32; 2],
    /// Part of the texel.
    pub part: TexelPart,
}

impl<T: Real> SurfaceHit<T> {
    /// The distance along the ray (`hit.t`).
    #[must_use]
    pub fn t(&self) -> T {
        self.hit.t
    }

    /// The hit's world position on `ray`, the ray that found it (`origin + t dir`).
    #[must_use]
    pub fn position(&self, ray: &Ray<T>) -> T::Vec3 {
        ray.at(self.hit.t)
    }
}
