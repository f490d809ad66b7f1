//! The library's errors. They are typed and carry where the fault lies (a file or a built-in scene's
//! name, a line, an element), so that each caller words its own message: the command line prints one
//! line and adds its flag hints, a viewer shows a banner and keeps its previous scene.

use crate::modes::Accel;
use std::fmt;

/// The part of a scene an error is about.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Element {
    /// The scene's camera.
    Camera,
    /// The render settings (size, depth, background).
    Render,
    /// The scene as a whole (its record counts, say).
    Scene,
    /// A sphere, by index.
    Sphere(usize),
    /// A triangle, by index.
    Triangle(usize),
    /// A plane, by index.
    Plane(usize),
    /// A light, by index.
    Light(usize),
    /// A material, by index.
    Material(usize),
    /// A material of a scene file, by its name there.
    NamedMaterial(String),
    /// A `[[mesh]]` table of a scene file.
    MeshTable(usize),
    /// A texture, by index.
    Texture(usize),
    /// A part of a glTF file, from the outermost in (`node 2: mesh 0 primitive 1: accessor 7`).
    Gltf(Vec<GltfPart>),
}

/// A part of a glTF file, by its index in the file's arrays, or by name (an attribute, an
/// extension, a sparse accessor's indices).
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GltfPart {
    /// An accessor, by index.
    Accessor(usize),
    /// An animation, by index.
    Animation(usize),
    /// A buffer, by index.
    Buffer(usize),
    /// A buffer view, by index.
    BufferView(usize),
    /// A camera, by index.
    Camera(usize),
    /// An animation's channel.
    Channel(usize),
    /// An image, by index.
    Image(usize),
    /// An instance of `EXT_mesh_gpu_instancing`.
    Instance(usize),
    /// A `KHR_lights_punctual` light, by index.
    Light(usize),
    /// A material, by index.
    Material(usize),
    /// A mesh, by index.
    Mesh(usize),
    /// A primitive's morph target, by index.
    MorphTarget(usize),
    /// A node, by index.
    Node(usize),
    /// A mesh's primitive (written after its mesh: `mesh 0 primitive 1`).
    Primitive(usize),
    /// A scene of the file, by index.
    Scene(usize),
    /// A skin, by index.
    Skin(usize),
    /// A part by name: an attribute (`TRANSLATION`), an extension, a sparse accessor's indices.
    Named(String),
}

impl fmt::Display for GltfPart {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (kind, index) = match self {
            GltfPart::Accessor(i) => ("accessor", i),
            GltfPart::Animation(i) => ("animation", i),
            GltfPart::Buffer(i) => ("buffer", i),
            GltfPart::BufferView(i) => ("buffer view", i),
            GltfPart::Camera(i) => ("camera", i),
            GltfPart::Channel(i) => ("channel", i),
            GltfPart::Image(i) => ("image", i),
            GltfPart::Instance(i) => ("instance", i),
            GltfPart::Light(i) => ("light", i),
            GltfPart::Material(i) => ("material", i),
            GltfPart::Mesh(i) => ("mesh", i),
            GltfPart::MorphTarget(i) => ("morph target", i),
            GltfPart::Node(i) => ("node", i),
            GltfPart::Primitive(i) => ("primitive", i),
            GltfPart::Scene(i) => ("scene", i),
            GltfPart::Skin(i) => ("skin", i),
            GltfPart::Named(name) => return f.write_str(name),
        };
        write!(f, "{kind} {index}")
    }
}

impl fmt::Display for Element {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Element::Camera => f.write_str("camera"),
            Element::Render => f.write_str("render"),
            Element::Scene => f.write_str("scene"),
            Element::Sphere(i) => write!(f, "sphere {i}"),
            Element::Triangle(i) => write!(f, "triangle {i}"),
            Element::Plane(i) => write!(f, "plane {i}"),
            Element::Light(i) => write!(f, "light {i}"),
            Element::Material(i) => write!(f, "material {i}"),
            Element::NamedMaterial(name) => write!(f, "material '{name}'"),
            Element::MeshTable(i) => write!(f, "mesh {i}"),
            Element::Texture(i) => write!(f, "texture {i}"),
            Element::Gltf(path) => {
                for (k, part) in path.iter().enumerate() {
                    match (k, part) {
                        (0, _) => {}
                        (_, GltfPart::Primitive(_)) if matches!(path[k - 1], GltfPart::Mesh(_)) => f.write_str(" ")?,
                        _ => f.write_str(": ")?,
                    }
                    write!(f, "{part}")?;
                }
                Ok(())
            }
        }
    }
}

/// Input that is malformed or breaks an invariant the tracers rely on: a scene file, a model file,
/// a built-in scene's parameters, or a scene built in code. Displayed as one line,
/// `ORIGIN:LINE: ELEMENT: message` with the parts that are known.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub struct InputError {
    /// The file the input came from, or the built-in scene's name, once known.
    pub origin: Option<String>,
    /// The line, where the input is text.
    pub line: Option<usize>,
    /// The element of the input (a glTF mesh, a TOML table), where known.
    pub element: Option<Element>,
    /// What is wrong, on one line.
    pub message: String,
}

impl InputError {
    /// An error whose place is not known yet (callers add it as it travels up).
    pub fn new(message: impl Into<String>) -> Self {
        Self {
            origin: None,
            line: None,
            element: None,
            message: one_line(&message.into()),
        }
    }

    /// An error at `line` (1-based) of a text format.
    pub fn at(line: usize, message: impl Into<String>) -> Self {
        Self::new(message).with_line(Some(line))
    }

    /// An error about `element`.
    pub fn of(element: Element, message: impl Into<String>) -> Self {
        Self {
            element: Some(element),
            ..Self::new(message)
        }
    }

    /// An error about a part of a glTF file.
    pub fn in_gltf(part: GltfPart, message: impl Into<String>) -> Self {
        Self::of(Element::Gltf(vec![part]), message)
    }

    /// The error as it reads from the glTF part that holds where it lies: `part` goes before the
    /// parts named already (an element of another kind becomes part of the message).
    pub fn within(mut self, part: GltfPart) -> Self {
        match &mut self.element {
            Some(Element::Gltf(path)) => path.insert(0, part),
            Some(other) => {
                self.message = format!("{other}: {}", self.message);
                self.element = Some(Element::Gltf(vec![part]));
            }
            None => self.element = Some(Element::Gltf(vec![part])),
        }
        self
    }

    /// [`InputError::within`] a part named by `name` (an attribute, an extension).
    pub fn within_named(self, name: impl Into<String>) -> Self {
        self.within(GltfPart::Named(name.into()))
    }

    /// Names the line, unless one is named already.
    pub fn with_line(mut self, line: Option<usize>) -> Self {
        self.line = self.line.or(line);
        self
    }

    /// Names the element, unless one is named already.
    pub fn with_element(mut self, element: Element) -> Self {
        self.element.get_or_insert(element);
        self
    }

    /// Names the file (or scene) the error came from, unless a deeper one is named already.
    pub fn in_origin(mut self, origin: impl Into<String>) -> Self {
        if self.origin.is_none() {
            self.origin = Some(origin.into());
        }
        self
    }

    /// The error as it reads inside a message about something else: an error of a model file that
    /// a scene file's mesh table names becomes part of the scene file's error.
    pub fn nested_in(self, origin: Option<String>, line: Option<usize>, element: Element) -> Self {
        Self {
            origin,
            line,
            element: Some(element),
            message: self.to_string(),
        }
    }
}

impl fmt::Display for InputError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.origin, self.line) {
            (Some(origin), Some(line)) => write!(f, "{origin}:{line}: ")?,
            (Some(origin), None) => write!(f, "{origin}: ")?,
            (None, Some(line)) => write!(f, "{line}: ")?,
            (None, None) => {}
        }
        if let Some(element) = &self.element {
            write!(f, "{element}: ")?;
        }
        f.write_str(&self.message)
    }
}

/// A BVH walk was asked for on a scene without its BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("the {accel} walk needs the scene's BVH, which was not built")]
pub struct MissingBvh {
    /// The walk asked for.
    pub accel: Accel,
}

/// Parser and driver messages may span lines; ours are one.
pub fn one_line(text: &str) -> String {
    shortened(&text.split_whitespace().collect::<Vec<_>>().join(" "), MAX_MESSAGE)
}

/// The longest message a line keeps, in characters: a parser that quotes its input must not turn
/// one bad file into a screenful.
pub(crate) const MAX_MESSAGE: usize = 300;

/// Input quoted in a message: control characters escaped, at most 40 characters of it.
pub fn quoted(input: &str) -> String {
    shortened(&input.escape_debug().to_string(), 40)
}

/// `text` cut to `max` characters, with an ellipsis where it was cut.
fn shortened(text: &str, max: usize) -> String {
    match text.char_indices().nth(max) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_string(),
    }
}
