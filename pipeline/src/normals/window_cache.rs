//! One eigen-solve per distinct window: members whose windows cover the
//! same table cells share a normal.
//!
//! A window holds the summed-area table cells its pixels touch, so its
//! moment sums are a function of four cell indices, and neighbouring
//! members often get the very same window: the two pixels of a table cell
//! (2 x 2 pixels) at the same radius, and every member of a narrow plane
//! (a stair riser) whose windows reach its bounding box's top and bottom.
//! On the recorded Kinect frames 10,000 members of a riser have 651
//! distinct windows, the Kinect v1 wall 2,240 of 9,870. The same cells give
//! the same sums, bit for bit, and the same sums the same eigenvector, so
//! the normal (before it is oriented towards the viewpoint, which depends
//! on the member's own point) is computed once per window and looked up
//! for the others: the normals are unchanged, bit for bit
//! (`normals::tests::shared_windows_give_each_member_its_own_normal`).
//!
//! The lookup is a direct-mapped table of [`SLOTS`] entries, cleared per
//! call: a window whose slot another window took is solved again, which
//! costs time, never a different answer.

use nalgebra::Vector3;

/// The table cells `[a0, a1) x [b0, b1)` a window covers, packed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(super) struct WindowKey(u128);

impl WindowKey {
    /// No window: never equal to a real key (a window has `a0 < a1`).
    const NONE: WindowKey = WindowKey(u128::MAX);

    /// The key of the cells `[a0, a1) x [b0, b1)`. Pixel indices are `u32`,
    /// so every cell index fits in 32 bits and no two windows share a key.
    pub(super) fn new(a0: usize, a1: usize, b0: usize, b1: usize) -> Self {
        let part = |x: usize| u128::from(x as u32);
        WindowKey(part(a0) | part(a1) << 32 | part(b0) << 64 | part(b1) << 96)
    }

    fn slot(self) -> usize {
        // Fibonacci hashing of both halves folded: the top bits of the
        // product.
        let folded = (self.0 as u64) ^ ((self.0 >> 64) as u64).rotate_left(16);
        (folded.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - SLOT_BITS)) as usize
    }
}

const SLOT_BITS: u32 = 11;
/// Entries of the lookup table.
pub(super) const SLOTS: usize = 1 << SLOT_BITS;

/// The normals of the windows solved so far in one call.
#[derive(Debug, Clone, Default)]
pub(super) struct WindowNormals {
    entries: Vec<(WindowKey, Option<Vector3<f64>>)>,
}

impl WindowNormals {
    /// Forgets every window (the table changed).
    pub(super) fn clear(&mut self) {
        self.entries.clear();
        self.entries.resize(SLOTS, (WindowKey::NONE, None));
    }

    /// The normal of `key`'s window: looked up, or `solve`d and kept.
    #[inline]
    pub(super) fn get_or_solve(
        &mut self,
        key: WindowKey,
        solve: impl FnOnce() -> Option<Vector3<f64>>,
    ) -> Option<Vector3<f64>> {
        let entry = &mut self.entries[key.slot()];
        if entry.0 != key {
            *entry = (key, solve());
        }
        entry.1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_of_different_windows_differ_and_a_taken_slot_is_solved_again() {
        let a = WindowKey::new(1, 9, 0, 13);
        assert_ne!(a, WindowKey::new(1, 9, 0, 14));
        assert_ne!(a, WindowKey::new(0, 9, 1, 13));
        assert_ne!(a, WindowKey::NONE);
        let mut cache = WindowNormals::default();
        cache.clear();
        let x = Vector3::x();
        let solved = std::cell::Cell::new(0);
        let solve = |n: Vector3<f64>| {
            solved.set(solved.get() + 1);
            Some(n)
        };
        assert_eq!(cache.get_or_solve(a, || solve(x)), Some(x));
        assert_eq!(cache.get_or_solve(a, || solve(-x)), Some(x));
        assert_eq!(solved.get(), 1);
        // A key in the same slot replaces it: `a` is solved again.
        let other = (0..100_000)
            .map(|i| WindowKey::new(i % 300, i % 300 + 1, i / 300, i / 300 + 1))
            .find(|k| *k != a && k.slot() == a.slot())
            .expect("2048 slots: some key of 100,000 shares a's");
        assert_eq!(cache.get_or_solve(other, || solve(-x)), Some(-x));
        assert_eq!(cache.get_or_solve(a, || solve(x)), Some(x));
        assert_eq!(solved.get(), 3);
    }
}
