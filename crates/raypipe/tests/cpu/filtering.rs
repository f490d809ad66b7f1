//! Texture filtering: the mip level a ray cone's footprint picks, against the footprint written
//! out; a checker floor to the horizon filtered, not aliased, at one sample per pixel; and the
//! sampler's NEAREST filters obeyed.

use crate::common::{
    checker_floor, checker_texture, hit_rows, quad_triangles, red_deviation, render_cpu, unlit_textured,
};
use glam::{Vec2, Vec3};
use raypipe::image::Frame;
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::{Camera, Filter, Material, RenderSettings, Scene, Sphere, TexelFilter, Texture, Wrap};

fn render(scene: &Scene) -> Frame {
    let mut packed = PackedScene::new(scene).unwrap();
    packed.build_bvh();
    render_cpu(&packed, Accel::Threaded)
}

fn red(frame: &Frame, x: u32, y: u32) -> f32 {
    frame.color[(y * frame.width + x) as usize][0]
}

/// An odd image size: the centre pixel's ray runs along the view direction.
const FACING_SIZE: u32 = 33;
const FACING_FOV: f32 = 30.0;

/// A wall facing the camera `distance` away, unlit, textured with `texture` through `uv`.
fn wall(texture: Texture, uv: &dyn Fn(Vec3) -> Vec2, distance: f32) -> Scene {
    let corners = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, distance),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: FACING_FOV,
        },
        settings: RenderSettings {
            width: FACING_SIZE,
            height: FACING_SIZE,
            max_depth: 0,
            background: Vec3::ZERO,
            ambient: 0.0,
            accel: None,
            integrator: Default::default(),
        },
        materials: vec![unlit_textured()],
        textures: vec![texture],
        triangles: quad_triangles(corners, 0, true, Some(uv)).to_vec(),
        ..Scene::default()
    }
}

/// A [`wall`] textured with `texture` at `texels_per_unit`, its texture coordinate at the wall's
/// centre (0.25, 0.25): the centre of texel (0, 0) of a 2 x 2 texture.
fn facing_wall(texture: Texture, texels_per_unit: f32, distance: f32) -> Scene {
    let size = texture.width as f32;
    let uv = |p: Vec3| Vec2::new(p.x, -p.y) * (texels_per_unit / size) + Vec2::splat(0.25);
    wall(texture, &uv, distance)
}

#[test]
fn the_mip_level_is_log2_of_the_texels_the_footprint_spans() {
    // A 2 x 2 checker (white at texel (0, 0)): its level 0 at a texel's centre is 1, its level 1
    // is 0.5, so trilinear filtering at level λ in (0, 1) reads 1 - λ / 2 there, and the centre
    // pixel's red gives λ back. The footprint written out: the cone through a pixel spreads by
    // atan(2 tan(fov / 2) / height), so at `distance` straight ahead it spans that times the
    // distance, times the texels per unit of length.
    let spread = (2.0 * (FACING_FOV.to_radians() / 2.0).tan() / FACING_SIZE as f32).atan();
    let texels_per_unit = 30.0;
    let centre = FACING_SIZE / 2;
    let mut levels = Vec::new();
    for distance in [2.2f32, 2.8, 3.4, 3.96] {
        let frame = render(&facing_wall(
            checker_texture(2, Filter::default()),
            texels_per_unit,
            distance,
        ));
        let measured = 2.0 * (1.0 - red(&frame, centre, centre));
        let expected = (spread * distance * texels_per_unit).log2();
        assert!(
            (0.02..0.98).contains(&expected),
            "distance {distance}: level {expected} is outside the test's range"
        );
        assert!(
            (measured - expected).abs() < 0.01,
            "distance {distance}: level {measured}, the footprint's {expected}"
        );
        levels.push(measured);
    }
    // 1.8 times the distance, log2(1.8) levels coarser.
    assert!((levels[3] - levels[0] - 1.8f32.log2()).abs() < 0.02, "{levels:?}");
}

#[test]
fn a_checker_floor_to_the_horizon_is_filtered_not_aliased() {
    // The target: the far rows' pixels vary by a standard deviation under 0.06 at one
    // sample per pixel. Unfiltered (minFilter NEAREST, no mipmaps) they alias: pixels land on
    // black and white texels at random, a deviation near 0.5.
    let (width, height) = (160, 120);
    let filtered = render(&checker_floor(Filter::default(), width, height));
    let unfiltered_filter = Filter {
        magnify: TexelFilter::Nearest,
        minify: TexelFilter::Nearest,
        mipmaps: None,
    };
    let unfiltered = render(&checker_floor(unfiltered_filter, width, height));
    let rows = hit_rows(&filtered);
    assert_eq!(rows, hit_rows(&unfiltered));
    assert!(rows.len() > 40 && rows[0] < height / 2, "floor rows {rows:?}");
    let far = &rows[..16];
    let near = &rows[rows.len() - 8..];
    let far_filtered = red_deviation(&filtered, far);
    let far_unfiltered = red_deviation(&unfiltered, far);
    println!("far rows {far:?}: deviation {far_filtered:.4} filtered, {far_unfiltered:.4} unfiltered");
    assert!(far_filtered < 0.06, "far rows filtered: deviation {far_filtered}");
    assert!(far_unfiltered > 0.3, "far rows unfiltered: deviation {far_unfiltered}");
    // Their mean stays the checker's: half the texels are white.
    let mean = far
        .iter()
        .flat_map(|&y| (0..width).map(move |x| (x, y)))
        .map(|(x, y)| red(&filtered, x, y))
        .sum::<f32>()
        / (far.len() as u32 * width) as f32;
    assert!((mean - 0.5).abs() < 0.02, "far rows' mean {mean}");
    // Near the camera a texel spans pixels, magnified: bilinear between one-texel squares, the
    // checker varies by 1/6 (0.5 times the mean square of (1 - 2 fx)(1 - 2 fy) for fractions fx,
    // fy spread evenly), not blurred to grey.
    let near_filtered = red_deviation(&filtered, near);
    println!("near rows {near:?}: deviation {near_filtered:.4}");
    assert!(near_filtered > 0.12, "near rows filtered: deviation {near_filtered}");
}

/// A 2 x 1 texture, black then white, magnified on a [`wall`] (a texel spans 4 units of it); the
/// centre pixel a quarter of a texel right of the boundary between them.
fn magnified_pair(filter: Filter) -> f32 {
    let texture = Texture::from_linear(2, 1, &[[0.0, 0.0, 0.0, 1.0], [1.0; 4]], [Wrap::Clamp; 2]).with_filter(filter);
    // u = 0.5 (the boundary) a quarter texel left of the centre: u = 0.5 + x / 2 / 4 at x.
    let uv = |p: Vec3| Vec2::new(0.625 + p.x / 8.0, 0.5);
    let frame = render(&wall(texture, &uv, 3.0));
    red(&frame, FACING_SIZE / 2, FACING_SIZE / 2)
}

#[test]
fn a_nearest_magnification_filter_reads_one_texel() {
    // Linear: a quarter texel right of the boundary, between the texel centres at u = 0.25 and
    // 0.75, is 0.75 of the way to white. NEAREST: the white texel itself.
    let linear = magnified_pair(Filter::default());
    assert!((linear - 0.75).abs() < 1e-3, "linear magnification: {linear}");
    let nearest = magnified_pair(Filter {
        magnify: TexelFilter::Nearest,
        ..Filter::default()
    });
    assert_eq!(nearest, 1.0, "nearest magnification");
}

/// The level the centre pixel reads off [`facing_wall`]'s texture behind the camera, seen in a
/// mirror `distance` ahead: a flat one, or a sphere of `radius` whose nearest point is there.
/// The wall stands `behind` the camera, facing it.
fn level_in_mirror(texels_per_unit: f32, distance: f32, behind: f32, radius: Option<f32>) -> f32 {
    let mut scene = facing_wall(
        checker_texture(2, Filter::default()),
        texels_per_unit,
        distance + behind,
    );
    // The wall turned to face the mirror.
    for triangle in &mut scene.triangles {
        triangle.vertices.swap(1, 2);
        triangle.uvs = triangle.uvs.map(|mut uvs| {
            uvs.swap(1, 2);
            uvs
        });
        triangle.material = 1;
        for v in &mut triangle.vertices {
            v.z = distance + behind;
        }
    }
    scene.camera.eye.z = distance;
    scene.settings.max_depth = 1;
    scene.materials = vec![
        Material {
            color: Vec3::ZERO,
            reflect: 1.0,
            ..Material::default()
        },
        unlit_textured(),
    ];
    let mirror = [(-50.0, -50.0), (50.0, -50.0), (50.0, 50.0), (-50.0, 50.0)].map(|(x, y)| Vec3::new(x, y, 0.0));
    match radius {
        None => scene.triangles.extend(quad_triangles(mirror, 0, true, None)),
        Some(radius) => scene.spheres.push(Sphere {
            center: Vec3::new(0.0, 0.0, -radius),
            radius,
            material: 0,
        }),
    }
    let frame = render(&scene);
    2.0 * (1.0 - red(&frame, FACING_SIZE / 2, FACING_SIZE / 2))
}

#[test]
fn the_cone_goes_on_through_mirrors() {
    let spread = (2.0 * (FACING_FOV.to_radians() / 2.0).tan() / FACING_SIZE as f32).atan();
    let texels_per_unit = 30.0;
    let (distance, behind) = (0.8, 0.7);
    // A flat mirror: the cone goes on as it came, its width the spread times the whole path.
    let flat = level_in_mirror(texels_per_unit, distance, behind, None);
    let path = distance + distance + behind;
    let expected = (spread * path * texels_per_unit).log2();
    assert!(
        (0.02..0.98).contains(&expected),
        "level {expected} is outside the test's range"
    );
    assert!(
        (flat - expected).abs() < 0.01,
        "flat mirror: level {flat}, the footprint's {expected}"
    );
    // A convex mirror of radius R met squarely: across the cone's width w = spread × distance the
    // normal turns by w / R, and the reflected rays spread by twice that more.
    let radius = 20.0;
    let curved = level_in_mirror(texels_per_unit, distance, behind, Some(radius));
    let width = spread * distance;
    let back = distance + behind;
    let expected = ((width + (spread + 2.0 * width / radius) * back) * texels_per_unit).log2();
    assert!(
        curved > flat + 0.01,
        "the convex mirror's level {curved} is no coarser than the flat one's {flat}"
    );
    assert!(
        (curved - expected).abs() < 0.01,
        "convex mirror: level {curved}, the footprint's {expected}"
    );
}
