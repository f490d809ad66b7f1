//! Host structs against their WGSL twins, and every shader variant through naga's validator: both
//! run without an adapter.

use raypipe::Choice;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::builders::lbvh::{BuildVariant, SiblingBoxes, SortRanking};
use raypipe::gpu::trace::shader::{SceneFeatures, ShaderConfig, compose};
use raypipe::gpu::trace::upload::{TEXELS_PER_ROW, record_arrays};
use raypipe::modes::{Accel, Integrator, MemoryMode, Pipeline};
use raypipe::records::PackedScene;
use raypipe::records::layouts::{LAYOUTS, StructLayout};
use raypipe::scene::{Scene, builtin};

/// Every variant of the build's kernels: the sort's three rankings (subgroups of 8 to 32
/// invocations, runs as lavapipe's), each with both ways of passing sibling boxes.
fn build_variants() -> impl Iterator<Item = BuildVariant> {
    let rankings = [
        SortRanking::Subgroups { group: 256 },
        SortRanking::Shared,
        SortRanking::Runs { group: 8 },
    ];
    rankings.into_iter().flat_map(|ranking| {
        [SiblingBoxes::Atomics, SiblingBoxes::Nodes].map(|sibling_boxes| BuildVariant { ranking, sibling_boxes })
    })
}

fn parse(source: &str) -> naga::Module {
    naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)))
}

/// Every struct that crosses to the GPU: the tracer's records, the build's and the threaded
/// layout's parameters, and the display pass's.
fn host_layouts() -> Vec<&'static StructLayout> {
    [
        LAYOUTS,
        raypipe::gpu::builders::lbvh::LAYOUTS,
        raypipe::gpu::builders::threaded_layout::LAYOUTS,
        raypipe::gpu::builders::wide_collapse::LAYOUTS,
        raypipe::gpu::trace::display::LAYOUTS,
        raypipe::gpu::builders::deform::LAYOUTS,
    ]
    .into_iter()
    .flatten()
    .collect()
}

/// The path integrator's parameters, declared in its own file (`sampling.wgsl`), which only a path
/// tracer's source holds.
#[test]
fn the_path_parameters_match_their_wgsl_twin() {
    let scene = PackedScene::new(&builtin::whitted()).unwrap();
    let source = compose(&ShaderConfig {
        pipeline: Pipeline::Fragment,
        memory: MemoryMode::Storage,
        accel: Accel::Stack,
        integrator: Integrator::Path,
        max_depth: 5,
        bvh_depth: 12,
        arrays: &record_arrays(&scene, Accel::Stack),
        texels_per_row: TEXELS_PER_ROW,
        write_cost: false,
        features: SceneFeatures::ALL,
    });
    let module = parse(&source);
    for host in raypipe::records::path::LAYOUTS {
        let (members, span) = module
            .types
            .iter()
            .find_map(|(_, ty)| match (&ty.name, &ty.inner) {
                (Some(name), naga::TypeInner::Struct { members, span }) if name == host.wgsl_name => {
                    Some((members, *span))
                }
                _ => None,
            })
            .unwrap_or_else(|| panic!("{} is missing from the path tracer's source", host.wgsl_name));
        assert_eq!(span as usize, host.size, "{}: sizes differ", host.wgsl_name);
        let wgsl: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap(), m.offset as usize))
            .collect();
        let rust: Vec<(String, usize)> = host.members.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(wgsl, rust, "{}: members (name, offset) differ", host.wgsl_name);
    }
}

#[test]
fn every_host_struct_matches_its_wgsl_twin() {
    let host_layouts = host_layouts();
    let mut seen = Vec::new();
    let types = parse(&raypipe::gpu::preamble::records_source());
    let display = parse(&raypipe::gpu::trace::display::shader_source());
    let deform = parse(&raypipe::gpu::builders::deform::shader_source());
    for (_, ty) in types
        .types
        .iter()
        .chain(display.types.iter())
        .chain(deform.types.iter())
    {
        let (Some(name), naga::TypeInner::Struct { members, span }) = (&ty.name, &ty.inner) else {
            continue;
        };
        let host = host_layouts
            .iter()
            .find(|l| l.wgsl_name == name)
            .unwrap_or_else(|| panic!("WGSL struct {name} has no host twin"));
        assert_eq!(
            *span as usize, host.size,
            "{name}: WGSL size {span}, Rust size {}",
            host.size
        );
        let wgsl: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap(), m.offset as usize))
            .collect();
        let rust: Vec<(String, usize)> = host.members.iter().map(|(n, o)| (n.to_string(), *o)).collect();
        assert_eq!(wgsl, rust, "{name}: members (name, offset) differ");
        seen.push(name.clone());
    }
    for layout in host_layouts {
        assert!(
            seen.iter().any(|s| s == layout.wgsl_name),
            "{} is missing from types.wgsl",
            layout.wgsl_name
        );
    }
}

#[test]
fn every_shader_variant_validates() {
    let scene = PackedScene::new(&builtin::whitted()).unwrap();
    let mut empty = Scene::default();
    empty.lights.clear();
    let empty = PackedScene::new(&empty).unwrap();
    for scene in [&scene, &empty] {
        for (&pipeline, &memory) in Pipeline::ALL
            .iter()
            .flat_map(|p| MemoryMode::ALL.iter().map(move |m| (p, m)))
        {
            for (&accel, &integrator) in Accel::ALL
                .iter()
                .flat_map(|a| Integrator::ALL.iter().map(move |i| (a, i)))
            {
                for max_depth in [0, 5] {
                    let source = compose(&ShaderConfig {
                        pipeline,
                        memory,
                        accel,
                        integrator,
                        max_depth,
                        bvh_depth: 12,
                        arrays: &record_arrays(scene, accel),
                        texels_per_row: TEXELS_PER_ROW,
                        write_cost: max_depth == 0,
                        features: SceneFeatures::ALL,
                    });
                    let module = parse(&source);
                    let flags = naga::valid::ValidationFlags::all();
                    let capabilities = if accel.needs_ray_queries() {
                        naga::valid::Capabilities::RAY_QUERY
                    } else {
                        naga::valid::Capabilities::empty()
                    };
                    naga::valid::Validator::new(flags, capabilities)
                        .validate(&module)
                        .unwrap_or_else(|e| {
                            panic!(
                                "{pipeline:?}, {memory:?}, {accel:?}, {integrator:?}, depth {max_depth}: {}",
                                e.emit_to_string(&source)
                            )
                        });
                }
            }
        }
    }
}

#[test]
fn the_build_layout_skinning_and_display_shaders_validate() {
    let mut sources = vec![
        (
            "threaded layout".to_string(),
            raypipe::gpu::builders::threaded_layout::shader_source(),
        ),
        (
            "wide collapse".to_string(),
            raypipe::gpu::builders::wide_collapse::shader_source(),
        ),
        ("display".to_string(), raypipe::gpu::trace::display::shader_source()),
        ("skinning".to_string(), raypipe::gpu::builders::deform::shader_source()),
    ];
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        for variant in build_variants() {
            sources.push((
                format!("LBVH build, {}-bit codes, {variant:?}", bits.total_bits()),
                raypipe::gpu::builders::lbvh::shader_source(bits, variant),
            ));
        }
    }
    for (what, source) in sources {
        let module = parse(&source);
        // Subgroup operations only where the source uses them.
        let capabilities = if what.contains("Subgroups") {
            naga::valid::Capabilities::SUBGROUP
        } else {
            naga::valid::Capabilities::empty()
        };
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{what}: {}", e.emit_to_string(&source)));
    }
}

/// WebGPU lets a shader stage bind 8 storage buffers unless the device asks for more, and browsers
/// may not grant more: every pipeline keeps within that.
#[test]
fn every_pipeline_binds_at_most_8_storage_buffers() {
    let storage_buffers = |source: &str| {
        parse(source)
            .global_variables
            .iter()
            .filter(|(_, v)| matches!(v.space, naga::AddressSpace::Storage { .. }))
            .count()
    };
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        for variant in build_variants() {
            let count = storage_buffers(&raypipe::gpu::builders::lbvh::shader_source(bits, variant));
            assert!(count <= 8, "the LBVH build binds {count} storage buffers");
        }
    }
    let count = storage_buffers(&raypipe::gpu::builders::threaded_layout::shader_source());
    assert!(count <= 8, "the threaded layout binds {count} storage buffers");
    let count = storage_buffers(&raypipe::gpu::builders::wide_collapse::shader_source());
    assert!(count <= 8, "the wide collapse binds {count} storage buffers");
    let scene = PackedScene::new(&builtin::whitted()).unwrap();
    for (&accel, &integrator) in Accel::ALL
        .iter()
        .flat_map(|a| Integrator::ALL.iter().map(move |i| (a, i)))
    {
        let source = compose(&ShaderConfig {
            pipeline: Pipeline::Fragment,
            memory: MemoryMode::Storage,
            accel,
            integrator,
            max_depth: 5,
            bvh_depth: 12,
            arrays: &record_arrays(&scene, accel),
            texels_per_row: TEXELS_PER_ROW,
            write_cost: false,
            features: SceneFeatures::ALL,
        });
        let count = storage_buffers(&source);
        assert!(
            count <= 8,
            "the {accel:?} {integrator:?} fragment shader binds {count} storage buffers"
        );
    }
}

/// A number shared with Rust: its WGSL name and Rust's value (scalars, flattened).
type Shared = (String, Vec<f64>);

/// A constant's value as naga evaluated it: its scalars in order (an array's or vector's
/// components flattened).
fn constant_values(module: &naga::Module, expression: naga::Handle<naga::Expression>) -> Vec<f64> {
    match &module.global_expressions[expression] {
        naga::Expression::Literal(literal) => vec![match *literal {
            naga::Literal::F32(v) => v as f64,
            naga::Literal::U32(v) => v as f64,
            naga::Literal::I32(v) => v as f64,
            naga::Literal::Bool(v) => v as u8 as f64,
            naga::Literal::AbstractInt(v) => v as f64,
            naga::Literal::AbstractFloat(v) => v,
            ref other => panic!("a literal of an unexpected type: {other:?}"),
        }],
        naga::Expression::Compose { components, .. } => {
            components.iter().flat_map(|&c| constant_values(module, c)).collect()
        }
        other => panic!("a constant of an unexpected kind: {other:?}"),
    }
}

/// Every number a shader module shares with Rust, by its WGSL name, as Rust has it; and each
/// module's source. The shaders get these from generated preambles: the hand-written WGSL must not
/// define them (checked below), and what the preambles define must be Rust's value.
fn shared_numbers() -> Vec<(String, String, Vec<Shared>)> {
    use raypipe::bvh::layout::{LEAF, NONE};
    use raypipe::bvh::threaded::{LEAF_BIT, MAX_QUANTUM, TINY_EXTENT};
    use raypipe::constants::*;
    use raypipe::records::constants::*;
    let one = |name: &str, value: f64| (name.to_string(), vec![value]);
    let mut records = vec![
        one("T_FAR", T_FAR as f64),
        one("MIN_WEIGHT", MIN_WEIGHT as f64),
        one("DEPTH_MISS", DEPTH_MISS as f64),
        one("RAY_BIAS", RAY_BIAS as f64),
        one("PARALLEL_EPSILON", PARALLEL_EPSILON as f64),
        one("TINY_DIRECTION", TINY_DIRECTION as f64),
        one("NO_HIT", NO_HIT as f64),
        one("R2_STEP_X", R2_STEP[0] as f64),
        one("R2_STEP_Y", R2_STEP[1] as f64),
        one("LEAF", LEAF as f64),
        one("NONE", NONE as f64),
        one("LEAF_BIT", LEAF_BIT as f64),
        one("MAX_QUANTUM", MAX_QUANTUM as f64),
        one("TINY_EXTENT", TINY_EXTENT as f64),
        one("WIDE_SPAN", raypipe::bvh::wide::SPAN as f64),
        one("WIDE_NODE_TEXELS", raypipe::bvh::wide::NODE_TEXELS as f64),
    ];
    records.extend(
        [
            ("WRAP_REPEAT", WRAP_REPEAT),
            ("WRAP_CLAMP", WRAP_CLAMP),
            ("WRAP_MIRROR", WRAP_MIRROR),
        ]
        .map(|(name, code)| one(name, code as f64)),
    );
    let mut tracer = records.clone();
    tracer.push(one("COMPUTE_TILE", raypipe::gpu::trace::shader::COMPUTE_TILE as f64));
    tracer.push(one("TEXELS_PER_ROW", TEXELS_PER_ROW as f64));
    let source = compose(&ShaderConfig {
        pipeline: Pipeline::Compute,
        memory: MemoryMode::Texture,
        accel: Accel::Threaded,
        integrator: Integrator::Path,
        max_depth: 5,
        bvh_depth: 1,
        arrays: &record_arrays(&PackedScene::new(&builtin::whitted()).unwrap(), Accel::Threaded),
        texels_per_row: TEXELS_PER_ROW,
        write_cost: false,
        features: SceneFeatures::ALL,
    });
    let mut build = records.clone();
    build.push(one("GROUP", raypipe::gpu::builders::lbvh::GROUP as f64));
    build.push(one("DIGIT_BITS", raypipe::gpu::builders::lbvh::DIGIT_BITS as f64));
    build.push(one("DIGITS", (1u32 << raypipe::gpu::builders::lbvh::DIGIT_BITS) as f64));
    let mut wide = records.clone();
    wide.push(one("GROUP", raypipe::gpu::builders::wide_collapse::GROUP as f64));
    let mut threaded = records;
    threaded.push(one("GROUP", raypipe::gpu::builders::threaded_layout::GROUP as f64));
    let mut display: Vec<_> = raypipe::modes::Aov::ALL
        .iter()
        .map(|&v| one(&format!("DISPLAY_{}", v.name().to_uppercase()), v as u32 as f64))
        .collect();
    let stops = raypipe::image::heatmap::STOPS;
    display.push(one("HEAT_STOP_COUNT", stops.len() as f64));
    display.push(("HEAT_STOPS".into(), stops.iter().flatten().map(|&c| c as f64).collect()));
    let build_source =
        raypipe::gpu::builders::lbvh::shader_source(MortonBits::Bits63, build_variants().next().unwrap());
    vec![
        ("tracer".into(), source, tracer),
        ("build".into(), build_source, build),
        (
            "threaded layout".into(),
            raypipe::gpu::builders::threaded_layout::shader_source(),
            threaded,
        ),
        (
            "wide collapse".into(),
            raypipe::gpu::builders::wide_collapse::shader_source(),
            wide,
        ),
        ("display".into(), raypipe::gpu::trace::display::shader_source(), display),
    ]
}

#[test]
fn shared_constants_come_from_rust() {
    let shaders = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/gpu/shaders");
    let hand_written: Vec<(String, String)> = std::fs::read_dir(&shaders)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "wgsl"))
        .map(|p| {
            (
                p.file_name().unwrap().to_string_lossy().into_owned(),
                std::fs::read_to_string(&p).unwrap(),
            )
        })
        .collect();
    assert!(
        hand_written.len() >= 10,
        "{} WGSL files in {}",
        hand_written.len(),
        shaders.display()
    );
    for (module_name, source, numbers) in shared_numbers() {
        let module = parse(&source);
        for (name, expected) in &numbers {
            let (_, constant) = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name.as_str()))
                .unwrap_or_else(|| panic!("{module_name}: no constant {name}"));
            let got = constant_values(&module, constant.init);
            assert_eq!(&got, expected, "{module_name}: WGSL's {name} is not Rust's");
            for (file, text) in &hand_written {
                assert!(
                    !text.contains(&format!("const {name}:")) && !text.contains(&format!("const {name} =")),
                    "{file} defines {name} by hand: it comes from Rust, in the preamble"
                );
            }
        }
    }
    // Workgroup sizes are named constants too, never literals.
    for (file, text) in &hand_written {
        for size in text.split("@workgroup_size(").skip(1) {
            assert!(
                !size.starts_with(|c: char| c.is_ascii_digit()),
                "{file}: a literal workgroup size"
            );
        }
    }
}
