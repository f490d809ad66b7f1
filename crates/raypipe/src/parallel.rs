//! Writes from parallel tasks into one buffer, each task at indices of its own.

/// A shared output buffer that tasks write at disjoint indices.
#[derive(Clone, Copy)]
pub(crate) struct DisjointWrites<T>(*mut T, usize);

// SAFETY: callers only write disjoint indices from different tasks and read after all have joined.
unsafe impl<T: Send> Send for DisjointWrites<T> {}
unsafe impl<T: Send> Sync for DisjointWrites<T> {}

impl<T> DisjointWrites<T> {
    pub(crate) fn new(slice: &mut [T]) -> Self {
        Self(slice.as_mut_ptr(), slice.len())
    }

    /// # Safety
    /// No other task may access `index` until the parallel section ends.
    pub(crate) unsafe fn write(&self, index: usize, value: T) {
        assert!(index < self.1, "index {index} out of bounds {}", self.1);
        // SAFETY: in bounds (checked above); exclusive by the caller's contract.
        unsafe { self.0.add(index).write(value) }
    }

    /// # Safety
    /// `index` must have been written by this task, and no other task may access it until the
    /// parallel section ends.
    pub(crate) unsafe fn read(&self, index: usize) -> T {
        assert!(index < self.1, "index {index} out of bounds {}", self.1);
        // SAFETY: in bounds (checked above), initialized and exclusive by the caller's contract.
        unsafe { self.0.add(index).read() }
    }
}

/// Rayon splits below this many items cost more than they save.
pub(crate) const MIN_TASK: usize = 4096;

/// How many leaves ahead the gather fetches their primitives' boxes.
pub(crate) const PREFETCH_DISTANCE: usize = 32;

pub(crate) fn prefetch<T>(value: &T) {
    #[cfg(target_arch = "x86_64")]
    // SAFETY: a prefetch is a hint; it reads nothing and cannot fault.
    unsafe {
        std::arch::x86_64::_mm_prefetch(value as *const T as *const i8, std::arch::x86_64::_MM_HINT_T0);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = value;
}
