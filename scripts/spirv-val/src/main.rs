//! SPIR-V of every kernel as wgpu would make it on Vulkan, through SPIRV-Tools' validator.
//!
//! Each shader of `rae_core::kernels::SHADERS` (conv3x3_mma.wgsl with the cooperative-matrix
//! entry points, as on a device with matrix units; f32 and f16 storage, sampled and storage
//! sources; every tile width NT, plain and split) is parsed and validated by naga with every capability, its
//! overrides set, and each entry point written as SPIR-V 1.3 and validated for Vulkan 1.3.
//! Exits non-zero on the first invalid module.

use rae_core::kernels::{SHADERS, STORAGE_SOURCES, conv_module_source, mma_source};
use spirv_tools::val::Validator;

/// Drop the ArrayStride decorations of sized arrays outside structs: naga puts them on
/// workgroup and function arrays too, which validators since 2025 refuse (VUID-StandaloneSpirv-None-10684) and drivers
/// ignore; every other rule is checked.
fn strip_array_strides(w: Vec<u32>) -> Vec<u32> {
    let ops = |w: &[u32]| {
        let mut v = Vec::new();
        let mut i = 5;
        while i < w.len() {
            let n = (w[i] >> 16) as usize;
            v.push(i..i + n);
            i += n;
        }
        v
    };
    // Sized arrays (OpTypeArray) that no struct (OpTypeStruct) holds: those of workgroup and
    // function variables; arrays inside a buffer's block keep their strides.
    let in_struct: std::collections::HashSet<u32> =
        ops(&w).into_iter().filter(|r| w[r.start] & 0xffff == 30).flat_map(|r| w[r.start + 2..r.end].to_vec()).collect();
    let sized: std::collections::HashSet<u32> =
        ops(&w).into_iter().filter(|r| w[r.start] & 0xffff == 28).map(|r| w[r.start + 1]).filter(|id| !in_struct.contains(id)).collect();
    let mut out = w[..5].to_vec();
    for r in ops(&w) {
        let op = w[r.start] & 0xffff;
        // OpDecorate id ArrayStride (6).
        if !(op == 71 && w[r.start + 2] == 6 && sized.contains(&w[r.start + 1])) {
            out.extend_from_slice(&w[r]);
        }
    }
    out
}

fn main() {
    let mut modules: Vec<(String, String, Vec<(&str, f64)>)> = Vec::new();
    for (name, _) in SHADERS {
        if ["conv3x3_rows", "conv3x3_wino", "conv3x3_mma", "conv3x3_mma_coop", "conv_common"].contains(name) {
            continue;
        }
        modules.push((name.to_string(), conv_module_source(name), vec![]));
    }
    for f16 in [false, true] {
        for storage in [false, true] {
            let mut src = mma_source(true);
            if storage {
                for (from, to) in STORAGE_SOURCES {
                    src = src.replace(from, to);
                }
            }
            if f16 {
                src = src.replace("rgba32float", "rgba16float");
            }
            for nt in 1..=4 {
                // Plain (MT 4) and split (MT 2, the activations split in f32), as ConvPlan sets
                // them.
                for split in [false, true] {
                    let label = format!(
                        "conv3x3_mma ({}, {} sources, NT = {nt}{})",
                        if f16 { "f16" } else { "f32" },
                        if storage { "storage" } else { "sampled" },
                        if split { ", SPLIT" } else { "" }
                    );
                    let mt = if split { 2.0 } else { 4.0 };
                    modules.push((
                        label,
                        src.clone(),
                        vec![
                            ("NT", nt as f64),
                            ("MT", mt),
                            ("MODE_A", 1.0),
                            ("MODE_B", 3.0),
                            ("SPLIT", split as u32 as f64),
                            ("SPLIT_A", (split && !f16) as u32 as f64),
                        ],
                    ));
                }
            }
        }
    }
    let validator = spirv_tools::val::create(Some(spirv_tools::TargetEnv::Vulkan_1_3));
    let mut checked = 0;
    for (label, src, constants) in modules {
        let module = naga::front::wgsl::parse_str(&src).unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(&src)));
        let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), naga::valid::Capabilities::all())
            .validate(&module)
            .unwrap_or_else(|e| panic!("{label}: {}", e.emit_to_string(&src)));
        let constants: naga::back::PipelineConstants = constants.into_iter().map(|(k, v)| (k.to_string(), v)).collect();
        let (module, info) = naga::back::pipeline_constants::process_overrides(&module, &info, None, &constants).unwrap();
        for entry in &module.entry_points {
            let options = naga::back::spv::Options { lang_version: (1, 3), ..Default::default() };
            let pipeline = naga::back::spv::PipelineOptions { shader_stage: entry.stage, entry_point: entry.name.clone() };
            let words = strip_array_strides(
                naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
                    .unwrap_or_else(|e| panic!("{label} {}: {e}", entry.name)),
            );
            match validator.validate(&words, None) {
                Ok(()) => println!("valid    {label} `{}` ({} words)", entry.name, words.len()),
                Err(e) => {
                    println!("INVALID  {label} `{}`: {e}", entry.name);
                    std::process::exit(1);
                }
            }
            checked += 1;
        }
    }
    println!("{checked} entry points valid");
}
