//! The page's settings by name: what the URL's query sets at the start (`?scene=whitted&accel=stack`)
//! and what the page's controls change later, through the same parser. Plain Rust, so that it is
//! tested natively.

use raypipe::Choice;
use raypipe::choice::impl_choice;
use raypipe::image::tonemap::{DisplayTransform, MAX_EXPOSURE};
use raypipe::modes::Aov;
use raypipe::modes::{Accel, Builder, Integrator, MemoryMode, Pipeline};
use raypipe::scene::MAX_DEPTH_LIMIT;
use raypipe::scene::ToneMap;
use raypipe::scene::environment::ENVIRONMENT_EXTENSIONS;
use raypipe::scene::model::Floor;

/// The browser API the page traces through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WebBackend {
    WebGpu,
    WebGl2,
}

impl_choice!(
    WebBackend,
    [
        (
            WebGpu,
            "webgpu",
            "WebGPU: storage or texture memory, compute; from storage the BVH rebuilt in compute passes"
        ),
        (
            WebGl2,
            "webgl2",
            "WebGL2: texture or uniform memory, the BVH rebuilt on the CPU in wasm"
        ),
    ]
);

/// The largest canvas side the page asks for; the adapter's texture limit may allow less.
pub const MAX_SIDE: u32 = 8192;
/// The most samples per pixel a still frame gathers.
pub const MAX_SPP: u32 = 4096;
/// The latest start time the page takes, in seconds (a day: far past any clip).
pub const MAX_TIME: f32 = 86_400.0;
/// The fastest playback, in scene seconds per second.
pub const MAX_SPEED: f32 = 16.0;

/// A change the page's controls or its URL ask for. `None` in a mode means "the backend's default"
/// until one is asked for.
#[derive(Clone, Debug, PartialEq)]
pub enum Setting {
    Scene(String),
    /// A model or scene file to fetch, by a URL relative to the page (the page's script fetches it).
    Model(String),
    /// An environment (.hdr, .exr) to fetch, by a URL relative to the page, before the model.
    Environment(String),
    Accel(Accel),
    Builder(Builder),
    Memory(MemoryMode),
    Pipeline(Pipeline),
    Depth(u32),
    Integrator(Integrator),
    View(Aov),
    Paused(bool),
    /// What a model file opened on the page stands on.
    Floor(Floor),
    /// Seconds into the motion.
    Time(f32),
    /// Scene seconds per second.
    Speed(f32),
    Spp(u32),
    /// Stops: radiance times 2^EV before the tone map.
    Exposure(f32),
    ToneMap(ToneMap),
    Width(u32),
    Height(u32),
    /// `None`: WebGPU where the browser has it, else WebGL2 (`auto`).
    Backend(Option<WebBackend>),
}

/// The keys, for messages.
pub const KEYS: &[&str] = &[
    "scene",
    "model",
    "environment",
    "accel",
    "builder",
    "memory",
    "pipeline",
    "depth",
    "integrator",
    "aov",
    "paused",
    "floor",
    "time",
    "speed",
    "spp",
    "exposure",
    "tonemap",
    "width",
    "height",
    "backend",
];

impl Setting {
    /// Parses `key=value`; the error is one line naming both.
    pub fn parse(key: &str, value: &str) -> Result<Setting, String> {
        fn choice<T: Choice>(key: &str, value: &str) -> Result<T, String> {
            T::from_name(value).ok_or_else(|| format!("{key}={value}: expected one of {}", T::names()))
        }
        let number = |range: std::ops::RangeInclusive<u32>| -> Result<u32, String> {
            match value.parse::<u32>() {
                Ok(n) if range.contains(&n) => Ok(n),
                _ => Err(format!(
                    "{key}={value}: expected a whole number in {}..={}",
                    range.start(),
                    range.end()
                )),
            }
        };
        let seconds = |most: f32| -> Result<f32, String> {
            match value.parse::<f32>() {
                Ok(x) if (0.0..=most).contains(&x) => Ok(x),
                _ => Err(format!("{key}={value}: expected a number of seconds in 0..={most}")),
            }
        };
        let flag = || match value {
            "true" | "1" => Ok(true),
            "false" | "0" => Ok(false),
            _ => Err(format!("{key}={value}: expected true or false")),
        };
        Ok(match key {
            "scene" if value.is_empty() => return Err("scene=: name a scene".into()),
            "scene" => Setting::Scene(value.to_string()),
            "model" if value.is_empty() => return Err("model=: give a file's URL".into()),
            "model" => Setting::Model(value.to_string()),
            "environment" if value.is_empty() => return Err("environment=: give a file's URL".into()),
            "environment" => Setting::Environment(value.to_string()),
            "accel" => {
                let accels = page_accels();
                let names = accels.iter().map(|a| a.name()).collect::<Vec<_>>().join(", ");
                match Accel::from_name(value) {
                    Some(accel) if accels.contains(&accel) => Setting::Accel(accel),
                    Some(_) => {
                        return Err(format!(
                            "{key}={value}: no browser offers ray queries yet; expected one of {names}"
                        ));
                    }
                    None => return Err(format!("{key}={value}: expected one of {names}")),
                }
            }
            "builder" => Setting::Builder(choice(key, value)?),
            "memory" => Setting::Memory(choice(key, value)?),
            "pipeline" => Setting::Pipeline(choice(key, value)?),
            "depth" => Setting::Depth(number(0..=MAX_DEPTH_LIMIT)?),
            "integrator" => Setting::Integrator(choice(key, value)?),
            "aov" => Setting::View(choice(key, value)?),
            "paused" => Setting::Paused(flag()?),
            "floor" => Setting::Floor(if flag()? { Floor::Checker } else { Floor::None }),
            "time" => Setting::Time(seconds(MAX_TIME)?),
            "speed" => Setting::Speed(seconds(MAX_SPEED)?),
            "spp" => Setting::Spp(number(1..=MAX_SPP)?),
            "exposure" => match value.parse::<f32>() {
                Ok(ev) if ev.is_finite() && ev.abs() <= MAX_EXPOSURE => Setting::Exposure(ev),
                _ => {
                    return Err(format!(
                        "{key}={value}: expected a number of stops in -{MAX_EXPOSURE}..={MAX_EXPOSURE}"
                    ));
                }
            },
            "tonemap" => Setting::ToneMap(choice(key, value)?),
            "width" => Setting::Width(number(1..=MAX_SIDE)?),
            "height" => Setting::Height(number(1..=MAX_SIDE)?),
            "backend" if value == "auto" => Setting::Backend(None),
            "backend" => match WebBackend::from_name(value) {
                Some(backend) => Setting::Backend(Some(backend)),
                None => return Err(format!("{key}={value}: expected auto, {}", WebBackend::names())),
            },
            _ => return Err(format!("unknown setting '{key}' (known: {})", KEYS.join(", "))),
        })
    }
}

/// What the page starts with.
#[derive(Clone, Debug, PartialEq)]
pub struct StartParams {
    pub scene: String,
    /// A file to fetch and open once the page runs, by a URL relative to the page.
    pub model: Option<String>,
    /// An environment to fetch and light every scene with, by a URL relative to the page.
    pub environment: Option<String>,
    /// `None`: the adapter's default (`GpuContext::default_accel`: the stack walk on a software
    /// adapter, the threaded walk on others).
    pub accel: Option<Accel>,
    /// How a still scene's BVH is built.
    pub builder: Builder,
    /// `None`: the adapter's default (`GpuContext::default_memory`: texture on WebGL2 and on a
    /// browser's software fallback adapter, storage on other WebGPU adapters).
    pub memory: Option<MemoryMode>,
    pub pipeline: Pipeline,
    /// `None`: the scene's own.
    pub depth: Option<u32>,
    /// `None`: the scene's own (path for a glTF file, Whitted for the paper's scenes).
    pub integrator: Option<Integrator>,
    pub view: Aov,
    pub paused: bool,
    /// What a model file stands on.
    pub floor: Floor,
    /// Where a moving scene's motion starts, in seconds.
    pub time: f32,
    pub speed: f32,
    pub spp: u32,
    /// The colour view's exposure and tone map.
    pub display: DisplayTransform,
    /// Whether `?tonemap=` chose the tone map; if not, each scene opened shows with its own.
    pub tone_map_chosen: bool,
    pub width: u32,
    pub height: u32,
    /// `None`: WebGPU where the browser has it, else WebGL2.
    pub backend: Option<WebBackend>,
}

impl Default for StartParams {
    fn default() -> Self {
        Self {
            scene: "whitted".into(),
            model: None,
            environment: None,
            accel: None,
            builder: Builder::Lbvh,
            memory: None,
            pipeline: Pipeline::Fragment,
            depth: None,
            integrator: None,
            view: Aov::Color,
            paused: false,
            floor: Floor::Checker,
            time: 0.0,
            speed: 1.0,
            spp: 64,
            display: DisplayTransform::IDENTITY,
            tone_map_chosen: false,
            width: 960,
            height: 540,
            backend: None,
        }
    }
}

impl StartParams {
    /// The settings of a URL query's pairs (already percent-decoded). A bad pair is skipped and its
    /// error returned beside the rest, so that the page starts and shows what it ignored.
    pub fn from_pairs<'a>(pairs: impl IntoIterator<Item = (&'a str, &'a str)>) -> (Self, Vec<String>) {
        let mut params = Self::default();
        let mut errors = Vec::new();
        for (key, value) in pairs {
            match Setting::parse(key, value) {
                Ok(setting) => params.apply(setting),
                Err(why) => errors.push(why),
            }
        }
        (params, errors)
    }

    fn apply(&mut self, setting: Setting) {
        match setting {
            Setting::Scene(name) => self.scene = name,
            Setting::Model(url) => self.model = Some(url),
            Setting::Environment(url) => self.environment = Some(url),
            Setting::Accel(accel) => self.accel = Some(accel),
            Setting::Builder(builder) => self.builder = builder,
            Setting::Memory(memory) => self.memory = Some(memory),
            Setting::Pipeline(pipeline) => self.pipeline = pipeline,
            Setting::Depth(depth) => self.depth = Some(depth),
            Setting::Integrator(integrator) => self.integrator = Some(integrator),
            Setting::View(view) => self.view = view,
            Setting::Paused(paused) => self.paused = paused,
            Setting::Floor(floor) => self.floor = floor,
            Setting::Time(time) => self.time = time,
            Setting::Speed(speed) => self.speed = speed,
            Setting::Spp(spp) => self.spp = spp,
            Setting::Exposure(ev) => self.display.exposure = ev,
            Setting::ToneMap(tone_map) => {
                self.display.tone_map = tone_map;
                self.tone_map_chosen = true;
            }
            Setting::Width(width) => self.width = width,
            Setting::Height(height) => self.height = height,
            Setting::Backend(backend) => self.backend = backend,
        }
    }
}

/// The page's select lists, by the setting each one sets: every name its `Choice` has that a browser can
/// trace with. The page's script fills its controls from these (through the wasm module), so the HTML holds no copy.
pub fn control_choices() -> Vec<(&'static str, Vec<&'static str>)> {
    fn names<T: Choice + 'static>() -> Vec<&'static str> {
        T::ALL.iter().map(|c| c.name()).collect()
    }
    vec![
        ("accel", page_accels().iter().map(|a| a.name()).collect()),
        ("builder", names::<Builder>()),
        ("memory", names::<MemoryMode>()),
        ("pipeline", names::<Pipeline>()),
        ("aov", names::<Aov>()),
        ("tonemap", names::<ToneMap>()),
        ("integrator", names::<Integrator>()),
    ]
}

/// The acceleration modes the page offers: all but ray queries, which no browser has yet.
pub fn page_accels() -> Vec<Accel> {
    Accel::ALL.iter().copied().filter(|a| !a.needs_ray_queries()).collect()
}

/// What the page's file input takes: every model, scene and environment format the library reads.
pub fn file_accept() -> String {
    let models = raypipe::scene::model_extension_list().replace(' ', "");
    let environments: Vec<String> = ENVIRONMENT_EXTENSIONS.iter().map(|e| format!(".{e}")).collect();
    format!("{models},.toml,{}", environments.join(","))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_issue_example_sets_every_named_field() {
        let query = [
            ("scene", "random:2000"),
            ("accel", "threaded"),
            ("builder", "sah"),
            ("memory", "texture"),
            ("width", "320"),
            ("height", "240"),
            ("backend", "webgl2"),
            ("depth", "3"),
            ("integrator", "path"),
            ("aov", "normal"),
            ("spp", "1"),
            ("model", "models/bunny.ply"),
            ("environment", "sky.hdr"),
            ("time", "1.5"),
            ("speed", "0.5"),
            ("floor", "0"),
            ("exposure", "-1.5"),
            ("tonemap", "neutral"),
        ];
        let (params, errors) = StartParams::from_pairs(query);
        assert!(errors.is_empty(), "{errors:?}");
        assert_eq!(
            params,
            StartParams {
                scene: "random:2000".into(),
                model: Some("models/bunny.ply".into()),
                environment: Some("sky.hdr".into()),
                accel: Some(Accel::Threaded),
                builder: Builder::Sah,
                memory: Some(MemoryMode::Texture),
                pipeline: Pipeline::Fragment,
                depth: Some(3),
                integrator: Some(Integrator::Path),
                view: Aov::Normal,
                paused: false,
                floor: Floor::None,
                time: 1.5,
                speed: 0.5,
                spp: 1,
                display: DisplayTransform {
                    exposure: -1.5,
                    tone_map: ToneMap::Neutral,
                },
                tone_map_chosen: true,
                width: 320,
                height: 240,
                backend: Some(WebBackend::WebGl2),
            }
        );
    }

    #[test]
    fn bad_pairs_are_reported_one_line_each_and_the_rest_applies() {
        let query = [
            ("accel", "bvh"),
            ("width", "0"),
            ("depth", "33"),
            ("colour", "red"),
            ("height", "200"),
            ("time", "NaN"),
            ("exposure", "inf"),
            ("tonemap", "filmic"),
        ];
        let (params, errors) = StartParams::from_pairs(query);
        assert_eq!(params.height, 200);
        assert_eq!(params.width, StartParams::default().width);
        // A bad walk leaves the adapter's default.
        assert_eq!(params.accel, None);
        assert_eq!(
            errors,
            [
                "accel=bvh: expected one of brute, stack, stackless, threaded, wide",
                "width=0: expected a whole number in 1..=8192",
                "depth=33: expected a whole number in 0..=32",
                "unknown setting 'colour' (known: scene, model, environment, accel, builder, memory, pipeline, depth, integrator, aov, paused, floor, time, speed, spp, exposure, tonemap, width, height, backend)",
                "time=NaN: expected a number of seconds in 0..=86400",
                "exposure=inf: expected a number of stops in -64..=64",
                "tonemap=filmic: expected one of none, neutral, aces",
            ]
        );
    }

    #[test]
    fn every_listed_control_value_parses() {
        let lists = control_choices();
        assert_eq!(lists.len(), 7);
        for (key, names) in lists {
            assert!(names.len() >= 2, "{key}: {names:?}");
            for name in names {
                assert!(Setting::parse(key, name).is_ok(), "{key}={name}");
            }
        }
        assert_eq!(file_accept(), ".ply,.obj,.off,.gltf,.glb,.toml,.hdr,.exr");
    }

    #[test]
    fn every_mode_name_parses_back() {
        for accel in page_accels() {
            assert_eq!(Setting::parse("accel", accel.name()), Ok(Setting::Accel(accel)));
        }
        assert_eq!(
            Setting::parse("accel", "rayquery"),
            Err(
                "accel=rayquery: no browser offers ray queries yet; expected one of brute, stack, stackless, threaded, wide"
                    .into()
            )
        );
        for &builder in Builder::ALL {
            assert_eq!(Setting::parse("builder", builder.name()), Ok(Setting::Builder(builder)));
        }
        for &memory in MemoryMode::ALL {
            assert_eq!(Setting::parse("memory", memory.name()), Ok(Setting::Memory(memory)));
        }
        for &view in Aov::ALL {
            assert_eq!(Setting::parse("aov", view.name()), Ok(Setting::View(view)));
        }
        for &backend in WebBackend::ALL {
            assert_eq!(
                Setting::parse("backend", backend.name()),
                Ok(Setting::Backend(Some(backend)))
            );
        }
        assert_eq!(Setting::parse("backend", "auto"), Ok(Setting::Backend(None)));
        assert!(Setting::parse("backend", "webgl").is_err());
        assert_eq!(Setting::parse("paused", "true"), Ok(Setting::Paused(true)));
        assert!(Setting::parse("paused", "yes").is_err());
        assert!(Setting::parse("scene", "").is_err());
        assert!(Setting::parse("model", "").is_err());
    }
}
