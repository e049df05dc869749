//! Height maps and the implicit min-max mipmap over them (Ogaki 2023, sec. 4.4 and 5.1).
//!
//! Heights are 16-bit samples `s / 65535` in `[0, 1]` (the displacement along the prism's
//! scaled normals). A map is `width x height` samples of any size (both at least 2), with no
//! resampling. Sample `(i, j)` sits at the texel corner `(i / width, j / height)` of a tile,
//! and texel `(x, y)` is the rectangle between corners `(x, y)` and `(x + 1, y + 1)`: with
//! [`Wrap::Repeat`] the last texel of a tile reaches the first sample of the next tile, so a
//! tiled map is seamless. The min-max pyramid is stored from level 2 up (a node of level `l`
//! covers `2^l x 2^l` texels; each level halves the one below, rounding up, so the last node
//! of a row or column may cover fewer texels); levels 0 (one texel: its four corners) and 1
//! (a 3 x 3 block of samples) are read from the samples when needed, which keeps a 4096^2 map
//! and its pyramid at 39.1 MB (the paper's float mipmap alone is 44.7 MB).
//!
//! The walks ask for nodes of the infinite texel grid, aligned to `2^l` there. On a map whose
//! sides are one power of two every such node is one stored node (the wrap is a mask). On
//! any other map a node of a repeated map may straddle a tile's edge, or sit across stored
//! nodes that are aligned to the tile: its bounds are the union of the stored nodes it
//! overlaps (at most three per axis), which holds every sample it covers, a little wider
//! than exact.

use alloc::vec::Vec;
use core::fmt;

/// How texel corners outside the tile are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Tiles repeat (`i mod width`, `j mod height`): the texture is periodic, as tiling needs.
    #[default]
    Repeat,
    /// Corners clamp to the edge (`clamp(i, 0, width - 1)`, the same along `j`).
    Clamp,
}

/// Why a height map was rejected.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum HeightMapError {
    /// A side is below 2 samples (a texel needs two corners per axis) or above
    /// [`MAX_SAMPLES_PER_SIDE`].
    BadSize {
        /// Samples per row.
        width: usize,
        /// Rows.
        height: usize,
    },
    /// The number of samples is not `width * height`.
    WrongSampleCount {
        /// Expected `width * height`.
        expected: usize,
        /// Given.
        got: usize,
    },
}

impl fmt::Display for HeightMapError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::BadSize { width, height } => write!(
                f,
                "height map is {width} x {height} samples; each side must be from 2 to {MAX_SAMPLES_PER_SIDE}"
            ),
            Self::WrongSampleCount { expected, got } => {
                write!(f, "height map has {got} samples, expected {expected}")
            }
        }
    }
}

/// A plain error (no source): `?` carries it into `Box<dyn core::error::Error>`.
impl core::error::Error for HeightMapError {}

/// Largest 16-bit sample; heights are `sample / HEIGHT_ONE`.
pub const HEIGHT_ONE: u16 = u16::MAX;

/// Most samples along one side of a map: 2^20. Texel coordinates of a tile then stay far
/// inside the tracers' texel grid (2^22 texels, `MAX_TEXEL_COORDINATE`), and the pyramid's top
/// level (a power of two at least the side) within its 2^21.
pub const MAX_SAMPLES_PER_SIDE: usize = 1 << 20;

/// One stored level of the pyramid: `(min, max)` per node, row-major, `columns` per row.
#[derive(Clone, Debug, PartialEq, Eq)]
struct Level {
    columns: usize,
    nodes: Vec<[u16; 2]>,
}

/// A height map of 16-bit samples with its min-max pyramid.
///
/// Sample `(i, j)` (row `j`, column `i`, `v` down the rows) sits at the texel *corner*
/// `(u, v) = (i / width, j / height)` of a tile, not at `i / (width - 1)`: texel `(x, y)` spans
/// the corners `(x, y)` to `(x + 1, y + 1)`, and the last texel of a row, `x = width - 1`,
/// reaches `u = 1`, where it reads sample column `width` through the [`Wrap`]:
/// [`Wrap::Repeat`] (the default) takes column 0 there, so a map that does not tile blends its
/// last column into its first; [`Wrap::Clamp`] takes column `width - 1` again (a terrain or any
/// map that is not periodic). The same holds for rows. Heights are `s / 65535` in `[0, 1]`,
/// times the surface's height scale along the prism's normals (`HEIGHT_ONE` is 1).
///
/// ```
/// use nlrt_accel::{HeightField, Wrap};
/// // 2 x 2 samples, 0 on the left column and 65535 on the right.
/// let samples = vec![0, u16::MAX, 0, u16::MAX];
/// // Texel (1, 0), from u = 1/2 to u = 1, reads columns 1 and 2: with Repeat column 2 is
/// // column 0 again (the ramp falls back to 0), with Clamp it is column 1 (it stays at 1).
/// let repeat = HeightField::new(2, 2, samples.clone(), Wrap::Repeat).unwrap();
/// let clamp = HeightField::new(2, 2, samples, Wrap::Clamp).unwrap();
/// assert_eq!(repeat.texel_bounds(0, 1, 0), [0, u16::MAX]);
/// assert_eq!(clamp.texel_bounds(0, 1, 0), [u16::MAX, u16::MAX]);
/// ```
#[derive(Clone, Debug)]
pub struct HeightField {
    width: usize,
    height: usize,
    /// The level whose one node covers a whole tile: `2^top >= width, height`.
    top: u32,
    wrap: Wrap,
    /// Square, a power of two on the side, and repeated: nodes of the infinite grid are
    /// stored nodes, read through masks (the walks' fast path).
    square_power_of_two: bool,
    /// Repeated, both sides powers of two: sample indices wrap by masks.
    masked: bool,
    samples: Vec<u16>,
    /// `pyramid[k]` holds level `k + 2`.
    pyramid: Vec<Level>,
    range: [u16; 2],
}

/// Nodes along one axis of a level: the side halved `level` times, rounding up.
#[inline]
fn nodes_along(samples: usize, level: u32) -> usize {
    samples.div_ceil(1 << level)
}

impl HeightField {
    /// A height field from `width * height` samples (row-major, `v` down the rows); builds
    /// the pyramid. Any size from 2 x 2 up: a map is traced as it is, never resampled.
    ///
    /// # Errors
    /// When a side is below 2 or above [`MAX_SAMPLES_PER_SIDE`], or the sample count is not
    /// `width * height`.
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap};
    /// let field = HeightField::new(4, 4, vec![0; 16], Wrap::Repeat).unwrap();
    /// assert_eq!(field.texel_bounds(0, 3, 5), [0, 0]);
    /// // A DEM export: 3 x 5 samples, neither square nor a power of two.
    /// let dem = HeightField::new(3, 5, (0..15).collect(), Wrap::Clamp).unwrap();
    /// assert_eq!((dem.width(), dem.height(), dem.grid_side()), (3, 5, 8));
    /// assert_eq!(dem.texel_bounds(3, 0, 0), [0, 14]);
    /// assert!(HeightField::new(1, 9, vec![0; 9], Wrap::Repeat).is_err());
    /// ```
    pub fn new(
        width: usize,
        height: usize,
        samples: Vec<u16>,
        wrap: Wrap,
    ) -> Result<Self, HeightMapError> {
        let usable = |n: usize| (2..=MAX_SAMPLES_PER_SIDE).contains(&n);
        if !(usable(width) && usable(height)) {
            return Err(HeightMapError::BadSize { width, height });
        }
        if samples.len() != width * height {
            return Err(HeightMapError::WrongSampleCount {
                expected: width * height,
                got: samples.len(),
            });
        }
        let top = width.max(height).next_power_of_two().trailing_zeros();
        let mut field = Self {
            width,
            height,
            top,
            wrap,
            square_power_of_two: width == height && width.is_power_of_two() && wrap == Wrap::Repeat,
            masked: width.is_power_of_two() && height.is_power_of_two() && wrap == Wrap::Repeat,
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
        width: usize,
        height: usize,
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
        Self::new(width, height, samples, wrap)
    }

    /// Samples per row (texels per row of one tile).
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows of samples (texels per column of one tile).
    #[must_use]
    pub fn height(&self) -> usize {
        self.height
    }

    /// The side of the square texel grid the tracers work in: the smallest power of two at
    /// least the width and the height (the width itself for a square power-of-two map).
    /// Texture coordinates times the tiling, scaled by [`HeightField::grid_scale`], put texel
    /// `(x, y)` at `[x, x + 1] x [y, y + 1] / grid_side`, exactly in binary.
    #[must_use]
    pub fn grid_side(&self) -> usize {
        1 << self.top
    }

    /// Per axis, the texels of a tile over [`HeightField::grid_side`]: what texture
    /// coordinates times the tiling are multiplied by for the tracers' grid (`[1, 1]` for a
    /// square power-of-two map, so its coordinates are used as they are).
    #[must_use]
    pub fn grid_scale(&self) -> [f64; 2] {
        let g = self.grid_side() as f64;
        [self.width as f64 / g, self.height as f64 / g]
    }

    /// The side of a square map whose side is a power of two, `None` for any other map: what
    /// the compared methods built on a square pyramid of their own (cone maps, distance maps,
    /// geometry images) need.
    #[must_use]
    pub fn square_side(&self) -> Option<usize> {
        (self.width == self.height && self.width.is_power_of_two()).then_some(self.width)
    }

    /// The wrap mode.
    #[must_use]
    pub fn wrap(&self) -> Wrap {
        self.wrap
    }

    /// Level whose single node covers a whole tile.
    #[must_use]
    pub fn top_level(&self) -> u32 {
        self.top
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
        self.samples.len() * 2
            + self
                .pyramid
                .iter()
                .map(|l| l.nodes.len() * 4)
                .sum::<usize>()
    }

    /// Index `i` of an axis of `n` samples, wrapped.
    #[inline]
    fn wrap_along(&self, i: i64, n: usize) -> usize {
        let n = n as i64;
        if self.masked {
            // A power of two: the mask is `rem_euclid` (two's complement) without a division,
            // which the walk would pay per sample read.
            (i & (n - 1)) as usize
        } else if self.wrap == Wrap::Repeat {
            i.rem_euclid(n) as usize
        } else {
            i.clamp(0, n - 1) as usize
        }
    }

    #[inline]
    fn wrap_x(&self, i: i64) -> usize {
        self.wrap_along(i, self.width)
    }

    #[inline]
    fn wrap_y(&self, j: i64) -> usize {
        self.wrap_along(j, self.height)
    }

    /// The sample at corner `(i, j)` of the infinite texel grid (wrapped).
    #[must_use]
    #[inline]
    pub fn sample(&self, i: i64, j: i64) -> u16 {
        self.samples[self.wrap_y(j) * self.width + self.wrap_x(i)]
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

    /// The height of the microtriangle surface at the texel-grid point `(x, y)` (texel
    /// units: texture coordinates times the tiling times the width and the height), in
    /// `[0, 1]`, evaluated in f64: the texel's two microtriangles share the diagonal from its
    /// `(0, 0)` to its `(1, 1)` corner, as in the tracers. With it, the bound on the surface's
    /// slope in that texel (height per texel, the largest of its microtriangles' gradient
    /// lengths, at most `sqrt 2` times the corner range).
    ///
    /// ```
    /// use nlrt_accel::{HeightField, Wrap, HEIGHT_ONE};
    /// let field = HeightField::new(2, 2, vec![0, HEIGHT_ONE, 0, HEIGHT_ONE], Wrap::Clamp).unwrap();
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
        let columns: [usize; N] = core::array::from_fn(|i| self.wrap_x(i0 + i as i64));
        core::array::from_fn(|j| {
            let row = &self.samples[self.wrap_y(j0 + j as i64) * self.width..][..self.width];
            columns.map(|i| row[i])
        })
    }

    /// Asks the CPU to fetch the memory that expanding node `(x, y)` of `level` will read
    /// (level 2: its 5 x 5 samples, five rows; above: its children's bounds, two rows of the
    /// level below, on a square power-of-two repeated map), so that a node pushed for later
    /// is in cache when it is popped (a walk waits on memory on a large map). A hint: no
    /// effect on any result, and nothing where the target has no prefetch instruction.
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
                let i = self.wrap_x(4 * x);
                for j in 0..5 {
                    let row = self.wrap_y(4 * y + j) * self.width;
                    fetch(core::ptr::from_ref(&self.samples[row + i]).cast());
                }
            } else if level >= 3 && level - 1 <= self.top && self.square_power_of_two {
                let l = level - 1;
                let n = (self.width >> l) as i64;
                let row = &self.pyramid[l as usize - 2].nodes;
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
    /// a square power-of-two repeated map read inline (the walks' inner loop).
    #[must_use]
    #[inline(always)]
    pub(crate) fn four_bounds(&self, level: u32, x: i64, y: i64) -> [[u16; 2]; 4] {
        if level >= 2 && level <= self.top && self.square_power_of_two {
            let n = (self.width >> level) as i64;
            let row = &self.pyramid[level as usize - 2].nodes;
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
    /// infinite and wraps), covering texels `[x 2^l, (x + 1) 2^l) x [y 2^l, (y + 1) 2^l)`.
    /// Exact on a square power-of-two repeated map and inside the tile of a clamped one;
    /// elsewhere the union of the stored nodes the node overlaps, which holds every sample
    /// it covers. Levels above the top cover several tiles and get the whole map's range.
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
            l if l <= self.top && self.square_power_of_two => {
                let n = (self.width >> l) as i64;
                let row = &self.pyramid[l as usize - 2].nodes;
                // A power of two: masks wrap like `rem_euclid`.
                row[((y & (n - 1)) * n + (x & (n - 1))) as usize]
            }
            l if l <= self.top => {
                let stored = &self.pyramid[l as usize - 2];
                let mut b = [u16::MAX, 0];
                let columns = self.stored_spans(l, x, self.width);
                for rows in self.stored_spans(l, y, self.height).into_iter().flatten() {
                    for j in rows[0]..=rows[1] {
                        for cols in columns.into_iter().flatten() {
                            for n in &stored.nodes[j * stored.columns..][cols[0]..=cols[1]] {
                                b = [b[0].min(n[0]), b[1].max(n[1])];
                            }
                        }
                    }
                }
                b
            }
            _ => self.range,
        }
    }

    /// The stored nodes of `level` (inclusive index spans, at most two) that node `i` of the
    /// infinite grid overlaps along an axis of `n` samples: the texels `[i 2^l, (i + 1) 2^l)`
    /// wrapped into the tile (a repeated map: one span, or two where they cross the tile's
    /// edge; the whole axis where they cover a tile), or clamped to it (a clamped map: texels
    /// outside read the edge samples, which the edge node holds).
    fn stored_spans(&self, level: u32, i: i64, n: usize) -> [Option<[usize; 2]>; 2] {
        let last = nodes_along(n, level) - 1;
        let span = 1i64 << level;
        let (n, start) = (n as i64, i.saturating_mul(span));
        match self.wrap {
            Wrap::Repeat if span >= n => [Some([0, last]), None],
            Wrap::Repeat => {
                let a = start.rem_euclid(n);
                let end = a + span; // exclusive
                if end <= n {
                    [
                        Some([(a >> level) as usize, ((end - 1) >> level) as usize]),
                        None,
                    ]
                } else {
                    [
                        Some([(a >> level) as usize, last]),
                        Some([0, ((end - n - 1) >> level) as usize]),
                    ]
                }
            }
            Wrap::Clamp => {
                let lo = start.clamp(0, n - 1);
                let hi = start.saturating_add(span - 1).clamp(0, n - 1);
                [Some([(lo >> level) as usize, (hi >> level) as usize]), None]
            }
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
        if self.top < 2 {
            return;
        }
        self.pyramid.push(self.level2_from_samples());
        for level in 3..=self.top {
            let (columns, rows) = (
                nodes_along(self.width, level),
                nodes_along(self.height, level),
            );
            let mut nodes = Vec::with_capacity(columns * rows);
            for y in 0..rows {
                for x in 0..columns {
                    nodes.push(self.node_from_children(level, x, y));
                }
            }
            self.pyramid.push(Level { columns, nodes });
        }
    }

    /// Stored node `(x, y)` of `level >= 3` from its children in the level below (those that
    /// exist: the last node of a row or column may have only one child along that axis).
    fn node_from_children(&self, level: u32, x: usize, y: usize) -> [u16; 2] {
        let below = &self.pyramid[level as usize - 3];
        let rows_below = below.nodes.len() / below.columns;
        let mut b = [u16::MAX, 0];
        for cy in 2 * y..(2 * y + 2).min(rows_below) {
            for cx in 2 * x..(2 * x + 2).min(below.columns) {
                let c = below.nodes[cy * below.columns + cx];
                b = [b[0].min(c[0]), b[1].max(c[1])];
            }
        }
        b
    }

    /// Level 2 (4 x 4 texels, up to 5 x 5 samples per node) in two separable passes: along
    /// rows, then down the columns of row results. A node's corners run from `4 x` to
    /// `min(4 x + 4, width)`; the corner at the width (the far side of the tile's last texel)
    /// is the wrapped one.
    fn level2_from_samples(&self) -> Level {
        let (w, h) = (self.width, self.height);
        let (columns, rows_of_nodes) = (nodes_along(w, 2), nodes_along(h, 2));
        let mut rows = alloc::vec![[0u16, 0u16]; h * columns];
        for j in 0..h {
            let row = &self.samples[j * w..(j + 1) * w];
            for x in 0..columns {
                let mut b = [u16::MAX, 0];
                for i in 4 * x..=(4 * x + 4).min(w) {
                    let s = row[if i < w { i } else { self.wrap_x(i as i64) }];
                    b = [b[0].min(s), b[1].max(s)];
                }
                rows[j * columns + x] = b;
            }
        }
        let mut nodes = alloc::vec![[u16::MAX, 0u16]; columns * rows_of_nodes];
        for y in 0..rows_of_nodes {
            for j in 4 * y..=(4 * y + 4).min(h) {
                let j = if j < h { j } else { self.wrap_y(j as i64) };
                let r = &rows[j * columns..(j + 1) * columns];
                let out = &mut nodes[y * columns..(y + 1) * columns];
                for (o, c) in out.iter_mut().zip(r) {
                    *o = [o[0].min(c[0]), o[1].max(c[1])];
                }
            }
        }
        Level { columns, nodes }
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
        let (w, h) = (self.width as i64, self.height as i64);
        // With Repeat, sample 0 is also the far corner of the tile's last texels.
        if self.wrap == Wrap::Repeat && x0 <= 0 && x1 > 0 {
            self.update_region(w - 1, y0, w, y1);
        }
        if self.wrap == Wrap::Repeat && y0 <= 0 && y1 > 0 {
            self.update_region(x0, h - 1, x1, h);
        }
        // A texel reads corners up to +1, so an edited sample touches the texels before it.
        let (x0, y0) = ((x0 - 1).max(0), (y0 - 1).max(0));
        let (x1, y1) = (x1.min(w), y1.min(h));
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        for j in y0..(y1 + 1).min(h) {
            for i in x0..(x1 + 1).min(w) {
                let s = self.samples[(j * w + i) as usize];
                self.range = [self.range[0].min(s), self.range[1].max(s)];
            }
        }
        for level in 2..=self.top {
            let (nx0, ny0) = ((x0 >> level) as usize, (y0 >> level) as usize);
            let (nx1, ny1) = (((x1 - 1) >> level) as usize, ((y1 - 1) >> level) as usize);
            for y in ny0..=ny1 {
                for x in nx0..=nx1 {
                    let b = if level == 2 {
                        let mut b = [u16::MAX, 0];
                        for j in 4 * y as i64..=(4 * y as i64 + 4).min(h) {
                            for i in 4 * x as i64..=(4 * x as i64 + 4).min(w) {
                                let s = self.sample(i, j);
                                b = [b[0].min(s), b[1].max(s)];
                            }
                        }
                        b
                    } else {
                        self.node_from_children(level, x, y)
                    };
                    let stored = &mut self.pyramid[level as usize - 2];
                    stored.nodes[y * stored.columns + x] = b;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec;

    /// `count` samples spread over the whole 16-bit range.
    fn pseudo_random(count: usize, seed: u64) -> Vec<u16> {
        let mut unit = crate::test_util::unit_randoms(seed);
        (0..count).map(|_| (unit() * 65536.0) as u16).collect()
    }

    /// Bounds over every corner sample of node `(x, y)` of `level`, read one by one.
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

    /// Sizes: square powers of two (the fast path), and maps that are neither square nor a
    /// power of two on either side (odd, one more than a power of two, tiny).
    const SIZES: [(usize, usize); 6] = [(16, 16), (8, 8), (13, 7), (17, 33), (2, 5), (24, 10)];

    /// Every node of every level, inside the tile, around it and several tiles away, holds
    /// every sample it covers; nodes the stored pyramid holds as they are (a square
    /// power-of-two repeated map, nodes inside a clamped tile, aligned nodes inside a repeated
    /// tile) are exact.
    #[test]
    fn bounds_enclose_every_sample_of_the_node() {
        for (w, h) in SIZES {
            for wrap in [Wrap::Repeat, Wrap::Clamp] {
                let f = HeightField::new(w, h, pseudo_random(w * h, 7), wrap).unwrap();
                for level in 0..=f.top_level() + 1 {
                    let span = 1i64 << level;
                    let reach = |n: usize| 3 * (n as i64 / span + 1);
                    for y in -reach(h)..=reach(h) {
                        for x in -reach(w)..=reach(w) {
                            let b = f.texel_bounds(level, x, y);
                            let t = brute_bounds(&f, level, x, y);
                            let at = (w, h, wrap, level, x, y);
                            assert!(b[0] <= t[0] && b[1] >= t[1], "{at:?}");
                            let inside = |i: i64, n: usize| i >= 0 && (i + 1) * span <= n as i64;
                            if level <= 1
                                || (w == h && w.is_power_of_two() && wrap == Wrap::Repeat)
                                || (inside(x, w) && inside(y, h) && level <= f.top_level())
                            {
                                assert_eq!(b, t, "{at:?}: a stored node is exact");
                            }
                        }
                    }
                }
                // The four children's bounds are the single ones.
                for level in 0..=f.top_level() {
                    for (x, y) in [(-4, 2), (0, 0), (6, -2), (10, 12)] {
                        let four = f.four_bounds(level, x, y);
                        for (k, b) in four.iter().enumerate() {
                            let (cx, cy) = (x + (k & 1) as i64, y + (k >> 1) as i64);
                            assert_eq!(*b, f.texel_bounds(level, cx, cy));
                        }
                    }
                }
            }
        }
    }

    /// Repeat reads the sample of the tile's copy the corner lies in, for negative and far
    /// corners too (a mask on a power-of-two side, which must agree with `rem_euclid`); Clamp
    /// reads the nearest edge sample.
    #[test]
    fn samples_wrap_like_the_repeated_or_clamped_tile() {
        for (w, h) in SIZES {
            let values = pseudo_random(w * h, 11);
            for wrap in [Wrap::Repeat, Wrap::Clamp] {
                let f = HeightField::new(w, h, values.clone(), wrap).unwrap();
                let (wi, hi) = (w as i64, h as i64);
                for j in [
                    -3 * hi - 1,
                    -hi,
                    -5,
                    -1,
                    0,
                    3,
                    hi - 1,
                    hi,
                    13,
                    5 * hi + 2,
                    1 << 40,
                ] {
                    for i in [
                        -(1 << 40) - 3,
                        -2 * wi + 1,
                        -1,
                        0,
                        wi - 2,
                        wi,
                        9,
                        4 * wi - 1,
                    ] {
                        let index = |c: i64, n: i64| match wrap {
                            Wrap::Repeat => c.rem_euclid(n),
                            Wrap::Clamp => c.clamp(0, n - 1),
                        };
                        let expected = values[(index(j, hi) * wi + index(i, wi)) as usize];
                        assert_eq!(f.sample(i, j), expected, "{w}x{h} {wrap:?} ({i}, {j})");
                    }
                }
            }
        }
    }

    /// Edits, at the tile's edges too (with Repeat, sample 0 is the far corner of the last
    /// texels), leave the same pyramid as a rebuild, on square and other maps.
    #[test]
    fn partial_update_matches_a_rebuild() {
        for (w, h) in [(32, 32), (37, 21), (20, 45)] {
            for wrap in [Wrap::Repeat, Wrap::Clamp] {
                let mut f = HeightField::new(w, h, pseudo_random(w * h, 3), wrap).unwrap();
                for j in 10..14 {
                    for i in 5..9 {
                        f.samples_mut()[j * w + i] = 65535 - (i * j) as u16;
                    }
                }
                f.update_region(5, 10, 9, 14);
                f.samples_mut()[0] = 12345;
                f.samples_mut()[1] = 65535;
                f.update_region(0, 0, 2, 1);
                let last = w * h - 1;
                f.samples_mut()[last] = 7;
                f.update_region(w as i64 - 1, h as i64 - 1, w as i64, h as i64);
                let mut g = f.clone();
                g.rebuild();
                assert_eq!(f.pyramid, g.pyramid, "{w}x{h} {wrap:?}");
            }
        }
    }

    /// Memory stays about 4/3 of the samples (16-bit samples, 32-bit nodes from 4 x 4 texels),
    /// whatever the size.
    #[test]
    fn the_pyramid_is_a_third_of_the_samples() {
        for (w, h) in [(1024, 1024), (1000, 1000), (1025, 513), (600, 371)] {
            let f = HeightField::new(w, h, vec![0; w * h], Wrap::Repeat).unwrap();
            let ratio = f.memory_bytes() as f64 / (2 * w * h) as f64;
            assert!((1.1..1.25).contains(&ratio), "{w}x{h}: {ratio}");
        }
    }

    #[test]
    fn rejects_bad_sizes() {
        for (w, h) in [(1, 9), (9, 1), (0, 0), (MAX_SAMPLES_PER_SIDE + 1, 2)] {
            assert_eq!(
                HeightField::new(w, h, vec![0; w * h], Wrap::Repeat).unwrap_err(),
                HeightMapError::BadSize {
                    width: w,
                    height: h
                }
            );
        }
        assert!(matches!(
            HeightField::new(8, 7, vec![0; 49], Wrap::Repeat),
            Err(HeightMapError::WrongSampleCount {
                expected: 56,
                got: 49
            })
        ));
        let message = alloc::format!(
            "{}",
            HeightField::new(1, 5, vec![0; 5], Wrap::Clamp).unwrap_err()
        );
        assert!(
            message.contains("1 x 5") && message.contains("from 2"),
            "{message}"
        );
    }
}
