// The path integrator's random numbers and the densities it draws directions from: Owen-scrambled
// Sobol points, the cosine lobe, the environment's importance table and the power heuristic.
// Mirrored by src/cpu/sampling.rs.

// The path integrator's parameters: the accumulation's epoch (samples restart at 0 with a new one,
// which scrambles them anew), the environment's sampling table, the chance that a light sample
// goes to the environment rather than the emitters, and the emitters' count (src/records/path.rs).
struct PathGlobals {
    epoch: u32,
    // The table's size in texels; 0 where the scene has no environment to sample.
    table_width: u32,
    table_height: u32,
    environment_share: f32,
    // The size pads the block to 32 bytes, as std140 (GL's uniform blocks) rounds it.
    @size(16) emitter_count: u32,
}

// The pixel's seed for this epoch, and which of its samples is traced (the Sobol index).
var<private> path_seed: u32;
var<private> path_sample: u32;

// x's bits in reverse order, by swaps of halves: WebGL2's GLSL ES 3.00 has no bitfieldReverse for
// WGSL's reverseBits to become.
fn reverse_bits(value: u32) -> u32 {
    var x = value;
    x = ((x >> 1u) & 0x55555555u) | ((x & 0x55555555u) << 1u);
    x = ((x >> 2u) & 0x33333333u) | ((x & 0x33333333u) << 2u);
    x = ((x >> 4u) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4u);
    x = ((x >> 8u) & 0x00ff00ffu) | ((x & 0x00ff00ffu) << 8u);
    return (x >> 16u) | (x << 16u);
}

// The Sobol sequence's dimension `dimension` (0 to 3) at `index`, in 0.32 fixed point: the XOR of
// the direction numbers of index's set bits. Dimension 0 is the van der Corput sequence; 1 to 3
// follow Joe and Kuo's primitive polynomials x + 1, x^2 + x + 1 and x^3 + x + 1 (initial numbers
// m = 1, 3, 1), their direction numbers computed as the bits are read.
fn sobol(index: u32, dimension: u32) -> u32 {
    if (dimension == 0u) {
        return reverse_bits(index);
    }
    // The last three direction numbers, newest first.
    var history = vec3<u32>(0u);
    var result = 0u;
    var k = 1u;
    while (k <= 32u && (index >> (k - 1u)) != 0u) {
        var v: u32;
        if (k <= dimension) {
            v = select(select(0x20000000u, 0xc0000000u, k == 2u), 0x80000000u, k == 1u);
        } else if (dimension == 1u) {
            v = history.x ^ (history.x >> 1u);
        } else if (dimension == 2u) {
            v = history.y ^ (history.y >> 2u) ^ history.x;
        } else {
            v = history.z ^ (history.z >> 3u) ^ history.y;
        }
        if (((index >> (k - 1u)) & 1u) != 0u) {
            result ^= v;
        }
        history = vec3<u32>(v, history.x, history.y);
        k += 1u;
    }
    return result;
}

// A random permutation of 32-bit integers in which each bit depends on itself and the bits below
// it only (Laine and Karras 2011, with Vegdahl's constants).
fn laine_karras_permutation(value: u32, seed: u32) -> u32 {
    var x = value + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return x;
}

// Owen scrambling of a 0.32 fixed-point number: each bit flipped by a hash of the bits above it
// (Burley, "Practical Hash-based Owen Scrambling", 2020).
fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    return reverse_bits(laine_karras_permutation(reverse_bits(x), seed));
}

fn fixed_to_unit(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0 / 16777216.0);
}

// Four numbers in [0, 1) for the dimensions of `group` of the current sample: the 4-D Sobol point
// of a shuffled index, each dimension Owen-scrambled by its own seed. Every group shuffles the
// sample index its own way, so groups do not repeat one another's pattern.
fn path_random(group: u32) -> vec4<f32> {
    let seed = hash_u32(path_seed ^ hash_u32(group));
    let index = nested_uniform_scramble(path_sample, seed);
    var u: vec4<f32>;
    for (var d = 0u; d < 4u; d++) {
        u[d] = fixed_to_unit(nested_uniform_scramble(sobol(index, d), hash_u32(seed ^ (d + 1u))));
    }
    return u;
}

// The two groups of each bounce: the BSDF's (lobe, direction, direction, roulette) and the light
// sample's (which light, position, position, whether a blended surface covers the ray).
fn bsdf_numbers(bounce: u32) -> vec4<f32> {
    return path_random(2u * bounce);
}

fn light_numbers(bounce: u32) -> vec4<f32> {
    return path_random(2u * bounce + 1u);
}

// A direction about n, its density cos θ / π (Malley's method: a disk point lifted to the
// hemisphere).
fn sample_cosine(n: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 2.0 * PI * u.y;
    let frame = tangent_frame(n);
    let z = sqrt(max(1.0 - u.x, 0.0));
    return normalize(r * cos(phi) * frame.t + r * sin(phi) * frame.b + z * n);
}

// The power heuristic's weight (β = 2) of a strategy of density `chosen` beside one of `other`.
fn power_heuristic(chosen: f32, other: f32) -> f32 {
    let a = chosen * chosen;
    let b = other * other;
    return select(0.0, a / (a + b), a > 0.0);
}

// The environment's sampling table (src/records/path.rs): table_width x table_height texels, row
// by row from the top, each holding the row's cumulative distribution up to and with it (x) and
// the texel's density over the unit square of (u, v) (y); then one texel per row with the
// cumulative distribution of the rows (x).
fn table_texel(index: u32) -> vec4<f32> {
    return textureLoad(path_texels, texel_coord(index), 0);
}

// Where the emitters' texels start: after the environment table's.
fn emitter_first() -> u32 {
    let width = path_globals.table_width;
    let height = path_globals.table_height;
    return width * height + select(0u, height, width > 0u);
}

// The first of `count` cumulative values from `first` above u (the last is 1), and where u falls
// between it and the one before, in [0, 1).
// `channel` holds the values: x for the environment's, y for the emitters'.
fn search_table(first: u32, count: u32, u: f32, channel: u32) -> vec2<f32> {
    var low = 0u;
    var high = count - 1u;
    while (low < high) {
        let middle = (low + high) / 2u;
        if (table_texel(first + middle)[channel] > u) {
            high = middle;
        } else {
            low = middle + 1u;
        }
    }
    var below = 0.0;
    if (low > 0u) {
        below = table_texel(first + low - 1u)[channel];
    }
    let above = table_texel(first + low)[channel];
    let within = select(0.5, (u - below) / (above - below), above > below);
    return vec2<f32>(f32(low), clamp(within, 0.0, 0.99999994));
}

// The unit direction that reads (u, v) of the environment's map: environment_uv inverted.
fn environment_direction(uv: vec2<f32>) -> vec3<f32> {
    let phi = 2.0 * PI * (uv.x - 0.5);
    let theta = PI * uv.y;
    let x = sin(theta) * sin(phi);
    let z = -sin(theta) * cos(phi);
    let turn = globals.scene.environment_turn;
    return vec3<f32>(turn.x * x + turn.y * z, cos(theta), -turn.y * x + turn.x * z);
}

// A direction drawn from the environment's table (xyz), and its density in solid angle (w).
fn sample_environment(u: vec2<f32>) -> vec4<f32> {
    let width = path_globals.table_width;
    let height = path_globals.table_height;
    let row = search_table(width * height, height, u.x, 0u);
    let y = u32(row.x);
    let column = search_table(y * width, width, u.y, 0u);
    let uv = vec2<f32>((column.x + column.y) / f32(width), (row.x + row.y) / f32(height));
    let dir = environment_direction(uv);
    return vec4<f32>(dir, environment_pdf(dir));
}

// The density in solid angle with which sample_environment draws `dir`: the texel's density over
// (u, v) over the map's Jacobian 2π² sin θ.
fn environment_pdf(dir: vec3<f32>) -> f32 {
    let width = path_globals.table_width;
    let height = path_globals.table_height;
    let sin_theta = sqrt(max(1.0 - dir.y * dir.y, 0.0));
    if (width == 0u || sin_theta == 0.0) {
        return 0.0;
    }
    let uv = environment_uv(dir);
    let x = min(u32(max(uv.x, 0.0) * f32(width)), width - 1u);
    let y = min(u32(max(uv.y, 0.0) * f32(height)), height - 1u);
    return table_texel(y * width + x).y / (2.0 * PI * PI * sin_theta);
}

// A point on an emitter: the triangle's index among the triangles, and its chance.
struct EmitterSample {
    point: vec3<f32>,
    index: u32,
    chance: f32,
}

// An emitter drawn by power (u.x), and a point drawn uniformly over it (u.yz).
fn sample_emitter(u: vec3<f32>) -> EmitterSample {
    let drawn = search_table(emitter_first(), path_globals.emitter_count, u.x, 1u);
    let texel = table_texel(emitter_first() + u32(drawn.x));
    let index = u32(texel.x);
    let triangle = load_triangle(index);
    let root = sqrt(u.y);
    let point = (1.0 - root) * triangle.v0 + root * (1.0 - u.z) * triangle.v1 + root * u.z * triangle.v2;
    return EmitterSample(point, index, texel.z);
}

// The chance that sample_emitter draws triangle `index`: its texel's, found by binary search in
// the list (in the triangles' order); 0 for a triangle that emits nothing.
fn emitter_chance(index: u32) -> f32 {
    let count = path_globals.emitter_count;
    if (count == 0u) {
        return 0.0;
    }
    let first = emitter_first();
    var low = 0u;
    var high = count - 1u;
    while (low < high) {
        let middle = (low + high) / 2u;
        if (u32(table_texel(first + middle).x) < index) {
            low = middle + 1u;
        } else {
            high = middle;
        }
    }
    let texel = table_texel(first + low);
    return select(0.0, texel.z, u32(texel.x) == index);
}

// A triangle's area.
fn triangle_area(triangle: Triangle) -> f32 {
    return 0.5 * length(cross(triangle.v1 - triangle.v0, triangle.v2 - triangle.v0));
}

// The density in solid angle, seen from `distance` away with the light's surface at cosine
// `cos_light` to the ray, of sample_emitter's point on triangle `index` drawn with `chance`.
fn emitter_pdf(index: u32, chance: f32, distance: f32, cos_light: f32) -> f32 {
    let area = triangle_area(load_triangle(index));
    if (!(area > 0.0) || !(cos_light > 0.0)) {
        return 0.0;
    }
    return chance / area * distance * distance / cos_light;
}
