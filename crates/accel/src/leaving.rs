//! Rays that leave a surface (shadow and bounce rays): the ray starts at its hit point, on
//! the element it was hit on (a microtriangle, a seam wall's piece or an object triangle),
//! and that element is excluded from its hits by its id, instead of the origin being moved
//! off the surface by an offset. An offset must outgrow the hit point's rounding error at
//! every angle and must stay below the thinnest feature and the narrowest crevice of the
//! scene; a ray that cannot hit its own element needs neither.
//!
//! Excluding the element alone is not enough where the origin lies on an edge or corner it
//! shares with neighbours (or within its rounding of one): the ray then touches a neighbour
//! at once. On a displaced surface, one sheet whose sides are named by the height (up is
//! the side the displacement directions point to, on every base triangle, across uv seams
//! too), such a touch is a crossing towards the side the ray left to, which a ray meeting
//! the sheet first never makes: it is not taken near the origin ([`Exclusion::skips`]).
//!
//! An element is named by its cell (texel or tile, in the tiled grid of the base triangle's
//! uv) and its index in the cell. A cell straddling base triangles has a piece in each of
//! them: the triangles that share a vertex with the origin's triangle share its uv there, so
//! the same cell and index name the same element's piece in them, judged as a neighbour on a
//! displaced surface and excluded on a shell-mapped one (an object triangle has no side the
//! ray is known to leave to). A triangle that shares no vertex (beyond a uv seam, or another
//! uv island) names other elements by the same numbers: nothing is excluded by id there.

use nlrt_poly::{Real, Vector2, Vector3};
use nlrt_shellmap::{Prism, world_normal};

use crate::mesh::BaseMesh;

/// An element of a cell: `index` in cell `cell` (a texel's microtriangle, flat texel or
/// seam wall; a tile's object triangle).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Element {
    /// The cell (texel or tile) in the tiled grid.
    pub(crate) cell: [i32; 2],
    /// The element in the cell.
    pub(crate) index: u32,
}

/// The element a ray leaves, in the base triangle it was hit in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Origin {
    /// The base triangle of the hit.
    pub(crate) triangle: u32,
    /// The element hit.
    pub(crate) element: Element,
    /// On a displaced surface, the ray parameter within which a crossing is a touch at the
    /// origin and the side the ray leaves to: see [`Exclusion::skips`]. `None` elsewhere
    /// (an object's triangles have no common up).
    pub(crate) touch: Option<Touch>,
    /// The seam whose wall the origin lies on (both prisms of a seam test its wall, each
    /// naming it by its own triangle and texel).
    pub(crate) seam: Option<u32>,
}

/// How a ray leaving a displaced surface may touch it at its origin.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Touch {
    /// Whether the ray leaves its element upwards (towards larger `h`); `None` for a seam
    /// wall, which has no up.
    pub(crate) leaves_up: Option<bool>,
    /// The ray parameter of [`TOUCH_RADIUS`] texels at the origin.
    pub(crate) within: f64,
}

/// What a ray leaving `Origin` does not hit in one base triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Exclusion {
    element: Element,
    touch: Option<Touch>,
    seam: Option<u32>,
    /// Whether the element's id names the origin's element here: the origin's own base
    /// triangle, or one sharing a vertex with it (its uv).
    same_chart: bool,
    /// Whether the base triangle is the origin's own.
    own_triangle: bool,
}

/// How far from the origin, in texels, a neighbour's crossing may be the ray touching it
/// at the origin: beyond the origin's rounding error in texels wherever it can be traced. A
/// base triangle spans at most 2^16 texels per axis (set-up refuses more), where an `f32`
/// texel coordinate's ulp is 2^-7 texel and the hit point carries a few of them; 1/16 texel
/// is four times that.
pub(crate) const TOUCH_RADIUS: f64 = 1.0 / 16.0;

/// The elements of a texel that are pieces of the displaced sheet: the two microtriangles
/// and the flat texel (`TexelPart::index`); seam walls follow.
const SHEET_ELEMENTS: u32 = 3;

impl Origin {
    /// What is excluded in base triangle `tri`: the origin's element by its id where `tri`
    /// is the origin's triangle or shares a vertex with it (the same uv around that vertex,
    /// so the same numbers name the same element); on a displaced surface, touches at the
    /// origin in every triangle.
    #[must_use]
    pub(crate) fn excluded_in<T: Real>(&self, mesh: &BaseMesh<T>, tri: usize) -> Option<Exclusion> {
        let own = self.triangle as usize;
        let same_chart = tri == own
            || (own < mesh.triangle_count() && {
                let (a, b) = (mesh.triangle(own), mesh.triangle(tri));
                a.iter().any(|v| b.contains(v))
            });
        (same_chart || self.touch.is_some()).then_some(Exclusion {
            element: self.element,
            touch: self.touch,
            seam: self.seam,
            same_chart,
            own_triangle: tri == own,
        })
    }
}

impl Exclusion {
    /// Whether `index` in `cell` is never hit: the origin's element, by its id. On a
    /// displaced surface a texel's piece only in the origin's own base triangle (a seam wall
    /// in any sharing a vertex): the same texel's piece in a neighbouring triangle is mapped
    /// by that triangle's prism, a piece of its own that meets the origin's along their base
    /// edge, and is judged as a neighbour is ([`Exclusion::skips`]).
    #[must_use]
    #[inline]
    pub(crate) fn excludes(&self, cell: [i32; 2], index: u32) -> bool {
        self.same_chart
            && self.element == Element { cell, index }
            && (self.own_triangle || self.touch.is_none() || index >= SHEET_ELEMENTS)
    }

    /// Whether a hit on `index` in `cell` at ray parameter `t` is not taken: the excluded
    /// element ([`Exclusion::excludes`]); on a displaced surface also a microtriangle or
    /// flat texel met within [`TOUCH_RADIUS`] texels of the origin (one that may hold the
    /// origin: it lies on their shared edges and corners, or within its rounding of them)
    /// that the ray crosses towards the side it left its own element to (`crossing`: the
    /// rate at which the ray climbs above the element's plane, `d/dt (h - H(u, v))`, where
    /// it meets it). Such a crossing is the ray touching the surface at its origin: a ray
    /// leaving a sheet upwards is below a neighbouring element only after it has crossed the
    /// sheet downwards, which is the nearer hit. A crossing the other way (the ray enters
    /// the neighbour: a valley's other face, met at once by a grazing ray) is a hit.
    #[must_use]
    #[inline]
    pub(crate) fn skips<T: Real>(
        &self,
        cell: [i32; 2],
        index: u32,
        t: f64,
        crossing: impl FnOnce() -> T,
    ) -> bool {
        if self.excludes(cell, index) {
            return true;
        }
        let Some(Touch {
            leaves_up: Some(up),
            within,
        }) = self.touch
        else {
            return false;
        };
        if index >= SHEET_ELEMENTS || !(t <= within) {
            return false;
        }
        let c = crossing();
        let enters = if up { c < T::ZERO } else { c > T::ZERO };
        !enters
    }

    /// Whether a crossing of seam `seam`'s wall at ray parameter `t` is not taken: the
    /// origin lies on that wall and the crossing is within a touch of it (the other prism of
    /// the seam meeting the same wall at the origin).
    #[must_use]
    #[inline]
    pub(crate) fn skips_wall(&self, seam: u32, t: f64) -> bool {
        self.seam == Some(seam) && self.touch.is_some_and(|touch| t <= touch.within)
    }
}

/// The world length of a texel at height `h` of `prism`, whose uv spans `texel_size` per
/// texel: the longest ratio of an edge's world length to its uv length (edges without uv
/// length left out; 0 if all are).
#[must_use]
pub(crate) fn texel_length<T: Real>(prism: &Prism<T>, h: T, texel_size: f64) -> f64 {
    let mut longest: f64 = 0.0;
    for (i, j) in [(0, 1), (1, 2), (2, 0)] {
        let world = (prism.vertex(j, h) - prism.vertex(i, h)).length().to_f64();
        let duv = prism.uv[j] - prism.uv[i];
        let uv = duv.x().mul_add(duv.x(), duv.y() * duv.y()).sqrt().to_f64();
        if uv > 0.0 {
            longest = longest.max(world / uv);
        }
    }
    longest * texel_size
}

/// `d/dt` of the height above the plane `abh` (in `prism`'s canonical coordinates, its
/// height coefficient positive) of a ray with direction `dir` at the canonical point
/// `(alpha, beta, h)`, up to a positive factor: the world normal of Eq. 13 (the plane's
/// gradient through `M^-T`, times `det M`) dotted with `dir`, times the sign of `det M`.
#[must_use]
pub(crate) fn up_crossing<T: Real>(
    prism: &Prism<T>,
    abh: &[T; 4],
    [alpha, beta, h]: [T; 3],
    dir: T::Vec3,
) -> T {
    let rate = world_normal(prism, abh, alpha, beta, h).dot(dir);
    let s0 = prism.vertex(0, h);
    let (e0, e1) = (prism.vertex(1, h) - s0, prism.vertex(2, h) - s0);
    let ns = prism.n[0] + (prism.n[1] - prism.n[0]) * alpha + (prism.n[2] - prism.n[0]) * beta;
    if e0.cross(e1).dot(ns) < T::ZERO {
        -rate
    } else {
        rate
    }
}
