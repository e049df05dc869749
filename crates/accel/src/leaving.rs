//! Rays that leave a surface (shadow and bounce rays): the ray starts at its hit point, on
//! the element it was hit on (a microtriangle, a seam wall's piece or an object triangle),
//! and that element is excluded from its hits by its id, instead of the origin being moved
//! off the surface by an offset. An offset must outgrow the hit point's rounding error at
//! every angle and must stay below the thinnest feature and the narrowest crevice of the
//! scene; a ray that cannot hit its own element needs neither.
//!
//! Excluding the element alone is not enough where the origin lies on an edge or corner it
//! shares with neighbours (or within its rounding of one): the ray then touches a neighbour
//! at once. On a displaced surface, one sheet whose sides are named by the height, such a
//! touch is a crossing towards the side the ray left to, which a ray meeting the sheet
//! first never makes: it is not taken near the origin ([`Exclusion::skips`]).
//!
//! An element is named by its cell (texel or tile, in the tiled grid of the base triangle's
//! uv) and its index in the cell. A cell straddling base triangles has a piece in each of
//! them: the triangles that share a vertex with the origin's triangle share its uv there, so
//! the same cell and index name the same element's piece in them, judged as a neighbour on a
//! displaced surface and excluded on a shell-mapped one (an object triangle has no side the
//! ray is known to leave to). A triangle that shares no vertex (beyond a uv seam, or another
//! uv island) names other elements by the same numbers: nothing is excluded there.

use nlrt_poly::{Real, Vector3};
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
    /// On a displaced surface (one sheet over the base mesh, its elements' sides named by
    /// the height: up, towards larger `h`, and down), whether the ray leaves its element
    /// upwards: see [`Exclusion::skips`]. `None` elsewhere (an object's triangles have no
    /// common up).
    pub(crate) leaves_up: Option<bool>,
    /// The origin's texture coordinates in texels.
    pub(crate) texel_point: [f64; 2],
}

/// What a ray leaving `Origin` does not hit in one base triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Exclusion {
    element: Element,
    leaves_up: Option<bool>,
    texel_point: [f64; 2],
    /// Whether the base triangle is the origin's own.
    own_triangle: bool,
}

/// How far from the origin (in texels, per axis) a neighbour's crossing may be the ray
/// touching it at the origin: beyond the origin's rounding error in texels wherever it can
/// be traced. A base triangle spans at most 2^16 texels per axis (set-up refuses more), where
/// an `f32` texel coordinate's ulp is 2^-7 texel and the hit point carries a few of them;
/// 1/16 texel is four times that.
const TOUCH_RADIUS: f64 = 1.0 / 16.0;

impl Origin {
    /// What is excluded in base triangle `tri`: the origin's element, where `tri` is the
    /// origin's triangle or shares a vertex with it (the same uv around that vertex, so the
    /// same numbers name the same element); else nothing.
    #[must_use]
    pub(crate) fn excluded_in<T: Real>(&self, mesh: &BaseMesh<T>, tri: usize) -> Option<Exclusion> {
        let own = self.triangle as usize;
        let exclusion = Exclusion {
            element: self.element,
            leaves_up: self.leaves_up,
            texel_point: self.texel_point,
            own_triangle: tri == own,
        };
        if tri == own {
            return Some(exclusion);
        }
        if own >= mesh.triangle_count() {
            return None;
        }
        let (a, b) = (mesh.triangle(own), mesh.triangle(tri));
        a.iter().any(|v| b.contains(v)).then_some(exclusion)
    }
}

/// The elements of a texel that are pieces of the displaced sheet: the two microtriangles
/// and the flat texel (`TexelPart::index`); seam walls follow.
const SHEET_ELEMENTS: u32 = 3;

impl Exclusion {
    /// Whether `index` in `cell` is never hit: the origin's element, by its id. On a
    /// displaced surface, only in the origin's own base triangle (and a seam wall in any):
    /// the same texel's piece in a neighbouring triangle is mapped by that triangle's prism,
    /// a piece of its own that meets the origin's along their base edge, and is judged as a
    /// neighbour is ([`Exclusion::skips`]).
    #[must_use]
    #[inline]
    pub(crate) fn excludes(&self, cell: [i32; 2], index: u32) -> bool {
        self.element == Element { cell, index }
            && (self.own_triangle || self.leaves_up.is_none() || index >= SHEET_ELEMENTS)
    }

    /// Whether a hit on `index` in `cell` at `point` (texture coordinates in texels) is not
    /// taken: the excluded element ([`Exclusion::excludes`]); on a displaced surface also a
    /// microtriangle or flat texel met within [`TOUCH_RADIUS`] of the origin (one that may
    /// hold the origin: it lies on their shared edges and corners, or within its rounding of
    /// them) that the ray crosses towards the side it left its own element to (`crossing`:
    /// the rate at which the ray climbs above the element's plane, `d/dt (h - H(u, v))`,
    /// where it meets it). Such a crossing is the ray touching the surface at its origin: a
    /// ray leaving a sheet upwards is below a neighbouring element only after it has crossed
    /// the sheet downwards, which is the nearer hit. A crossing the other way (the ray
    /// enters the neighbour: a valley's other face, met at once by a grazing ray) is a hit.
    #[must_use]
    #[inline]
    pub(crate) fn skips<T: Real>(
        &self,
        cell: [i32; 2],
        index: u32,
        point: [f64; 2],
        crossing: impl FnOnce() -> T,
    ) -> bool {
        if self.excludes(cell, index) {
            return true;
        }
        let Some(up) = self.leaves_up else {
            return false;
        };
        let near = |k: usize| (point[k] - self.texel_point[k]).abs() <= TOUCH_RADIUS;
        if index >= SHEET_ELEMENTS || !(near(0) && near(1)) {
            return false;
        }
        let c = crossing();
        let enters = if up { c < T::ZERO } else { c > T::ZERO };
        !enters
    }
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
