//! The sort key both hierarchy finders work on, and the gather of the primitives' boxes into its
//! order: shared by Karras's searches ([`super::lbvh`]) and the bottom-up merges ([`super::merge`]).

use super::aabb::Aabb;
use crate::parallel::{MIN_TASK, PREFETCH_DISTANCE, prefetch};
use rayon::prelude::*;
use std::ops::{BitXor, Not};

/// A sort key: the Morton code above the primitive index, so that one stable radix sort of the code
/// bits orders primitives by code and keeps equal codes in primitive order. 30-bit codes fit a u64
/// with the index (half the sort's memory traffic); 63-bit codes need a u128.
///
/// After the sort, the same type with the sorted position in place of the primitive is what the
/// hierarchy search compares (see `shares_more` in `lbvh.rs`).
pub trait Key: Copy + Default + Ord + BitXor<Output = Self> + Not<Output = Self> + Send + Sync + 'static {
    /// The widest Morton code the key holds above the index.
    const CODE_BITS: u32;
    /// The key of `primitive` with Morton code `code`.
    fn new(code: u64, primitive: u32) -> Self;
    /// The key's Morton code.
    fn code(self) -> u64;
    /// The primitive the key sorts.
    fn primitive(self) -> u32;
    /// The same code above `position`.
    fn at_position(self, position: u32) -> Self;
    /// Every bit below the highest set bit (`self` is the xor of two distinct keys). Another key
    /// shares more leading bits with a key than these two keys share when its xor with it is at
    /// most this.
    fn below_top_bit(self) -> Self;
    /// `self` is the xor of two distinct keys: a number that orders such xors as their highest set
    /// bits do, where those differ. A u64 xor is its own; a u128 xor is ranked by its highest bit,
    /// which is cheaper to carry and compare than the xor.
    fn xor_rank(self) -> u64;
}

impl Key for u64 {
    const CODE_BITS: u32 = 32;
    fn new(code: u64, primitive: u32) -> Self {
        (code << 32) | primitive as u64
    }
    fn code(self) -> u64 {
        self >> 32
    }
    fn primitive(self) -> u32 {
        self as u32
    }
    fn at_position(self, position: u32) -> Self {
        (self & !0xffff_ffff) | position as u64
    }
    #[inline(always)]
    fn below_top_bit(self) -> Self {
        u64::MAX >> self.leading_zeros() >> 1
    }
    #[inline(always)]
    fn xor_rank(self) -> u64 {
        self
    }
}

impl Key for u128 {
    const CODE_BITS: u32 = 64;
    fn new(code: u64, primitive: u32) -> Self {
        ((code as u128) << 32) | primitive as u128
    }
    fn code(self) -> u64 {
        (self >> 32) as u64
    }
    fn primitive(self) -> u32 {
        self as u32
    }
    fn at_position(self, position: u32) -> Self {
        (self & !0xffff_ffff) | position as u128
    }
    #[inline(always)]
    fn below_top_bit(self) -> Self {
        u128::MAX >> self.leading_zeros() >> 1
    }
    #[inline(always)]
    fn xor_rank(self) -> u64 {
        (u128::BITS - self.leading_zeros()) as u64
    }
}

/// The primitives' boxes in sorted order. They are scattered; a gather with nothing else in flight
/// overlaps their cache misses better than a climb would with its loads and branches between them.
pub(crate) fn gather_leaf_boxes<K: Key>(keys: &[K], boxes: &[Aabb], leaf_boxes: &mut Vec<Aabb>) {
    leaf_boxes.resize(keys.len(), Aabb::EMPTY);
    leaf_boxes
        .par_chunks_mut(MIN_TASK)
        .enumerate()
        .for_each(|(chunk, leaf_boxes)| {
            for (position, leaf_box) in (chunk * MIN_TASK..).zip(leaf_boxes) {
                if let Some(ahead) = keys.get(position + PREFETCH_DISTANCE) {
                    prefetch(&boxes[ahead.primitive() as usize]);
                }
                *leaf_box = boxes[keys[position].primitive() as usize];
            }
        });
}
