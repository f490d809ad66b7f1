//! Where a frame's primary rays can hit anything: the pixels that the scene's boxes project to. The
//! fragment tracer runs only there, under scissor rectangles; every other pixel's primary ray misses
//! every box, so a shader that traces nothing writes what the tracer would (the background, one
//! ray). A software rasterizer runs the whole tracer for every 2x2 group of pixels, hit or miss
//! (docs/BENCHMARKS.md): a model that fills a third of the frame pays for a third of it.
//!
//! The boxes are the BVH's own, from the root down (a `BoxCover`): a node whose projection is
//! large is replaced by its children's, so the traced pixels hug the model's outline instead of its
//! bounding box, in tiles of `TILE` pixels.

use crate::bvh::aabb::Aabb;
use crate::records::GpuCamera;
use crate::records::packed::PackedBvh;
use glam::{DVec2, DVec3, Vec3};

/// The side of the square tiles the traced pixels are made of: even, so that no 2x2 group of
/// pixels is split between the tracer and the misses' shader.
pub(crate) const TILE: u32 = 4;
/// A node whose rectangle holds more pixels than this is replaced by its children's.
const REFINE_ABOVE_PIXELS: u32 = 64;
/// The levels of the BVH a cover keeps below its root: at most 2047 boxes to project each time the
/// camera moves (0.4 ms for the Bunny on one core of the development machine), and tiles that
/// hold 1.27 times the pixels of the 2x2 groups that hit it (docs/BENCHMARKS.md).
const COVER_LEVELS: u32 = 10;

/// A rectangle of pixels: columns `x..x + width`, rows `y..y + height` (row 0 at the top).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelRect {
    /// The first column.
    pub x: u32,
    /// The first row.
    pub y: u32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl PixelRect {
    /// The whole of a `width` x `height` image.
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            x: 0,
            y: 0,
            width,
            height,
        }
    }
}

/// The pixels a frame traces: disjoint rectangles, in rows from the top.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct TracedPixels {
    /// The rectangles.
    pub rects: Vec<PixelRect>,
}

impl TracedPixels {
    /// Every pixel of a `width` x `height` image, as one rectangle.
    pub fn whole(width: u32, height: u32) -> Self {
        Self {
            rects: vec![PixelRect::whole(width, height)],
        }
    }

    /// Whether these are every pixel of a `width` x `height` image.
    pub fn is_whole(&self, width: u32, height: u32) -> bool {
        self.rects == [PixelRect::whole(width, height)]
    }

    /// How many pixels are traced.
    pub fn pixel_count(&self) -> u64 {
        self.rects.iter().map(|r| r.width as u64 * r.height as u64).sum()
    }

    /// Whether pixel (`x`, `y`) is traced.
    pub fn contains(&self, x: u32, y: u32) -> bool {
        self.rects
            .iter()
            .any(|r| (r.x..r.x + r.width).contains(&x) && (r.y..r.y + r.height).contains(&y))
    }
}

/// The top levels of a BVH as world-space boxes, each holding its subtree's primitives: a ray that
/// enters none of a cut's boxes misses every primitive. The boxes are the threaded nodes' (the stack
/// and threaded walks'), whose quantized corners are rounded outward from the build layout's (the
/// stackless walk's), so they hold both.
#[derive(Clone, Debug)]
pub(crate) struct BoxCover {
    /// Depth-first from the root.
    nodes: Vec<CoverNode>,
}

#[derive(Clone, Copy, Debug)]
struct CoverNode {
    bounds: Aabb,
    /// Where the children are in the cover; none for a leaf or a node on the last level kept.
    children: Option<[u32; 2]>,
}

impl BoxCover {
    /// None for a tree without nodes.
    pub fn new(bvh: &PackedBvh) -> Option<Self> {
        let tree = &bvh.threaded_nodes;
        if tree.is_empty() {
            return None;
        }
        let mut nodes: Vec<CoverNode> = Vec::new();
        // (threaded node, its level, the cover node that points to it, which child it is)
        let mut pending = vec![(0usize, 0u32, None::<(usize, usize)>)];
        while let Some((index, level, parent)) = pending.pop() {
            let at = nodes.len();
            if let Some((parent, side)) = parent {
                nodes[parent].children.get_or_insert([0; 2])[side] = at as u32;
            }
            nodes.push(CoverNode {
                bounds: bvh.frame.world_box(&tree[index]),
                children: None,
            });
            if tree[index].is_leaf() || level == COVER_LEVELS {
                continue;
            }
            // Depth-first numbering: the left child is the next node, the right one comes after
            // the left subtree.
            let left = index + 1;
            let right = if tree[left].is_leaf() {
                left + 1
            } else {
                tree[left].link as usize
            };
            pending.push((right, level + 1, Some((at, 1))));
            pending.push((left, level + 1, Some((at, 0))));
        }
        Some(Self { nodes })
    }

    /// The root's box: the one every walk tests first.
    #[cfg(test)]
    pub fn root(&self) -> Aabb {
        self.nodes[0].bounds
    }

    /// The pixels where a primary ray can enter one of the boxes: the tiles that the rectangles of
    /// a cut through the cover overlap (`Projection::rect`), a node's children's replacing its own
    /// while it spans more than 64 pixels (`REFINE_ABOVE_PIXELS`).
    pub fn traced_pixels(&self, camera: &GpuCamera) -> TracedPixels {
        let (width, height) = (camera.width as u32, camera.height as u32);
        let (columns, rows) = (width.div_ceil(TILE) as usize, height.div_ceil(TILE) as usize);
        let mut covered = vec![false; columns * rows];
        // The rows of tiles a rectangle overlaps, as ranges of `covered`.
        let tile_rows = |rect: PixelRect| {
            let (x0, x1) = ((rect.x / TILE) as usize, (rect.x + rect.width).div_ceil(TILE) as usize);
            (rect.y / TILE..(rect.y + rect.height).div_ceil(TILE)).map(move |y| {
                let row = y as usize * columns;
                row + x0..row + x1
            })
        };
        let projection = Projection::new(camera);
        let mut pending = vec![0usize];
        while let Some(index) = pending.pop() {
            let node = &self.nodes[index];
            let Some(rect) = projection.rect(&node.bounds) else {
                continue;
            };
            match node.children {
                Some([left, right]) if rect.width * rect.height > REFINE_ABOVE_PIXELS => {
                    pending.push(right as usize);
                    pending.push(left as usize);
                }
                _ => tile_rows(rect).for_each(|row| covered[row].fill(true)),
            }
        }
        TracedPixels {
            rects: tile_rects(&covered, columns, width, height),
        }
    }
}

/// The covered tiles as few disjoint rectangles: each row's runs, a run stretched down over the
/// rows below that have the same run.
fn tile_rects(covered: &[bool], columns: usize, width: u32, height: u32) -> Vec<PixelRect> {
    // Runs of a row: [first column, end column).
    let runs = |row: &[bool]| {
        let mut runs = Vec::new();
        let mut start = None;
        for (column, &on) in row.iter().chain([&false]).enumerate() {
            match (on, start) {
                (true, None) => start = Some(column),
                (false, Some(first)) => {
                    runs.push((first, column));
                    start = None;
                }
                _ => {}
            }
        }
        runs
    };
    let pixels = |tiles: (usize, usize), size: u32| {
        let first = tiles.0 as u32 * TILE;
        (first, (tiles.1 as u32 * TILE).min(size) - first)
    };
    let mut rects: Vec<PixelRect> = Vec::new();
    // Rectangles that reach down to the row above, by their runs.
    let mut open: Vec<((usize, usize), usize)> = Vec::new();
    for (row_index, row) in covered.chunks(columns).enumerate() {
        let (y, rect_height) = pixels((row_index, row_index + 1), height);
        let mut still_open = Vec::new();
        for run in runs(row) {
            match open.iter().find(|(r, _)| *r == run) {
                Some(&(_, rect)) => {
                    rects[rect].height += rect_height;
                    still_open.push((run, rect));
                }
                None => {
                    let (x, rect_width) = pixels(run, width);
                    still_open.push((run, rects.len()));
                    rects.push(PixelRect {
                        x,
                        y,
                        width: rect_width,
                        height: rect_height,
                    });
                }
            }
        }
        open = still_open;
    }
    rects
}

/// A camera's projection onto pixel positions, in f64: corners near the eye's plane project far
/// out.
struct Projection {
    width: u32,
    height: u32,
    eye: DVec3,
    forward: DVec3,
    /// The camera's right and up axes scaled so that a point's dot product with them over its
    /// depth is its offset from the frame's centre in pixels (down for `down`).
    right: DVec3,
    down: DVec3,
}

impl Projection {
    fn new(camera: &GpuCamera) -> Self {
        let f = |v: [f32; 3]| Vec3::from(v).as_dvec3();
        let (width, height) = (camera.width as u32, camera.height as u32);
        // camera_ray: x = (2 px / width - 1) tan aspect, y = (1 - 2 py / height) tan.
        let half_width = camera.tan_half_fov as f64 * camera.aspect as f64;
        let half_height = camera.tan_half_fov as f64;
        Self {
            width,
            height,
            eye: f(camera.eye),
            forward: f(camera.forward),
            right: f(camera.right) * (0.5 * width as f64 / half_width),
            down: f(camera.up) * (-0.5 * height as f64 / half_height),
        }
    }

    /// The pixels where a primary ray (anywhere in its pixel: later samples are jittered) can
    /// enter `bounds`: the rectangle around its corners' projections, a pixel wider on every side
    /// for the rounding of the shader's `camera_ray`. `None` where no pixel can: the box projects
    /// outside the frame, or lies wholly behind the eye (a primary ray only goes forward). The
    /// whole frame where it reaches from behind the eye to its front: the projection folds there.
    fn rect(&self, bounds: &Aabb) -> Option<PixelRect> {
        let (width, height) = (self.width, self.height);
        let whole = Some(PixelRect::whole(width, height));
        if width == 0 || height == 0 || bounds.min.cmpgt(bounds.max).any() {
            return None;
        }
        let centre = DVec2::new(width as f64, height as f64) * 0.5;
        let (low_corner, high_corner) = (bounds.min.as_dvec3(), bounds.max.as_dvec3());
        let (mut low, mut high) = (DVec2::INFINITY, DVec2::NEG_INFINITY);
        let mut behind = 0;
        for corner in 0..8 {
            let point = DVec3::select(
                glam::BVec3::new(corner & 1 != 0, corner & 2 != 0, corner & 4 != 0),
                high_corner,
                low_corner,
            );
            let to_corner = point - self.eye;
            let depth = to_corner.dot(self.forward);
            if depth < 0.0 {
                behind += 1;
                continue;
            }
            let in_front = depth * depth > 1e-12 * to_corner.length_squared();
            let scale = 1.0 / depth;
            let position = centre + DVec2::new(to_corner.dot(self.right), to_corner.dot(self.down)) * scale;
            if !in_front || !position.is_finite() {
                return whole;
            }
            low = low.min(position);
            high = high.max(position);
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
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    fn projected_rect(camera: &GpuCamera, bounds: &Aabb) -> Option<PixelRect> {
        Projection::new(camera).rect(bounds)
    }

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

    /// Every sub-pixel position whose ray enters one of a BVH's leaf boxes lies in the traced
    /// pixels, which are fewer than the root box's rectangle: a ring of spheres seen from above (a
    /// hole in the middle), from its side, and from inside it.
    #[test]
    fn rays_that_enter_a_leaf_box_start_in_the_traced_pixels() {
        let scene = crate::scene::builtin::by_name("torus:400").unwrap().unwrap();
        let mut packed = crate::records::PackedScene::new(&scene).unwrap();
        packed.build_bvh();
        let bvh = packed.bvh.as_ref().unwrap();
        let cover = BoxCover::new(bvh).unwrap();
        let leaves: Vec<Aabb> = bvh
            .threaded_nodes
            .iter()
            .filter(|node| node.is_leaf())
            .map(|node| bvh.frame.world_box(node))
            .collect();
        for (eye, tighter) in [
            (Vec3::new(0.3, 3.0, 0.4), true),
            (Vec3::new(3.5, 0.8, -1.0), true),
            (Vec3::new(0.9, 0.0, 0.0), false),
        ] {
            let camera = camera(eye, Vec3::ZERO);
            let traced = cover.traced_pixels(&camera);
            assert!(disjoint(&traced.rects), "from {eye}: {:?}", traced.rects);
            let mut entered = 0;
            for iy in 0..360 {
                for ix in 0..480 {
                    let (px, py) = (ix as f32 / 3.0 + 1.0 / 6.0, iy as f32 / 3.0 + 1.0 / 6.0);
                    let dir = ray_dir(&camera, px, py);
                    if !leaves.iter().any(|leaf| ray_enters(eye, dir, leaf)) {
                        continue;
                    }
                    entered += 1;
                    let (x, y) = (px as u32, py as u32);
                    assert!(
                        traced.contains(x, y),
                        "from {eye}: pixel ({x}, {y}) sees a leaf but is not traced"
                    );
                }
            }
            assert!(entered > 1000, "from {eye}: only {entered} rays enter a leaf");
            if tighter {
                let rect = projected_rect(&camera, &cover.root()).unwrap();
                let root_pixels = rect.width as u64 * rect.height as u64;
                assert!(
                    traced.pixel_count() * 10 < root_pixels * 9,
                    "from {eye}: {} traced against the root's {root_pixels}",
                    traced.pixel_count()
                );
            }
        }
    }

    fn disjoint(rects: &[PixelRect]) -> bool {
        rects.iter().enumerate().all(|(i, a)| {
            rects[i + 1..]
                .iter()
                .all(|b| a.x + a.width <= b.x || b.x + b.width <= a.x || a.y + a.height <= b.y || b.y + b.height <= a.y)
        })
    }

    proptest::proptest! {
        /// The rectangles are disjoint and hold exactly the covered tiles' pixels, cut at the
        /// image's edges.
        #[test]
        fn tile_rects_hold_exactly_the_covered_tiles(
            width in 1u32..40,
            height in 1u32..40,
            bits in proptest::collection::vec(proptest::bool::weighted(0.6), 100),
        ) {
            let (columns, rows) = (width.div_ceil(TILE) as usize, height.div_ceil(TILE) as usize);
            let covered: Vec<bool> = (0..columns * rows).map(|i| bits[i % bits.len()]).collect();
            let rects = tile_rects(&covered, columns, width, height);
            proptest::prop_assert!(disjoint(&rects));
            let traced = TracedPixels { rects };
            for y in 0..height {
                for x in 0..width {
                    let tile = (y / TILE) as usize * columns + (x / TILE) as usize;
                    proptest::prop_assert_eq!(traced.contains(x, y), covered[tile], "pixel ({}, {})", x, y);
                }
            }
        }
    }
}
