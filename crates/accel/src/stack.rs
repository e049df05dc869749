//! The traversal stack of the BVH walks: a short fixed array (initialised once per walk, so
//! its length is paid on every ray) that spills onto the heap only for a walk deeper than
//! any sane tree needs. The worst case of a 4-ary tree built with median splits past a
//! depth limit is hundreds of entries; zero-filling that many per ray (or per tile of a
//! shell) cost more than the traversal of shallow trees, while sizing the array for the
//! typical case alone would need an unsafe bound.

use alloc::vec::Vec;

/// A last-in-first-out stack of `N` inline entries, then a heap-allocated spill (allocated
/// on the first push beyond `N`, never in walks that stay within it).
pub(crate) struct SpillStack<E, const N: usize> {
    inline: [E; N],
    len: usize,
    spill: Vec<E>,
}

impl<E: Copy, const N: usize> SpillStack<E, N> {
    /// An empty stack whose unused entries hold `fill`.
    #[inline]
    pub(crate) fn new(fill: E) -> Self {
        Self {
            inline: [fill; N],
            len: 0,
            spill: Vec::new(),
        }
    }

    /// Pushes `entry` on top.
    #[inline]
    pub(crate) fn push(&mut self, entry: E) {
        if self.len < N {
            self.inline[self.len] = entry;
            self.len += 1;
        } else {
            self.spill.push(entry);
        }
    }

    /// Removes and returns the top entry.
    #[inline]
    pub(crate) fn pop(&mut self) -> Option<E> {
        if let Some(entry) = self.spill.pop() {
            return Some(entry);
        }
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        Some(self.inline[self.len])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries come back last in, first out, across the inline part and the spill, and the
    /// spill is used only beyond the inline length.
    #[test]
    fn entries_come_back_in_reverse_order_across_the_spill() {
        let mut stack = SpillStack::<u32, 4>::new(0);
        for round in 0..2 {
            for i in 0..10 {
                stack.push(i);
                assert_eq!(stack.spill.len(), (i as usize + 1).saturating_sub(4));
            }
            for i in (5..10).rev() {
                assert_eq!(stack.pop(), Some(i));
            }
            stack.push(100 + round);
            assert_eq!(stack.pop(), Some(100 + round));
            for i in (0..5).rev() {
                assert_eq!(stack.pop(), Some(i));
            }
            assert_eq!(stack.pop(), None);
        }
    }
}
