//! A stable parallel radix sort. The first pass scatters the items by their most significant digit,
//! in parallel: per-chunk digit histograms, one prefix sum over (digit, chunk), then each chunk
//! scatters its items to their places. Each bucket that makes (a few thousand items, for a million
//! evenly spread keys) is then sorted by the digits below on one thread, least significant first,
//! while it stays in cache; the buckets run in parallel. A bucket too large for that (clustered keys)
//! is split by its next digit the same way. Chunks and items keep their order at every step, so
//! equal keys keep their input order.

use crate::parallel::DisjointWrites;
use rayon::prelude::*;

/// Digits of the parallel passes over the whole array. Wider ones measured slower: each chunk's
/// writes then go to more places at once than the caches keep apart.
const DIGIT_BITS: u32 = 8;
const BUCKETS: usize = 1 << DIGIT_BITS;

/// Digits of the passes within a bucket, which stays in cache: 22 bits below a 30-bit code's top
/// digit take two passes instead of three.
const SERIAL_DIGIT_BITS: u32 = 11;
const SERIAL_BUCKETS: usize = 1 << SERIAL_DIGIT_BITS;

/// Buckets up to this many items are sorted on one thread.
const SERIAL_ITEMS: usize = 1 << 16;

/// Sorts `items` by the `bits` low bits of `key(item)`, stably. `scratch` is resized to match and
/// keeps its capacity for the next sort.
#[cfg(test)]
pub(crate) fn radix_sort_by_key<T, K>(items: &mut [T], scratch: &mut Vec<T>, bits: u32, key: K)
where
    T: Copy + Default + Send + Sync,
    K: Fn(T) -> u64 + Sync,
{
    radix_sort_by_key_then(items, scratch, bits, key, |_, _| {});
}

/// [`radix_sort_by_key`] that hands each stretch of the result to `then(start, stretch)` as soon
/// as it is in place, while it is still in cache, on the thread that sorted it. The stretches tile
/// the whole array.
pub(crate) fn radix_sort_by_key_then<T, K, F>(items: &mut [T], scratch: &mut Vec<T>, bits: u32, key: K, then: F)
where
    T: Copy + Default + Send + Sync,
    K: Fn(T) -> u64 + Sync,
    F: Fn(usize, &[T]) + Sync,
{
    scratch.resize(items.len(), T::default());
    sort_slice(items, scratch, bits.min(64), &key, 0, &then);
}

/// Sorts `items`, which start at `start` in the whole array, by the `bits` low bits of their keys,
/// stably, using `scratch` (as long) on the way; hands the sorted stretches to `then`.
fn sort_slice<T, K, F>(items: &mut [T], scratch: &mut [T], bits: u32, key: &K, start: usize, then: &F)
where
    T: Copy + Send + Sync,
    K: Fn(T) -> u64 + Sync,
    F: Fn(usize, &[T]) + Sync,
{
    let n = items.len();
    if n < 2 || bits == 0 {
        if n > 0 {
            then(start, items);
        }
        return;
    }
    if n <= SERIAL_ITEMS {
        if serial_lsd(items, scratch, bits, key) {
            items.copy_from_slice(scratch);
        }
        then(start, items);
        return;
    }
    let shift = bits.saturating_sub(DIGIT_BITS);
    let Some(starts) = scatter_by_digit(items, scratch, bits, shift, key) else {
        // Every item has the same top digit: nothing moved.
        return sort_slice(items, scratch, shift, key, start, then);
    };
    // The buckets are in `scratch` now; each is sorted back into its place in `items`.
    let mut buckets = Vec::with_capacity(BUCKETS);
    let (mut rest_items, mut rest_scratch) = (items, scratch);
    for d in 0..BUCKETS {
        let len = starts[d + 1] - starts[d];
        let (bucket_items, after_items) = rest_items.split_at_mut(len);
        let (bucket_scratch, after_scratch) = rest_scratch.split_at_mut(len);
        if len > 0 {
            buckets.push((start + starts[d], bucket_items, bucket_scratch));
        }
        (rest_items, rest_scratch) = (after_items, after_scratch);
    }
    buckets
        .into_par_iter()
        .for_each(|(bucket_start, bucket_items, bucket_scratch)| {
            if bucket_items.len() <= SERIAL_ITEMS {
                // Sorted from `scratch`, with `items` as the scratch space.
                if !serial_lsd(bucket_scratch, bucket_items, shift, key) {
                    bucket_items.copy_from_slice(bucket_scratch);
                }
                then(bucket_start, bucket_items);
            } else {
                bucket_items.copy_from_slice(bucket_scratch);
                sort_slice(bucket_items, bucket_scratch, shift, key, bucket_start, then);
            }
        });
}

/// One parallel pass that moves `items` into `out`, stably grouped by their key bits from `shift` up
/// to `bits` (at most a digit); returns where each digit's bucket starts (and, last, the end), or
/// `None` and moves nothing when all items share the digit.
fn scatter_by_digit<T, K>(items: &[T], out: &mut [T], bits: u32, shift: u32, key: &K) -> Option<[usize; BUCKETS + 1]>
where
    T: Copy + Send + Sync,
    K: Fn(T) -> u64 + Sync,
{
    let n = items.len();
    let chunk = n.div_ceil(rayon::current_num_threads() * 4).max(1 << 14);
    let mask = digit_mask(bits - shift, DIGIT_BITS);
    // The constant mask tells the compiler that the digit indexes the histograms in bounds.
    let digit = |item: &T| ((key(*item) >> shift) as usize) & mask & (BUCKETS - 1);
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
    // Offsets in digit-major, chunk-minor order keep the pass stable.
    let mut offsets = vec![[0usize; BUCKETS]; histograms.len()];
    let mut starts = [0usize; BUCKETS + 1];
    let mut running = 0;
    for d in 0..BUCKETS {
        starts[d] = running;
        for (c, h) in histograms.iter().enumerate() {
            offsets[c][d] = running;
            running += h[d];
        }
        if running - starts[d] == n {
            return None;
        }
    }
    starts[BUCKETS] = n;
    let out = DisjointWrites::new(out);
    items.par_chunks(chunk).zip(offsets).for_each(|(c, mut offset)| {
        for &item in c {
            let d = digit(&item);
            // SAFETY: the prefix sums give every item of every chunk its own slot.
            unsafe { out.write(offset[d], item) };
            offset[d] += 1;
        }
    });
    Some(starts)
}

/// The mask of a digit of `digit_bits` of which only the low `bits` count.
fn digit_mask(bits: u32, digit_bits: u32) -> usize {
    (1 << bits.min(digit_bits)) - 1
}

/// Sorts `items` by the `bits` low bits of their keys on this thread, least significant digit first,
/// moving them between `items` and `other` (as long); returns true when the result is in `other`.
/// One read counts every digit; a digit that all items share costs no pass.
fn serial_lsd<T, K>(items: &mut [T], other: &mut [T], bits: u32, key: &K) -> bool
where
    T: Copy,
    K: Fn(T) -> u64,
{
    const MAX_DIGITS: usize = 64usize.div_ceil(SERIAL_DIGIT_BITS as usize);
    let digits = bits.div_ceil(SERIAL_DIGIT_BITS) as usize;
    let masks: [usize; MAX_DIGITS] =
        std::array::from_fn(|p| digit_mask(bits.saturating_sub(p as u32 * SERIAL_DIGIT_BITS), SERIAL_DIGIT_BITS));
    let mut counts = [[0u32; SERIAL_BUCKETS]; MAX_DIGITS];
    for &item in items.iter() {
        let k = key(item);
        for (p, count) in counts[..digits].iter_mut().enumerate() {
            // The constant mask tells the compiler that the digit indexes the counts in bounds.
            count[((k >> (p as u32 * SERIAL_DIGIT_BITS)) as usize) & masks[p] & (SERIAL_BUCKETS - 1)] += 1;
        }
    }
    let n = items.len() as u32;
    let (mut from, mut to) = (items, other);
    let mut in_other = false;
    for (p, count) in counts[..digits].iter().enumerate() {
        if count.contains(&n) {
            continue;
        }
        let mut offset = [0u32; SERIAL_BUCKETS];
        let mut running = 0;
        for (o, c) in offset.iter_mut().zip(count) {
            *o = running;
            running += c;
        }
        let (shift, mask) = (p as u32 * SERIAL_DIGIT_BITS, masks[p]);
        for &item in from.iter() {
            let d = ((key(item) >> shift) as usize) & mask & (SERIAL_BUCKETS - 1);
            // SAFETY: the counts give the items of each digit the slots from its offset on, in bounds.
            unsafe { *to.get_unchecked_mut(offset[d] as usize) = item };
            offset[d] += 1;
        }
        (from, to) = (to, from);
        in_other = !in_other;
    }
    in_other
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Radix-sorts `(key, index)` pairs by `bits` key bits and compares with the standard library's
    /// stable sort.
    fn check(keys: impl Iterator<Item = u64>, bits: u32) {
        let mut items: Vec<(u64, u32)> = keys.zip(0..).collect();
        let mut expected = items.clone();
        expected.sort_by_key(|&(k, _)| k & (u64::MAX >> (64 - bits)));
        radix_sort_by_key(&mut items, &mut Vec::new(), bits, |(k, _)| k);
        assert_eq!(items, expected, "{bits}-bit keys");
    }

    #[test]
    fn sorts_stably_across_chunks() {
        let mut rng = SplitMix64::new(3);
        check((0..100_000).map(|_| rng.next_u64() % 1000), 10);
    }

    #[test]
    fn sorts_wide_keys_and_small_inputs() {
        let mut rng = SplitMix64::new(5);
        for (n, bits) in [
            (0, 30),
            (1, 30),
            (2, 30),
            (1000, 30),
            (300_000, 30),
            (300_000, 63),
            (5000, 63),
        ] {
            check((0..n).map(|_| rng.next_u64() >> (64 - bits)), bits);
        }
        // Bits above `bits` do not count.
        for (n, bits) in [(1000, 3), (1000, 30), (200_000, 5), (200_000, 30)] {
            check((0..n).map(|_| rng.next_u64()), bits);
        }
    }

    #[test]
    fn hands_over_stretches_that_tile_the_result() {
        let mut rng = SplitMix64::new(11);
        for n in [0, 1, 3000, 300_000] {
            // Half the keys share a top digit, so that bucket is split again.
            let mut items: Vec<u64> = (0..n)
                .map(|i| {
                    if i % 2 == 0 {
                        rng.next_u64() >> 34
                    } else {
                        (5 << 22) | (rng.next_u64() >> 44)
                    }
                })
                .collect();
            let stretches = std::sync::Mutex::new(Vec::new());
            radix_sort_by_key_then(
                &mut items,
                &mut Vec::new(),
                30,
                |k| k,
                |start, stretch: &[u64]| {
                    stretches.lock().unwrap().push((start, stretch.to_vec()));
                },
            );
            let mut stretches = stretches.into_inner().unwrap();
            stretches.sort_by_key(|&(start, _)| start);
            let mut next = 0;
            for (start, stretch) in stretches {
                assert_eq!(start, next, "{n} items: stretches must tile the array");
                assert_eq!(
                    stretch[..],
                    items[start..start + stretch.len()],
                    "{n} items: a stretch is the final result"
                );
                next += stretch.len();
            }
            assert_eq!(next, n);
            assert!(items.is_sorted());
        }
    }

    #[test]
    fn sorts_clustered_and_equal_keys() {
        let mut rng = SplitMix64::new(7);
        // Most keys share the top digit, so one bucket is too large for one thread and is split
        // again; some share every digit.
        check((0..400_000).map(|_| (3 << 22) | (rng.next_u64() % 5000)), 30);
        check(
            (0..200_000).map(|i| if i % 3 == 0 { 17 } else { rng.next_u64() >> 34 }),
            30,
        );
        check(std::iter::repeat_n(12345, 150_000), 30);
    }
}
