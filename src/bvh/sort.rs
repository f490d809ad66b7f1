//! A stable parallel LSD radix sort: per-chunk digit histograms, one prefix sum over (digit, chunk),
//! then each chunk scatters its items to their places. Chunks and items keep their order, so equal
//! keys keep their input order.

use rayon::prelude::*;

const DIGIT_BITS: u32 = 8;
const BUCKETS: usize = 1 << DIGIT_BITS;

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

/// Sorts `items` by the `bits` low bits of `key(item)`, stably. `scratch` is resized to match and
/// keeps its capacity for the next sort.
pub fn radix_sort_by_key<T, K>(items: &mut Vec<T>, scratch: &mut Vec<T>, bits: u32, key: K)
where
    T: Copy + Default + Send + Sync,
    K: Fn(T) -> u64 + Sync,
{
    let n = items.len();
    if n < 2 {
        return;
    }
    let threads = rayon::current_num_threads();
    let chunk = n.div_ceil(threads * 4).max(1 << 14);
    scratch.resize(n, T::default());
    let mut shift = 0;
    while shift < bits {
        let digit = |item: &T| ((key(*item) >> shift) as usize) & (BUCKETS - 1);
        let histograms: Vec<[usize; BUCKETS]> = items
            .par_chunks(chunk)
            .map(|c| {
                let mut h = [0usize; BUCKETS];
                for item in c {
                    h[digit(item)] += 1;
                }
                h
            })
            .collect();
        // Skip a digit that every item shares: the pass would not move anything.
        let single_bucket = (0..BUCKETS).any(|d| histograms.iter().map(|h| h[d]).sum::<usize>() == n);
        if !single_bucket {
            // Offsets in digit-major, chunk-minor order keep the sort stable.
            let mut offsets = vec![[0usize; BUCKETS]; histograms.len()];
            let mut running = 0;
            for d in 0..BUCKETS {
                for (c, h) in histograms.iter().enumerate() {
                    offsets[c][d] = running;
                    running += h[d];
                }
            }
            let out = DisjointWrites::new(scratch);
            items.par_chunks(chunk).zip(offsets).for_each(|(c, mut offset)| {
                for &item in c {
                    let d = digit(&item);
                    // SAFETY: the prefix sums give every item of every chunk its own slot.
                    unsafe { out.write(offset[d], item) };
                    offset[d] += 1;
                }
            });
            std::mem::swap(items, scratch);
        }
        shift += DIGIT_BITS;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::SplitMix64;

    #[test]
    fn sorts_stably_across_chunks() {
        let mut rng = SplitMix64::new(3);
        let mut items: Vec<(u64, u32)> = (0..100_000).map(|i| (rng.next_u64() % 1000, i)).collect();
        let mut expected = items.clone();
        expected.sort_by_key(|&(k, _)| k);
        radix_sort_by_key(&mut items, &mut Vec::new(), 10, |(k, _)| k);
        assert_eq!(items, expected);
    }
}
