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

// SAFETY: the threads sharing a `Disjoint` touch disjoint elements (each use says why), and `T`
// is sent between them.
#[allow(unsafe_code)]
unsafe impl<T: Send> Sync for Disjoint<'_, T> {}

impl<'a, T: Copy> Disjoint<'a, T> {
    /// Shares `slice` for the time of the borrow.
    pub(crate) fn new(slice: &'a mut [T]) -> Self {
        Self {
            ptr: slice.as_mut_ptr(),
            len: slice.len(),
            _borrow: std::marker::PhantomData,
        }
    }

    /// Element `i`.
    ///
    /// # Safety
    /// No other thread may write element `i` at the same time.
    #[allow(unsafe_code)]
    #[inline]
    pub(crate) unsafe fn get(&self, i: usize) -> T {
        assert!(i < self.len, "an index past the end of a shared slice");
        // SAFETY: in bounds (just checked); the caller guarantees no concurrent write.
        unsafe { *self.ptr.add(i) }
    }

    /// Sets element `i`.
    ///
    /// # Safety
    /// No other thread may read or write element `i` at the same time.
    #[allow(unsafe_code)]
    #[inline]
    pub(crate) unsafe fn set(&self, i: usize, value: T) {
        assert!(i < self.len, "an index past the end of a shared slice");
        // SAFETY: in bounds (just checked); the caller guarantees exclusive access.
        unsafe { *self.ptr.add(i) = value }
    }

    /// A pointer to the `len` elements from `start`, for a task's vector loads and stores.
    ///
    /// # Safety
    /// No other thread may write these elements while the pointer is read from, nor read or
    /// write them while it is written through.
    #[cfg(target_arch = "x86_64")]
    #[allow(unsafe_code)]
    #[inline]
    pub(crate) unsafe fn run(&self, start: usize, len: usize) -> *mut T {
        assert!(
            start <= self.len && len <= self.len - start,
            "a run past the end of a shared slice"
        );
        // SAFETY: in bounds (just checked).
        unsafe { self.ptr.add(start) }
    }
}
