//! [`Roots`]: the fixed-capacity, sorted result of a solver (no heap, `Copy`).

use crate::Real;
use core::ops::Deref;

/// Up to three distinct real roots in increasing order.
///
/// Dereferences to a slice, so `roots.len()`, `roots[0]`, `roots.iter()` and
/// `roots.first()` work as on `&[T]`.
///
/// ```
/// use nlrt_poly::solve_cubic;
/// // (x - 1)(x - 2)(x - 3) = x^3 - 6x^2 + 11x - 6, coefficients by ascending power.
/// let roots = solve_cubic([-6.0f64, 11.0, -6.0, 1.0]);
/// assert_eq!(roots.len(), 3);
/// assert!((roots[1] - 2.0).abs() < 1e-15);
/// ```
/// Two root sets are equal when they hold the same roots (`as_slice` equality).
#[derive(Clone, Copy)]
pub struct Roots<T: Real> {
    values: [T; 3],
    len: u8,
}

impl<T: Real> Roots<T> {
    /// No roots.
    #[must_use]
    #[inline]
    pub const fn none() -> Self {
        Self {
            values: [T::ZERO; 3],
            len: 0,
        }
    }

    /// Builds a root set from up to three values, which are sorted; used by the solvers.
    ///
    /// # Panics
    /// If more than three values are given.
    #[must_use]
    pub fn from_slice(values: &[T]) -> Self {
        let mut roots = Self::none();
        for &v in values {
            roots.push(v);
        }
        roots.sort();
        roots
    }

    /// The first `len` of `values` (`len <= 3`; the rest is ignored), sorted by a three-element
    /// min/max network and with repeated values kept once: what a caller of a whole-line
    /// solver that returns its roots unordered needs to meet this type's contract, with no
    /// branch on the data. NaN values are the caller's to filter first.
    ///
    /// ```
    /// use nlrt_poly::Roots;
    /// let r = Roots::from_unsorted([0.75f64, 0.25, 0.75], 3);
    /// assert_eq!(r.as_slice(), &[0.25, 0.75]);
    /// assert_eq!(Roots::from_unsorted([0.5f32, 9.0, 9.0], 1).as_slice(), &[0.5]);
    /// ```
    ///
    /// # Panics
    /// If `len > 3`.
    #[must_use]
    #[inline(always)]
    pub fn from_unsorted(values: [T; 3], len: usize) -> Self {
        assert!(len <= 3, "a cubic has at most three roots");
        // Unused slots become +inf, which the network moves behind the `len` values (a value
        // of +inf itself sorts beside them, the same).
        let v: [T; 3] = core::array::from_fn(|i| if i < len { values[i] } else { T::INFINITY });
        let (a, b) = (v[0].min(v[1]), v[0].max(v[1]));
        let (b, c) = (b.min(v[2]), b.max(v[2]));
        let (a, b) = (a.min(b), a.max(b));
        // Sorted: a repeat sits beside its twin. Keep each value's first copy.
        let repeat_b = usize::from(len >= 2 && b == a);
        let repeat_c = usize::from(len >= 3 && c == b);
        Self {
            values: [a, if repeat_b == 1 { c } else { b }, c],
            len: (len - repeat_b - repeat_c) as u8,
        }
    }

    /// Three roots already in increasing order.
    #[must_use]
    #[inline(always)]
    pub(crate) fn from_sorted(values: [T; 3]) -> Self {
        Self { values, len: 3 }
    }

    /// Sets the roots to the first `len` of `values` (already in increasing order); the rest
    /// is ignored.
    #[inline(always)]
    pub(crate) fn set_first(&mut self, values: [T; 3], len: u8) {
        debug_assert!(len <= 3);
        self.values = values;
        self.len = len;
    }

    /// Appends a root (the solvers push in increasing order).
    #[inline]
    pub(crate) fn push(&mut self, value: T) {
        self.values[self.len as usize] = value;
        self.len += 1;
    }

    /// Replaces the last root.
    #[inline]
    pub(crate) fn set_last(&mut self, value: T) {
        self.values[self.len as usize - 1] = value;
    }

    /// The roots as a slice.
    #[must_use]
    #[inline]
    pub fn as_slice(&self) -> &[T] {
        &self.values[..self.len as usize]
    }

    /// Sorts by value (insertion sort of at most three elements).
    #[inline]
    pub(crate) fn sort(&mut self) {
        let n = self.len as usize;
        for i in 1..n {
            let mut j = i;
            while j > 0 && self.values[j - 1] > self.values[j] {
                self.values.swap(j - 1, j);
                j -= 1;
            }
        }
    }

    /// Keeps only the roots in `[lo, hi]`.
    #[must_use]
    #[inline]
    pub fn within(self, lo: T, hi: T) -> Self {
        let mut out = Self::none();
        for &v in self.as_slice() {
            if v >= lo && v <= hi {
                out.push(v);
            }
        }
        out
    }
}

impl<T: Real> PartialEq for Roots<T> {
    #[inline]
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

impl<T: Real> Default for Roots<T> {
    fn default() -> Self {
        Self::none()
    }
}

impl<T: Real> Deref for Roots<T> {
    type Target = [T];
    #[inline]
    fn deref(&self) -> &[T] {
        self.as_slice()
    }
}

impl<T: Real> core::fmt::Debug for Roots<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

#[cfg(test)]
mod tests {
    use super::Roots;
    extern crate std;

    /// `from_unsorted` agrees with sorting and removing repeats by hand on every ordering of
    /// every pattern of repeats among three values, for every length.
    #[test]
    fn from_unsorted_sorts_and_keeps_each_value_once() {
        let patterns: [[f64; 3]; 5] = [
            [0.1, 0.2, 0.3],
            [0.1, 0.1, 0.3],
            [0.1, 0.3, 0.3],
            [0.2, 0.2, 0.2],
            [-0.0, 0.5, f64::INFINITY],
        ];
        let orders = [
            [0, 1, 2],
            [0, 2, 1],
            [1, 0, 2],
            [1, 2, 0],
            [2, 0, 1],
            [2, 1, 0],
        ];
        for pattern in patterns {
            for order in orders {
                let values = order.map(|i| pattern[i]);
                for len in 0..=3 {
                    let mut expected: std::vec::Vec<f64> = values[..len].to_vec();
                    expected.sort_by(f64::total_cmp);
                    expected.dedup();
                    let got = Roots::from_unsorted(values, len);
                    assert_eq!(got.as_slice(), &expected[..], "{values:?} len {len}");
                    let narrow = Roots::from_unsorted(values.map(|v| v as f32), len);
                    assert_eq!(narrow.len(), expected.len(), "{values:?} len {len}");
                }
            }
        }
    }
}
