//! Which training item each step takes: every epoch visits every item once, in an
//! order shuffled by the seed.
//!
//! The order of epoch `e` is a pure function of `(seed, e)` (Fisher–Yates driven by
//! SplitMix64 seeded from both), so the sampler's whole state is the cursor
//! `(epoch, position)`: a checkpoint stores two integers and a resumed run draws exactly
//! the items the uninterrupted run would have drawn.

use serde::{Deserialize, Serialize};
use weft_mesh::rng::SplitMix64;

/// Where the sampler is: the epoch and the position within its order.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Cursor {
    /// Completed epochs.
    pub epoch: usize,
    /// Items of the current epoch already taken.
    pub position: usize,
}

/// The shuffled order of `items` training items.
#[derive(Clone, Debug)]
pub struct Sampler {
    seed: u64,
    items: usize,
    cursor: Cursor,
    order: Vec<usize>,
}

/// The order of epoch `epoch`.
pub fn epoch_order(seed: u64, epoch: usize, items: usize) -> Vec<usize> {
    let mut rng = SplitMix64::new(seed ^ (epoch as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
    let mut order: Vec<usize> = (0..items).collect();
    for i in (1..items).rev() {
        order.swap(i, rng.below(i + 1));
    }
    order
}

impl Sampler {
    /// A sampler over `items > 0` items at `cursor`.
    pub fn new(seed: u64, items: usize, cursor: Cursor) -> Self {
        Sampler {
            seed,
            items,
            cursor,
            order: epoch_order(seed, cursor.epoch, items),
        }
    }

    /// The cursor (to store in a checkpoint).
    pub fn cursor(&self) -> Cursor {
        self.cursor
    }

    /// Items per epoch.
    pub fn items(&self) -> usize {
        self.items
    }

    /// The next item, and whether it is the last of its epoch.
    pub fn next_item(&mut self) -> (usize, bool) {
        if self.cursor.position >= self.items {
            self.cursor = Cursor {
                epoch: self.cursor.epoch + 1,
                position: 0,
            };
            self.order = epoch_order(self.seed, self.cursor.epoch, self.items);
        }
        let item = self.order[self.cursor.position];
        self.cursor.position += 1;
        (item, self.cursor.position == self.items)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_epoch_is_a_permutation_and_depends_on_seed_and_epoch() {
        let a = epoch_order(7, 0, 50);
        let mut sorted = a.clone();
        sorted.sort_unstable();
        assert_eq!(sorted, (0..50).collect::<Vec<_>>());
        assert_ne!(a, epoch_order(7, 1, 50));
        assert_ne!(a, epoch_order(8, 0, 50));
        assert_eq!(a, epoch_order(7, 0, 50));
    }

    #[test]
    fn a_sampler_restarted_at_its_cursor_draws_the_same_items() {
        let mut straight = Sampler::new(3, 7, Cursor::default());
        let all: Vec<(usize, bool)> = (0..30).map(|_| straight.next_item()).collect();
        let mut first = Sampler::new(3, 7, Cursor::default());
        let mut drawn: Vec<(usize, bool)> = (0..12).map(|_| first.next_item()).collect();
        let mut resumed = Sampler::new(3, 7, first.cursor());
        drawn.extend((0..18).map(|_| resumed.next_item()));
        assert_eq!(drawn, all);
        assert_eq!(all.iter().filter(|(_, last)| *last).count(), 4);
    }
}
