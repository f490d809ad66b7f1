//! The viewer's status: what runs, as the page's readout, the package's `status` event and
//! `window.raypipeStatus` read it. Its one schema is [`Status::fields`]: each field's name in
//! JavaScript and its type in `raypipe.d.ts`, which a test holds to the package's declaration.
//!
//! A status is made every frame (plain numbers and names, no JavaScript) and published when it
//! says something new: at once where a setting, the scene, an error or the samples' completion
//! changes, and at most every [`CLOCK_PERIOD_MS`] where only what moves with every frame does
//! (the frame count, the clock, the rates).

/// How often a status whose only news is the clock's is published, in milliseconds.
pub const CLOCK_PERIOD_MS: f64 = 250.0;

/// What runs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Status {
    pub frames: u32,
    pub backend: &'static str,
    pub adapter: String,
    pub scene: String,
    /// The one-line message shown, if any.
    pub error: Option<String>,
    /// Whether the GPU is lost (until the viewer has drawn again on a new device).
    pub lost: bool,
    /// Whether a tracer is being built.
    pub busy: bool,
    pub width: u32,
    pub height: u32,
    pub primitives: u32,
    pub pipeline: &'static str,
    pub accel: &'static str,
    pub builder: &'static str,
    pub memory: &'static str,
    /// The memory modes the adapter offers.
    pub memories: Vec<&'static str>,
    pub depth: u32,
    pub integrator: &'static str,
    pub aov: &'static str,
    pub exposure: f32,
    pub tonemap: &'static str,
    pub paused: bool,
    pub floor: bool,
    pub environment: Option<String>,
    pub moving: bool,
    pub time: f32,
    pub duration: Option<f32>,
    pub speed: f32,
    /// Samples per pixel in the frame shown, and the number gathered at most.
    pub samples: u32,
    pub spp: u32,
    /// Frames per second and milliseconds per frame, by the wall clock.
    pub fps: f64,
    pub frame_ms: f64,
    pub build_ms: Option<f64>,
    pub first_frame_ms: Option<f64>,
    /// The camera now.
    pub camera: StatusCamera,
}

/// The camera in a status: eye, target and up, and the vertical field of view in degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StatusCamera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    pub fov: f32,
}

impl StatusCamera {
    /// The camera's eye, target, up and field of view.
    pub fn of(camera: &raypipe::scene::Camera) -> Self {
        Self {
            eye: camera.eye.to_array(),
            target: camera.target.to_array(),
            up: camera.up.to_array(),
            fov: camera.fov_degrees,
        }
    }

    /// As JavaScript reads it: `{ eye, target, up, fov }` (`ViewerCamera` in raypipe.d.ts).
    pub fn value(&self) -> Value<'static> {
        let numbers = |v: [f32; 3]| Value::Numbers(v.map(f64::from).to_vec());
        Value::Record(vec![
            ("eye", numbers(self.eye)),
            ("target", numbers(self.target)),
            ("up", numbers(self.up)),
            ("fov", Value::Number(self.fov.into())),
        ])
    }
}

/// A field's value, as JavaScript receives it.
#[derive(Clone, Debug, PartialEq)]
pub enum Value<'a> {
    Number(f64),
    Text(&'a str),
    Flag(bool),
    Texts(&'a [&'static str]),
    Numbers(Vec<f64>),
    /// An object of named values.
    Record(Vec<(&'static str, Value<'a>)>),
    Null,
}

/// One field of the schema: its name in JavaScript, its type as `raypipe.d.ts` declares it, and
/// its value.
#[derive(Clone, Debug, PartialEq)]
pub struct Field<'a> {
    pub name: &'static str,
    pub declared: &'static str,
    pub value: Value<'a>,
}

impl Status {
    /// Every field, in the declaration's order.
    pub fn fields(&self) -> Vec<Field<'_>> {
        use Value::{Flag, Number, Text, Texts};
        let optional = |n: Option<f64>| n.map_or(Value::Null, Number);
        let field = |name, declared, value| Field { name, declared, value };
        vec![
            field("frames", "number", Number(self.frames.into())),
            field("backend", r#""webgpu" | "webgl2""#, Text(self.backend)),
            field("adapter", "string", Text(&self.adapter)),
            field("scene", "string", Text(&self.scene)),
            field(
                "error",
                "string | null",
                self.error.as_deref().map_or(Value::Null, Text),
            ),
            field("lost", "boolean", Flag(self.lost)),
            field("busy", "boolean", Flag(self.busy)),
            field("width", "number", Number(self.width.into())),
            field("height", "number", Number(self.height.into())),
            field("primitives", "number", Number(self.primitives.into())),
            field("pipeline", "Pipeline", Text(self.pipeline)),
            field("accel", "Accel", Text(self.accel)),
            field("builder", "Builder", Text(self.builder)),
            field("memory", "Memory", Text(self.memory)),
            field("memories", "Memory[]", Texts(&self.memories)),
            field("depth", "number", Number(self.depth.into())),
            field("integrator", "Integrator", Text(self.integrator)),
            field("aov", "View", Text(self.aov)),
            field("exposure", "number", Number(self.exposure.into())),
            field("tonemap", "ToneMap", Text(self.tonemap)),
            field("paused", "boolean", Flag(self.paused)),
            field("floor", "boolean", Flag(self.floor)),
            field(
                "environment",
                "string | null",
                self.environment.as_deref().map_or(Value::Null, Text),
            ),
            field("moving", "boolean", Flag(self.moving)),
            field("time", "number", Number(self.time.into())),
            field("duration", "number | null", optional(self.duration.map(f64::from))),
            field("speed", "number", Number(self.speed.into())),
            field("samples", "number", Number(self.samples.into())),
            field("spp", "number", Number(self.spp.into())),
            field("fps", "number", Number(self.fps)),
            field("frameMs", "number", Number(self.frame_ms)),
            field("buildMs", "number | null", optional(self.build_ms)),
            field("firstFrameMs", "number | null", optional(self.first_frame_ms)),
            field("camera", "ViewerCamera", self.camera.value()),
        ]
    }

    /// Whether the frame shown has all its samples.
    pub fn done(&self) -> bool {
        self.samples >= self.spp
    }

    /// The status without what moves with every frame: the frame count, the clock, the samples
    /// (but for whether they are all in), the rates and the CPU's build time.
    fn settings(&self) -> Status {
        Status {
            frames: 0,
            time: 0.0,
            samples: self.done().into(),
            fps: 0.0,
            frame_ms: 0.0,
            build_ms: None,
            // A camera that moves every frame (a drag, auto-rotate) publishes with the clock.
            camera: StatusCamera::default(),
            ..self.clone()
        }
    }

    /// Whether a page that published `shown` `since_ms` milliseconds ago publishes this status:
    /// at once where more than the clock changed, and after [`CLOCK_PERIOD_MS`] where the clock
    /// alone did.
    pub fn publishes_over(&self, shown: Option<&Status>, since_ms: f64) -> bool {
        match shown {
            None => true,
            Some(shown) if self.settings() != shown.settings() => true,
            Some(shown) => self != shown && since_ms >= CLOCK_PERIOD_MS,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn web_file(name: &str) -> String {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../web").join(name);
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    }

    /// `raypipe.d.ts`'s `ViewerStatus`: each field's name and type, in order, comments left out.
    fn declared_fields() -> Vec<(String, String)> {
        let declaration = web_file("package/raypipe.d.ts");
        let start = declaration
            .find("export interface ViewerStatus {")
            .expect("raypipe.d.ts declares ViewerStatus");
        let body = &declaration[start..];
        let body = &body[body.find('{').unwrap() + 1..body.find("\n}").unwrap()];
        body.lines()
            .map(str::trim)
            .filter(|line| !line.is_empty() && !line.starts_with("/*") && !line.starts_with('*'))
            .map(|line| {
                let (name, declared) = line.split_once(':').unwrap_or_else(|| panic!("a field: {line}"));
                (
                    name.trim().to_string(),
                    declared.trim().trim_end_matches(';').to_string(),
                )
            })
            .collect()
    }

    #[test]
    fn the_schema_is_the_packages_declaration() {
        let schema: Vec<(String, String)> = Status::default()
            .fields()
            .iter()
            .map(|f| (f.name.to_string(), f.declared.to_string()))
            .collect();
        assert_eq!(schema, declared_fields());
    }

    /// The page's script reads only fields the status has (its comments left out).
    #[test]
    fn the_page_reads_fields_the_status_has() {
        let script: String = web_file("main.js")
            .lines()
            .filter(|line| !line.trim_start().starts_with("//"))
            .collect::<Vec<_>>()
            .join("\n");
        let names: Vec<&str> = Status::default().fields().iter().map(|f| f.name).collect();
        let mut read = 0;
        for (at, _) in script.match_indices("status.") {
            let rest = &script[at + "status.".len()..];
            let name: String = rest.chars().take_while(|c| c.is_ascii_alphanumeric()).collect();
            assert!(names.contains(&name.as_str()), "main.js reads status.{name}");
            read += 1;
        }
        assert!(read > 10, "main.js reads the status ({read} reads found)");
    }

    #[test]
    fn only_news_beyond_the_clock_publishes_at_once() {
        let shown = Status {
            frames: 10,
            samples: 2,
            spp: 4,
            fps: 30.0,
            ..Status::default()
        };
        assert!(shown.publishes_over(None, 0.0));
        let later = Status {
            frames: 11,
            samples: 3,
            fps: 31.0,
            time: 0.5,
            ..shown.clone()
        };
        assert!(!later.publishes_over(Some(&shown), 10.0), "the clock alone, soon after");
        assert!(
            later.publishes_over(Some(&shown), CLOCK_PERIOD_MS),
            "the clock alone, a period after"
        );
        assert!(!shown.publishes_over(Some(&shown), 1e9), "nothing new");
        let done = Status {
            samples: 4,
            ..later.clone()
        };
        assert!(done.publishes_over(Some(&shown), 0.0), "the samples all in");
        let busy = Status {
            busy: true,
            ..later.clone()
        };
        assert!(busy.publishes_over(Some(&shown), 0.0), "a tracer being built");
        let turned = Status {
            camera: StatusCamera {
                eye: [1.0, 2.0, 3.0],
                ..shown.camera
            },
            ..shown.clone()
        };
        assert!(
            !turned.publishes_over(Some(&shown), 10.0),
            "a camera that moves every frame, soon after"
        );
        assert!(
            turned.publishes_over(Some(&shown), CLOCK_PERIOD_MS),
            "the camera, a period after"
        );
        let failed = Status {
            error: Some("a line".into()),
            ..later
        };
        assert!(failed.publishes_over(Some(&shown), 0.0), "an error");
    }
}
