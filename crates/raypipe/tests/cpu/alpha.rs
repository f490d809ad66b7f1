//! Alpha and sides on the CPU reference, against radiance worked out here: an alpha-masked quad's
//! holes in the image and in its shadow, a blended quad's mix (and the light it lets through to
//! the floor), a single-sided quad that disappears from behind. Each test also renders the quad
//! opaque or double-sided and checks that the answer changes, so that it fails where the feature is
//! broken. The GPU matches the CPU on these scenes in tests/gpu/gltf.rs.

use crate::common::quad_triangles;
use glam::{Vec2, Vec3};
use raypipe::cpu::intersect::Ray;
use raypipe::cpu::trace::{PixelTrace, Tracer};
use raypipe::modes::Accel;
use raypipe::records::PackedScene;
use raypipe::scene::{AlphaMode, Camera, Light, LightKind, Material, RenderSettings, Scene, Texture, Wrap};

/// Irradiance of the light at normal incidence (lux: the light is directional).
const E: f32 = 2.0;
/// A surface facing +z meets the light at 45 degrees.
const COS_45: f32 = std::f32::consts::FRAC_1_SQRT_2;
const RED: [f32; 4] = [1.0, 0.0, 0.0, 1.0];
const GREEN_HOLE: [f32; 4] = [0.0, 1.0, 0.0, 0.0];

/// A white floor (z = 0, Whitted, albedo 1) under a quad over x, y in [-1, 1] at z = 1 in `quad`,
/// with the quad's 2x1 texture (`texels`: x < 0, then x > 0), lit by parallel light travelling
/// along (1, 0, -1): the quad's shadow lies one unit toward +x. No ambient light, black background,
/// no bounces: a pixel is direct light alone. `facing_up` winds the quad to face +z.
fn quad_over_floor(quad: Material, texels: [[f32; 4]; 2], facing_up: bool) -> Scene {
    let square = |z: f32, size: f32| {
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)].map(|(x, y)| Vec3::new(x * size, y * size, z))
    };
    let uv = |p: Vec3| Vec2::new((p.x + 1.0) / 2.0, (1.0 - p.y) / 2.0);
    let triangles = |corners, material, up| quad_triangles(corners, material, up, Some(&uv));
    let floor = Material {
        color: Vec3::ONE,
        ..Material::default()
    };
    let mut all = triangles(square(0.0, 20.0), 0, true).to_vec();
    all.extend(triangles(square(1.0, 1.0), 1, facing_up));
    Scene {
        camera: Camera {
            eye: Vec3::new(0.0, 0.0, 20.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_degrees: 20.0,
        },
        settings: RenderSettings {
            width: 8,
            height: 8,
            max_depth: 0,
            background: Vec3::ZERO,
            ambient: 0.0,
            accel: None,
            integrator: Default::default(),
        },
        lights: vec![Light {
            position: Vec3::ZERO,
            color: Vec3::splat(E),
            kind: LightKind::Directional {
                direction: Vec3::new(1.0, 0.0, -1.0).normalize(),
            },
        }],
        materials: vec![floor, quad],
        triangles: all,
        textures: vec![Texture::from_linear(2, 1, &texels, [Wrap::Clamp; 2])],
        ..Scene::default()
    }
}

/// A quad material with the texture as its base colour map.
fn textured(alpha_mode: AlphaMode) -> Material {
    Material {
        color: Vec3::ONE,
        texture: Some(raypipe::scene::TextureMap::plain(0)),
        alpha_mode,
        ..Material::default()
    }
}

/// What a ray straight down at (x, 0) brings back, with every walk and brute force agreeing (on
/// all but the nodes tested).
fn straight_down(scene: &Scene, x: f32) -> PixelTrace {
    let mut packed = PackedScene::new(scene).unwrap();
    packed.build_bvh();
    let ray = Ray::new(Vec3::new(x, 0.0, 20.0), Vec3::NEG_Z);
    let trace = |accel| PixelTrace {
        cost: 0,
        ..Tracer::new(&packed, accel).unwrap().trace_pixel(ray)
    };
    let brute = trace(Accel::Brute);
    for accel in [Accel::Stack, Accel::Stackless, Accel::Threaded] {
        assert_eq!(trace(accel), brute, "{accel:?} against brute force at x = {x}");
    }
    brute
}

fn assert_radiance(trace: &PixelTrace, expected: Vec3, what: &str) {
    assert!(
        (trace.color - expected).abs().max_element() <= 1e-5,
        "{what}: {} where {expected} is expected",
        trace.color
    );
}

#[test]
fn an_alpha_masked_quad_has_holes_in_the_image_and_in_its_shadow() {
    // Red and opaque for x < 0, a hole (alpha 0) for x > 0.
    let masked = quad_over_floor(textured(AlphaMode::Mask { cutoff: 0.5 }), [RED, GREEN_HOLE], true);
    let lit_floor = Vec3::splat(E * COS_45);
    // x = -0.5: the quad's red half, lit.
    let red = straight_down(&masked, -0.5);
    assert_radiance(&red, Vec3::new(E * COS_45, 0.0, 0.0), "the quad's opaque half");
    assert_eq!(red.depth, Some(19.0));
    // x = 0.5: through the hole to the floor, in the shadow of the red half (its shadow ray
    // crosses the quad at x = -0.5).
    let hole = straight_down(&masked, 0.5);
    assert_eq!(hole.depth, Some(20.0), "the ray goes through the hole");
    assert_radiance(&hole, Vec3::ZERO, "the floor under the hole, in the red half's shadow");
    // x = 1.5: the floor, whose shadow ray crosses the hole at x = 0.5: lit.
    assert_radiance(&straight_down(&masked, 1.5), lit_floor, "the hole in the shadow");
    // The same quad opaque: the green half is seen, and shades the floor.
    let opaque = quad_over_floor(textured(AlphaMode::Opaque), [RED, GREEN_HOLE], true);
    assert_radiance(&straight_down(&opaque, 0.5), Vec3::new(0.0, E * COS_45, 0.0), "opaque");
    assert_radiance(&straight_down(&opaque, 1.5), Vec3::ZERO, "the opaque quad's shadow");
    // A cutoff above the red half's alpha cuts it away too.
    let cut = quad_over_floor(textured(AlphaMode::Mask { cutoff: 1.5 }), [RED, GREEN_HOLE], true);
    assert_eq!(straight_down(&cut, -0.5).depth, Some(20.0));
}

#[test]
fn a_blended_quad_mixes_with_what_lies_behind_it_and_lets_light_through() {
    // A uniform quad of alpha 0.25: red, untextured (white texels keep the colour).
    let white = [1.0; 4];
    let blended = Material {
        color: Vec3::new(1.0, 0.0, 0.0),
        alpha: 0.25,
        alpha_mode: AlphaMode::Blend,
        ..Material::default()
    };
    let scene = quad_over_floor(blended, [white, white], true);
    // The floor at x = 0.5 gets 0.75 of the light through the quad at x = -0.5; seen through the
    // quad, it is 0.75 of the pixel, the quad's lit red the other 0.25. With no bounces
    // (max_depth 0): passing through is not a bounce.
    let lit = E * COS_45;
    let mix = straight_down(&scene, 0.5);
    let expected = 0.25 * Vec3::new(lit, 0.0, 0.0) + 0.75 * Vec3::splat(0.75 * lit);
    assert_radiance(&mix, expected, "the blend");
    assert_eq!(mix.depth, Some(19.0), "the depth is the first surface's");
    // x = 1.5: the floor beside the quad, its light through the quad at x = 0.5.
    assert_radiance(
        &straight_down(&scene, 1.5),
        Vec3::splat(0.75 * lit),
        "light through the quad",
    );
    // Opaque, the same material shows its red alone and casts a full shadow.
    let opaque = quad_over_floor(
        Material {
            alpha_mode: AlphaMode::Opaque,
            ..blended
        },
        [white, white],
        true,
    );
    assert_radiance(&straight_down(&opaque, 0.5), Vec3::new(lit, 0.0, 0.0), "opaque");
    assert_radiance(&straight_down(&opaque, 1.5), Vec3::ZERO, "the opaque shadow");
    // Alpha 0 is the floor alone; alpha 1 the quad alone.
    for (alpha, expected) in [(0.0, Vec3::splat(lit)), (1.0, Vec3::new(lit, 0.0, 0.0))] {
        let scene = quad_over_floor(Material { alpha, ..blended }, [white, white], true);
        assert_radiance(&straight_down(&scene, 0.5), expected, &format!("alpha {alpha}"));
    }
}

#[test]
fn a_single_sided_quad_disappears_from_behind_and_still_casts_its_shadow() {
    let white = [1.0; 4];
    let one_side = Material {
        double_sided: false,
        ..Material::default()
    };
    // Wound to face the floor: the camera sees its back, and through it the floor.
    let away = quad_over_floor(one_side, [white, white], false);
    let behind = straight_down(&away, 0.5);
    assert_eq!(behind.depth, Some(20.0), "a single-sided quad seen from behind");
    // Shadow rays meet both sides: the floor there is in the quad's shadow.
    assert_radiance(&behind, Vec3::ZERO, "the shadow of a single-sided quad");
    // Facing the camera, it is seen; double-sided, it is seen from either side.
    assert_eq!(
        straight_down(&quad_over_floor(one_side, [white, white], true), 0.5).depth,
        Some(19.0)
    );
    let both = quad_over_floor(Material::default(), [white, white], false);
    assert_eq!(straight_down(&both, 0.5).depth, Some(19.0), "double-sided");
}

#[test]
fn spheres_and_planes_refuse_what_only_triangles_carry() {
    let mut scene = quad_over_floor(Material::default(), [[1.0; 4]; 2], true);
    scene.materials[1].alpha_mode = AlphaMode::Blend;
    scene.spheres.push(raypipe::scene::Sphere {
        center: Vec3::new(0.0, 0.0, 3.0),
        radius: 0.5,
        material: 1,
    });
    let error = PackedScene::new(&scene).unwrap_err().to_string();
    assert!(error.contains("only triangles"), "{error}");
}
