//! Scene files in TOML (format: `docs/scene-format.md`).
//!
//! Every table denies unknown keys, and every error names the file and, where the element has one,
//! its line: `scene.toml:12: sphere 3: radius must be finite and at least 1e-12 (got -1)`.

use super::animation::ClipChoice;
use super::model::{DEFAULT_CREASE_DEGREES, MeshAs, Normals, Placement, SphereCount, add_mesh};
use super::{Camera, Checker, Environment, Light, Material, Plane, RenderSettings, Scene, Sphere, unit_vector};
use crate::choice::Choice;
use crate::error::{Element, InputError};
use crate::modes::{Accel, Integrator};
use glam::Vec3;
use serde::Deserialize;
use std::collections::{BTreeMap, HashMap};
use std::path::Path;
use toml::Spanned;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneDef {
    camera: Option<CameraDef>,
    render: Option<RenderDef>,
    #[serde(default)]
    light: Vec<Spanned<LightDef>>,
    #[serde(default)]
    material: BTreeMap<String, Spanned<MaterialDef>>,
    #[serde(default)]
    sphere: Vec<Spanned<SphereDef>>,
    #[serde(default)]
    plane: Vec<Spanned<PlaneDef>>,
    #[serde(default)]
    mesh: Vec<Spanned<MeshDef>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraDef {
    eye: [f32; 3],
    target: [f32; 3],
    up: Option<[f32; 3]>,
    fov: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RenderDef {
    width: Option<u32>,
    height: Option<u32>,
    max_depth: Option<u32>,
    background: Option<[f32; 3]>,
    ambient: Option<f32>,
    /// An acceleration mode's name (`Accel`'s).
    accel: Option<Spanned<String>>,
    /// An integrator's name (`Integrator`'s).
    integrator: Option<Spanned<String>>,
    /// An equirectangular .hdr or .exr, relative to the scene file.
    environment: Option<Spanned<String>>,
    environment_rotation: Option<Spanned<f32>>,
    environment_intensity: Option<Spanned<f32>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LightDef {
    position: [f32; 3],
    color: Option<[f32; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MaterialDef {
    color: Option<[f32; 3]>,
    specular: Option<f32>,
    shininess: Option<f32>,
    reflect: Option<f32>,
    transmit: Option<f32>,
    ior: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SphereDef {
    center: [f32; 3],
    radius: f32,
    material: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PlaneDef {
    point: [f32; 3],
    normal: [f32; 3],
    material: Option<String>,
    checker_material: Option<String>,
    checker_size: Option<f32>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MeshDef {
    /// Relative to the scene file.
    file: String,
    #[serde(rename = "as")]
    as_: Option<String>,
    spheres: Option<SpheresDef>,
    radius: Option<f32>,
    rotate: Option<[f32; 3]>,
    normalize: Option<bool>,
    scale: Option<f32>,
    translate: Option<[f32; 3]>,
    seed: Option<u64>,
    material: Option<String>,
    normals: Option<String>,
    crease: Option<f32>,
    /// glTF only: the clip that plays, by index or name.
    animation: Option<AnimationDef>,
    /// glTF only: the clip's time, in seconds, at the scene's time 0.
    time: Option<f32>,
}

/// `animation = 2` or `animation = "Walk"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum AnimationDef {
    Index(i64),
    Name(String),
}

/// `spheres = 20000` or `spheres = "vertices"`.
#[derive(Deserialize)]
#[serde(untagged)]
enum SpheresDef {
    Count(i64),
    Word(String),
}

/// The name elements get when they leave `material` out; a file may define it to change it.
const DEFAULT_MATERIAL: &str = "default";

/// Reads and parses a scene file; every error is one line that starts with the path.
pub fn load(path: &Path) -> Result<Scene, InputError> {
    let shown = path.display().to_string();
    let bytes = crate::input::read_regular(path, "scene file", crate::input::MAX_SCENE_BYTES)?;
    let text = String::from_utf8(bytes)
        .map_err(|_| InputError::new("cannot read scene file: it is not UTF-8 text").in_origin(&shown))?;
    let base = path.parent().unwrap_or(Path::new("."));
    parse_in(&text, base).map_err(|e| e.in_origin(shown))
}

/// Parses scene TOML whose mesh files are relative to the working directory.
pub fn parse(text: &str) -> Result<Scene, InputError> {
    parse_in(text, Path::new("."))
}

/// Parses scene TOML whose mesh files are relative to `base`. Errors carry the line and element, not
/// the file, which the caller names.
pub(crate) fn parse_in(text: &str, base: &Path) -> Result<Scene, InputError> {
    let def: SceneDef = toml::from_str(text).map_err(|e| {
        let line = e.span().map(|s| line_of(text, s.start));
        at_line(line, e.message().trim())
    })?;
    build(def, text, base)
}

fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

fn at_line(line: Option<usize>, message: impl std::fmt::Display) -> InputError {
    InputError::new(message.to_string()).with_line(line)
}

fn at_element(line: Option<usize>, element: Element, message: impl std::fmt::Display) -> InputError {
    InputError::of(element, message.to_string()).with_line(line)
}

fn vec3(a: [f32; 3]) -> Vec3 {
    Vec3::from_array(a)
}

/// The camera, the render settings and the lights: what a scene file says outright, with nothing to
/// resolve.
fn set_view(scene: &mut Scene, def: &SceneDef) {
    if let Some(c) = &def.camera {
        scene.camera = Camera {
            eye: vec3(c.eye),
            target: vec3(c.target),
            up: c.up.map_or(Vec3::Y, vec3),
            fov_degrees: c.fov.unwrap_or(40.0),
        };
    }
    if let Some(r) = &def.render {
        let d = RenderSettings::default();
        scene.settings = RenderSettings {
            width: r.width.unwrap_or(d.width),
            height: r.height.unwrap_or(d.height),
            max_depth: r.max_depth.unwrap_or(d.max_depth),
            background: r.background.map_or(d.background, vec3),
            ambient: r.ambient.unwrap_or(d.ambient),
            accel: None,
            integrator: d.integrator,
        };
    }

    for l in &def.light {
        scene.lights.push(Light::constant(
            vec3(l.get_ref().position),
            l.get_ref().color.map_or(Vec3::ONE, vec3),
        ));
    }
}

fn build(def: SceneDef, text: &str, base: &Path) -> Result<Scene, InputError> {
    let line = |span: std::ops::Range<usize>| Some(line_of(text, span.start));
    let mut tables = Tables {
        scene: Scene::default(),
        material_index: HashMap::new(),
    };
    set_view(&mut tables.scene, &def);
    let material_lines = tables.add_materials(&def, &line);
    let sphere_lines = tables.add_spheres(&def, &line)?;
    let plane_lines = tables.add_planes(&def, &line)?;
    tables.add_meshes(&def, base, &line)?;
    // After the meshes, whose textures make room for it.
    if let Some(render) = &def.render {
        set_environment(&mut tables.scene, render, base, &line)?;
        if let Some(accel) = &render.accel {
            let name = accel.get_ref();
            tables.scene.settings.accel = Some(Accel::from_name(name).ok_or_else(|| {
                at_element(
                    line(accel.span()),
                    Element::Render,
                    format!("accel must be one of {} (got \"{name}\")", Accel::names()),
                )
            })?);
        }
        if let Some(integrator) = &render.integrator {
            let name = integrator.get_ref();
            tables.scene.settings.integrator = Integrator::from_name(name).ok_or_else(|| {
                at_element(
                    line(integrator.span()),
                    Element::Render,
                    format!("integrator must be one of {} (got \"{name}\")", Integrator::names()),
                )
            })?;
        }
    }
    let scene = tables.scene;

    // Semantic checks run on the finished scene; the element they name has its line here.
    scene.validate().map_err(|e| {
        let at = match &e.element {
            Some(Element::Sphere(i)) => sphere_lines.get(*i).copied().flatten(),
            Some(Element::Plane(i)) => plane_lines.get(*i).copied().flatten(),
            Some(Element::Light(i)) => def.light.get(*i).and_then(|l| line(l.span())),
            Some(Element::Material(i)) => material_lines.get(*i).and_then(|(_, l)| *l),
            _ => None,
        };
        let element = match &e.element {
            Some(Element::Material(i)) => material_lines
                .get(*i)
                .map(|(name, _)| Element::NamedMaterial(name.to_string())),
            other => other.clone(),
        };
        InputError { element, ..e }.with_line(at)
    })?;
    Ok(scene)
}

/// The `[render]` table's environment, read relative to `base`, turned and scaled as it says.
fn set_environment(scene: &mut Scene, render: &RenderDef, base: &Path, line: LineOf) -> Result<(), InputError> {
    let Some(file) = &render.environment else {
        let mut keys = [&render.environment_rotation, &render.environment_intensity]
            .into_iter()
            .flatten();
        return match keys.next() {
            Some(key) => Err(at_element(
                line(key.span()),
                Element::Render,
                "environment_rotation and environment_intensity need an environment",
            )),
            None => Ok(()),
        };
    };
    let at = line(file.span());
    let mut environment =
        Environment::load(&base.join(file.get_ref())).map_err(|e| e.nested_in(None, at, Element::Render))?;
    if let Some(rotation) = &render.environment_rotation {
        environment.rotation_degrees = *rotation.get_ref();
    }
    if let Some(intensity) = &render.environment_intensity {
        environment.intensity = *intensity.get_ref();
    }
    environment
        .validate()
        .map_err(|e| e.with_element(Element::Render).with_line(at))?;
    scene.set_environment(Some(environment));
    Ok(())
}

/// The line a table starts on, from its span in the file's text.
type LineOf<'t> = &'t dyn Fn(std::ops::Range<usize>) -> Option<usize>;

/// A scene as its file's tables are added, with its materials' indices by name.
struct Tables<'d> {
    scene: Scene,
    material_index: HashMap<&'d str, u32>,
}

impl<'d> Tables<'d> {
    /// The `[material.NAME]` tables; returns each one's name and line.
    fn add_materials(&mut self, def: &'d SceneDef, line: LineOf) -> Vec<(&'d str, Option<usize>)> {
        let mut lines = Vec::new();
        for (name, m) in &def.material {
            let d = Material::default();
            let r = m.get_ref();
            self.material_index
                .insert(name.as_str(), self.scene.materials.len() as u32);
            lines.push((name.as_str(), line(m.span())));
            self.scene.materials.push(Material {
                color: r.color.map_or(d.color, vec3),
                specular: r.specular.unwrap_or(d.specular),
                shininess: r.shininess.unwrap_or(d.shininess),
                reflect: r.reflect.unwrap_or(d.reflect),
                transmit: r.transmit.unwrap_or(d.transmit),
                ior: r.ior.unwrap_or(d.ior),
                ..d
            });
        }
        lines
    }

    /// Resolves a material name; an element without one gets the default material, added on
    /// first use.
    fn resolve(&mut self, name: &Option<String>, element: &Element, at: Option<usize>) -> Result<u32, InputError> {
        let name = name.as_deref().unwrap_or(DEFAULT_MATERIAL);
        if let Some(&index) = self.material_index.get(name) {
            return Ok(index);
        }
        if name == DEFAULT_MATERIAL {
            let index = self.scene.materials.len() as u32;
            self.scene.materials.push(Material::default());
            self.material_index.insert(DEFAULT_MATERIAL, index);
            return Ok(index);
        }
        Err(at_element(at, element.clone(), format!("unknown material '{name}'")))
    }

    /// The `[[sphere]]` tables; returns each one's line.
    fn add_spheres(&mut self, def: &SceneDef, line: LineOf) -> Result<Vec<Option<usize>>, InputError> {
        let mut lines = Vec::new();
        for (i, s) in def.sphere.iter().enumerate() {
            let at = line(s.span());
            let r = s.get_ref();
            let material = self.resolve(&r.material, &Element::Sphere(i), at)?;
            lines.push(at);
            self.scene.spheres.push(Sphere {
                center: vec3(r.center),
                radius: r.radius,
                material,
            });
        }
        Ok(lines)
    }

    /// The `[[plane]]` tables; returns each one's line.
    fn add_planes(&mut self, def: &SceneDef, line: LineOf) -> Result<Vec<Option<usize>>, InputError> {
        let mut lines = Vec::new();
        for (i, p) in def.plane.iter().enumerate() {
            let at = line(p.span());
            let r = p.get_ref();
            let element = Element::Plane(i);
            let material = self.resolve(&r.material, &element, at)?;
            let checker = match (&r.checker_material, r.checker_size) {
                (None, None) => None,
                (Some(_), _) => Some(Checker {
                    material: self.resolve(&r.checker_material, &element, at)?,
                    size: r.checker_size.unwrap_or(1.0),
                }),
                (None, Some(_)) => {
                    return Err(at_element(at, element, "checker_size needs checker_material"));
                }
            };
            let normal = vec3(r.normal);
            let Some(normal) = unit_vector(normal).filter(|_| normal.is_finite()) else {
                return Err(at_element(at, element, "normal must be finite and not zero"));
            };
            lines.push(at);
            self.scene.planes.push(Plane {
                point: vec3(r.point),
                normal,
                material,
                checker,
            });
        }
        Ok(lines)
    }

    /// The `[[mesh]]` tables: every placement checked first, then each file read (relative to
    /// `base`) and placed.
    fn add_meshes(&mut self, def: &SceneDef, base: &Path, line: LineOf) -> Result<(), InputError> {
        let mut placements = Vec::new();
        for (i, m) in def.mesh.iter().enumerate() {
            let at = line(m.span());
            let element = Element::MeshTable(i);
            let mut resolve = |name: &Option<String>, element: &Element, at| self.resolve(name, element, at);
            placements.push((placement(m.get_ref(), &mut resolve, &element, at)?, element, at));
        }
        for (m, (placement, element, at)) in def.mesh.iter().zip(placements) {
            let path = base.join(&m.get_ref().file);
            if super::gltf::is_gltf_path(&path) {
                add_gltf(&mut self.scene, &path, &placement).map_err(|e| e.nested_in(None, at, element.clone()))?;
                continue;
            }
            let mesh = crate::mesh::load(&path).map_err(|e| e.nested_in(None, at, element.clone()))?;
            add_mesh(&mut self.scene, mesh, &placement).map_err(|e| e.with_element(element).with_line(at))?;
        }
        Ok(())
    }
}

/// A glTF's triangles placed by a mesh table, after the file's own node transforms, with the file's
/// materials and textures (the table's material colours spheres only); or spheres on its surface.
fn add_gltf(scene: &mut Scene, path: &Path, placement: &Placement) -> Result<(), InputError> {
    let shown = path.display().to_string();
    let file = super::gltf::load(path)?;
    if file.camera.is_some() || !file.lights.is_empty() {
        log::info!("{shown}: its camera and lights are not used in a scene file");
    }
    super::model::place_gltf(scene, &file, placement)
        .map(|_| ())
        .map_err(|e| e.in_origin(shown))
}

/// A mesh table's placement, its material resolved.
fn placement(
    def: &MeshDef,
    resolve: &mut impl FnMut(&Option<String>, &Element, Option<usize>) -> Result<u32, InputError>,
    element: &Element,
    at: Option<usize>,
) -> Result<Placement, InputError> {
    let fail = |message: String| at_element(at, element.clone(), message);
    let as_ = match def.as_.as_deref() {
        None | Some("triangles") => MeshAs::Triangles,
        Some("spheres") => MeshAs::Spheres,
        Some(other) => {
            return Err(fail(format!(
                "as must be \"triangles\" or \"spheres\" (got \"{other}\")"
            )));
        }
    };
    let spheres = match &def.spheres {
        None => SphereCount::Vertices,
        Some(_) if as_ == MeshAs::Triangles => {
            return Err(fail("spheres applies to as = \"spheres\"".into()));
        }
        Some(SpheresDef::Count(n)) if *n >= 1 => SphereCount::Sampled(usize::try_from(*n).unwrap_or(usize::MAX)),
        Some(SpheresDef::Count(n)) => return Err(fail(format!("spheres must be at least 1 (got {n})"))),
        Some(SpheresDef::Word(word)) if word == "vertices" => SphereCount::Vertices,
        Some(SpheresDef::Word(word)) => {
            return Err(fail(format!(
                "spheres must be a count or \"vertices\" (got \"{word}\")"
            )));
        }
    };
    let normals = match def.normals.as_deref() {
        None => Normals::Auto,
        Some(name) => Normals::from_name(name)
            .ok_or_else(|| fail(format!("normals must be one of {} (got \"{name}\")", Normals::names())))?,
    };
    if (def.animation.is_some() || def.time.is_some()) && !super::gltf::is_gltf_path(Path::new(&def.file)) {
        return Err(fail("animation and time apply to glTF files (.gltf, .glb)".into()));
    }
    let animation = match &def.animation {
        None => None,
        Some(AnimationDef::Index(i)) => {
            Some(ClipChoice::Index(usize::try_from(*i).map_err(|_| {
                fail(format!("animation must be a name or an index from 0 (got {i})"))
            })?))
        }
        Some(AnimationDef::Name(name)) => Some(ClipChoice::Name(name.clone())),
    };
    let placement = Placement {
        as_,
        spheres,
        animation,
        time: def.time.unwrap_or(0.0),
        normals,
        crease_degrees: def.crease.unwrap_or(DEFAULT_CREASE_DEGREES),
        radius: def.radius,
        rotate: def.rotate.map_or(Vec3::ZERO, vec3),
        normalize: def.normalize.unwrap_or(true),
        scale: def.scale.unwrap_or(1.0),
        translate: def.translate.map_or(Vec3::ZERO, vec3),
        seed: def.seed.unwrap_or(0),
        material: resolve(&def.material, element, at)?,
    };
    placement
        .validate()
        .map_err(|e| e.with_element(element.clone()).with_line(at))?;
    Ok(placement)
}

#[cfg(test)]
mod tests {
    use super::parse;
    use crate::error::Element;

    #[test]
    fn minimal_scene_parses_with_defaults() {
        let scene = parse("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1.0\n").unwrap();
        assert_eq!(scene.spheres.len(), 1);
        assert_eq!(scene.materials.len(), 1, "the default material is added on use");
        assert_eq!(scene.settings.accel, None, "no accel: the program's default");
    }

    #[test]
    fn render_integrator_names_one_or_is_refused_on_its_line() {
        use crate::modes::Integrator;
        assert_eq!(parse("").unwrap().settings.integrator, Integrator::Whitted);
        let scene = parse("[render]\nintegrator = \"path\"\n").unwrap();
        assert_eq!(scene.settings.integrator, Integrator::Path);
        let e = parse("[render]\nwidth = 64\nintegrator = \"bidirectional\"\n").unwrap_err();
        let text = e.to_string();
        assert!(text.starts_with("3: render: integrator must be one of"), "{text}");
    }

    #[test]
    fn render_accel_names_a_mode_or_is_refused_on_its_line() {
        use crate::modes::Accel;
        for (name, accel) in [("rayquery", Accel::RayQuery), ("stack", Accel::Stack)] {
            let scene = parse(&format!("[render]\naccel = \"{name}\"\n")).unwrap();
            assert_eq!(scene.settings.accel, Some(accel));
        }
        let e = parse("[render]\nwidth = 64\naccel = \"fastest\"\n").unwrap_err();
        assert_eq!(e.line, Some(3));
        assert_eq!(e.element, Some(Element::Render));
        assert!(e.message.contains("rayquery (got \"fastest\")"), "{}", e.message);
    }

    #[test]
    fn errors_name_the_line() {
        let text = "[camera]\neye = [0, 0, -5]\ntarget = [0, 0, 0]\n\n[[sphere]]\ncenter = [0, 0, 0]\nradius = -1.0\n";
        let err = parse(text).unwrap_err();
        assert_eq!((err.line, &err.element), (Some(5), &Some(Element::Sphere(0))), "{err}");
        assert!(err.message.starts_with("radius"), "{err}");

        let err = parse("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1.0\nradus = 2.0\n").unwrap_err();
        assert_eq!(err.line, Some(4), "{err}");
        assert!(err.message.starts_with("unknown field `radus`"), "{err}");

        let err = parse("[[sphere]]\ncenter = [0, 0, 0]\nradius = 1.0\nmaterial = \"gold\"\n").unwrap_err();
        assert!(err.message.contains("unknown material 'gold'"), "{err}");

        let err = parse("[camera\n").unwrap_err();
        assert_eq!(err.line, Some(1), "{err}");
        assert!(!err.to_string().contains('\n'));
        // Named, the file comes first.
        assert!(err.in_origin("a.toml").to_string().starts_with("a.toml:1: "));
    }

    #[test]
    fn nan_radius_is_rejected() {
        let err = parse("[[sphere]]\ncenter = [0, 0, 0]\nradius = nan\n").unwrap_err();
        assert!(
            err.message.contains("radius must be finite and at least 1e-12"),
            "{err}"
        );
    }
}
