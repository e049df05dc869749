//! The built-in scenes' height maps: value-noise fBm, spike fields and the seam scenes' atlas,
//! generated from a seed (no files).

use nlrt_accel::{HeightField, Wrap};
use rayon::prelude::*;

/// A hash of a lattice point to `[0, 1)`.
pub(super) fn lattice(i: i64, j: i64, seed: u64) -> f64 {
    let mut z = (i as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15)
        ^ (j as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f)
        ^ seed;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as f64 / u64::MAX as f64
}

/// Periodic value noise with period `period` lattice cells, smooth (quintic) interpolation.
pub(super) fn value_noise(x: f64, y: f64, period: i64, seed: u64) -> f64 {
    let (fx, fy) = (x.floor(), y.floor());
    let (i, j) = (fx as i64, fy as i64);
    let s = |t: f64| t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
    let (tx, ty) = (s(x - fx), s(y - fy));
    let at = |a: i64, b: i64| lattice(a.rem_euclid(period), b.rem_euclid(period), seed);
    let top = at(i, j) + (at(i + 1, j) - at(i, j)) * tx;
    let bottom = at(i, j + 1) + (at(i + 1, j + 1) - at(i, j + 1)) * tx;
    top + (bottom - top) * ty
}

/// A tileable fBm height map (`octaves` of value noise, gain 0.5), normalised to `[0, 1]`.
#[must_use]
pub fn fbm_map(side: usize, base_period: i64, octaves: u32, seed: u64) -> Vec<f32> {
    let rows: Vec<Vec<f64>> = (0..side)
        .into_par_iter()
        .map(|j| {
            (0..side)
                .map(|i| {
                    let (mut sum, mut amp, mut period) = (0.0, 1.0, base_period);
                    for o in 0..octaves {
                        let scale = period as f64 / side as f64;
                        sum += amp
                            * value_noise(
                                i as f64 * scale,
                                j as f64 * scale,
                                period,
                                seed + u64::from(o),
                            );
                        amp *= 0.5;
                        period *= 2;
                    }
                    sum
                })
                .collect()
        })
        .collect();
    let (lo, hi) = rows
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let span = (hi - lo).max(f64::MIN_POSITIVE);
    rows.iter()
        .flatten()
        .map(|&v| ((v - lo) / span) as f32)
        .collect()
}

/// A spike map for fur: a cone of radius `radius` texels around a jittered centre in each
/// cell of `cells x cells`, heights 1 at the tip.
#[must_use]
pub fn spike_map(side: usize, cells: usize, radius: f64, seed: u64) -> Vec<f32> {
    let cell = side as f64 / cells as f64;
    let centres: Vec<(f64, f64)> = (0..cells * cells)
        .map(|k| {
            let (i, j) = ((k % cells) as i64, (k / cells) as i64);
            (
                (i as f64 + 0.25 + 0.5 * lattice(i, j, seed)) * cell,
                (j as f64 + 0.25 + 0.5 * lattice(i, j, seed + 1)) * cell,
            )
        })
        .collect();
    (0..side * side)
        .map(|k| {
            let (x, y) = ((k % side) as f64, (k / side) as f64);
            let (ci, cj) = ((x / cell) as usize, (y / cell) as usize);
            let (cx, cy) = centres[cj.min(cells - 1) * cells + ci.min(cells - 1)];
            let d = ((x - cx).powi(2) + (y - cy).powi(2)).sqrt();
            (1.0 - d / radius).max(0.0) as f32
        })
        .collect()
}

pub(super) fn field(side: usize, heights: &[f32]) -> HeightField {
    HeightField::from_unit_heights(side, side, heights, Wrap::Repeat).expect("power-of-two side")
}

/// A non-periodic fBm map (clamped at the border) for the seam scenes: the cells of an atlas
/// hold unrelated relief, so the heights on the two sides of a seam differ.
pub(super) fn atlas_map(side: usize, seed: u64) -> HeightField {
    HeightField::from_unit_heights(side, side, &fbm_map(side, 8, 6, seed), Wrap::Clamp)
        .expect("power-of-two side")
}
