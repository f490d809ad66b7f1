//! The path integrator's random numbers and the densities it draws directions from: the twin of
//! `shaders/sampling.wgsl`.

// `!(x > 0.0)` is true for a NaN, as the shader's tests are: the guards keep NaNs out.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::brdf::tangent_frame;
use super::environment::environment_uv;
use super::intersect::v3;
use super::trace::hash_u32;
use crate::records::PackedScene;
use crate::scene::environment::texel_direction;
use glam::{Vec2, Vec3, Vec4};
use std::f32::consts::PI;

/// The Sobol sequence's dimension `dimension` (0 to 3) at `index`, in 0.32 fixed point
/// (`sobol`): the XOR of the direction numbers of index's set bits. Dimension 0 is the van der
/// Corput sequence; 1 to 3 follow Joe and Kuo's primitive polynomials x + 1, x² + x + 1 and
/// x³ + x + 1 (initial numbers m = 1, 3, 1).
pub fn sobol(index: u32, dimension: u32) -> u32 {
    if dimension == 0 {
        return index.reverse_bits();
    }
    // The last three direction numbers, newest first.
    let mut history = [0u32; 3];
    let mut result = 0;
    let mut k = 1;
    while k <= 32 && (index >> (k - 1)) != 0 {
        let v = if k <= dimension {
            [0x8000_0000, 0xc000_0000, 0x2000_0000][k as usize - 1]
        } else {
            match dimension {
                1 => history[0] ^ (history[0] >> 1),
                2 => history[1] ^ (history[1] >> 2) ^ history[0],
                _ => history[2] ^ (history[2] >> 3) ^ history[1],
            }
        };
        if (index >> (k - 1)) & 1 != 0 {
            result ^= v;
        }
        history = [v, history[0], history[1]];
        k += 1;
    }
    result
}

/// A random permutation of 32-bit integers in which each bit depends on itself and the bits below
/// it only (Laine and Karras 2011, with Vegdahl's constants).
fn laine_karras_permutation(value: u32, seed: u32) -> u32 {
    let mut x = value.wrapping_add(seed);
    for constant in [0x6c50_b47c_u32, 0xb82f_1e52, 0xc7af_e638, 0x8d22_f6e6] {
        x ^= x.wrapping_mul(constant);
    }
    x
}

/// Owen scrambling of a 0.32 fixed-point number: each bit flipped by a hash of the bits above it
/// (Burley, "Practical Hash-based Owen Scrambling", 2020).
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    laine_karras_permutation(x.reverse_bits(), seed).reverse_bits()
}

fn fixed_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Four numbers in [0, 1) for the dimensions of `group` of sample `sample` of a pixel whose seed
/// for this epoch is `seed` (`path_random`): the 4-D Sobol point of a shuffled index, each
/// dimension Owen-scrambled by its own seed.
pub fn path_random(seed: u32, sample: u32, group: u32) -> Vec4 {
    let seed = hash_u32(seed ^ hash_u32(group));
    let index = nested_uniform_scramble(sample, seed);
    Vec4::from_array(
        [0, 1, 2, 3].map(|d| fixed_to_unit(nested_uniform_scramble(sobol(index, d), hash_u32(seed ^ (d + 1))))),
    )
}

/// A direction about `n` of density cos θ / π (`sample_cosine`; Malley's method).
pub(crate) fn sample_cosine(n: Vec3, u: Vec2) -> Vec3 {
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let (t, b) = tangent_frame(n);
    let z = (1.0 - u.x).max(0.0).sqrt();
    (r * phi.cos() * t + r * phi.sin() * b + z * n).normalize()
}

/// The power heuristic's weight (β = 2) of a strategy of density `chosen` beside one of `other`.
pub(crate) fn power_heuristic(chosen: f32, other: f32) -> f32 {
    let a = chosen * chosen;
    let b = other * other;
    if a > 0.0 { a / (a + b) } else { 0.0 }
}

/// Where the emitters' texels start: after the environment table's (`emitter_first`).
fn emitter_first(scene: &PackedScene) -> u32 {
    let g = &scene.path.globals;
    g.table_width * g.table_height + if g.table_width > 0 { g.table_height } else { 0 }
}

/// The first of `count` cumulative values from `first` above `u` (the last is 1), and where `u`
/// falls between it and the one before, in [0, 1) (`search_table`); `channel` holds the values.
fn search_table(texels: &[[f32; 4]], first: u32, count: u32, u: f32, channel: usize) -> Vec2 {
    let value = |i: u32| texels[(first + i) as usize][channel];
    let (mut low, mut high) = (0, count - 1);
    while low < high {
        let middle = (low + high) / 2;
        if value(middle) > u {
            high = middle;
        } else {
            low = middle + 1;
        }
    }
    let below = if low > 0 { value(low - 1) } else { 0.0 };
    let above = value(low);
    let within = if above > below {
        (u - below) / (above - below)
    } else {
        0.5
    };
    Vec2::new(low as f32, within.clamp(0.0, 0.999_999_94))
}

/// The unit direction that reads (u, v) of the environment's map: `environment_uv` inverted.
pub(crate) fn environment_direction(scene: &PackedScene, uv: Vec2) -> Vec3 {
    let unturned = texel_direction(uv.x, uv.y);
    let [cos, sin] = scene.globals.scene.environment_turn;
    Vec3::new(
        cos * unturned.x + sin * unturned.z,
        unturned.y,
        -sin * unturned.x + cos * unturned.z,
    )
}

/// A direction drawn from the environment's table, and its density in solid angle
/// (`sample_environment`).
pub(crate) fn sample_environment(scene: &PackedScene, u: Vec2) -> (Vec3, f32) {
    let g = &scene.path.globals;
    let (width, height) = (g.table_width, g.table_height);
    let texels = &scene.path.texels;
    let row = search_table(texels, width * height, height, u.x, 0);
    let y = row.x as u32;
    let column = search_table(texels, y * width, width, u.y, 0);
    let uv = Vec2::new((column.x + column.y) / width as f32, (row.x + row.y) / height as f32);
    let dir = environment_direction(scene, uv);
    (dir, environment_pdf(scene, dir))
}

/// The density in solid angle with which [`sample_environment`] draws `dir`
/// (`environment_pdf`): the texel's density over (u, v) over the map's Jacobian 2π² sin θ.
pub(crate) fn environment_pdf(scene: &PackedScene, dir: Vec3) -> f32 {
    let g = &scene.path.globals;
    let (width, height) = (g.table_width, g.table_height);
    let sin_theta = (1.0 - dir.y * dir.y).max(0.0).sqrt();
    if width == 0 || sin_theta == 0.0 {
        return 0.0;
    }
    let uv = environment_uv(scene, dir);
    let x = ((uv.x.max(0.0) * width as f32) as u32).min(width - 1);
    let y = ((uv.y.max(0.0) * height as f32) as u32).min(height - 1);
    scene.path.texels[(y * width + x) as usize][1] / (2.0 * PI * PI * sin_theta)
}

/// A point on an emitter: the triangle's index among the triangles, and its chance
/// (`EmitterSample`).
pub(crate) struct EmitterSample {
    pub point: Vec3,
    pub index: u32,
    pub chance: f32,
}

/// An emitter drawn by power (u.x), and a point drawn uniformly over it (u.yz)
/// (`sample_emitter`).
pub(crate) fn sample_emitter(scene: &PackedScene, u: Vec3) -> EmitterSample {
    let first = emitter_first(scene);
    let drawn = search_table(&scene.path.texels, first, scene.path.globals.emitter_count, u.x, 1);
    let texel = scene.path.texels[(first + drawn.x as u32) as usize];
    let index = texel[0] as u32;
    let t = &scene.triangles[index as usize];
    let root = u.y.sqrt();
    let point = (1.0 - root) * v3(t.v0) + root * (1.0 - u.z) * v3(t.v1) + root * u.z * v3(t.v2);
    EmitterSample {
        point,
        index,
        chance: texel[2],
    }
}

/// The chance that [`sample_emitter`] draws triangle `index`; 0 for a triangle that emits
/// nothing (`emitter_chance`).
pub(crate) fn emitter_chance(scene: &PackedScene, index: u32) -> f32 {
    let count = scene.path.globals.emitter_count;
    if count == 0 {
        return 0.0;
    }
    let first = emitter_first(scene) as usize;
    let list = &scene.path.texels[first..first + count as usize];
    let (mut low, mut high) = (0, count as usize - 1);
    while low < high {
        let middle = (low + high) / 2;
        if (list[middle][0] as u32) < index {
            low = middle + 1;
        } else {
            high = middle;
        }
    }
    if list[low][0] as u32 == index {
        list[low][2]
    } else {
        0.0
    }
}

/// The density in solid angle of [`sample_emitter`]'s point on triangle `index` drawn with
/// `chance`, `distance` away with the light's surface at cosine `cos_light` (`emitter_pdf`).
pub(crate) fn emitter_pdf(scene: &PackedScene, index: u32, chance: f32, distance: f32, cos_light: f32) -> f32 {
    let t = &scene.triangles[index as usize];
    let area = 0.5 * (v3(t.v1) - v3(t.v0)).cross(v3(t.v2) - v3(t.v0)).length();
    if !(area > 0.0) || !(cos_light > 0.0) {
        return 0.0;
    }
    chance / area * distance * distance / cos_light
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first 2^m points of dimensions 0 and 1, scrambled or not, form a (0, m, 2)-net: every
    /// box of area 2^-m with sides 2^-a by 2^-(m-a) holds one point; each dimension alone puts one
    /// point in every interval of 2^-m. The scrambling keeps the strata; a wrong direction number
    /// breaks them.
    #[test]
    fn sobol_pairs_are_nets() {
        let m = 6;
        let n = 1u32 << m;
        for seed in [None, Some(0x1234_5678u32)] {
            let points: Vec<[u32; 4]> = (0..n)
                .map(|i| {
                    [0, 1, 2, 3].map(|d| match seed {
                        None => sobol(i, d),
                        Some(seed) => nested_uniform_scramble(sobol(i, d), hash_u32(seed ^ d)),
                    })
                })
                .collect();
            for (d0, d1) in [(0, 1), (1, 0), (2, 2), (3, 3)] {
                let sides = if d0 == d1 { 0..=0 } else { 0..=m };
                for a in sides {
                    let mut seen = vec![false; n as usize];
                    for p in &points {
                        let x = if a == 0 { 0 } else { p[d0] >> (32 - a) };
                        let y = if a == m { 0 } else { p[d1] >> (32 - (m - a)) };
                        let cell = ((x << (m - a)) | y) as usize;
                        assert!(!seen[cell], "dims {d0},{d1}, boxes 2^-{a} x 2^-{}: two points", m - a);
                        seen[cell] = true;
                    }
                }
            }
        }
    }

    /// Dimension 1's first points, by hand from its direction numbers 1/2, 3/4, 5/8.
    #[test]
    fn sobol_dimension_one_starts_as_its_direction_numbers_say() {
        let unit = |i| sobol(i, 1) as f64 / 4_294_967_296.0;
        assert_eq!([1, 2, 3, 4].map(unit), [0.5, 0.75, 0.25, 0.625]);
    }
}
