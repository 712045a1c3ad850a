//! Every WGSL file parses and validates with naga: no GPU needed, a broken shader fails here.

use rae_core::kernels::{ROWS_STUB, SHADERS, STORAGE_SOURCES, STORAGE_WEIGHTS, UNIFORM_WEIGHTS, WITHOUT_SUBGROUPS, shader_source};

#[test]
fn every_shader_validates_with_naga() {
    assert!(SHADERS.len() >= 3);
    // The sources as written (conv3x3_rows.wgsl inside conv3x3.wgsl, the only way it is
    // used), and the rewrites kernels::Kernels::new makes (f16 storage textures, storage-buffer
    // weights, storage-texture sources; no subgroups, validated without the capability).
    let conv = shader_source("conv3x3");
    assert!(conv.contains(UNIFORM_WEIGHTS), "the weight declaration Kernels::new rewrites");
    assert!(conv.contains(ROWS_STUB), "the empty accumulate_rows Kernels::conv replaces");
    let without_subgroups = WITHOUT_SUBGROUPS.iter().fold(conv.to_string(), |src, (from, to)| {
        assert!(src.contains(from), "conv3x3.wgsl has {from}");
        src.replace(from, to)
    });
    assert!(WITHOUT_SUBGROUPS.iter().all(|(from, _)| !without_subgroups.contains(from)), "no subgroup operation is left");
    let storage_sources = STORAGE_SOURCES.iter().fold(conv.to_string(), |src, (from, to)| {
        assert!(src.contains(from), "conv3x3.wgsl has {from}");
        src.replace(from, to)
    });
    let rewritten = [
        ("conv3x3 (two-column lanes)", conv.replace(ROWS_STUB, shader_source("conv3x3_rows"))),
        ("conv3x3 (storage sources, two-column lanes, f16)", storage_sources.replace(ROWS_STUB, shader_source("conv3x3_rows")).replace("rgba32float", "rgba16float")),
        ("conv3x3 (f16, storage weights)", conv.replace("rgba32float", "rgba16float").replace(UNIFORM_WEIGHTS, STORAGE_WEIGHTS)),
        ("conv3x3 (without subgroups)", without_subgroups),
    ];
    let all = SHADERS.iter().filter(|(n, _)| *n != "conv3x3_rows").map(|&(n, s)| (n, s.to_string())).chain(rewritten);
    for (name, source) in all {
        let source = source.as_str();
        let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
        let caps = if name.contains("without subgroups") { naga::valid::Capabilities::all() - naga::valid::Capabilities::SUBGROUP } else { naga::valid::Capabilities::all() };
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(&module)
            .unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
        assert!(module.entry_points.iter().any(|e| e.name == "main"), "{name}.wgsl has no `main`");
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
