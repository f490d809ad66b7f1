//! The display pass against the host's conversions of the same frame: what a window shows is what
//! a PNG file holds, within one 8-bit step (the shader's `pow` against the host's).

use crate::common::harness::Test;
use crate::common::*;
use pollster::block_on;
use raypipe::cpu::Count;
use raypipe::gpu::device::readback::TextureReadback;
use raypipe::gpu::{Display, GpuContext, Renderer, RendererOptions, Shown};
use raypipe::image::heatmap::color_scale;
use raypipe::image::tonemap::DisplayTransform;
use raypipe::image::{FloatImage, Frame};
use raypipe::modes::Accel;
use raypipe::modes::Aov;
use raypipe::scene::ToneMap;

/// The frame `renderer` traces with `samples` samples per pixel, and the display pass's 8-bit image
/// of it in `format`.
fn displayed(
    renderer: &mut Renderer,
    samples: u32,
    format: wgpu::TextureFormat,
    view: Aov,
    cost_max: f32,
    transform: DisplayTransform,
) -> (Frame, Vec<u8>) {
    let frame = block_on(renderer.render_samples(samples, |_| {}, |_| {}))
        .unwrap()
        .frame;
    let ctx = renderer.context();
    let (width, height) = renderer.size();
    // A target larger than the frame, as a window with room for a panel: the frame is at its corner.
    let target = ctx.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("display test target"),
        size: wgpu::Extent3d {
            width: width + 13,
            height: height + 5,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });
    let display = Display::new(ctx, format);
    let readback = TextureReadback::new(&ctx.device, target.width(), target.height(), 4);
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    // The targets still hold the frame read above.
    let shown = Shown {
        aov: view,
        depth_far: 10.0,
        cost_max,
        transform,
    };
    display.encode(
        &mut encoder,
        renderer.targets(),
        &target.create_view(&Default::default()),
        &shown,
    );
    readback.encode_copy(&mut encoder, &target);
    ctx.queue.submit([encoder.finish()]);
    let bytes = block_on(readback.read(&ctx.device)).unwrap();
    // The frame's rows out of the larger target.
    let row = target.width() as usize * 4;
    let pixels = (0..height as usize)
        .flat_map(|y| bytes[y * row..y * row + width as usize * 4].to_vec())
        .collect();
    (frame, pixels)
}

/// The largest difference, in 8-bit steps, between the rgb of `rgba` and `expected` (values in
/// [0, 1]), and the pixel where it is.
fn worst_difference(rgba: &[u8], expected: &FloatImage) -> (i32, usize) {
    let mut worst = (0, 0);
    for (i, pixel) in rgba.chunks(4).enumerate() {
        for (c, &byte) in pixel[..3].iter().enumerate() {
            let want = (expected.pixel(i)[c].clamp(0.0, 1.0) * 255.0).round() as i32;
            let off = (byte as i32 - want).abs();
            if off > worst.0 {
                worst = (off, i);
            }
        }
    }
    worst
}

/// Every pixel's rgb within `steps` 8-bit steps of `expected`.
fn assert_close(name: &str, rgba: &[u8], expected: &FloatImage, steps: i32) {
    let worst = worst_difference(rgba, expected);
    assert!(
        worst.0 <= steps,
        "{name}: pixel {} is {} steps off (allowed {steps})",
        worst.1,
        worst.0
    );
}

fn scene_renderer(ctx: &GpuContext, count: Count) -> Renderer {
    let mut scene = packed("whitted", 64, 48, 5);
    scene.build_bvh();
    let options = RendererOptions {
        accel: Accel::Threaded,
        count,
        ..Default::default()
    };
    renderer(ctx, &scene, options)
}

fn color_and_normals_match_the_files(ctx: &GpuContext) {
    let mut renderer = scene_renderer(ctx, Count::Rays);
    for format in [wgpu::TextureFormat::Rgba8Unorm, wgpu::TextureFormat::Rgba8UnormSrgb] {
        let (frame, rgba) = displayed(&mut renderer, 1, format, Aov::Color, 1.0, DisplayTransform::IDENTITY);
        assert_close(&format!("colour into {format:?}"), &rgba, &frame.display(), 1);
        let (frame, rgba) = displayed(&mut renderer, 1, format, Aov::Normal, 1.0, DisplayTransform::IDENTITY);
        assert_close(&format!("normals into {format:?}"), &rgba, &frame.normals(), 1);
    }
}

/// Exposure and each tone map in the display pass as on the host (`Frame::display_with`): what the
/// window shows is what `render --exposure --tonemap` writes.
fn exposure_and_tone_maps_match_the_files(ctx: &GpuContext) {
    let mut renderer = scene_renderer(ctx, Count::Rays);
    let format = wgpu::TextureFormat::Rgba8Unorm;
    for tone_map in [ToneMap::None, ToneMap::Neutral, ToneMap::Aces] {
        for exposure in [-1.0, 0.0, 1.5] {
            let transform = DisplayTransform { exposure, tone_map };
            let (frame, rgba) = displayed(&mut renderer, 1, format, Aov::Color, 1.0, transform);
            assert_close(
                &format!("{tone_map:?} at {exposure} EV"),
                &rgba,
                &frame.display_with(&transform),
                1,
            );
        }
    }
    // The transform reaches the pass: a stop up is not the picture at 0 EV.
    let bright = DisplayTransform {
        exposure: 1.0,
        tone_map: ToneMap::Neutral,
    };
    let (frame, rgba) = displayed(&mut renderer, 1, format, Aov::Color, 1.0, bright);
    assert!(
        worst_difference(&rgba, &frame.display()).0 > 10,
        "the exposure is ignored"
    );
}

/// Accumulated samples show as their mean, as the frame read back holds it.
fn accumulated_samples_show_their_mean(ctx: &GpuContext) {
    let mut renderer = scene_renderer(ctx, Count::Rays);
    let format = wgpu::TextureFormat::Rgba8Unorm;
    let (frame, rgba) = displayed(&mut renderer, 5, format, Aov::Color, 1.0, DisplayTransform::IDENTITY);
    assert_eq!(renderer.samples(), 5);
    assert_close("five samples", &rgba, &frame.display(), 1);
    let (single, _) = displayed(&mut renderer, 1, format, Aov::Color, 1.0, DisplayTransform::IDENTITY);
    assert_ne!(
        frame.color, single.color,
        "five jittered samples must differ from the centre's one"
    );
}

fn cost_view_uses_the_heat_map_scale(ctx: &GpuContext) {
    let mut renderer = scene_renderer(ctx, Count::Cost);
    let (frame, rgba) = displayed(
        &mut renderer,
        1,
        wgpu::TextureFormat::Rgba8Unorm,
        Aov::Cost,
        40.0,
        DisplayTransform::IDENTITY,
    );
    let data = frame
        .counts()
        .iter()
        .flat_map(|&c| color_scale(c as f32 / 40.0))
        .collect();
    let expected = FloatImage {
        width: frame.width,
        height: frame.height,
        channels: ["R", "G", "B"].map(String::from).to_vec(),
        data,
    };
    assert_close("cost", &rgba, &expected, 1);
}

/// The check above must fail when the picture is off: one pixel two steps brighter.
fn a_displayed_image_two_steps_off_fails(ctx: &GpuContext) {
    let mut renderer = scene_renderer(ctx, Count::Rays);
    let (frame, mut rgba) = displayed(
        &mut renderer,
        1,
        wgpu::TextureFormat::Rgba8Unorm,
        Aov::Color,
        1.0,
        DisplayTransform::IDENTITY,
    );
    let pixel = rgba.chunks(4).position(|p| p[0] < 250).expect("a pixel short of white") * 4;
    assert!(worst_difference(&rgba, &frame.display()).0 <= 1);
    rgba[pixel] += 2;
    let (steps, at) = worst_difference(&rgba, &frame.display());
    assert!(steps >= 2 && at == pixel / 4, "a pixel two steps off went unseen");
}

pub fn tests() -> Vec<Test> {
    raypipe_test_support::tests![
        gpu color_and_normals_match_the_files,
        gpu exposure_and_tone_maps_match_the_files,
        gpu accumulated_samples_show_their_mean,
        gpu cost_view_uses_the_heat_map_scale,
        gpu a_displayed_image_two_steps_off_fails,
    ]
}
