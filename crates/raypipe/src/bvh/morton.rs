//! Morton codes: primitive centroids quantized in the scene's centroid bounds, their bits interleaved
//! (x highest), so that sorting by code orders primitives along a Z-order curve.

use super::aabb::Aabb;
use glam::{Vec3, Vec3A};
use rayon::prelude::*;

/// How many bits a Morton code has: the key width of the LBVH.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MortonBits {
    /// 10 bits per axis, in the low 30 bits.
    #[default]
    Bits30,
    /// 21 bits per axis, in the low 63 bits.
    Bits63,
}

crate::choice::impl_choice!(
    MortonBits,
    [
        (Bits30, "30", "10 bits per axis, in the low 30 bits"),
        (Bits63, "63", "21 bits per axis, in the low 63 bits"),
    ]
);

impl MortonBits {
    /// Bits of each axis in a code.
    pub const fn bits_per_axis(self) -> u32 {
        match self {
            MortonBits::Bits30 => 10,
            MortonBits::Bits63 => 21,
        }
    }

    /// Bits of a code: three axes' worth.
    pub const fn total_bits(self) -> u32 {
        3 * self.bits_per_axis()
    }
}

/// Spreads the low 10 bits of `v` so that two zero bits separate each.
pub const fn spread_bits_10(v: u32) -> u32 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    x = (x | (x << 2)) & 0x0924_9249;
    x
}

/// [`spread_bits_10`] of every 10-bit value: three lookups in 4 KiB that stays in cache are cheaper
/// than three spreads of five shifts and masks each.
static SPREAD_10: [u32; 1024] = {
    let mut table = [0; 1024];
    let mut v = 0;
    while v < 1024 {
        table[v] = spread_bits_10(v as u32);
        v += 1;
    }
    table
};

/// Spreads the low 21 bits of `v` so that two zero bits separate each.
pub(crate) fn spread_bits_21(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | (x << 32)) & 0x001f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x001f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// The grid cell of `value` along one axis: `cells` cells over [lo, lo + extent], clamped, then
/// truncated (the same as floor on the clamped, non-negative value, without a libm call where the CPU
/// lacks SSE4.1). A GPU port must compute the same expression; a fused multiply-add there can move a
/// centroid that lies within one rounding of a cell boundary into the neighbouring cell, which changes
/// the tree but not its validity.
#[cfg(test)]
pub(crate) fn quantize(value: f32, lo: f32, scale: f32, cells: u32) -> u32 {
    ((value - lo) * scale).max(0.0).min((cells - 1) as f32) as u32
}

/// Per-axis scale that maps the bounds' extent to `cells` cells; a flat axis maps to cell 0.
pub fn scales(bounds: Aabb, cells: u32) -> Vec3 {
    let extent = bounds.max - bounds.min;
    Vec3::select(extent.cmpgt(Vec3::ZERO), Vec3::splat(cells as f32) / extent, Vec3::ZERO)
}

/// The grid that Morton codes quantize centroids in: the centroids' bounds, cut into `2^bits` cells
/// per axis.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Grid {
    min: Vec3A,
    scale: Vec3A,
    last_cell: Vec3A,
    bits: MortonBits,
}

impl Grid {
    /// The grid over the centroids of `boxes`.
    pub fn around_centroids(boxes: &[Aabb], bits: MortonBits) -> Grid {
        let bounds = centroid_bounds(boxes);
        let cells = 1 << bits.bits_per_axis();
        Grid {
            min: bounds.min.into(),
            scale: scales(bounds, cells).into(),
            last_cell: Vec3A::splat((cells - 1) as f32),
            bits,
        }
    }

    /// The Morton code of `b`'s centroid: [`quantize`] on all three axes at once.
    #[inline]
    pub fn code(&self, b: &Aabb) -> u64 {
        let cell = ((Vec3A::from(b.centroid()) - self.min) * self.scale)
            .max(Vec3A::ZERO)
            .min(self.last_cell);
        let (x, y, z) = (cell.x as u32, cell.y as u32, cell.z as u32);
        match self.bits {
            MortonBits::Bits30 => {
                let spread = |v: u32| SPREAD_10[v as usize & 0x3ff];
                ((spread(x) << 2) | (spread(y) << 1) | spread(z)) as u64
            }
            MortonBits::Bits63 => {
                (spread_bits_21(x as u64) << 2) | (spread_bits_21(y as u64) << 1) | spread_bits_21(z as u64)
            }
        }
    }
}

/// Bounds of the boxes' centroids: the grid that Morton codes quantize in.
pub(crate) fn centroid_bounds(boxes: &[Aabb]) -> Aabb {
    let (min, max) = boxes
        .par_chunks(4096)
        .map(|chunk| {
            chunk
                .iter()
                .fold((Vec3A::INFINITY, Vec3A::NEG_INFINITY), |(min, max), b| {
                    let c = Vec3A::from(b.centroid());
                    (min.min(c), max.max(c))
                })
        })
        .reduce(
            || (Vec3A::INFINITY, Vec3A::NEG_INFINITY),
            |(a_min, a_max), (b_min, b_max)| (a_min.min(b_min), a_max.max(b_max)),
        );
    Aabb::new(min.into(), max.into())
}

/// The Morton codes of the boxes' centroids, quantized in the centroids' bounds: the codes the LBVH
/// builders compute.
pub fn centroid_codes(boxes: &[Aabb], bits: MortonBits) -> Vec<u64> {
    let grid = Grid::around_centroids(boxes, bits);
    boxes.par_iter().with_min_len(4096).map(|b| grid.code(b)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spreading_interleaves() {
        assert_eq!(spread_bits_10(0b111), 0b1001001);
        assert_eq!(spread_bits_10(0x3ff), 0x0924_9249);
        assert_eq!(spread_bits_21(0x1f_ffff), 0x1249_2492_4924_9249);
        for v in [0u32, 1, 5, 0x155, 0x3ff] {
            assert_eq!(spread_bits_21(v as u64), spread_bits_10(v) as u64);
        }
    }

    #[test]
    fn codes_quantize_each_axis_as_quantize_does() {
        let bounds = Aabb::new(Vec3::splat(-1.0), Vec3::new(2.0, 1.0, 5.0));
        let scale = scales(bounds, 1024);
        let corners = [bounds.min, bounds.max].map(|p| Aabb::new(p, p));
        let grid = Grid::around_centroids(&corners, MortonBits::Bits30);
        for p in [
            Vec3::new(0.3, -0.7, 4.9),
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(1.999, 0.5, 2.5),
        ] {
            let q = |a: usize| spread_bits_10(quantize(p[a], bounds.min[a], scale[a], 1024)) as u64;
            assert_eq!(grid.code(&Aabb::new(p, p)), (q(0) << 2) | (q(1) << 1) | q(2));
        }
    }

    #[test]
    fn corners_get_extreme_codes() {
        let points = [Vec3::ZERO, Vec3::ONE, Vec3::new(1.0, 0.0, 0.0)].map(|p| Aabb::new(p, p));
        let codes = centroid_codes(&points, MortonBits::Bits30);
        assert_eq!(codes[0], 0);
        assert_eq!(codes[1], (1 << 30) - 1);
        assert_eq!(codes[2], 0x0924_9249 << 2);
    }
}
