//! What names a scene and how it is traced, shared by `render`, `view` and `bench`: the scene's
//! flags (`SceneArgs`), loading it, and the image an AOV makes of a frame.

use crate::args::choice;
use anyhow::bail;
use clap::Args;
use raypipe::image::tonemap::{DisplayTransform, MAX_EXPOSURE};
use raypipe::modes::Backend;
use raypipe::modes::{Accel, Aov, Builder, Integrator, MemoryMode, Pipeline};
use raypipe::scene::ToneMap;
use raypipe::scene::animation::ClipChoice;
use raypipe::scene::is_model_file;
use raypipe::scene::model::{Floor, MeshAs, ModelOptions, Normals};
use raypipe::scene::{Environment, Scene};

/// What names the scene and how it is traced: the flags `render` and `view` share.
#[derive(Args)]
pub struct SceneArgs {
    /// A built-in scene (whitted, sphere-8k, torus-5k, sphere:N, torus:N, random:N[:SEED],
    /// bounce:N[:SEED]), a TOML scene file, a model file (.ply, .obj, .off) to frame and render, or a glTF
    /// scene (.gltf, .glb) with its camera and lights.
    #[arg(default_value = "whitted", value_name = "SCENE")]
    pub spec: String,
    /// With a model file: render its triangles, or spheres on its surface.
    #[arg(long = "as", value_parser = choice::<MeshAs>())]
    pub as_: Option<MeshAs>,
    /// With a model file: this many spheres, sampled uniformly by area (implies --as spheres).
    /// Without it, --as spheres puts one sphere on every vertex.
    #[arg(long)]
    pub spheres: Option<usize>,
    /// With a model file: rotate it first by these Euler angles in degrees, about x, then y, then z
    /// (say --rotate=-90,0,0 to stand up a model whose up axis is z).
    #[arg(long, value_parser = parse_angles, allow_hyphen_values = true)]
    pub rotate: Option<glam::Vec3>,
    /// With a model file's triangles: shade with the file's vertex normals where it has them, else
    /// smooth ones (auto); with each face's own normal (flat); or with smooth normals computed from
    /// the faces (smooth).
    #[arg(long, value_parser = choice::<Normals>())]
    pub normals: Option<Normals>,
    /// With smooth normals: faces meeting at more than this many degrees keep a sharp edge
    /// (default 60).
    #[arg(long, value_name = "DEGREES")]
    pub crease: Option<f32>,
    /// With a model file: what it stands on: a checkered floor just below its lowest point, or
    /// none. (A glTF with a camera of its own gets none.)
    #[arg(long, value_parser = choice::<Floor>())]
    pub floor: Option<Floor>,
    /// The radiance of rays that escape the scene: linear R,G,B, each finite and not negative
    /// (default the scene's background).
    #[arg(long, value_parser = parse_color, value_name = "R,G,B")]
    pub background: Option<glam::Vec3>,
    /// Light the scene by an equirectangular environment (a Radiance .hdr or OpenEXR .exr, twice as
    /// wide as high): rays that escape return its radiance, glTF surfaces take its irradiance.
    /// `none` leaves it out, a scene file's or the studio a glTF without lights gets.
    #[arg(long, value_name = "FILE|none")]
    pub environment: Option<String>,
    /// Turn the environment about +y by this many degrees (counter-clockwise seen from above).
    #[arg(long, value_name = "DEGREES", allow_hyphen_values = true, value_parser = parse_finite)]
    pub environment_rotation: Option<f32>,
    /// Multiply the environment's radiance by this (finite, not negative).
    #[arg(long, value_name = "F", allow_hyphen_values = true, value_parser = parse_intensity)]
    pub environment_intensity: Option<f32>,
    #[arg(long)]
    pub width: Option<u32>,
    #[arg(long)]
    pub height: Option<u32>,
    /// Maximum bounces after the primary ray (default 5, or the scene's; at most 32).
    #[arg(long, value_parser = clap::value_parser!(u32).range(0..=raypipe::scene::MAX_DEPTH_LIMIT as i64))]
    pub depth: Option<u32>,
    /// How light is carried: the paper's Whitted tracer, or a path tracer [default: the scene
    /// file's `integrator`; path for a glTF file, whitted for the others]
    #[arg(long, value_parser = choice::<Integrator>())]
    pub integrator: Option<Integrator>,
    #[arg(long, value_parser = choice::<Backend>())]
    pub backend: Option<Backend>,
    /// The stage that traces on the GPU: the fragment shader of a full-screen triangle (the paper's
    /// route), or a compute kernel. The images are the same.
    #[arg(long, value_parser = choice::<Pipeline>(), default_value_t)]
    pub pipeline: Pipeline,
    #[arg(long, value_parser = choice::<MemoryMode>(), default_value_t)]
    pub memory: MemoryMode,
    /// How rays find their closest primitive [default: the scene file's `accel`, else threaded]
    #[arg(long, value_parser = choice::<Accel>())]
    pub accel: Option<Accel>,
    /// How the BVH is built: the LBVH, or binned SAH for a still scene (about 50 times slower to
    /// build, some 10 % fewer tests a ray). A moving scene's tree is rebuilt every frame by the LBVH.
    #[arg(long, value_parser = choice::<Builder>(), default_value_t)]
    pub builder: Builder,
    /// What the image shows: color (PNG in sRGB, EXR linear), depth (channel Z of a float EXR, +inf
    /// where nothing is hit), normal (first-hit normals mapped to [0, 1]), cost (a heat map of the
    /// BVH nodes each primary ray tested, with a legend; PNG only).
    #[arg(long, value_parser = choice::<Aov>(), default_value_t)]
    pub aov: Aov,
    /// Exposure in stops: radiance is multiplied by 2^EV before the tone map (and in EXR colour,
    /// which takes no tone map).
    #[arg(long, value_name = "EV", default_value_t = 0.0, value_parser = parse_exposure, allow_hyphen_values = true)]
    pub exposure: f32,
    /// How exposed radiance is brought into [0, 1] for PNG and the window: clipped (none), Khronos
    /// PBR Neutral, or ACES filmic (default neutral for a glTF file, none for other scenes).
    #[arg(long, value_parser = choice::<ToneMap>())]
    pub tonemap: Option<ToneMap>,
    /// With a glTF that has animations: the one that plays, by name or index (default the first).
    #[arg(long, value_name = "NAME|INDEX")]
    pub animation: Option<String>,
    /// For a moving scene (an animated glTF, bounce:N): its time in seconds (with --frames, the
    /// first frame's). Past the end of an animation it holds its last pose, unless --loop.
    #[arg(long, value_name = "SECONDS", allow_hyphen_values = true)]
    pub time: Option<f32>,
    /// With --time and --frames: an animation starts again at its end.
    #[arg(long = "loop")]
    pub looping: bool,
}

impl SceneArgs {
    /// Refuses a builder other than the LBVH where the scene moves frame by frame: its tree is
    /// rebuilt every frame, and by the LBVH.
    pub fn check_builder_for_motion(&self, scene: &Scene) -> anyhow::Result<()> {
        if scene.motion.is_some() && !self.builder.follows_motion() {
            bail!(
                "{}: --builder {} builds a still scene's tree once; this scene moves, and its tree is rebuilt every frame by the LBVH",
                self.spec,
                self.builder
            );
        }
        Ok(())
    }

    /// The motion time `t` seconds asks for: checked, and wrapped where --loop says.
    pub fn scene_time(&self, scene: &Scene, t: f32) -> anyhow::Result<f32> {
        anyhow::ensure!(t.is_finite(), "--time must be a finite number of seconds");
        Ok(match &scene.motion {
            Some(motion) if self.looping => motion.looped(t),
            _ => t,
        })
    }
    /// The scene, with the size and depth the flags give.
    pub fn load(&self) -> anyhow::Result<Scene> {
        let model = ModelOptions {
            as_: self.as_,
            spheres: self.spheres,
            rotate: self.rotate,
            normals: self.normals,
            crease: self.crease,
            animation: self.animation.as_deref().map(ClipChoice::parse),
            floor: self.floor.unwrap_or_default(),
        };
        let mut scene = load_scene(&self.spec, &model)?;
        if scene.motion.is_none() && (self.time.is_some() || self.looping) {
            bail!(
                "{}: --time and --loop apply to moving scenes (an animated glTF, bounce:N)",
                self.spec
            );
        }
        self.set_environment(&mut scene)?;
        let settings = &mut scene.settings;
        settings.integrator = self.integrator.unwrap_or(settings.integrator);
        settings.width = self.width.unwrap_or(settings.width);
        settings.height = self.height.unwrap_or(settings.height);
        settings.max_depth = self.depth.unwrap_or(settings.max_depth);
        settings.accel = self.accel.or(settings.accel);
        settings.background = self.background.unwrap_or(settings.background);
        // Legal but probably not meant: said once, here, rather than per packed frame.
        if scene.spheres.is_empty() && scene.triangles.is_empty() && scene.planes.is_empty() {
            log::warn!(
                "{}: the scene holds nothing to hit: the image is its background",
                self.spec
            );
        } else if scene.lights.is_empty() && scene.environment.is_none() {
            let lit_by = match scene.settings.integrator {
                Integrator::Whitted => "only its ambient term shades it",
                Integrator::Path => "the path integrator sees only its emitters and background",
            };
            log::warn!("{}: the scene has no lights: {lit_by}", self.spec);
        }
        Ok(scene)
    }
}

impl SceneArgs {
    /// The environment `--environment` names (or none), turned and scaled as the flags say.
    fn set_environment(&self, scene: &mut Scene) -> anyhow::Result<()> {
        match self.environment.as_deref() {
            Some("none") => {
                scene.set_environment(None);
            }
            Some(path) => {
                let environment = Environment::load(std::path::Path::new(path))?;
                let halvings = scene.set_environment(Some(environment));
                if halvings > 0 {
                    log::warn!(
                        "{}: textures halved {halvings} times to fit beside the environment",
                        self.spec
                    );
                }
            }
            None => {}
        }
        match &mut scene.environment {
            Some(environment) => {
                environment.rotation_degrees = self.environment_rotation.unwrap_or(environment.rotation_degrees);
                environment.intensity = self.environment_intensity.unwrap_or(environment.intensity);
            }
            None if self.environment_rotation.is_some() || self.environment_intensity.is_some() => bail!(
                "{}: --environment-rotation and --environment-intensity need an environment (--environment FILE)",
                self.spec
            ),
            None => {}
        }
        Ok(())
    }
}

/// A finite number.
fn parse_finite(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(x) if x.is_finite() => Ok(x),
        _ => Err(format!("'{text}' is not a finite number")),
    }
}

/// A finite number, not negative.
fn parse_intensity(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        _ => Err(format!("'{text}' is not an intensity: a finite number, not negative")),
    }
}

/// The most samples per pixel `--spp` takes: far past where an 8-bit image stops changing.
pub const MAX_SPP: u32 = 65_536;

/// Loads a scene the way every subcommand names one; the model options are flags of model files.
pub fn load_scene(spec: &str, model: &ModelOptions) -> anyhow::Result<Scene> {
    if !model.is_default() && !is_model_file(std::path::Path::new(spec)) {
        bail!(
            "scene '{spec}': --as, --spheres, --rotate, --normals, --crease, --animation and --floor apply to model files ({})",
            raypipe::scene::model_extension_list()
        );
    }
    if model.as_ == Some(MeshAs::Triangles) && model.spheres.is_some() {
        bail!("{spec}: --spheres needs --as spheres");
    }
    Ok(Scene::load_with(spec, model)?)
}

/// `R,G,B`, linear radiance: three finite numbers, none negative.
pub fn parse_color(text: &str) -> Result<glam::Vec3, String> {
    parse_three(
        text,
        |c| c >= 0.0,
        "three finite, non-negative numbers, as in 0.05,0.05,0.1",
    )
}

/// `X,Y,Z` in degrees.
pub fn parse_angles(text: &str) -> Result<glam::Vec3, String> {
    parse_three(text, |_| true, "three finite angles in degrees, as in -90,0,0")
}

/// Three comma-separated finite numbers that each pass `allowed`; the error names a field that is
/// no number, or says what was `expected`.
fn parse_three(text: &str, allowed: fn(f32) -> bool, expected: &str) -> Result<glam::Vec3, String> {
    let numbers: Vec<f32> = text
        .split(',')
        .map(|n| n.trim().parse::<f32>().map_err(|_| format!("'{n}' is not a number")))
        .collect::<Result<_, _>>()?;
    match numbers[..] {
        [x, y, z] if numbers.iter().all(|&n| n.is_finite() && allowed(n)) => Ok(glam::Vec3::new(x, y, z)),
        _ => Err(format!("expected {expected}")),
    }
}

/// An exposure in stops: finite, within ±MAX_EXPOSURE.
fn parse_exposure(text: &str) -> Result<f32, String> {
    match text.trim().parse::<f32>() {
        Ok(ev) if ev.is_finite() && ev.abs() <= MAX_EXPOSURE => Ok(ev),
        _ => Err(format!(
            "'{text}' is not an exposure: a number of stops within -{MAX_EXPOSURE} to {MAX_EXPOSURE}"
        )),
    }
}

impl SceneArgs {
    /// What PNG output and the window apply to `scene`'s colour: `--exposure`, and `--tonemap` or
    /// the scene's own tone map.
    pub fn display_transform(&self, scene: &Scene) -> DisplayTransform {
        DisplayTransform {
            exposure: self.exposure,
            tone_map: self.tonemap.unwrap_or(scene.tone_map),
        }
    }
}
