//! Height maps and the implicit min-max mipmap over them (Ogaki 2023, sec. 4.4 and 5.1).
//!
//! Heights are 16-bit samples `s / 65535` in `[0, 1]` (the displacement along the prism's
//! scaled normals). Sample `(i, j)` sits at the texel corner `(i / n, j / n)` of a tile, and
//! texel `(x, y)` is the square between corners `(x, y)` and `(x + 1, y + 1)`: with
//! [`Wrap::Repeat`] the last texel of a tile reaches the first sample of the next tile, so a
//! tiled map is seamless. The min-max pyramid is stored from level 2 up (a node of level `l`
//! covers `2^l x 2^l` texels); levels 0 (one texel: its four corners) and 1 (a 3 x 3 block of
//! samples) are read from the samples when needed, which keeps a 4096^2 map and its pyramid at
//! 39.1 MB (the paper's float mipmap alone is 44.7 MB).

use alloc::vec::Vec;
use core::fmt;

/// How texel corners outside `[0, n)` are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Tiles repeat (`i mod n`): the texture is periodic, as tiling needs.
    #[default]
    Repeat,
    /// Corners clamp to the edge (`clamp(i, 0, n - 1)`).
    Clamp,
}

/// Why a height map was rejected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HeightMapError {
    /// The side is not a power of two of at least 2 (the implicit pyramid halves it per level).
    SideNotPowerOfTwo(usize),
    /// The number of samples is not `side * side`.
    WrongSampleCount {
        /// Expected `side * side`.
        expected: usize,
        /// Given.
        got: usize,
    },
}

impl fmt::Display for HeightMapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::SideNotPowerOfTwo(n) => write!(
                f,
                "height map side {n} is not a power of two >= 2 (resample it, e.g. to {})",
                n.next_power_of_two().max(2)
            ),
            Self::WrongSampleCount { expected, got } => {
                write!(f, "height map has {got} samples, expected {expected}")
            }
        }
    }
}

/// Largest 16-bit sample; heights are `sample / HEIGHT_ONE`.
pub const HEIGHT_ONE: u16 = u16::MAX;

/// A square height map of 16-bit samples with its min-max pyramid.
#[derive(Clone, Debug)]
pub struct HeightField {
    side: usize,
    log2_side: u32,
    wrap: Wrap,
    samples: Vec<u16>,
    /// `pyramid[k]` holds level `k + 2`: `(min, max)` per node, row-major.
    pyramid: Vec<Vec<[u16; 2]>>,
    range: [u16; 2],
}

impl HeightField {
    /// A height field from `side * side` samples (row-major, `v` down the rows); builds the
    /// pyramid.
    ///
    /// # Errors
    /// When `side` is not a power of two `>= 2` or the sample count is not `side * side`.
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap};
    /// let field = HeightField::new(4, vec![0; 16], Wrap::Repeat).unwrap();
    /// assert_eq!(field.texel_bounds(0, 3, 5), [0, 0]);
    /// assert!(HeightField::new(3, vec![0; 9], Wrap::Repeat).is_err());
    /// ```
    pub fn new(side: usize, samples: Vec<u16>, wrap: Wrap) -> Result<Self, HeightMapError> {
        if side < 2 || !side.is_power_of_two() {
            return Err(HeightMapError::SideNotPowerOfTwo(side));
        }
        if samples.len() != side * side {
            return Err(HeightMapError::WrongSampleCount {
                expected: side * side,
                got: samples.len(),
            });
        }
        let mut field = Self {
            side,
            log2_side: side.trailing_zeros(),
            wrap,
            samples,
            pyramid: Vec::new(),
            range: [0, 0],
        };
        field.rebuild();
        Ok(field)
    }

    /// A height field from heights in `[0, 1]` (clamped; NaN reads as 0), rounded to 16 bits.
    ///
    /// # Errors
    /// As [`HeightField::new`].
    pub fn from_unit_heights(
        side: usize,
        heights: &[f32],
        wrap: Wrap,
    ) -> Result<Self, HeightMapError> {
        let samples = heights
            .iter()
            .map(|&h| {
                let h = if h.is_nan() { 0.0 } else { h.clamp(0.0, 1.0) };
                // Round to nearest; the cast saturates.
                (h * f32::from(HEIGHT_ONE) + 0.5) as u16
            })
            .collect();
        Self::new(side, samples, wrap)
    }

    /// Samples per side (texels per side of one tile).
    #[must_use]
    pub fn side(&self) -> usize {
        self.side
    }

    /// The wrap mode.
    #[must_use]
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// Level whose single node covers a whole tile.
    #[must_use]
    pub fn top_level(&self) -> u32 {
        self.log2_side
    }

    /// Smallest and largest sample of the whole map.
    #[must_use]
    pub fn range(&self) -> [u16; 2] {
        self.range
    }

    /// The raw samples, row-major.
    #[must_use]
    pub fn samples(&self) -> &[u16] {
        &self.samples
    }

    /// Bytes of samples and pyramid.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.samples.len() * 2 + self.pyramid.iter().map(|l| l.len() * 4).sum::<usize>()
    }

    #[inline]
    fn wrap_index(&self, i: i64) -> usize {
        let n = self.side as i64;
        match self.wrap {
            // `side` is a power of two: the mask is `rem_euclid` (two's complement) without
            // a division, which the walk would pay per sample read.
            Wrap::Repeat => (i & (n - 1)) as usize,
            Wrap::Clamp => i.clamp(0, n - 1) as usize,
        }
    }

    /// The sample at corner `(i, j)` of the infinite texel grid (wrapped).
    #[must_use]
    #[inline]
    pub fn sample(&self, i: i64, j: i64) -> u16 {
        self.samples[self.wrap_index(j) * self.side + self.wrap_index(i)]
    }

    /// The four corner samples of texel `(x, y)`: `[s00, s10, s01, s11]`.
    #[must_use]
    #[inline]
    pub fn texel_corners(&self, x: i64, y: i64) -> [u16; 4] {
        [
            self.sample(x, y),
            self.sample(x + 1, y),
            self.sample(x, y + 1),
            self.sample(x + 1, y + 1),
        ]
    }

    /// The height of the microtriangle surface at the texel-grid point `(x, y)` (texture
    /// coordinates times the map's side), in `[0, 1]`, evaluated in f64: the texel's two
    /// microtriangles share the diagonal from its `(0, 0)` to its `(1, 1)` corner, as in the
    /// tracers. With it, the bound on the surface's slope in that texel (height per texel,
    /// the largest of its microtriangles' gradient lengths, at most `sqrt 2` times the corner
    /// range).
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap, HEIGHT_ONE};
    /// let field = HeightField::new(2, vec![0, HEIGHT_ONE, 0, HEIGHT_ONE], Wrap::Clamp).unwrap();
    /// let (h, slope) = field.height_at(0.25, 0.5);
    /// assert_eq!(h, 0.25);
    /// assert!(slope >= 1.0);
    /// ```
    #[must_use]
    pub fn height_at(&self, x: f64, y: f64) -> (f64, f64) {
        let (tx, ty) = (
            f64::from(crate::tlas::texel_floor(x)),
            f64::from(crate::tlas::texel_floor(y)),
        );
        let (fx, fy) = (x - tx, y - ty);
        let unit = f64::from(HEIGHT_ONE);
        let c = self
            .texel_corners(tx as i64, ty as i64)
            .map(|s| f64::from(s) / unit);
        let height = if fx >= fy {
            c[0] + fx * (c[1] - c[0]) + fy * (c[3] - c[1])
        } else {
            c[0] + fy * (c[2] - c[0]) + fx * (c[3] - c[2])
        };
        let length = |a: f64, b: f64| nlrt_poly::Real::sqrt(a * a + b * b);
        let lower = length(c[1] - c[0], c[3] - c[1]);
        let upper = length(c[2] - c[0], c[3] - c[2]);
        (height, lower.max(upper))
    }

    /// The `N x N` samples at corners `(i0 + i, j0 + j)`, by rows `j` (`N = 3`: a node of
    /// level 1 at `(i0 / 2, j0 / 2)`, its four texels' corners; `N = 5`: a node of level 2),
    /// each row and column wrapped once.
    #[must_use]
    #[inline]
    pub(crate) fn samples_block<const N: usize>(&self, i0: i64, j0: i64) -> [[u16; N]; N] {
        let columns: [usize; N] = core::array::from_fn(|i| self.wrap_index(i0 + i as i64));
        core::array::from_fn(|j| {
            let row = &self.samples[self.wrap_index(j0 + j as i64) * self.side..][..self.side];
            columns.map(|i| row[i])
        })
    }

    /// Asks the CPU to fetch the memory that expanding node `(x, y)` of `level` will read
    /// (level 2: its 5 x 5 samples, five rows; above: its children's bounds, two rows of the
    /// level below), so that a node pushed for later is in cache when it is popped (a walk
    /// waits on memory on a large map). A hint: no effect on any result, and nothing where
    /// the target has no prefetch instruction.
    #[inline(always)]
    pub(crate) fn prefetch_node(&self, level: u32, x: i64, y: i64) {
        #[cfg(target_arch = "x86_64")]
        {
            use core::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
            let fetch = |p: *const u8| {
                // SAFETY: a prefetch is a hint that never faults, whatever the address; the
                // pointers here are in bounds anyway (wrapped indices into the slices).
                unsafe { _mm_prefetch::<_MM_HINT_T0>(p.cast()) }
            };
            if level == 2 {
                let i = self.wrap_index(4 * x);
                for j in 0..5 {
                    let row = self.wrap_index(4 * y + j) * self.side;
                    fetch(core::ptr::from_ref(&self.samples[row + i]).cast());
                }
            } else if level >= 3 && level - 1 <= self.log2_side && self.wrap == Wrap::Repeat {
                let l = level - 1;
                let n = (self.side >> l) as i64;
                let row = &self.pyramid[l as usize - 2];
                let i = (2 * x) & (n - 1);
                for j in [2 * y, 2 * y + 1] {
                    fetch(core::ptr::from_ref(&row[((j & (n - 1)) * n + i) as usize]).cast());
                }
            }
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = (level, x, y);
    }

    /// [`HeightField::texel_bounds`] of the four nodes `(x + (k & 1), y + (k >> 1))` of
    /// `level`, `k` in `0..4` (a node's children, `x` and `y` even), with the stored levels of
    /// a repeated map read inline (the walks' inner loop).
    #[must_use]
    #[inline(always)]
    pub(crate) fn four_bounds(&self, level: u32, x: i64, y: i64) -> [[u16; 2]; 4] {
        if level >= 2 && level <= self.log2_side && self.wrap == Wrap::Repeat {
            let n = (self.side >> level) as i64;
            let row = &self.pyramid[level as usize - 2];
            let (x0, x1) = (x & (n - 1), (x + 1) & (n - 1));
            let (y0, y1) = ((y & (n - 1)) * n, ((y + 1) & (n - 1)) * n);
            return [
                row[(y0 + x0) as usize],
                row[(y0 + x1) as usize],
                row[(y1 + x0) as usize],
                row[(y1 + x1) as usize],
            ];
        }
        core::array::from_fn(|k| self.texel_bounds(level, x + (k & 1) as i64, y + (k >> 1) as i64))
    }

    /// `(min, max)` sample over the node `(x, y)` of `level` (any integers: the grid is
    /// infinite and wraps). Levels above the top cover several tiles and get the whole map's
    /// range (with [`Wrap::Clamp`] a node outside the tile still reads edge samples, inside
    /// that range too).
    #[must_use]
    pub fn texel_bounds(&self, level: u32, x: i64, y: i64) -> [u16; 2] {
        match level {
            0 => {
                let c = self.texel_corners(x, y);
                [
                    c[0].min(c[1]).min(c[2]).min(c[3]),
                    c[0].max(c[1]).max(c[2]).max(c[3]),
                ]
            }
            1 => {
                let mut b = [u16::MAX, 0];
                for row in self.samples_block::<3>(2 * x, 2 * y) {
                    for s in row {
                        b = [b[0].min(s), b[1].max(s)];
                    }
                }
                b
            }
            l if l <= self.log2_side && self.wrap == Wrap::Repeat => {
                let n = (self.side >> l) as i64;
                let row = &self.pyramid[l as usize - 2];
                // A power of two: masks wrap like `rem_euclid`.
                row[((y & (n - 1)) * n + (x & (n - 1))) as usize]
            }
            l if l <= self.log2_side => {
                // Clamp: a node inside the tile is stored; outside it only edge samples are
                // read, bounded by the whole range.
                let n = (self.side >> l) as i64;
                if (0..n).contains(&x) && (0..n).contains(&y) {
                    self.pyramid[l as usize - 2][(y * n + x) as usize]
                } else {
                    self.range
                }
            }
            _ => self.range,
        }
    }

    /// Rebuilds the pyramid from the samples (after an edit of [`HeightField::samples_mut`]
    /// use [`HeightField::update_region`] instead, which touches only what changed).
    pub fn rebuild(&mut self) {
        self.pyramid.clear();
        self.range = [
            self.samples.iter().copied().min().unwrap_or(0),
            self.samples.iter().copied().max().unwrap_or(0),
        ];
        if self.log2_side < 2 {
            return;
        }
        self.pyramid.push(self.level2_from_samples());
        for level in 3..=self.log2_side {
            let m = self.side >> level;
            let below = &self.pyramid[level as usize - 3];
            let mut nodes = Vec::with_capacity(m * m);
            for y in 0..m {
                for x in 0..m {
                    let at = |cx: usize, cy: usize| below[(2 * y + cy) * 2 * m + 2 * x + cx];
                    let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
                    nodes.push([
                        a[0].min(b[0]).min(c[0]).min(d[0]),
                        a[1].max(b[1]).max(c[1]).max(d[1]),
                    ]);
                }
            }
            self.pyramid.push(nodes);
        }
    }

    /// Level 2 (4 x 4 texels, 5 x 5 samples per node) in two separable passes: along rows,
    /// then down the columns of row results. Only the last node of a row or column reads
    /// past the tile (the wrapped corner).
    fn level2_from_samples(&self) -> Vec<[u16; 2]> {
        let n = self.side;
        let m = n >> 2;
        let wrapped = |i: usize| if i < n { i } else { self.wrap_index(i as i64) };
        let mut rows = alloc::vec![[0u16, 0u16]; n * m];
        for j in 0..n {
            let row = &self.samples[j * n..(j + 1) * n];
            for x in 0..m {
                let mut b = [u16::MAX, 0];
                for i in 4 * x..4 * x + 5 {
                    let s = row[wrapped(i)];
                    b = [b[0].min(s), b[1].max(s)];
                }
                rows[j * m + x] = b;
            }
        }
        let mut nodes = alloc::vec![[u16::MAX, 0u16]; m * m];
        for y in 0..m {
            for j in 4 * y..4 * y + 5 {
                let r = &rows[wrapped(j) * m..wrapped(j) * m + m];
                let out = &mut nodes[y * m..(y + 1) * m];
                for (o, c) in out.iter_mut().zip(r) {
                    *o = [o[0].min(c[0]), o[1].max(c[1])];
                }
            }
        }
        nodes
    }

    /// Mutable access to the samples; call [`HeightField::update_region`] for the edited
    /// texels afterwards.
    pub fn samples_mut(&mut self) -> &mut [u16] {
        &mut self.samples
    }

    /// Recomputes the pyramid nodes over texels `[x0, x1) x [y0, y1)` of the tile after their
    /// corner samples changed (a brush stroke); cost proportional to the region, plus one
    /// row of nodes per level. The map-wide range only grows here (it stays conservative).
    pub fn update_region(&mut self, x0: i64, y0: i64, x1: i64, y1: i64) {
        let n = self.side as i64;
        // With Repeat, sample 0 is also the far corner of the tile's last texel.
        if self.wrap == Wrap::Repeat && x0 <= 0 && x1 > 0 {
            self.update_region(n - 1, y0, n, y1);
        }
        if self.wrap == Wrap::Repeat && y0 <= 0 && y1 > 0 {
            self.update_region(x0, n - 1, x1, n);
        }
        // A texel reads corners up to +1, so an edited sample touches the texels before it.
        let (mut x0, mut y0) = ((x0 - 1).max(0), (y0 - 1).max(0));
        let (mut x1, mut y1) = (x1.min(n), y1.min(n));
        for j in y0.max(0)..(y1 + 1).min(n) {
            for i in x0.max(0)..(x1 + 1).min(n) {
                let s = self.samples[(j * n + i) as usize];
                self.range = [self.range[0].min(s), self.range[1].max(s)];
            }
        }
        for level in 2..=self.log2_side {
            let shift = level;
            let (nx0, ny0) = (x0 >> shift, y0 >> shift);
            let (nx1, ny1) = (((x1 - 1) >> shift) + 1, ((y1 - 1) >> shift) + 1);
            let m = (self.side >> level) as i64;
            for y in ny0..ny1.min(m) {
                for x in nx0..nx1.min(m) {
                    let b = if level == 2 {
                        let mut b = [u16::MAX, 0];
                        for cy in 0..2 {
                            for cx in 0..2 {
                                let c = self.texel_bounds(1, 2 * x + cx, 2 * y + cy);
                                b = [b[0].min(c[0]), b[1].max(c[1])];
                            }
                        }
                        b
                    } else {
                        let below = &self.pyramid[level as usize - 3];
                        let mb = m * 2;
                        let mut b = [u16::MAX, 0];
                        for cy in 0..2 {
                            for cx in 0..2 {
                                let c = below[((2 * y + cy) * mb + 2 * x + cx) as usize];
                                b = [b[0].min(c[0]), b[1].max(c[1])];
                            }
                        }
                        b
                    };
                    self.pyramid[level as usize - 2][(y * m + x) as usize] = b;
                }
            }
            (x0, y0, x1, y1) = (nx0 << shift, ny0 << shift, nx1 << shift, ny1 << shift);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    fn pseudo_random(side: usize, seed: u64) -> Vec<u16> {
        let mut s = seed;
        (0..side * side)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (s >> 48) as u16
            })
            .collect()
    }

    fn brute_bounds(f: &HeightField, level: u32, x: i64, y: i64) -> [u16; 2] {
        let k = 1i64 << level;
        let mut b = [u16::MAX, 0];
        for j in y * k..=(y + 1) * k {
            for i in x * k..=(x + 1) * k {
                let s = f.sample(i, j);
                b = [b[0].min(s), b[1].max(s)];
            }
        }
        b
    }

    #[test]
    fn bounds_enclose_every_sample_of_the_node() {
        for wrap in [Wrap::Repeat, Wrap::Clamp] {
            let f = HeightField::new(16, pseudo_random(16, 7), wrap).unwrap();
            for level in 0..=4 {
                let n = 16i64 >> level;
                for y in -1..=n {
                    for x in -1..=n {
                        let b = f.texel_bounds(level, x, y);
                        let t = brute_bounds(&f, level, x, y);
                        assert!(b[0] <= t[0] && b[1] >= t[1], "{wrap:?} {level} {x} {y}");
                        if wrap == Wrap::Repeat || (0..n).contains(&x) && (0..n).contains(&y) {
                            assert_eq!(b, t, "{wrap:?} {level} {x} {y}: stored bounds are exact");
                        }
                    }
                }
            }
        }
    }

    /// Repeat reads the sample of the tile's copy the corner lies in, for negative and far
    /// corners too (the index is a mask, which must agree with `rem_euclid`); Clamp reads the
    /// nearest edge sample.
    #[test]
    fn samples_wrap_like_the_repeated_or_clamped_tile() {
        let side = 8i64;
        let values = pseudo_random(8, 11);
        for wrap in [Wrap::Repeat, Wrap::Clamp] {
            let f = HeightField::new(8, values.clone(), wrap).unwrap();
            for j in [
                -3 * side - 1,
                -side,
                -5,
                -1,
                0,
                3,
                7,
                8,
                13,
                5 * side + 2,
                1 << 40,
            ] {
                for i in [-(1 << 40) - 3, -2 * side + 1, -1, 0, 6, 9, 4 * side - 1] {
                    let index = |c: i64| match wrap {
                        Wrap::Repeat => c.rem_euclid(side),
                        Wrap::Clamp => c.clamp(0, side - 1),
                    };
                    let expected = values[(index(j) * side + index(i)) as usize];
                    assert_eq!(f.sample(i, j), expected, "{wrap:?} ({i}, {j})");
                }
            }
        }
    }

    #[test]
    fn partial_update_matches_a_rebuild() {
        let mut f = HeightField::new(32, pseudo_random(32, 3), Wrap::Repeat).unwrap();
        for j in 10..14 {
            for i in 5..9 {
                f.samples_mut()[j * 32 + i] = 65535 - (i * j) as u16;
            }
        }
        f.update_region(5, 10, 9, 14);
        // Sample (0, 0) is also the far corner of the tile's last texels (Repeat).
        f.samples_mut()[0] = 12345;
        f.samples_mut()[1] = 65535;
        f.update_region(0, 0, 2, 1);
        let mut g = f.clone();
        g.rebuild();
        assert_eq!(f.pyramid, g.pyramid);
    }

    #[test]
    fn rejects_bad_sides() {
        assert_eq!(
            HeightField::new(6, vec![0; 36], Wrap::Repeat).unwrap_err(),
            HeightMapError::SideNotPowerOfTwo(6)
        );
        assert!(matches!(
            HeightField::new(8, vec![0; 63], Wrap::Repeat),
            Err(HeightMapError::WrongSampleCount {
                expected: 64,
                got: 63
            })
        ));
    }
}
