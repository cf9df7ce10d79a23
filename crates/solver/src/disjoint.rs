//! A slice shared between threads that touch disjoint elements.

/// A slice that several threads read and write at once, each at its own indices.
///
/// NOTE: the threaded passes write interleaved or scattered but disjoint elements of one array
/// (self-collision's placement: each run has its own places in every box; its resolution:
/// each box the anchors of its own points, a few from each of a few rows; the colored stretch
/// limit: each task the ends of its own class's springs), which no safe split of a slice
/// can express. Holding the exclusive borrow keeps anything else off the array meanwhile.
pub(crate) struct Disjoint<'a, T> {
    ptr: *mut T,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [T]>,
}

// SAFETY: the threads sharing a `Disjoint` touch disjoint elements (each use of `run` says why),
// and `T` is sent between them.
#[allow(unsafe_code)]
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T> Disjoint<'a, T> {
    /// Shares `slice` for the time of the borrow.
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: std::marker::PhantomData,
        }
    }

    /// The `len` elements from `start`, for one thread's reads and writes.
    ///
    /// # Safety
    /// While the returned slice lives, nothing else (no other thread, no other slice from this
    /// `Disjoint`) may read or write these elements.
    ///
    /// # Panics
    /// When the run is past the end of the slice.
    #[allow(unsafe_code, clippy::mut_from_ref)]
    #[inline]
    pub(crate) unsafe fn run(&self, start: usize, len: usize) -> &mut [T] {
        assert!(
            start <= self.len && len <= self.len - start,
            "a run past the end of a shared slice"
        );
        // SAFETY: in bounds (just checked) of a slice borrowed mutably for `'a`, which outlives
        // `&self`; the caller guarantees that the run is touched through this slice alone.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(start), len) }
    }
}
