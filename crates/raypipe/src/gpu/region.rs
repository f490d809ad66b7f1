//! Where a frame's primary rays can hit anything: the pixels that the box around the scene's
//! primitives projects to. The fragment tracer runs only there, under a scissor rectangle; every
//! other pixel's primary ray misses the box, so a shader that traces nothing writes what the tracer
//! would (the background, one ray). A software rasterizer runs the whole tracer for every 2x2 group
//! of pixels, hit or miss (docs/BENCHMARKS.md): a model that fills a third of the frame pays for a
//! third of it.

use crate::bvh::aabb::Aabb;
use crate::records::GpuCamera;
use crate::records::packed::PackedBvh;
use glam::{DVec2, DVec3, Vec3};

/// A rectangle of pixels: columns `x..x + width`, rows `y..y + height` (row 0 at the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    pub x: u32,
    pub y: u32,
    pub width: u32,
    pub height: u32,
}

impl PixelRect {
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }
}

/// The box the BVH walks test first, in world space: the root of the threaded nodes (the stack and
/// threaded walks'), its quantized corners rounded outward from the build layout's root (the
/// stackless walk's), so it holds both. A ray that misses it misses every primitive of the tree.
pub fn walked_box(bvh: &PackedBvh) -> Option<Aabb> {
    let root = bvh.threaded_nodes.first()?;
    let (low, high) = root.corners();
    let frame = &bvh.frame;
    Some(Aabb {
        min: frame.origin + low * frame.quantum,
        max: frame.origin + high * frame.quantum,
    })
}

/// The pixels where a primary ray (anywhere in its pixel: later samples are jittered) can enter
/// `bounds`: the rectangle around its corners' projections, a pixel wider on every side for the
/// rounding of the shader's `camera_ray`. `None` where no pixel can: the box projects outside the
/// frame, or lies wholly behind the eye (a primary ray only goes forward). The whole frame where it
/// reaches from behind the eye to its front: the projection folds there.
pub fn projected_rect(camera: &GpuCamera, bounds: &Aabb) -> Option<PixelRect> {
    let (width, height) = (camera.width as u32, camera.height as u32);
    let whole = Some(PixelRect::whole(width, height));
    if width == 0 || height == 0 || bounds.min.cmpgt(bounds.max).any() {
        return None;
    }
    // In f64: corners near the eye's plane project far out.
    let f = |v: [f32; 3]| Vec3::from(v).as_dvec3();
    let (eye, forward, right, up) = (f(camera.eye), f(camera.forward), f(camera.right), f(camera.up));
    let half_width = camera.tan_half_fov as f64 * camera.aspect as f64;
    let half_height = camera.tan_half_fov as f64;
    let (mut low, mut high) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
    let mut behind = 0;
    for corner in 0..8 {
        let pick = |axis: usize, lo: f32, hi: f32| if corner & (1 << axis) == 0 { lo } else { hi };
        let point = DVec3::new(
            pick(0, bounds.min.x, bounds.max.x) as f64,
            pick(1, bounds.min.y, bounds.max.y) as f64,
            pick(2, bounds.min.z, bounds.max.z) as f64,
        );
        let to_corner = point - eye;
        let depth = to_corner.dot(forward);
        if depth < 0.0 {
            behind += 1;
            continue;
        }
        // camera_ray: x = (2 px / width - 1) tan aspect, y = (1 - 2 py / height) tan.
        let x = (to_corner.dot(right) / depth / half_width + 1.0) * 0.5 * width as f64;
        let y = (1.0 - to_corner.dot(up) / depth / half_height) * 0.5 * height as f64;
        let in_front = depth > 1e-6 * to_corner.length();
        if !in_front || !x.is_finite() || !y.is_finite() {
            return whole;
        }
        low = low.min(DVec2::new(x, y));
        high = high.max(DVec2::new(x, y));
    }
    match behind {
        0 => {}
        8 => return None,
        _ => return whole,
    }
    // Pixel i holds the positions i..i + 1; one more on each side for rounding.
    let first = |v: f64, size: u32| (v.floor() - 1.0).clamp(0.0, size as f64) as u32;
    let end = |v: f64, size: u32| (v.floor() + 2.0).clamp(0.0, size as f64) as u32;
    let (x0, x1) = (first(low.x, width), end(high.x, width));
    let (y0, y1) = (first(low.y, height), end(high.y, height));
    (x0 < x1 && y0 < y1).then_some(PixelRect {
        x: x0,
        y: y0,
        width: x1 - x0,
        height: y1 - y0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    fn camera(eye: Vec3, target: Vec3) -> GpuCamera {
        let camera = Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_degrees: 40.0,
        };
        GpuCamera::new(&camera, 160, 120)
    }

    /// The direction of the shader's camera_ray through pixel position (px, py).
    fn ray_dir(camera: &GpuCamera, px: f32, py: f32) -> Vec3 {
        let x = (2.0 * px / camera.width - 1.0) * camera.tan_half_fov * camera.aspect;
        let y = (1.0 - 2.0 * py / camera.height) * camera.tan_half_fov;
        (Vec3::from(camera.forward) + x * Vec3::from(camera.right) + y * Vec3::from(camera.up)).normalize()
    }

    /// Every pixel position whose ray enters the box lies inside the rectangle, over a grid of
    /// positions finer than the pixels, for boxes seen from several sides.
    #[test]
    fn rays_that_enter_the_box_start_inside_the_rectangle() {
        let bounds = Aabb {
            min: Vec3::new(-0.3, -0.2, -0.5),
            max: Vec3::new(0.4, 0.25, 0.1),
        };
        for eye in [
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(2.0, 1.5, -2.5),
            Vec3::new(-4.0, -0.5, 0.3),
        ] {
            let camera = camera(eye, Vec3::new(0.6, 0.1, 0.0));
            let rect = projected_rect(&camera, &bounds).expect("the box is in view");
            assert!(rect.width < 160 || rect.height < 120, "{rect:?} is the whole frame");
            let mut entered = 0;
            for iy in 0..480 {
                for ix in 0..640 {
                    let (px, py) = (ix as f32 / 4.0 + 0.125, iy as f32 / 4.0 + 0.125);
                    let dir = ray_dir(&camera, px, py);
                    if !ray_enters(eye, dir, &bounds) {
                        continue;
                    }
                    entered += 1;
                    let (x, y) = (px as u32, py as u32);
                    assert!(
                        (rect.x..rect.x + rect.width).contains(&x) && (rect.y..rect.y + rect.height).contains(&y),
                        "from {eye}: pixel ({x}, {y}) sees the box outside {rect:?}"
                    );
                }
            }
            assert!(entered > 100, "from {eye}: only {entered} rays enter the box");
        }
    }

    fn ray_enters(origin: Vec3, dir: Vec3, bounds: &Aabb) -> bool {
        let inv = dir.recip();
        let (a, b) = ((bounds.min - origin) * inv, (bounds.max - origin) * inv);
        let near = a.min(b).max_element().max(0.0);
        let far = a.max(b).min_element();
        near <= far
    }

    /// A box around the eye gets the whole frame (the projection folds there); a box behind it
    /// none.
    #[test]
    fn a_box_around_the_eye_gets_the_whole_frame_and_one_behind_it_none() {
        let camera = camera(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
        let whole = Some(PixelRect::whole(160, 120));
        let around = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        assert_eq!(projected_rect(&camera, &around), whole);
        let behind = Aabb {
            min: Vec3::new(-1.0, -1.0, 2.0),
            max: Vec3::new(1.0, 1.0, 3.0),
        };
        assert_eq!(projected_rect(&camera, &behind), None);
        let across = Aabb {
            min: Vec3::new(3.0, -1.0, -2.0),
            max: Vec3::new(4.0, 1.0, 2.0),
        };
        assert_eq!(projected_rect(&camera, &across), whole);
    }

    /// An empty box (a scene without primitives) projects to no pixel; a box beside the view to none.
    #[test]
    fn an_empty_or_unseen_box_gets_no_pixel() {
        let camera = camera(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0));
        let empty = Aabb {
            min: Vec3::splat(1.0),
            max: Vec3::splat(-1.0),
        };
        assert_eq!(projected_rect(&camera, &empty), None);
        let aside = Aabb {
            min: Vec3::new(50.0, -1.0, -3.0),
            max: Vec3::new(51.0, 1.0, -2.0),
        };
        assert_eq!(projected_rect(&camera, &aside), None);
    }
}
