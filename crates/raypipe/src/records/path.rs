//! What the path integrator reads beside the scene's records: its parameters, and the table it
//! draws environment directions from (`sampling.wgsl`'s `sample_environment`, `environment_pdf`),
//! built here on the host for both tracers.
//!
//! The table is piecewise constant over a map of the environment's radiance averaged down to at
//! most [`ENVIRONMENT_TABLE_WIDTH`] texels across: each texel's chance is its luminance times
//! sin θ (the solid angle a row of an equirectangular map covers), a row is drawn from the rows'
//! cumulative distribution and a texel from its row's, each by binary search.

// `!(x > 0.0)` is true for a NaN, as the shader's tests are: the guards keep NaNs out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

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
    /// The accumulation's number: the renderer counts its restarts from 0, so that a restarted
    /// accumulation draws other numbers than the one before. It seeds the samples' scrambling.
    pub epoch: u32,
    /// The environment table's width in texels; 0 where there is nothing to sample.
    pub table_width: u32,
    /// Its height in texels.
    pub table_height: u32,
    /// The chance that a vertex's area-light sample is drawn from the environment.
    pub environment_share: f32,
}

/// The parameters and the texels of the environment table: `table_width` x `table_height`
/// texels row by row from the top, each the row's cumulative distribution up to and with it (x)
/// and the texel's density over the unit square of (u, v) (y); then one texel a row, the rows'
/// cumulative distribution (x). The last value of each distribution is exactly 1.
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
    pub fn new(environment: Option<&Environment>) -> PathTables {
        let Some(environment) = environment else {
            return PathTables::default();
        };
        let mut map = environment.radiance().clone();
        while map.width > ENVIRONMENT_TABLE_WIDTH {
            map = map.halved();
        }
        environment_table(&map).unwrap_or_default()
    }
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
            epoch: 0,
            table_width: width as u32,
            table_height: height as u32,
            environment_share: 1.0,
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
    [epoch, table_width, table_height, environment_share]
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
        let tables = PathTables::new(Some(&environment));
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

    #[test]
    fn black_or_missing_environments_have_no_table() {
        assert_eq!(PathTables::new(None).globals.table_width, 0);
        let black = Environment::uniform(Vec3::ZERO);
        assert_eq!(PathTables::new(Some(&black)).texels.len(), 0);
    }
}
