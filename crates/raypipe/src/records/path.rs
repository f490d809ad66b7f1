//! What the path integrator reads beside the scene's records: its parameters, and the table it
//! draws environment directions from (`sampling.wgsl`'s `sample_environment`, `environment_pdf`),
//! built here on the host for both tracers.
//!
//! The table is piecewise constant over a map of the environment's radiance averaged down to at
//! most [`ENVIRONMENT_TABLE_WIDTH`] texels across: each texel's chance is its luminance times
//! sin θ (the solid angle a row of an equirectangular map covers), a row is drawn from the rows'
//! cumulative distribution and a texel from its row's, each by binary search.
//!
//! The emitters follow: the triangles whose material emits, in the triangles' order, each with
//! its chance by power (its emission's luminance times its area when packed) and the cumulative
//! distribution, for `sample_emitter` to draw one by binary search and `emitter_pdf` to find a
//! hit triangle's chance.

// `!(x > 0.0)` is true for a NaN, as the shader's tests are: the guards keep NaNs out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use crate::records::constants::MATERIAL_INDEX_MASK;
use crate::records::{GpuMaterial, GpuTriangle};
use crate::scene::Environment;
use crate::scene::texture::Texture;
use bytemuck::{Pod, Zeroable};
use std::f64::consts::PI;

/// The widest environment table: 512 x 256 texels tell a sun from the sky around it, and take
/// 2 MiB.
pub const ENVIRONMENT_TABLE_WIDTH: u32 = 512;

/// The path integrator's parameters, `PathGlobals` in `sampling.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuPathGlobals {
    /// Which draw of the pixels' sample sequences this is (0 unless set: `render --frames` gives
    /// frame k epoch k): it seeds the samples' scrambling, so that frames differ.
    pub epoch: u32,
    /// The environment table's width in texels; 0 where there is nothing to sample.
    pub table_width: u32,
    /// Its height in texels.
    pub table_height: u32,
    /// The chance that a vertex's area-light sample is drawn from the environment; the rest go
    /// to the emitters.
    pub environment_share: f32,
    /// Emitting triangles: their list follows the environment table's texels.
    pub emitter_count: u32,
    /// Padding to 32 bytes, a std140 uniform block's size (`@size(16)` in WGSL).
    pub _pad: [u32; 3],
}

/// The parameters and the texels of the environment table: `table_width` x `table_height`
/// texels row by row from the top, each the row's cumulative distribution up to and with it (x)
/// and the texel's density over the unit square of (u, v) (y); then one texel a row, the rows'
/// cumulative distribution (x). The last value of each distribution is exactly 1. Then one texel
/// an emitter: its triangle's index (x, exact in f32), the emitters' cumulative distribution up to
/// and with it (y), its chance (z).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PathTables {
    /// The parameters.
    pub globals: GpuPathGlobals,
    /// The texels, rgba32float on the GPU.
    pub texels: Vec<[f32; 4]>,
}

impl PathTables {
    /// The tables for a scene lit by `environment`, if any. An environment that is black
    /// everywhere has no table: rays that escape to it find nothing to weigh.
    pub fn new(environment: Option<&Environment>, triangles: &[GpuTriangle], materials: &[GpuMaterial]) -> PathTables {
        let mut tables = environment
            .and_then(|environment| {
                let mut map = environment.radiance().clone();
                while map.width > ENVIRONMENT_TABLE_WIDTH {
                    map = map.halved();
                }
                environment_table(&map)
            })
            .unwrap_or_default();
        let emitters = emitter_list(triangles, materials);
        tables.globals.emitter_count = (emitters.len()) as u32;
        tables.texels.extend(emitters);
        // Half the light samples to each where both light the scene: their powers are not in
        // one unit (a radiance seen from everywhere, and emitted watts).
        let has_table = tables.globals.table_width > 0;
        tables.globals.environment_share = match (has_table, tables.globals.emitter_count > 0) {
            (true, true) => 0.5,
            (true, false) => 1.0,
            (false, _) => 0.0,
        };
        tables
    }
}

/// The emitting triangles' texels, by power.
fn emitter_list(triangles: &[GpuTriangle], materials: &[GpuMaterial]) -> Vec<[f32; 4]> {
    let powers: Vec<(usize, f64)> = triangles
        .iter()
        .enumerate()
        .filter_map(|(i, t)| {
            let material = &materials[(t.material & MATERIAL_INDEX_MASK) as usize];
            let [r, g, b] = material.emission;
            let glow = luminance([r, g, b, 0.0]);
            let [v0, v1, v2] = [t.v0, t.v1, t.v2].map(|v| glam::DVec3::from_array(v.map(f64::from)));
            let area = 0.5 * (v1 - v0).cross(v2 - v0).length();
            let power = glow * area;
            (power > 0.0 && power.is_finite()).then_some((i, power))
        })
        .collect();
    let total: f64 = powers.iter().map(|(_, p)| p).sum();
    let mut running = 0.0;
    powers
        .iter()
        .enumerate()
        .map(|(k, &(i, power))| {
            running += power;
            let cumulative = if k + 1 == powers.len() { 1.0 } else { running / total };
            [i as f32, cumulative as f32, (power / total) as f32, 0.0]
        })
        .collect()
}

/// Rec. 709 luminance.
fn luminance(rgb: [f32; 4]) -> f64 {
    0.2126 * rgb[0] as f64 + 0.7152 * rgb[1] as f64 + 0.0722 * rgb[2] as f64
}

fn environment_table(map: &Texture) -> Option<PathTables> {
    let (width, height) = (map.width as usize, map.height as usize);
    let weights: Vec<f64> = (0..height)
        .flat_map(|y| {
            let sin_theta = (PI * (y as f64 + 0.5) / height as f64).sin();
            (0..width).map(move |x| (x, y, sin_theta))
        })
        .map(|(x, y, sin_theta)| luminance(map.texel(x as u32, y as u32)).max(0.0) * sin_theta)
        .collect();
    let row_sums: Vec<f64> = weights.chunks(width).map(|row| row.iter().sum()).collect();
    let total: f64 = row_sums.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let mut texels = Vec::with_capacity(width * height + height);
    for (row, &sum) in weights.chunks(width).zip(&row_sums) {
        let mut running = 0.0;
        for (x, &w) in row.iter().enumerate() {
            running += w;
            // A black row is never drawn; its distribution is uniform, to stay well formed.
            let cumulative = if x + 1 == width {
                1.0
            } else if sum > 0.0 {
                running / sum
            } else {
                (x + 1) as f64 / width as f64
            };
            let density = w / total * (width * height) as f64;
            texels.push([cumulative as f32, density as f32, 0.0, 0.0]);
        }
    }
    let mut running = 0.0;
    for (y, &sum) in row_sums.iter().enumerate() {
        running += sum;
        let cumulative = if y + 1 == height { 1.0 } else { running / total };
        texels.push([cumulative as f32, 0.0, 0.0, 0.0]);
    }
    Some(PathTables {
        globals: GpuPathGlobals {
            table_width: width as u32,
            table_height: height as u32,
            ..GpuPathGlobals::default()
        },
        texels,
    })
}

/// The layout of the parameters' host struct, for the test that holds it to `PathGlobals` in
/// `sampling.wgsl`.
#[cfg(feature = "internals")]
pub const LAYOUTS: &[super::layouts::StructLayout] = &[super::layouts::struct_layout!(
    GpuPathGlobals,
    "PathGlobals",
    [epoch, table_width, table_height, environment_share, emitter_count]
)];

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Each texel's density over (u, v) times its area in (u, v) is its chance, and the chances
    /// sum to 1; the distributions end at exactly 1.
    #[test]
    fn the_table_is_a_distribution_over_the_map() {
        let environment = Environment::from_function(64, |d| Vec3::splat(1.0 + 10.0 * d.y.max(0.0).powi(8))).unwrap();
        let tables = PathTables::new(Some(&environment), &[], &[]);
        let g = tables.globals;
        assert_eq!((g.table_width, g.table_height), (64, 32));
        let cells = (g.table_width * g.table_height) as usize;
        assert_eq!(tables.texels.len(), cells + g.table_height as usize);
        let chances: f64 = tables.texels[..cells].iter().map(|t| t[1] as f64 / cells as f64).sum();
        assert!((chances - 1.0).abs() < 1e-5, "{chances}");
        for row in tables.texels[..cells].chunks(g.table_width as usize) {
            assert_eq!(row.last().unwrap()[0], 1.0);
            assert!(row.windows(2).all(|w| w[0][0] <= w[1][0]));
        }
        assert_eq!(tables.texels.last().unwrap()[0], 1.0);
        // A row near the bright zenith is likelier than the horizon's, for all its smaller sin θ.
        let row_chance = |y: usize| tables.texels[cells + y][0] - tables.texels[cells + y - 1][0];
        assert!(
            row_chance(4) > 1.5 * row_chance(16),
            "{} {}",
            row_chance(4),
            row_chance(16)
        );
    }

    /// Emitters are listed in the triangles' order with chances by power (luminance times area):
    /// a triangle twice as bright and twice as big is four times as likely; dark ones are left out.
    #[test]
    fn emitters_are_drawn_by_power() {
        let triangle = |scale: f32, material: u32| GpuTriangle {
            v0: [0.0, 0.0, 0.0],
            v1: [scale, 0.0, 0.0],
            v2: [0.0, scale, 0.0],
            material,
            ..GpuTriangle::default()
        };
        let glowing = |e: f32| GpuMaterial {
            emission: [e; 3],
            ..GpuMaterial::default()
        };
        let materials = [glowing(0.0), glowing(1.0), glowing(2.0)];
        let triangles = [triangle(1.0, 1), triangle(1.0, 0), triangle(2.0f32.sqrt(), 2)];
        let tables = PathTables::new(None, &triangles, &materials);
        assert_eq!(tables.globals.emitter_count, 2);
        assert_eq!(tables.globals.environment_share, 0.0);
        let [first, second] = [tables.texels[0], tables.texels[1]];
        assert_eq!((first[0], second[0]), (0.0, 2.0), "triangle indices, in order");
        assert!(
            (first[2] - 0.2).abs() < 1e-6 && (second[2] - 0.8).abs() < 1e-6,
            "{first:?} {second:?}"
        );
        assert_eq!(second[1], 1.0);
        let environment = Environment::uniform(Vec3::ONE);
        let both = PathTables::new(Some(&environment), &triangles, &materials);
        assert_eq!(both.globals.environment_share, 0.5);
    }

    #[test]
    fn black_or_missing_environments_have_no_table() {
        assert_eq!(PathTables::new(None, &[], &[]).globals.table_width, 0);
        let black = Environment::uniform(Vec3::ZERO);
        assert_eq!(PathTables::new(Some(&black), &[], &[]).texels.len(), 0);
    }
}
