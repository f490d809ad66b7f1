//! The library's modules depend one way, as lib.rs's map says: each top-level module uses only
//! those of lower layers ([`LAYERS`]), and no files of one folder use each other in a circle.
//! Read from the sources: the `crate::` and `super::` paths of the code (comments and the unit
//! tests at the end of a file left out), with a folder's `pub use` re-exports followed to the
//! file that defines the item.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library's top-level modules, bottom layer first: a module may use the modules of lower
/// layers only (lib.rs's map says the same).
const LAYERS: &[&[&str]] = &[
    &["choice", "constants", "parallel", "rng"],
    &["modes"],
    &["error"],
    &["input"],
    &["bvh"],
    &["mesh"],
    &["scene"],
    &["records"],
    &["image"],
    &["cpu", "gpu"],
];

/// A module by its path from the crate's root (`["gpu", "renderer"]`).
type ModulePath = Vec<String>;

struct Source {
    module: ModulePath,
    /// Where the file is, for messages.
    file: String,
    code: String,
}

fn sources() -> Vec<Source> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    collect(&root, &mut files);
    files
        .into_iter()
        .map(|path| {
            let relative = path.strip_prefix(&root).unwrap().with_extension("");
            let mut module: ModulePath = relative.iter().map(|c| c.to_string_lossy().into_owned()).collect();
            if module.last().is_some_and(|m| m == "mod" || m == "lib") {
                module.pop();
            }
            let text = std::fs::read_to_string(&path).unwrap();
            Source {
                module,
                file: relative.display().to_string(),
                code: without_comments_and_tests(&text),
            }
        })
        .collect()
}

fn collect(dir: &Path, files: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            collect(&path, files);
        } else if path.extension().is_some_and(|e| e == "rs") {
            files.push(path);
        }
    }
}

/// The code without its line comments (doc comments too: their links are no dependency) and
/// without the unit tests, which every file keeps last, behind `#[cfg(test)]`.
fn without_comments_and_tests(text: &str) -> String {
    let code = text.split("#[cfg(test)]").next().unwrap();
    code.lines()
        .map(|line| line.split("//").next().unwrap())
        .collect::<Vec<_>>()
        .join("\n")
}

/// Every path the code names from `crate::` or `super::`, resolved from `module` to a path from
/// the crate's root; a group (`crate::{a::b, c::{d, e}}`) gives each of its paths.
fn named_paths(module: &ModulePath, code: &str) -> Vec<ModulePath> {
    let mut paths = Vec::new();
    let bytes = code.as_bytes();
    let word_start =
        |i: usize| i == 0 || !(bytes[i - 1].is_ascii_alphanumeric() || bytes[i - 1] == b'_' || bytes[i - 1] == b':');
    for start in (0..code.len()).filter(|&i| code.is_char_boundary(i) && word_start(i)) {
        let rest = &code[start..];
        let (mut base, mut tail) = if let Some(tail) = rest.strip_prefix("crate::") {
            (Vec::new(), tail)
        } else if let Some(tail) = rest.strip_prefix("super::") {
            (module[..module.len().saturating_sub(1)].to_vec(), tail)
        } else {
            continue;
        };
        while let Some(more) = tail.strip_prefix("super::") {
            base.pop();
            tail = more;
        }
        use_tree(base, tail, &mut paths);
    }
    paths
}

/// The paths of a use tree that starts at `text`, below `path`.
fn use_tree(mut path: ModulePath, text: &str, paths: &mut Vec<ModulePath>) {
    let mut rest = text.trim_start();
    loop {
        if let Some(group) = rest.strip_prefix('{') {
            for item in group_items(group) {
                use_tree(path.clone(), item, paths);
            }
            return;
        }
        let end = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        if !rest[..end].is_empty() && &rest[..end] != "self" {
            path.push(rest[..end].to_string());
        }
        match rest[end..].strip_prefix("::") {
            Some(more) => rest = more,
            None => break,
        }
    }
    paths.push(path);
}

/// A group's items, up to its closing brace: split at its own commas, not its inner groups'.
fn group_items(group: &str) -> Vec<&str> {
    let (mut items, mut depth, mut from) = (Vec::new(), 0, 0);
    for (i, c) in group.char_indices() {
        match c {
            '{' => depth += 1,
            '}' if depth == 0 => {
                items.push(&group[from..i]);
                return items;
            }
            '}' => depth -= 1,
            ',' if depth == 0 => {
                items.push(&group[from..i]);
                from = i + 1;
            }
            _ => {}
        }
    }
    items.push(&group[from..]);
    items
}

/// A folder's `pub use child::{A, B as C}`: the path each re-exported name stands for.
fn re_exports(sources: &[Source]) -> BTreeMap<ModulePath, ModulePath> {
    let mut map = BTreeMap::new();
    for source in sources {
        for statement in source.code.split("pub use ").skip(1) {
            let statement = &statement[..statement.find(';').unwrap_or(statement.len())];
            let Some((child, names)) = statement.split_once("::") else {
                continue;
            };
            if child.contains(['{', ' ']) || child == "crate" || child == "super" {
                continue;
            }
            let names = names.trim_start_matches('{').trim_end_matches('}');
            for name in names.split(',') {
                let (item, alias) = name.split_once(" as ").unwrap_or((name, name));
                let (item, alias) = (item.trim(), alias.trim());
                if alias.is_empty() || item.contains("::") {
                    continue;
                }
                let mut from = source.module.clone();
                from.push(alias.to_string());
                let mut to = source.module.clone();
                to.extend([child.to_string(), item.to_string()]);
                map.insert(from, to);
            }
        }
    }
    map
}

/// The module (a file, or a folder) that `path` names, following re-exports.
fn resolve(
    path: &ModulePath,
    modules: &BTreeSet<ModulePath>,
    exports: &BTreeMap<ModulePath, ModulePath>,
) -> ModulePath {
    for len in (1..=path.len()).rev() {
        let prefix = &path[..len];
        if let Some(target) = exports.get(prefix) {
            let mut followed = target.clone();
            followed.extend_from_slice(&path[len..]);
            return resolve(&followed, modules, exports);
        }
        if modules.contains(prefix) {
            return prefix.to_vec();
        }
    }
    Vec::new()
}

/// Every dependency between two modules of one folder, by the folder: (from, to, the file that
/// names it). A file and the folders around it (mod.rs and its children) are not counted.
fn dependencies(sources: &[Source]) -> BTreeMap<String, BTreeSet<(String, String, String)>> {
    let modules: BTreeSet<ModulePath> = sources.iter().map(|s| s.module.clone()).collect();
    let exports = re_exports(sources);
    let mut by_folder: BTreeMap<String, BTreeSet<(String, String, String)>> = BTreeMap::new();
    for source in sources {
        for path in named_paths(&source.module, &source.code) {
            let target = resolve(&path, &modules, &exports);
            let shared = source.module.iter().zip(&target).take_while(|(a, b)| a == b).count();
            if shared == source.module.len() || shared == target.len() {
                continue;
            }
            let folder = if shared == 0 {
                "src".to_string()
            } else {
                source.module[..shared].join("/")
            };
            by_folder.entry(folder).or_default().insert((
                source.module[shared].clone(),
                target[shared].clone(),
                source.file.clone(),
            ));
        }
    }
    by_folder
}

fn layer(module: &str) -> usize {
    LAYERS
        .iter()
        .position(|layer| layer.contains(&module))
        .unwrap_or_else(|| {
            panic!("src/{module}: a top-level module missing from LAYERS (tests/cpu/layers.rs) and lib.rs's map")
        })
}

#[test]
fn top_level_modules_use_lower_layers_only() {
    let dependencies = dependencies(&sources());
    let upward: Vec<String> = dependencies["src"]
        .iter()
        .filter(|(from, to, _)| layer(to) >= layer(from))
        .map(|(from, to, file)| format!("{from} uses {to} (src/{file}.rs)"))
        .collect();
    assert!(
        upward.is_empty(),
        "modules using their own layer or one above:\n{}",
        upward.join("\n")
    );
}

#[test]
fn no_files_of_one_folder_form_a_circle() {
    let circles = circles(&dependencies(&sources()));
    assert!(circles.is_empty(), "circles:\n{}", circles.join("\n"));
}

/// Each dependency that closes a circle, as a line.
fn circles(dependencies: &BTreeMap<String, BTreeSet<(String, String, String)>>) -> Vec<String> {
    let mut circles = Vec::new();
    for (folder, edges) in dependencies {
        let mut graph: BTreeMap<&str, BTreeSet<&str>> = BTreeMap::new();
        for (from, to, _) in edges {
            graph.entry(from).or_default().insert(to);
        }
        for (from, to, file) in edges {
            // A circle through this edge: `to` leads back to `from`.
            if reaches(&graph, to, from) {
                circles.push(format!(
                    "{folder}: {from} uses {to} (src/{file}.rs), and {to} leads back to {from}"
                ));
            }
        }
    }
    circles
}

fn reaches(graph: &BTreeMap<&str, BTreeSet<&str>>, from: &str, to: &str) -> bool {
    let mut seen = BTreeSet::new();
    let mut waiting = vec![from];
    while let Some(node) = waiting.pop() {
        if node == to {
            return true;
        }
        if seen.insert(node) {
            waiting.extend(graph.get(node).into_iter().flatten());
        }
    }
    false
}

/// The checker itself, on a made-up folder: comments and unit tests are left out, re-exports
/// followed, and the circle they hide found.
/// The parts of a moving scene that only the library's `gpu::MovingScene` puts together.
const MOVING_SCENE_PARTS: &[&str] = &[
    "SceneRebuild",
    "GpuLbvhBuilder",
    "GpuDeform",
    "MortonBits",
    "depth_bound",
];

/// Every program that moves a scene (the viewer, the page, `render --frames`, `bench --rebuild`
/// and `--motion`) does it through `MovingScene`, and names none of its parts. (`raypipe bvh`
/// times the builders themselves, key widths among its choices, and is left out.)
#[test]
fn programs_move_scenes_through_the_library_alone() {
    let crates = Path::new(env!("CARGO_MANIFEST_DIR")).parent().unwrap();
    let mut files = Vec::new();
    for program in ["raypipe-view/src", "raypipe-web/src", "raypipe-cli/src"] {
        collect(&crates.join(program), &mut files);
    }
    let mut named = Vec::new();
    for file in files.iter().filter(|f| !f.ends_with("raypipe-cli/src/bvh.rs")) {
        let code = without_comments_and_tests(&std::fs::read_to_string(file).unwrap());
        for part in MOVING_SCENE_PARTS.iter().filter(|part| code.contains(*part)) {
            named.push(format!("{} names {part}", file.strip_prefix(crates).unwrap().display()));
        }
    }
    assert!(named.is_empty(), "{named:#?}");
    assert!(files.len() > 20, "the programs' sources were found");
}

/// The longest a source file may grow: past it, a file holds more than one concern.
const MAX_FILE_LINES: usize = 700;

/// No source file of the workspace (Rust, WGSL, the page's and the package's JavaScript) is
/// longer than [`MAX_FILE_LINES`].
#[test]
fn no_source_file_is_over_700_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .parent()
        .unwrap();
    let mut files = Vec::new();
    for folder in ["crates", "bench", "tools", "fuzz", "web", "scripts"] {
        source_files(&root.join(folder), &mut files);
    }
    let long: Vec<String> = files
        .iter()
        .filter_map(|file| {
            let lines = std::fs::read_to_string(file).unwrap().lines().count();
            (lines > MAX_FILE_LINES).then(|| format!("{}: {lines} lines", file.strip_prefix(root).unwrap().display()))
        })
        .collect();
    assert!(long.is_empty(), "{long:#?}");
    assert!(files.len() > 200, "the sources were found ({})", files.len());
}

fn source_files(dir: &Path, files: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for entry in entries {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy();
        // Built or installed, not written here.
        if ["target", "node_modules", "pkg", "dist"].contains(&name.as_ref()) || name.starts_with('.') {
            continue;
        }
        if path.is_dir() {
            source_files(&path, files);
        } else if path
            .extension()
            .is_some_and(|e| ["rs", "wgsl", "js", "mjs", "ts", "py", "sh"].contains(&e.to_str().unwrap()))
        {
            files.push(path);
        }
    }
}

#[test]
fn the_checker_sees_circles_and_re_exports() {
    let module = |p: &[&str]| p.iter().map(|s| s.to_string()).collect::<ModulePath>();
    let sources = vec![
        Source {
            module: module(&["gpu"]),
            file: "gpu/mod".into(),
            code: "mod a;\nmod b;\npub use a::{Alpha, Beta as B};".into(),
        },
        Source {
            module: module(&["gpu", "a"]),
            file: "gpu/a".into(),
            code: without_comments_and_tests("use super::b::Thing; // crate::scene\n#[cfg(test)]\nuse crate::cpu;"),
        },
        Source {
            module: module(&["gpu", "b"]),
            file: "gpu/b".into(),
            code: "use super::B;\nuse crate::{records::X, gpu::{Alpha, a::Gamma}};".into(),
        },
    ];
    let exports = re_exports(&sources);
    assert_eq!(exports[&module(&["gpu", "B"])], module(&["gpu", "a", "Beta"]));
    let modules: BTreeSet<ModulePath> = sources.iter().map(|s| s.module.clone()).collect();
    let named = |s: &Source| -> Vec<ModulePath> {
        named_paths(&s.module, &s.code)
            .iter()
            .map(|p| resolve(p, &modules, &exports))
            .collect()
    };
    assert_eq!(
        named(&sources[1]),
        vec![module(&["gpu", "b"])],
        "comments and unit tests are no dependency"
    );
    assert_eq!(
        named(&sources[2]),
        vec![
            module(&["gpu", "a"]),
            vec![],
            module(&["gpu", "a"]),
            module(&["gpu", "a"])
        ],
        "re-exports lead to the defining file; a group, nested too, gives each path"
    );
    let found = circles(&dependencies(&sources));
    assert_eq!(
        found.len(),
        2,
        "a uses b, b uses a through the folder's re-export: {found:?}"
    );
    assert!(found[0].starts_with("gpu: a uses b (src/gpu/a.rs)"), "{found:?}");
    assert!(layer("gpu") > layer("scene") && layer("cpu") == layer("gpu"));
}
