//! Host structs against their WGSL twins, and every shader variant through naga's validator: both
//! run without an adapter.

use raypipe::Choice;
use raypipe::bvh::morton::MortonBits;
use raypipe::gpu::build::{BuildVariant, SiblingBoxes, SortRanking};
use raypipe::gpu::shader::{ShaderConfig, compose};
use raypipe::gpu::upload::{TEXELS_PER_ROW, record_arrays};
use raypipe::modes::{Accel, MemoryMode, Pipeline};
use raypipe::records::{LAYOUTS, PackedScene, StructLayout};
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
        raypipe::gpu::build::LAYOUTS,
        raypipe::gpu::threaded::LAYOUTS,
        raypipe::gpu::display::LAYOUTS,
    ]
    .into_iter()
    .flatten()
    .collect()
}

#[test]
fn every_host_struct_matches_its_wgsl_twin() {
    let host_layouts = host_layouts();
    let mut seen = Vec::new();
    let types = parse(&raypipe::gpu::shader::records_source());
    let display = parse(raypipe::gpu::display::shader_source());
    for (_, ty) in types.types.iter().chain(display.types.iter()) {
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
            for &accel in Accel::ALL {
                for max_depth in [0, 5] {
                    let source = compose(&ShaderConfig {
                        pipeline,
                        memory,
                        accel,
                        max_depth,
                        bvh_depth: 12,
                        arrays: &record_arrays(scene, accel),
                        texels_per_row: TEXELS_PER_ROW,
                        write_cost: max_depth == 0,
                    });
                    let module = parse(&source);
                    let flags = naga::valid::ValidationFlags::all();
                    naga::valid::Validator::new(flags, naga::valid::Capabilities::empty())
                        .validate(&module)
                        .unwrap_or_else(|e| {
                            panic!(
                                "{pipeline:?}, {memory:?}, {accel:?}, depth {max_depth}: {}",
                                e.emit_to_string(&source)
                            )
                        });
                }
            }
        }
    }
}

#[test]
fn the_build_layout_and_display_shaders_validate() {
    let mut sources = vec![
        ("threaded layout".to_string(), raypipe::gpu::threaded::shader_source()),
        (
            "display".to_string(),
            raypipe::gpu::display::shader_source().to_string(),
        ),
    ];
    for bits in [MortonBits::Bits30, MortonBits::Bits63] {
        for variant in build_variants() {
            sources.push((
                format!("LBVH build, {}-bit codes, {variant:?}", bits.total_bits()),
                raypipe::gpu::build::shader_source(bits, variant),
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
            let count = storage_buffers(&raypipe::gpu::build::shader_source(bits, variant));
            assert!(count <= 8, "the LBVH build binds {count} storage buffers");
        }
    }
    let count = storage_buffers(&raypipe::gpu::threaded::shader_source());
    assert!(count <= 8, "the threaded layout binds {count} storage buffers");
    let scene = PackedScene::new(&builtin::whitted()).unwrap();
    for &accel in Accel::ALL {
        let source = compose(&ShaderConfig {
            pipeline: Pipeline::Fragment,
            memory: MemoryMode::Storage,
            accel,
            max_depth: 5,
            bvh_depth: 12,
            arrays: &record_arrays(&scene, accel),
            texels_per_row: TEXELS_PER_ROW,
            write_cost: false,
        });
        let count = storage_buffers(&source);
        assert!(
            count <= 8,
            "the {accel:?} fragment shader binds {count} storage buffers"
        );
    }
}
