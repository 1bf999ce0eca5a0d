//! Every shader in `wgsl/` is registered, validates with naga, and the host structs and
//! constants (`slayer::abi`, the contract between `wgsl/`, the CPU mirrors and the GPU host
//! code) match naga's layout and values of their WGSL declarations.

use std::path::Path;

use slayer::abi::{
    ApplyMode, ApplyParams, BackstopParams, CellKeyParams, CountParams, DeformParams,
    DispatchParams, EntryParams, FrameParams, GateParams, GateStage, GateStatus, MovingVertex,
    NormalParams, OverlayParams, ProximityParams, SCAN_BLOCK, SelectParams, SelectedVertex,
    brush_code, falloff_code,
};
use slayer::brush::BrushKind;
use slayer::brush::Falloff;
use slayer::gpu::shaders::{
    FRAGMENT_ENTRY, KERNELS, RENDER_SHADERS, SHARED, VERTEX_ENTRY, expand_imports, kernel_source,
    render_source, validate,
};
use slayer::mesh::{INVALID, VertexFlags};
use slayer::render::{PreviewUniforms, RenderVertex};

fn wgsl_files(folder: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(folder)
        .unwrap_or_else(|e| panic!("{}: {e}", folder.display()))
        .filter_map(|e| e.ok())
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "wgsl"))
        .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn every_kernel_file_is_registered_and_validates() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    let files = wgsl_files(&root);
    assert!(!files.is_empty());
    for name in &files {
        assert!(
            KERNELS.iter().any(|(k, _)| k == name),
            "wgsl/{name}.wgsl is not registered in gpu::shaders::KERNELS"
        );
        let on_disk = std::fs::read_to_string(root.join(format!("{name}.wgsl"))).unwrap();
        let source = expand_imports(name, &on_disk).expect("imports expand");
        let (module, _) = validate(name, &source).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            module.entry_points.iter().any(|e| e.name == "main"),
            "wgsl/{name}.wgsl has no entry point `main`"
        );
    }
    assert_eq!(
        KERNELS.len(),
        files.len(),
        "KERNELS names a file that does not exist"
    );
}

#[test]
fn every_render_shader_is_registered_and_has_vertex_and_fragment_stages() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl/render");
    let files = wgsl_files(&root);
    assert!(!files.is_empty());
    for name in &files {
        assert!(
            RENDER_SHADERS.iter().any(|(k, _)| k == name),
            "wgsl/render/{name}.wgsl is not registered in gpu::shaders::RENDER_SHADERS"
        );
        let on_disk = std::fs::read_to_string(root.join(format!("{name}.wgsl"))).unwrap();
        let source = expand_imports(name, &on_disk).expect("imports expand");
        let (module, _) = validate(name, &source).unwrap_or_else(|e| panic!("{e}"));
        for (entry, stage) in [
            (VERTEX_ENTRY, naga::ShaderStage::Vertex),
            (FRAGMENT_ENTRY, naga::ShaderStage::Fragment),
        ] {
            assert!(
                module
                    .entry_points
                    .iter()
                    .any(|e| e.name == entry && e.stage == stage),
                "wgsl/render/{name}.wgsl has no {stage:?} entry point `{entry}`"
            );
        }
    }
    assert_eq!(
        RENDER_SHADERS.len(),
        files.len(),
        "RENDER_SHADERS names a file that does not exist"
    );
}

#[test]
fn every_shared_file_is_registered() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl/shared");
    for name in wgsl_files(&root) {
        let import = format!("shared/{name}");
        assert!(
            SHARED.iter().any(|(k, _)| *k == import),
            "wgsl/shared/{name}.wgsl is not registered in gpu::shaders::SHARED"
        );
    }
}

/// Each kernel's parity tests in `tests/gpu_parity/` (in any of its modules): the tests that
/// dispatch it on the GPU and compare it with its CPU mirror. Adding a kernel to `wgsl/`
/// without naming its parity tests here fails `every_kernel_has_a_cpu_mirror_and_a_parity_test`.
const PARITY_TESTS: &[(&str, &[&str])] = &[
    (
        "cell_keys",
        &[
            "cell_keys_matches_cpu_mirror_at_awkward_sizes",
            "cell_keys_agree_on_cell_boundaries_and_negative_cells",
            "wide_dispatches_fold_into_two_dimensions",
        ],
    ),
    (
        "cell_counts",
        &["cell_counts_match_cpu_mirror_and_ranks_number_each_bucket"],
    ),
    ("scan", &["scan_matches_cpu_mirror_and_a_running_sum"]),
    // The multi-level scan adds each block's offset with `scan_add` past 256 entries.
    ("scan_add", &["scan_matches_cpu_mirror_and_a_running_sum"]),
    (
        "scatter",
        &[
            "scatter_matches_cpu_mirror_given_the_same_ranks",
            "hash_table_matches_cpu_chain_and_the_grid",
            "hash_build_folds_wide_dispatches",
        ],
    ),
    (
        "select",
        &[
            "select_matches_cpu_mirror_at_awkward_sizes",
            "select_scans_vertices_for_huge_brushes_and_folds_wide_dispatches",
            "select_through_an_overlay_matches_a_fresh_table",
            "select_finds_vertices_that_moved_since_the_table_was_built",
        ],
    ),
    (
        "deform",
        &[
            "deform_matches_cpu_mirror_and_the_brush_fields",
            "deform_reads_neighbours_split_over_several_bindings",
            "deform_takes_the_frame_from_the_sums_as_the_mirror_does",
        ],
    ),
    (
        "brush_frame",
        &["brush_frame_sums_match_the_cpu_mirror_bit_for_bit_in_any_order"],
    ),
    (
        "dispatch_args",
        &["dispatch_args_match_the_host_fold_and_the_cpu_mirror"],
    ),
    (
        "proximity",
        &[
            "proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_pressed_sheets",
            "proximity_matches_cpu_mirror_and_the_cpu_pipeline_on_a_folded_sheet",
            "proximity_reads_a_topology_split_over_several_bindings",
        ],
    ),
    (
        "apply_moves",
        &[
            "apply_moves_matches_cpu_mirror_in_every_mode",
            "clamp_loop_matches_the_cpu_pipeline_on_pressed_sheets",
            "clamp_loop_matches_the_cpu_pipeline_on_a_folded_sheet",
        ],
    ),
    (
        "moving_entries",
        &[
            "moving_entries_match_the_cpu_mirror_and_the_hosts_rings",
            "moving_entries_read_a_topology_split_over_several_bindings",
        ],
    ),
    (
        "backstop_filter",
        &["backstop_filter_matches_cpu_mirror_and_keeps_every_crossing"],
    ),
    (
        "vertex_normals",
        &[
            "vertex_normals_match_cpu_mirror_and_the_mesh",
            "vertex_normals_read_a_topology_split_over_several_bindings",
        ],
    ),
    (
        "moved_normals",
        &[
            "moved_normals_match_cpu_mirror_and_the_mesh",
            "moved_normals_read_a_topology_split_over_several_bindings",
        ],
    ),
    (
        "overlay_members",
        &["overlay_members_file_the_moved_entries_as_the_cpu_mirror_does"],
    ),
    (
        "overlay_keys",
        &["overlay_tables_rebuilt_from_slots_match_the_cpu_chain_and_the_host_filing"],
    ),
    (
        "overlay_entries",
        &["overlay_tables_rebuilt_from_slots_match_the_cpu_chain_and_the_host_filing"],
    ),
    (
        "longest_move",
        &["longest_move_matches_the_cpu_mirror_at_awkward_sizes"],
    ),
    ("sample_gate", &["sample_gate_stages_match_the_cpu_mirror"]),
    (
        "moved_edges",
        &[
            "moved_edges_grow_the_edge_bound_as_the_cpu_mirror_and_the_pipeline_do",
            "moved_edges_read_a_topology_split_over_several_bindings",
        ],
    ),
];

/// The sources of the parity tests: `folder/main.rs` and each module it declares (a file the
/// test target does not declare runs nothing, so its tests do not count).
fn parity_sources(folder: &Path) -> Vec<String> {
    let read = |file: &str| {
        let path = folder.join(file);
        std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
    };
    let main = read("main.rs");
    let modules: Vec<String> = main
        .lines()
        .filter_map(|l| l.trim().strip_prefix("mod ")?.strip_suffix(';'))
        .map(|module| read(&format!("{module}.rs")))
        .collect();
    assert!(!modules.is_empty(), "{}: no modules", folder.display());
    std::iter::once(main).chain(modules).collect()
}

#[test]
fn every_kernel_has_a_cpu_mirror_and_a_parity_test() {
    // docs/gpu.md: every kernel in `wgsl/` has a mirror of the same name in `src/cpu/` (a module
    // of `slayer::cpu`: declared, so the crate would not build without the file) and at least
    // one parity test, and every test named here is a test.
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let cpu_mod = std::fs::read_to_string(root.join("src/cpu/mod.rs")).unwrap();
    let parity = parity_sources(&root.join("tests/gpu_parity"));
    for name in wgsl_files(&root.join("wgsl")) {
        assert!(
            cpu_mod.lines().any(|l| l.trim() == format!("mod {name};")),
            "wgsl/{name}.wgsl has no CPU mirror: src/cpu/mod.rs declares no `mod {name};`"
        );
        let tests = PARITY_TESTS
            .iter()
            .find(|(kernel, _)| *kernel == name)
            .map(|(_, tests)| *tests)
            .unwrap_or_else(|| panic!("wgsl/{name}.wgsl has no parity test in PARITY_TESTS"));
        assert!(!tests.is_empty(), "{name}: no parity test named");
        for test in tests {
            let declared = format!("#[test]\nfn {test}()");
            assert!(
                parity.iter().any(|source| source.contains(&declared)),
                "{name}: no module of tests/gpu_parity/ has a test `{test}`"
            );
        }
    }
    for (kernel, _) in PARITY_TESTS {
        assert!(
            KERNELS.iter().any(|(k, _)| k == kernel),
            "PARITY_TESTS names `{kernel}`, which is not a kernel"
        );
    }
}

#[test]
fn unknown_imports_are_reported() {
    let error = expand_imports("x", "#import shared/nope\n").unwrap_err();
    assert!(error.to_string().contains("shared/nope"));
}

/// Size and member offsets of a named struct in a kernel or render shader, per naga.
fn naga_struct(shader: &str, name: &str) -> (u32, Vec<(String, u32)>) {
    let source = match shader.strip_prefix("render/") {
        Some(render) => render_source(render).unwrap(),
        None => kernel_source(shader).unwrap(),
    };
    let kernel = shader;
    let (module, _) = validate(kernel, &source).unwrap();
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{kernel}: no struct {name}"));
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let offsets = members
        .iter()
        .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
        .collect();
    (layouter[handle].size, offsets)
}

/// Checks a host struct (in scope by its bare name) against the WGSL struct of the same name.
macro_rules! assert_layout {
    ($shader:expr, $ty:ident { $($field:ident),* $(,)? }) => {{
        let (size, offsets) = naga_struct($shader, stringify!($ty));
        assert_eq!(size as usize, std::mem::size_of::<$ty>(), "size of {}", stringify!($ty));
        let host: Vec<(String, u32)> = vec![
            $((stringify!($field).to_string(), std::mem::offset_of!($ty, $field) as u32)),*
        ];
        assert_eq!(offsets, host, "field offsets of {}", stringify!($ty));
    }};
}

#[test]
fn host_structs_match_naga_layout() {
    assert_layout!(
        "cell_keys",
        CellKeyParams {
            count,
            table_mask,
            inv_cell_size,
            _pad
        }
    );
    for kernel in ["cell_counts", "scan", "scan_add", "scatter"] {
        assert_layout!(
            kernel,
            CountParams {
                count,
                _pad0,
                _pad1,
                _pad2
            }
        );
    }
}

#[test]
fn select_structs_match_naga_layout() {
    assert_layout!(
        "select",
        SelectParams {
            center,
            radius,
            cell_min,
            table_mask,
            cell_span,
            inv_cell_size,
            candidate_count,
            scan_vertices,
            falloff,
            blend_n,
            capacity,
            layer_count,
            drift,
            skip_marked,
            blend_inner,
            _pad0,
            _pad1,
            _pad2
        }
    );
    assert_layout!("select", SelectedVertex { vertex, weight });
    assert_layout!("deform", SelectedVertex { vertex, weight });
    assert_layout!("brush_frame", SelectedVertex { vertex, weight });
    assert_layout!(
        "brush_frame",
        FrameParams {
            center,
            inv_radius,
            capacity,
            _pad0,
            _pad1,
            _pad2
        }
    );
    assert_layout!(
        "dispatch_args",
        DispatchParams {
            workgroup_size,
            max_per_dimension,
            capacity,
            per_item
        }
    );
    assert_layout!(
        "deform",
        DeformParams {
            center,
            radius,
            normal,
            strength,
            plane_point,
            pressure,
            motion,
            share,
            kind,
            sign,
            capacity,
            frame
        }
    );
}

/// The value of a `u32` constant declared in a kernel (with its imports), per naga.
fn naga_constant(kernel: &str, name: &str) -> naga::Literal {
    let source = kernel_source(kernel).unwrap();
    let (module, _) = validate(kernel, &source).unwrap();
    let (_, constant) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{kernel}: no constant {name}"));
    match module.global_expressions[constant.init] {
        naga::Expression::Literal(literal) => literal,
        ref other => panic!("{kernel}: {name} is not a literal: {other:?}"),
    }
}

fn naga_u32_constant(kernel: &str, name: &str) -> u32 {
    match naga_constant(kernel, name) {
        naga::Literal::U32(value) => value,
        other => panic!("{kernel}: {name} is not a u32: {other:?}"),
    }
}

fn naga_f32_constant(kernel: &str, name: &str) -> f32 {
    match naga_constant(kernel, name) {
        naga::Literal::F32(value) => value,
        other => panic!("{kernel}: {name} is not an f32: {other:?}"),
    }
}

#[test]
fn wgsl_constants_match_the_host() {
    for (name, host) in [
        ("VERTEX_LOCKED", VertexFlags::LOCKED.bits()),
        ("VERTEX_MASKED", VertexFlags::MASKED.bits()),
        ("VERTEX_DEAD", VertexFlags::DEAD.bits()),
        ("INVALID", INVALID),
    ] {
        assert_eq!(naga_u32_constant("cell_counts", name), host, "{name}");
    }
    for (name, falloff) in [
        ("FALLOFF_BLEND", Falloff::blend(3)),
        ("FALLOFF_SMOOTH", Falloff::Smooth),
        ("FALLOFF_SPHERE", Falloff::Sphere),
        ("FALLOFF_LINEAR", Falloff::Linear),
    ] {
        assert_eq!(
            naga_u32_constant("select", name),
            falloff_code(falloff).0,
            "{name}"
        );
    }
    for (name, flag) in [
        ("FRAME_PLANE_FROM_SUMS", slayer::abi::FRAME_PLANE_FROM_SUMS),
        (
            "FRAME_NORMAL_FROM_SUMS",
            slayer::abi::FRAME_NORMAL_FROM_SUMS,
        ),
    ] {
        assert_eq!(naga_u32_constant("deform", name), flag, "{name}");
    }
    for kind in BrushKind::ALL {
        let name = format!("BRUSH_{}", kind.name().to_uppercase().replace('-', "_"));
        assert_eq!(
            naga_u32_constant("deform", &name),
            brush_code(kind),
            "{name}"
        );
    }
    for (name, mode) in [
        ("MODE_PLACE", ApplyMode::Place),
        ("MODE_PULL", ApplyMode::Pull),
        ("MODE_PULL_LAST", ApplyMode::PullLast),
        ("MODE_GATHER", ApplyMode::Gather),
        ("MODE_MARK_MOVED", ApplyMode::MarkMoved),
        ("MODE_CLEAR", ApplyMode::Clear),
    ] {
        assert_eq!(
            naga_u32_constant("apply_moves", name),
            mode as u32,
            "{name}"
        );
    }
    for (name, code) in [
        ("GATE_OPEN", GateStage::Open as u32),
        ("GATE_DECIDE", GateStage::Decide as u32),
        ("GATE_VACATE", GateStage::Vacate as u32),
        ("STOPPED_EARLIER", GateStatus::EARLIER),
        ("STOPPED_SELECTION", GateStatus::SELECTION),
        ("STOPPED_RINGS", GateStatus::RINGS),
        ("STOPPED_MOVE", GateStatus::MOVE),
        ("STOPPED_EDGES", GateStatus::EDGES),
    ] {
        assert_eq!(naga_u32_constant("sample_gate", name), code, "{name}");
    }
    assert_eq!(
        naga_f32_constant("proximity", "CLAMP_SLACK"),
        slayer::abi::CLAMP_SLACK
    );
    assert_eq!(
        naga_f32_constant("backstop_filter", "MARGIN"),
        slayer::abi::BACKSTOP_MARGIN
    );
    for kernel in ["proximity", "apply_moves"] {
        assert_eq!(
            naga_f32_constant(kernel, "PULL_SCALE"),
            slayer::abi::PULL_SCALE
        );
    }
    // One scan workgroup is one block on the host side.
    for kernel in ["scan", "scan_add"] {
        assert_eq!(naga_u32_constant(kernel, "WORKGROUP_SIZE"), SCAN_BLOCK);
    }
    // Kernels dispatched indirectly, and the gate's: the host sizes the dispatch with its own
    // constant, and a smaller one than the shader's would leave entries out without a word.
    let named = [
        ("brush_frame", slayer::abi::FRAME_WORKGROUP_SIZE),
        ("apply_moves", slayer::abi::APPLY_WORKGROUP_SIZE),
        ("proximity", slayer::abi::PROXIMITY_WORKGROUP_SIZE),
        ("backstop_filter", slayer::abi::BACKSTOP_WORKGROUP_SIZE),
        ("moving_entries", slayer::abi::ENTRIES_WORKGROUP_SIZE),
        ("longest_move", slayer::abi::GATE_WORKGROUP_SIZE),
        ("sample_gate", slayer::abi::GATE_WORKGROUP_SIZE),
    ];
    for (kernel, host) in named {
        assert_eq!(
            naga_u32_constant(kernel, "WORKGROUP_SIZE"),
            host,
            "{kernel}"
        );
    }
    // Every other kernel but `dispatch_args` (one invocation) runs the common size, in whose
    // workgroups the CPU mirrors walk the invocations.
    for (kernel, _) in KERNELS {
        if named.iter().any(|(k, _)| k == kernel)
            || ["scan", "scan_add", "dispatch_args"].contains(kernel)
        {
            continue;
        }
        let size = naga_u32_constant(kernel, "WORKGROUP_SIZE");
        assert_eq!(size, slayer::abi::WORKGROUP_SIZE, "{kernel}");
    }
}

#[test]
fn render_host_structs_match_naga_layout() {
    assert_layout!(
        "render/preview",
        RenderVertex {
            position,
            layer,
            normal,
            roughness,
            diffuse,
            mask,
            specular,
            _pad1
        }
    );
    assert_layout!(
        "render/preview",
        PreviewUniforms {
            view_proj,
            eye,
            key_direction,
            key_irradiance,
            fill_direction,
            fill_irradiance,
            sky,
            ground,
            wireframe,
            false_colour,
            line_width,
            hidden_layers,
            show_mask,
            _pad0,
            _pad1,
            _pad2,
            palette
        }
    );
}

#[test]
fn proximity_and_normal_structs_match_naga_layout() {
    assert_layout!(
        "proximity",
        ProximityParams {
            distance,
            cell_reach,
            vertex_reach,
            inv_cell_size,
            table_mask,
            count,
            vertex_rows_base,
            all_faces,
            span,
            cells_per_entry,
            overlay,
            overlay_mask,
            _pad0,
            _pad1
        }
    );
    // Every kernel that reads the moving list declares it alike.
    for kernel in [
        "proximity",
        "apply_moves",
        "moving_entries",
        "backstop_filter",
        "moved_normals",
        "overlay_members",
        "sample_gate",
        "moved_edges",
    ] {
        assert_layout!(
            kernel,
            MovingVertex {
                start,
                vertex,
                layer,
                ring_start,
                ring_end,
                _pad
            }
        );
    }
    assert_layout!(
        "apply_moves",
        ApplyParams {
            count,
            mode,
            next_invocations,
            _pad
        }
    );

    assert_layout!(
        "moving_entries",
        EntryParams {
            capacity,
            ring,
            ring_stride,
            vertex_rows_base
        }
    );
    assert_layout!("moving_entries", SelectedVertex { vertex, weight });

    assert_layout!(
        "backstop_filter",
        BackstopParams {
            cell_reach,
            vertex_reach,
            inv_cell_size,
            table_mask,
            count,
            vertex_rows_base,
            cells_per_entry,
            capacity,
            span,
            overlay,
            overlay_mask,
            face_reach,
            _pad1,
            _pad2
        }
    );
    for kernel in ["vertex_normals", "moved_normals"] {
        assert_layout!(
            kernel,
            NormalParams {
                count,
                vertex_rows_base,
                _pad0,
                _pad1
            }
        );
    }
    for kernel in ["longest_move", "sample_gate"] {
        assert_layout!(
            kernel,
            GateParams {
                capacity,
                stage,
                assumed_move,
                max_edge,
                defer_over,
                if_deferred,
                _pad0,
                _pad1
            }
        );
        assert_layout!(
            kernel,
            GateStatus {
                stopped,
                longest,
                edge,
                deferred
            }
        );
    }
    assert_layout!(
        "moved_edges",
        GateStatus {
            stopped,
            longest,
            edge,
            deferred
        }
    );
    assert_layout!(
        "moved_edges",
        NormalParams {
            count,
            vertex_rows_base,
            _pad0,
            _pad1
        }
    );
    assert_layout!("longest_move", SelectedVertex { vertex, weight });
    for kernel in ["overlay_members", "overlay_keys", "overlay_entries"] {
        assert_layout!(
            kernel,
            OverlayParams {
                count,
                room,
                table_mask,
                inv_cell_size
            }
        );
    }
}

#[test]
fn paged_kernels_declare_the_pages_and_the_shift_the_host_binds() {
    // A kernel with paged arrays has PAGE_COUNT read-only bindings in each bind group past 0
    // (the host binds that many per array, groups 1, 2, … in order) and the override the host
    // sets when it compiles the kernel.
    let expected_groups = [
        ("proximity", 2),
        ("backstop_filter", 1),
        ("vertex_normals", 1),
        ("moved_normals", 1),
        ("moved_edges", 1),
        ("deform", 1),
        ("moving_entries", 1),
    ];
    for (kernel, _) in KERNELS {
        let source = kernel_source(kernel).unwrap();
        let (module, _) = validate(kernel, &source).unwrap();
        let mut pages: Vec<(u32, u32)> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| g.binding.as_ref().map(|b| (b, g.space)))
            .filter(|(b, _)| b.group > 0)
            .map(|(b, space)| {
                assert_eq!(
                    space,
                    naga::AddressSpace::Storage {
                        access: naga::StorageAccess::LOAD
                    },
                    "{kernel}: pages are read-only storage"
                );
                (b.group, b.binding)
            })
            .collect();
        pages.sort();
        let overrides: Vec<&str> = module
            .overrides
            .iter()
            .filter_map(|(_, o)| o.name.as_deref())
            .collect();
        let groups = expected_groups
            .iter()
            .find(|(k, _)| k == kernel)
            .map_or(0, |&(_, g)| g);
        let expected: Vec<(u32, u32)> = (1..=groups)
            .flat_map(|g| (0..slayer::abi::PAGE_COUNT as u32).map(move |b| (g, b)))
            .collect();
        assert_eq!(pages, expected, "{kernel}: page bindings");
        if groups > 0 {
            assert_eq!(overrides, [slayer::abi::PAGE_SHIFT_CONSTANT], "{kernel}");
        } else {
            assert!(overrides.is_empty(), "{kernel}: {overrides:?}");
        }
    }
}

#[test]
fn paged_declarations_are_checked() {
    for bad in [
        "#paged",
        "#paged name",
        "#paged name 0",
        "#paged 9name 1",
        "#paged a b 1",
    ] {
        let error = expand_imports("x", bad).unwrap_err();
        assert!(
            error.to_string().contains("#paged NAME GROUP"),
            "{bad}: {error}"
        );
    }
    let error = expand_imports("x", "#import shared/paged_array").unwrap_err();
    assert!(error.to_string().contains("#paged"), "{error}");
    let expanded = expand_imports("x", "#paged rows 3").unwrap();
    assert!(expanded.contains("fn rows(i: u32) -> u32"), "{expanded}");
    assert!(expanded.contains("@group(3) @binding(3)"), "{expanded}");
    assert!(!expanded.contains("PAGED") && !expanded.contains("PAGE_GROUP"));
}
