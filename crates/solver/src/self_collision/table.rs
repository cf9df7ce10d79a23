//! The table from box keys to cells: open addressing, linear probing, at most half full. Cells
//! are numbered in order of first appearance and keep their numbers until the table is cleared.

/// A key no box has: box keys use the low 63 bits.
const EMPTY: u64 = u64::MAX;

/// An open-addressing table from box keys to cells (linear probing, at most half full).
#[derive(Debug, Default, Clone)]
pub(super) struct Table {
    slots: Vec<Slot>,
    /// Cells handed out, which is the number of keys in the table.
    pub(super) cells: usize,
}

/// Bytes of one slot of the table.
pub(super) const SLOT_BYTES: usize = std::mem::size_of::<Slot>();

#[derive(Debug, Clone, Copy)]
struct Slot {
    key: u64,
    cell: u32,
}

impl Table {
    /// Empties the table and gives it `size` slots (a power of two).
    pub(super) fn clear(&mut self, size: usize) {
        self.slots.clear();
        self.slots.resize(
            size,
            Slot {
                key: EMPTY,
                cell: 0,
            },
        );
        self.cells = 0;
    }

    /// Where `key` is, or the empty slot where it would go.
    #[inline]
    fn home(&self, key: u64) -> usize {
        let size = self.slots.len();
        // Fibonacci hashing: the top bits of key * 2^64/phi spread neighbouring boxes.
        let mut slot =
            (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> (64 - size.trailing_zeros())) as usize;
        loop {
            let seen = self.slots[slot].key;
            if seen == key || seen == EMPTY {
                return slot;
            }
            slot = (slot + 1) & (size - 1);
        }
    }

    /// The cell of `key`, if it has one.
    #[inline]
    pub(super) fn find(&self, key: u64) -> Option<u32> {
        let slot = self.slots[self.home(key)];
        (slot.key == key).then_some(slot.cell)
    }

    /// The cell of `key`, a new one (the next number) when the key is new.
    pub(super) fn cell(&mut self, key: u64) -> u32 {
        let slot = self.home(key);
        if self.slots[slot].key == key {
            return self.slots[slot].cell;
        }
        if 2 * (self.cells + 1) > self.slots.len() {
            // NOTE: cells keep their numbers, so the points' cells stay valid.
            let old = std::mem::take(&mut self.slots);
            self.slots = vec![
                Slot {
                    key: EMPTY,
                    cell: 0
                };
                2 * old.len()
            ];
            for s in old.iter().filter(|s| s.key != EMPTY) {
                let home = self.home(s.key);
                self.slots[home] = *s;
            }
            return self.cell(key);
        }
        let cell = self.cells as u32;
        self.slots[slot] = Slot { key, cell };
        self.cells += 1;
        cell
    }
}

/// A table for `boxes` boxes in use: a quarter full, so the cloth can enter as many boxes again
/// before it grows.
pub(super) fn table_size(boxes: usize) -> usize {
    (4 * boxes).max(64).next_power_of_two()
}
