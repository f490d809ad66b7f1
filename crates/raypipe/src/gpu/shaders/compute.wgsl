// The compute entry point: the same tracer as the fragment stage's, one invocation per pixel over
// 8x8 workgroups (tiles), writing the targets as storage textures.

// The targets this sample writes (the other pair of the accumulation).
@group(1) @binding(2) var next_color: texture_storage_2d<rgba32uint, write>;
@group(1) @binding(3) var next_surface: texture_storage_2d<rgba32uint, write>;

fn greatest_common_divisor(a: u32, b: u32) -> u32 {
    var x = a;
    var y = b;
    while (y != 0u) {
        let rest = x % y;
        x = y;
        y = rest;
    }
    return x;
}

// Which row of tiles workgroup row `group_row` of `rows` traces: rows in steps of about 0.618 of
// the image, coprime with `rows` so that every row is traced once. llvmpipe gives each thread one
// run of consecutive workgroups (lp_cs_tpool), which in row order is a band of the image, and the
// bands of a scene differ in cost (sky above, the floor below); stepping spreads every run over
// the image. GPUs take workgroups as they free up, in any order.
fn tile_row(group_row: u32, rows: u32) -> u32 {
    var step = u32(f32(rows) * 0.618034);
    while (greatest_common_divisor(step, rows) != 1u) {
        step += 1u;
    }
    return (group_row * step) % rows;
}

@compute @workgroup_size(COMPUTE_TILE, COMPUTE_TILE)
fn cs_main(@builtin(workgroup_id) group: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>,
           @builtin(local_invocation_id) local: vec3<u32>) {
    let pixel = vec2<u32>(group.x, tile_row(group.y, groups.y)) * COMPUTE_TILE + local.xy;
    // The last workgroups of a row or column reach past the image.
    if (f32(pixel.x) >= globals.camera.width || f32(pixel.y) >= globals.camera.height) {
        return;
    }
    let sums = sample_pixel(pixel);
    textureStore(next_color, pixel, sums.color);
    textureStore(next_surface, pixel, sums.surface);
}
