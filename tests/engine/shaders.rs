//! Every WGSL file parses and validates with naga: no GPU needed, a broken shader fails here.

use rae_core::kernels::{
    LanesModule, MMA_ENABLE, MMA_WORKGROUP_BYTES, PREP_WITHOUT_SUBGROUPS, ROWS_STUB, SHADERS, STORAGE_SOURCES, STORAGE_WEIGHTS,
    SourceAccess, UNIFORM_WEIGHTS, WARP_F16, WITHOUT_SUBGROUPS, conv_module_source, lanes_module_source, mma_source, shader_source,
};

/// `src` (from `file`) with each of `rewrites` made, each of which must find its text.
fn apply(src: String, file: &str, rewrites: &[(&str, &str)]) -> String {
    rewrites.iter().fold(src, |src, (from, to)| {
        assert!(src.contains(from), "{file} has {from}");
        src.replace(from, to)
    })
}

#[test]
fn every_shader_validates_with_naga() {
    assert!(SHADERS.len() >= 3);
    // The sources as written (conv3x3_rows.wgsl, conv3x3_wino.wgsl and conv3x3_wino4.wgsl inside conv3x3.wgsl,
    // the only way they are used), and the rewrites kernels::Kernels::new makes (f16 storage textures, storage-buffer
    // weights, storage-texture sources, 64-bit staged stores; no subgroups, validated without the capability).
    // The conv kernels as modules are made: with conv_common.wgsl and carve.wgsl appended.
    let conv = conv_module_source("conv3x3");
    let conv = conv.as_str();
    assert!(conv.contains(UNIFORM_WEIGHTS), "the weight declaration Kernels::new rewrites");
    assert!(conv.contains(ROWS_STUB), "the empty accumulate_rows Kernels::conv replaces");
    let without_subgroups = apply(conv.to_string(), "conv3x3.wgsl", &WITHOUT_SUBGROUPS);
    assert!(WITHOUT_SUBGROUPS.iter().all(|(from, _)| !without_subgroups.contains(from)), "no subgroup operation is left");
    let storage_sources = apply(conv.to_string(), "conv3x3.wgsl", &STORAGE_SOURCES);
    let prep_without_subgroups = apply(conv_module_source("prep"), "prep.wgsl", &PREP_WITHOUT_SUBGROUPS);
    assert!(!prep_without_subgroups.contains("subgroupMax("), "no subgroup operation is left in prep");
    let rewritten = [
        ("prep (without subgroups)", prep_without_subgroups),
        ("motion (f16 activations)", apply(shader_source("motion").to_string(), "motion.wgsl", &WARP_F16)),
        ("conv3x3 (lanes tiles)", lanes_module_source(conv, SourceAccess::Sampled, LanesModule::default())),
        (
            "conv3x3 (storage sources, lanes tiles, f16)",
            lanes_module_source(&storage_sources, SourceAccess::Storage, LanesModule::default()).replace("rgba32float", "rgba16float"),
        ),
        // The staged stores in 64-bit words (conv3x3_stage64.wgsl in place of stage_row).
        (
            "conv3x3 (storage sources, lanes tiles, 64-bit staged stores)",
            lanes_module_source(&storage_sources, SourceAccess::Storage, LanesModule { wide_stores: true, ..Default::default() }),
        ),
        // Two sources: the F(4x4) step in a loop per source (kernels::TWO_SOURCE_LOOPS).
        (
            "conv3x3 (lanes tiles, two sources)",
            lanes_module_source(conv, SourceAccess::Sampled, LanesModule { two_sources: true, ..Default::default() }),
        ),
        (
            "conv3x3 (storage sources, lanes tiles, two sources, 64-bit staged stores)",
            lanes_module_source(
                &storage_sources,
                SourceAccess::Storage,
                LanesModule { wide_stores: true, two_sources: true, ..Default::default() },
            ),
        ),
        // Gathers for 8-lane subgroups (conv3x3_gather8.wgsl in place of conv3x3_gather16.wgsl).
        (
            "conv3x3 (storage sources, lanes tiles, two sources, 64-bit staged stores, 8-lane gathers)",
            lanes_module_source(
                &storage_sources,
                SourceAccess::Storage,
                LanesModule { wide_stores: true, two_sources: true, gathers8: true },
            ),
        ),
        (
            "conv3x3 (lanes tiles, 8-lane gathers)",
            lanes_module_source(conv, SourceAccess::Sampled, LanesModule { gathers8: true, ..Default::default() }),
        ),
        ("conv3x3 (f16, storage weights)", conv.replace("rgba32float", "rgba16float").replace(UNIFORM_WEIGHTS, STORAGE_WEIGHTS)),
        ("conv3x3 (without subgroups)", without_subgroups),
    ];
    // conv3x3_mma.wgsl as written (`mma_emulated`) and with the cooperative-matrix entry point
    // (conv3x3_mma_coop.wgsl, only used inside it), both with storage-texture sources and f16.
    let mma = shader_source("conv3x3_mma");
    assert!(mma.contains(MMA_ENABLE), "the enable mma_source extends");
    let storage_mma = |src: String| apply(src, "conv3x3_mma.wgsl", &STORAGE_SOURCES);
    let mma_rewritten = [
        ("conv3x3_mma (matrix units)", mma_source(true)),
        ("conv3x3_mma (matrix units, storage sources, f16)", storage_mma(mma_source(true)).replace("rgba32float", "rgba16float")),
        ("conv3x3_mma (emulated, storage sources, f16)", storage_mma(mma_source(false)).replace("rgba32float", "rgba16float")),
    ];
    let all = SHADERS
        .iter()
        .filter(|(n, _)| {
            ![
                "conv3x3_rows",
                "conv3x3_wino",
                "conv3x3_wino4",
                "conv3x3_gather16",
                "conv3x3_gather8",
                "conv3x3_stage64",
                "conv3x3_mma_coop",
                "conv_common",
                "input_policy",
                "carve",
            ]
            .contains(n)
        })
        .map(|&(n, _)| (n, conv_module_source(n)))
        .chain(rewritten)
        .chain(mma_rewritten);
    for (name, source) in all {
        let source = source.as_str();
        let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
        let caps = if name.contains("without subgroups") {
            naga::valid::Capabilities::all() - naga::valid::Capabilities::SUBGROUP
        } else {
            naga::valid::Capabilities::all()
        };
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
        let entries: &[&str] = if name.starts_with("motion") {
            &["motion_in", "motion_down", "warp", "guide_store"]
        } else if name.starts_with("conv3x3_mma") {
            &["mma_emulated", "mma_split_emulated"]
        } else if name.contains("lanes tiles") {
            &["main", "lanes", "winograd_lanes", "winograd4_lanes"]
        } else {
            &["main"]
        };
        for entry in entries {
            assert!(module.entry_points.iter().any(|e| e.name == *entry), "{name}.wgsl has no `{entry}`");
        }
    }
}

#[test]
fn the_matrix_unit_kernel_translates_to_spirv() {
    // What wgpu does with conv3x3_mma.wgsl on a device with cooperative matrices (none here):
    // the module validates, the entry points `mma` and `mma_split` use cooperative matrices,
    // and naga's SPIR-V writer emits them with the cooperative-matrix capability and the
    // Vulkan memory model, once for every tile width (the override NT) and split mode, as the
    // pipeline's constants set them.
    let source = mma_source(true);
    let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
    assert!(module.entry_points.iter().any(|e| e.name == "mma"), "the cooperative entry point");
    assert!(module.types.iter().any(|(_, t)| matches!(t.inner, naga::TypeInner::CooperativeMatrix { .. })), "cooperative matrix types");
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
    let plain = (1..=4).map(|nt| ("mma", nt, false, false));
    let split = (1..=2).flat_map(|nt| [true, false].map(|split_a| ("mma_split", nt, true, split_a)));
    for (entry, nt, split, split_a) in plain.chain(split) {
        let case = format!("{entry} NT = {nt} SPLIT_A = {split_a}");
        let constants: naga::back::PipelineConstants =
            [("NT", nt as f64), ("SPLIT", split as u32 as f64), ("SPLIT_A", split_a as u32 as f64)]
                .into_iter()
                .map(|(k, v)| (k.to_string(), v))
                .collect();
        let (module, info) = naga::back::pipeline_constants::process_overrides(&module, &info, None, &constants).unwrap();
        let options = naga::back::spv::Options { lang_version: (1, 3), ..Default::default() };
        let pipeline = naga::back::spv::PipelineOptions { shader_stage: naga::ShaderStage::Compute, entry_point: entry.to_string() };
        let words = naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline)).unwrap_or_else(|e| panic!("{case}: {e}"));
        // OpCapability CooperativeMatrixKHR (6022) and OpMemoryModel Logical Vulkan (3).
        let has = |op: u32, operands: &[u32]| {
            words.windows(1 + operands.len()).any(|w| w[0] == ((1 + operands.len() as u32) << 16 | op) && w[1..] == *operands)
        };
        assert!(has(17, &[6022]), "{case}: OpCapability CooperativeMatrixKHR");
        assert!(has(14, &[0, 3]), "{case}: OpMemoryModel Logical Vulkan");
    }
}

#[test]
fn each_matrix_unit_entry_point_uses_only_its_workgroup_memory() {
    // Workgroup memory is the sum of the workgroup arrays an entry point uses, the byte count
    // ConvPlan checks against the device's limit: the split entry points keep their
    // remainders inside the window array (a second array made them 2.5x slower on the H100,
    // `docs/perf/h100-2026-11-24-s15.log`), so every entry point uses the same.
    let source = mma_source(true);
    let module = naga::front::wgsl::parse_str(&source).unwrap_or_else(|e| panic!("{}", e.emit_to_string(&source)));
    let info =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all()).validate(&module).unwrap();
    let workgroup: Vec<_> = module.global_variables.iter().filter(|(_, g)| g.space == naga::AddressSpace::WorkGroup).collect();
    let bytes = |entry: &str| -> (u32, Vec<String>) {
        let at = module.entry_points.iter().position(|e| e.name == entry).unwrap_or_else(|| panic!("no `{entry}`"));
        let used: Vec<_> = workgroup.iter().filter(|(h, _)| !info.get_entry_point(at)[*h].is_empty()).collect();
        let size = used.iter().map(|(_, g)| module.types[g.ty].inner.size(module.to_ctx())).sum();
        (size, used.iter().map(|(_, g)| g.name.clone().unwrap_or_default()).collect())
    };
    for entry in ["mma", "mma_emulated", "mma_split", "mma_split_emulated"] {
        let (size, names) = bytes(entry);
        assert_eq!(size, MMA_WORKGROUP_BYTES, "{entry} uses {names:?}");
        assert_eq!(names, ["win", "stage"], "{entry}");
    }
}

#[test]
fn shader_table_covers_the_shaders_folder() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "wgsl") {
            let stem = path.file_stem().unwrap().to_str().unwrap();
            assert!(SHADERS.iter().any(|(n, _)| *n == stem), "{} is not in kernels::SHADERS", path.display());
        }
    }
}
