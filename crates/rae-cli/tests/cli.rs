//! rae-cli as a user runs it.

use std::process::Command;

fn rae() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rae-cli"))
}

fn fixture(name: &str) -> String {
    format!("{}/../../tests/fixtures/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn info_describes_the_reference_network() {
    let out = rae().args(["info", &fixture("weights_full.safetensors")]).output().unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(text.contains("1504301"), "{text}");
    assert!(text.contains("73661 multiply-adds"), "{text}");
    assert!(text.contains("color, normal, depth, roughness"), "{text}");
}

#[test]
fn info_on_a_bad_file_names_it_and_fails() {
    let golden = fixture("golden_full_64x64.safetensors");
    let out = rae().args(["info", &golden]).output().unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("golden_full_64x64.safetensors") && err.contains("rae.arch"), "{err}");
}

#[test]
fn no_matching_adapter_says_how_to_install_lavapipe() {
    let out = rae()
        .args(["verify", &fixture("golden_paper_tiny_40x24.safetensors")])
        .env("WGPU_ADAPTER_NAME", "no-such-adapter-anywhere")
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8(out.stderr).unwrap();
    assert!(err.contains("mesa-vulkan-drivers") && err.contains("no-such-adapter-anywhere"), "{err}");
}
