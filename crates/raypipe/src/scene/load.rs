//! Where a scene comes from: a built-in name, a TOML file, or a model file (PLY, OBJ, OFF, glTF)
//! read by its reader and then placed by [`model`](super::model); from a path, or from a file's
//! bytes where there is no file system.

use super::{Scene, builtin, file, gltf, model};
use crate::error::InputError;
use crate::mesh;
use model::ModelOptions;
use std::path::Path;

impl Scene {
    /// Loads a scene by built-in name (`whitted`, `random:100:7`, ...), from a TOML file, from a
    /// model file (`.ply`, `.obj`, `.off`) with a camera that frames it, or from a glTF
    /// (`.gltf`, `.glb`) with its own camera and lights where it has them.
    pub fn load(spec: &str) -> Result<Scene, InputError> {
        Self::load_with(spec, &ModelOptions::default())
    }

    /// [`Scene::load`], with the options that apply to a model file; `options` must be the default
    /// for anything else.
    pub fn load_with(spec: &str, options: &ModelOptions) -> Result<Scene, InputError> {
        let path = Path::new(spec);
        if is_model_file(path) {
            return model_scene(path, options);
        }
        if !options.is_default() {
            return Err(not_a_model().in_origin(spec));
        }
        if let Some(scene) = builtin::by_name(spec)? {
            return Ok(scene);
        }
        match path.extension() {
            Some(ext) if ext == "toml" => return file::load(path),
            None if path.exists() => return file::load(path),
            Some(_) if path.exists() => {
                return Err(InputError::new(format!(
                    "unknown model format (expected a .toml scene, or a model ending in {})",
                    model_extension_list()
                ))
                .in_origin(spec));
            }
            _ => {}
        }
        Err(InputError::new(format!(
            "unknown scene '{spec}': not a file, and not a built-in ({})",
            builtin::NAMES.join(", ")
        )))
    }

    /// A scene from a file's contents rather than its path, for hosts without a file system (a web
    /// page given a file): a TOML scene, a model (`.ply`, `.obj`, `.off`) framed as
    /// [`Scene::load`] frames it, or a glTF (a `.glb`, or a `.gltf` whose buffers and images are
    /// `data:` URIs: there is no folder to read others from). `name` is the file's name: its
    /// extension picks the format, and every error starts with it. A TOML scene's `[[mesh]]` files
    /// are read relative to the working directory, where there is one.
    pub fn from_bytes(name: &str, bytes: &[u8]) -> Result<Scene, InputError> {
        Self::from_bytes_with(name, bytes, &ModelOptions::default())
    }

    /// [`Scene::from_bytes`], with the options that apply to a model file; `options` must be the
    /// default for a TOML scene.
    pub fn from_bytes_with(name: &str, bytes: &[u8], options: &ModelOptions) -> Result<Scene, InputError> {
        let path = Path::new(name);
        if gltf::is_gltf_path(path) {
            let mut notices = Vec::new();
            let file = gltf::parse(bytes, gltf::Files::None, &mut notices).map_err(|e| e.in_origin(name))?;
            log_notices(name, notices);
            return model::gltf_scene(&file, name, options);
        }
        if let Some(format) = mesh::MeshFormat::from_path(path) {
            let mut notices = Vec::new();
            let mesh = mesh::parse(bytes, format, &mut notices).map_err(|e| e.in_origin(name))?;
            log_notices(name, notices);
            return model::scene_around(mesh, name, options);
        }
        if !path.extension().is_some_and(|ext| ext.eq_ignore_ascii_case("toml")) {
            return Err(InputError::new(format!(
                "unknown file type (expected a .toml scene, or a model ending in {})",
                model_extension_list()
            ))
            .in_origin(name));
        }
        if !options.is_default() {
            return Err(not_a_model().in_origin(name));
        }
        if bytes.len() as u64 > crate::input::MAX_SCENE_BYTES {
            return Err(InputError::new(format!(
                "cannot read scene file: {} bytes, more than the {} read",
                bytes.len(),
                crate::input::MAX_SCENE_BYTES
            ))
            .in_origin(name));
        }
        let text = std::str::from_utf8(bytes)
            .map_err(|_| InputError::new("cannot read scene file: it is not UTF-8 text").in_origin(name))?;
        file::parse(text).map_err(|e| e.in_origin(name))
    }
}

/// The scene for `raypipe render MODEL`: the file read by its reader, then framed by
/// [`model::scene_around`] (a mesh) or [`model::gltf_scene`] (a glTF, with its own camera and
/// lights where it has them).
fn model_scene(path: &Path, options: &ModelOptions) -> Result<Scene, InputError> {
    let shown = path.display().to_string();
    options.placement().map_err(|e| e.in_origin(&shown))?;
    if gltf::is_gltf_path(path) {
        return model::gltf_scene(&gltf::load(path)?, &shown, options);
    }
    model::scene_around(mesh::load(path)?, &shown, options)
}

/// Model options given for a scene that is not a model file.
fn not_a_model() -> InputError {
    InputError::new(format!(
        "placement, sphere count, rotation and floor apply to model files ({}) only",
        model_extension_list()
    ))
}

fn log_notices(name: &str, notices: Vec<String>) {
    for notice in notices {
        log::info!("{name}: {notice}");
    }
}

/// Whether `path` names a model file by its extension: a mesh (.ply, .obj, .off) or a glTF.
pub fn is_model_file(path: &Path) -> bool {
    mesh::is_model_path(path) || gltf::is_gltf_path(path)
}

/// The model extensions read, for messages: ".ply, .obj, .off, .gltf, .glb".
pub fn model_extension_list() -> String {
    format!("{}, .gltf, .glb", mesh::MeshFormat::extension_list())
}
