//! Every WGSL file parses and validates with naga: no GPU needed, a broken shader fails here.

use rae_core::kernels::SHADERS;

#[test]
fn every_shader_validates_with_naga() {
    assert!(SHADERS.len() >= 3);
    for (name, source) in SHADERS {
        let module = naga::front::wgsl::parse_str(source).unwrap_or_else(|e| panic!("{name}.wgsl: {}", e.emit_to_string(source)));
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
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
