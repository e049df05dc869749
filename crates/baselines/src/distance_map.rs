//! The 3D distance map of Jeschke, Mantler and Wimmer 2007, sec. 4.4, for a height field: a
//! regular grid over texture space `(u, v, w)` whose cells store the radius of an empty
//! neighbourhood, so that a ray marcher may jump that far without missing the surface
//! (sphere tracing). Cells below the surface store 0.
//!
//! Our radii are conservative Chebyshev radii in cell units: a cell with radius `r` has no
//! point of the solid (`w <= height(u, v)`, the marcher's hit test) in the box of cells
//! `r` around it, so from any point in the cell a step of at most `r` cells along each axis
//! stays in empty space. They are computed exactly from the samples (column maxima of each
//! cell, dilated one cell at a time), not by a Euclidean distance transform: a box is what a
//! per-axis step needs, and it needs no square roots.

use alloc::vec;
use alloc::vec::Vec;
use nlrt_poly::Real;

use nlrt_accel::{HEIGHT_ONE, HeightField, Wrap};

/// Largest radius stored (cells): beyond it the box test costs more than the jumps save.
pub const MAX_RADIUS: u8 = 31;

/// A 3D distance map over a height field's texture space (see the module documentation).
#[derive(Clone, Debug)]
pub struct DistanceMap {
    /// Cells per axis in `u` and `v`.
    cells: usize,
    /// Texels per cell along `u` and `v` (a power of two dividing the map's side, so that
    /// cells tile the periodic map evenly).
    cell_texels: usize,
    /// Height layers (cells along `w`).
    layers: usize,
    wrap: Wrap,
    /// `radius[(layer * cells + cy) * cells + cx]`.
    radius: Vec<u8>,
}

impl DistanceMap {
    /// The distance map of `field` with `layers` height layers (at least 1) and at most
    /// `max_cells` cells per axis where the side allows: cells of a power-of-two number of
    /// texels (maps have power-of-two sides).
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap};
    /// use nlrt_baselines::DistanceMap;
    /// // A single spike in the middle of a flat map at height 0.
    /// let mut heights = vec![0.0; 64 * 64];
    /// heights[32 * 64 + 32] = 1.0;
    /// let field = HeightField::from_unit_heights(64, 64, &heights, Wrap::Clamp).unwrap();
    /// let map = DistanceMap::new(&field, 16, 64);
    /// // Far above a corner of the map: a long jump; next to the spike: none.
    /// assert!(map.radius_at(2.0f64, 2.0, 0.9) >= 10);
    /// assert_eq!(map.radius_at(32.5f64, 32.5, 0.5), 0);
    /// ```
    ///
    /// # Panics
    /// On a map that is not square with a power-of-two side.
    #[must_use]
    pub fn new(field: &HeightField, layers: usize, max_cells: usize) -> Self {
        let side = field
            .square_side()
            .expect("distance maps are built for square maps with a power-of-two side");
        let layers = layers.max(1);
        let mut cell_texels = 1;
        while side / cell_texels > max_cells.max(1) && side.is_multiple_of(cell_texels * 2) {
            cell_texels *= 2;
        }
        let cells = side / cell_texels;
        // Column maxima: a cell's texels use the samples up to the next cell's first.
        let mut max = vec![0u16; cells * cells];
        for cy in 0..cells {
            for cx in 0..cells {
                let (x0, y0) = ((cx * cell_texels) as i64, (cy * cell_texels) as i64);
                let mut m = 0;
                for j in y0..=y0 + cell_texels as i64 {
                    for i in x0..=x0 + cell_texels as i64 {
                        m = m.max(field.sample(i, j));
                    }
                }
                max[cy * cells + cx] = m;
            }
        }
        let wrap = field.wrap();
        let neighbour = |i: usize, d: isize| -> usize {
            let j = i as isize + d;
            match wrap {
                Wrap::Repeat => j.rem_euclid(cells as isize) as usize,
                Wrap::Clamp => j.clamp(0, cells as isize - 1) as usize,
            }
        };
        let mut radius = vec![0u8; cells * cells * layers];
        for r in 0..=MAX_RADIUS {
            if r > 0 {
                // Dilate by one cell: 3-wide maxima along u, then along v.
                let along_u: Vec<u16> = (0..cells * cells)
                    .map(|k| {
                        let (x, y) = (k % cells, k / cells);
                        (-1..=1)
                            .map(|d| max[y * cells + neighbour(x, d)])
                            .max()
                            .unwrap_or(0)
                    })
                    .collect();
                max = (0..cells * cells)
                    .map(|k| {
                        let (x, y) = (k % cells, k / cells);
                        (-1..=1)
                            .map(|d| along_u[neighbour(y, d) * cells + x])
                            .max()
                            .unwrap_or(0)
                    })
                    .collect();
            }
            let mut any = false;
            for layer in (r as usize)..layers {
                // Empty box: every height below the box's bottom, layer - r, with one sample
                // unit to spare, so that a point rounded into the layer from just below it
                // (an f32 `w * layers` rounds by far less than 1 / HEIGHT_ONE) is still above.
                let bottom = (layer - r as usize) as u64 * u64::from(HEIGHT_ONE);
                for c in 0..cells * cells {
                    let top = (u64::from(max[c]) + 1) * layers as u64;
                    if top < bottom {
                        radius[layer * cells * cells + c] = r;
                        any = true;
                    }
                }
            }
            if !any {
                break;
            }
        }
        Self {
            cells,
            cell_texels,
            layers,
            wrap,
            radius,
        }
    }

    /// Texels per cell along `u` and `v`.
    #[must_use]
    pub fn cell_texels(&self) -> usize {
        self.cell_texels
    }

    /// Height layers.
    #[must_use]
    pub fn layers(&self) -> usize {
        self.layers
    }

    /// Bytes of the radii.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.radius.len()
    }

    /// The radius (cells) at texel coordinates `(u, v)` (of the infinite tiled grid, as the
    /// marcher's samples have them) and texture height `w` (clamped to `[0, 1]`); 0 for
    /// non-finite input.
    #[must_use]
    pub fn radius_at<T: Real>(&self, u: T, v: T, w: T) -> u8 {
        let (u, v, w) = (u.to_f64(), v.to_f64(), w.to_f64());
        if !(u.is_finite() && v.is_finite() && w.is_finite()) {
            return 0;
        }
        let cell = |x: f64| -> usize {
            // floor without std; |x| is far below i64's range for any texel coordinate the
            // marcher produces, and saturating `as` keeps absurd ones in range.
            let t = x as i64;
            let texel = if (t as f64) > x {
                t.saturating_sub(1)
            } else {
                t
            };
            let c = texel.div_euclid(self.cell_texels as i64);
            match self.wrap {
                Wrap::Repeat => c.rem_euclid(self.cells as i64) as usize,
                Wrap::Clamp => c.clamp(0, self.cells as i64 - 1) as usize,
            }
        };
        let layer = ((w.clamp(0.0, 1.0) * self.layers as f64) as usize).min(self.layers - 1);
        self.radius[(layer * self.cells + cell(v)) * self.cells + cell(u)]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force: the largest `r` such that no sample under the box of cells `r` around
    /// the cell reaches the box's bottom layer.
    fn brute_radius(field: &HeightField, map: &DistanceMap, cx: i64, cy: i64, layer: usize) -> u8 {
        let k = map.cell_texels as i64;
        let mut best = 0;
        for r in 0..=i64::from(MAX_RADIUS) {
            if (layer as i64) < r {
                break;
            }
            let mut top = 0u16;
            for cell_y in cy - r..=cy + r {
                for cell_x in cx - r..=cx + r {
                    let clamp = |c: i64| match map.wrap {
                        Wrap::Repeat => c.rem_euclid(map.cells as i64),
                        Wrap::Clamp => c.clamp(0, map.cells as i64 - 1),
                    };
                    let (x0, y0) = (clamp(cell_x) * k, clamp(cell_y) * k);
                    for j in y0..=y0 + k {
                        for i in x0..=x0 + k {
                            top = top.max(field.sample(i, j));
                        }
                    }
                }
            }
            let bottom = (layer as i64 - r) as f64 / map.layers as f64;
            if (f64::from(top) + 1.0) / f64::from(HEIGHT_ONE) < bottom {
                best = r as u8;
            } else {
                break;
            }
        }
        best
    }

    #[test]
    fn radii_equal_brute_force_for_both_wrap_modes() {
        let side = 32;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| {
                let (x, y) = ((k % side) as f32, (k / side) as f32);
                (0.5 + 0.45 * (x * 0.4).sin() * (y * 0.3).cos()).powi(3)
            })
            .collect();
        for wrap in [Wrap::Repeat, Wrap::Clamp] {
            let field = HeightField::from_unit_heights(side, side, &heights, wrap).unwrap();
            let map = DistanceMap::new(&field, 12, 8);
            assert_eq!(map.cell_texels, 4);
            for layer in 0..12 {
                for cy in 0..8 {
                    for cx in 0..8 {
                        let (u, v) = (cx as f64 * 4.0 + 0.5, cy as f64 * 4.0 + 3.5);
                        let w = (layer as f64 + 0.5) / 12.0;
                        assert_eq!(
                            map.radius_at(u, v, w),
                            brute_radius(&field, &map, cx, cy, layer),
                            "{wrap:?} cell {cx} {cy} layer {layer}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn no_point_within_a_radius_is_under_the_surface() {
        // Every texel corner within r cells of a cell with radius r is below the cell's layer
        // minus r: the guarantee a marcher relies on, over tiled coordinates too.
        let side = 16;
        let heights: Vec<f32> = (0..side * side)
            .map(|k| ((k * 7919) % 97) as f32 / 97.0 * 0.6)
            .collect();
        let field = HeightField::from_unit_heights(side, side, &heights, Wrap::Repeat).unwrap();
        let map = DistanceMap::new(&field, 20, 4);
        let mut jumps = 0;
        for layer in 0..20 {
            for ty in -20i64..36 {
                for tx in -20i64..36 {
                    let w = (layer as f64 + 0.01) / 20.0;
                    let r = i64::from(map.radius_at(tx as f64 + 0.5, ty as f64 + 0.5, w));
                    if r == 0 {
                        continue;
                    }
                    jumps += 1;
                    let reach = (r + 1) * map.cell_texels as i64;
                    let k = map.cell_texels as i64;
                    let (cx, cy) = (tx.div_euclid(k) * k, ty.div_euclid(k) * k);
                    for j in cy - r * k..=cy + reach {
                        for i in cx - r * k..=cx + reach {
                            let h = f64::from(field.sample(i, j)) / f64::from(HEIGHT_ONE);
                            assert!(h < w - r as f64 / 20.0, "{tx} {ty} layer {layer}");
                        }
                    }
                }
            }
        }
        assert!(jumps > 1000, "{jumps}");
    }

    #[test]
    fn small_maps_use_texel_cells_and_absurd_input_gives_no_jump() {
        let field = HeightField::from_unit_heights(4, 4, &[0.1; 16], Wrap::Clamp).unwrap();
        let map = DistanceMap::new(&field, 8, 4);
        assert_eq!(map.cell_texels(), 1);
        assert!(map.radius_at(2.0f32, 2.0, 1.0) > 0);
        assert_eq!(map.radius_at(f64::NAN, 2.0, 1.0), 0);
        assert_eq!(
            map.radius_at(1e300, -1e300, 1.0),
            map.radius_at(3.5, 0.5, 1.0)
        );
        assert_eq!(map.radius_at(2.0f32, 2.0, -3.0), 0);
    }
}
