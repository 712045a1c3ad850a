//! Weights files: the fixtures load; every kind of broken file is a clear error naming the
//! tensor or the problem, never a panic.

use std::collections::HashMap;

use rae_core::graph::{Graph, Value};
use rae_core::{Arch, Error, Weights};
use safetensors::Dtype;
use safetensors::tensor::TensorView;

use crate::fixture;

/// One tensor of a weights file: name, dtype, shape, bytes.
type Tensor = (String, Dtype, Vec<usize>, Vec<u8>);

/// Tensors of a fixture, and its metadata.
fn parts(name: &str) -> (Vec<Tensor>, HashMap<String, String>) {
    let bytes = std::fs::read(fixture(name)).unwrap();
    let (_, meta) = safetensors::SafeTensors::read_metadata(&bytes).unwrap();
    let st = safetensors::SafeTensors::deserialize(&bytes).unwrap();
    let tensors = st.tensors().into_iter().map(|(n, t)| (n, t.dtype(), t.shape().to_vec(), t.data().to_vec())).collect();
    (tensors, meta.metadata().clone().unwrap())
}

fn build(tensors: &[Tensor], meta: Option<HashMap<String, String>>) -> Vec<u8> {
    let views: Vec<(String, TensorView)> =
        tensors.iter().map(|(n, d, s, b)| (n.clone(), TensorView::new(*d, s.clone(), b).unwrap())).collect();
    safetensors::serialize(views, meta).unwrap()
}

const TINY: &str = "weights_color_tiny.safetensors";

#[test]
fn fixtures_load_with_their_architecture() {
    let w = Weights::load(fixture("weights_full.safetensors")).unwrap();
    assert_eq!(w.arch, Arch::reference());
    assert_eq!(w.arch.parameter_count(), 1_504_301, "PAPER.md's parameter count");
    let macs = Graph::new(&w.arch).macs_per_pixel();
    assert!((macs - 73_661.0).abs() < 1.0, "PAPER.md's 73,661 multiply-adds per pixel, got {macs}");
    let t = w.get("u5.l1.1.weight").unwrap();
    assert_eq!(t.shape, vec![76, 202, 3, 3]);
    for name in ["weights_paper_tiny.safetensors", TINY] {
        Weights::load(fixture(name)).unwrap();
    }
}

#[test]
fn graph_names_match_pytorch_and_values_share_arenas() {
    for arch in [Arch::reference(), Weights::load(fixture("weights_paper_tiny.safetensors")).unwrap().arch] {
        let g = Graph::new(&arch);
        let names: Vec<&str> = g.nodes.iter().map(|n| n.name.as_str()).collect();
        assert_eq!(names.first(), Some(&"d1.l1.0"));
        assert_eq!(names.last(), Some(&"u1.l1.3"));
        assert_eq!(names.len(), 3 * (arch.levels() + 1) + 2 * arch.levels());
        let placed = g.place();
        // Every frame-local value: its lifetime (written, last read) and the texels of the
        // 64x64 frame's arenas it covers.
        let (w, h) = (64u32, 64u32);
        let last_read = |v: Value, from: usize| {
            g.nodes.iter().rposition(|n| n.a.value == v || n.b.is_some_and(|b| b.value == v)).unwrap_or(from).max(from)
        };
        let mut values = vec![(Value::Input, 0, last_read(Value::Input, 0))];
        values.extend(g.temps.iter().enumerate().map(|(t, i)| (Value::Temp(t), i.def, i.last_use)));
        values.extend(g.pools.iter().enumerate().map(|(k, p)| (Value::Pooled(k), p.after, last_read(Value::Pooled(k), p.after))));
        // Its cells: (arena, layer, x0, y0, x1, y1).
        let cells = |v: Value| {
            let p = placed.of(v).unwrap();
            let (cw, ch) = (w >> p.level, h >> p.level);
            (0..p.blocks)
                .map(|j| {
                    let (x, y, layer) = p.cell(j, w, h);
                    assert!(layer < placed.arena_layers[p.arena], "{v:?} block {j} inside its arena");
                    assert!(x + cw <= w && y + ch <= h, "{v:?} block {j}'s cell inside the layer");
                    (p.arena, layer, x, y, x + cw, y + ch)
                })
                .collect::<Vec<_>>()
        };
        let overlap = |a: Value, b: Value| {
            cells(a).iter().any(|c| cells(b).iter().any(|d| c.0 == d.0 && c.1 == d.1 && c.2 < d.4 && d.2 < c.4 && c.3 < d.5 && d.3 < c.5))
        };
        // Values live at once never share a texel; a conv never writes an arena it reads.
        for (i, &(a, da, la)) in values.iter().enumerate() {
            for &(b, db, lb) in &values[i + 1..] {
                if da <= lb && db <= la {
                    assert!(!overlap(a, b), "{a:?} and {b:?} are live at once and overlap");
                }
            }
        }
        for (i, n) in g.nodes.iter().enumerate() {
            let written: Vec<Value> = std::iter::once(n.out).chain(g.pools.iter().position(|p| p.after == i).map(Value::Pooled)).collect();
            for s in std::iter::once(n.a).chain(n.b) {
                for &out in &written {
                    if let (Some(r), Some(o)) = (placed.of(s.value), placed.of(out)) {
                        assert_ne!(r.arena, o.arena, "{} reads {:?} and writes {out:?} in one arena", n.name, s.value);
                    }
                }
            }
        }
    }
}

#[test]
fn the_least_live_memory_is_d1s_recurrent_conv_at_full_resolution() {
    // While d1.l2.0 runs, its two 32-channel sources (d1.l1.0's output and the old state) and
    // its output are live at full resolution beside every deeper block's state: the floor that
    // no sharing of textures by liveness goes below, and below what the denoiser allocates.
    let arch = Arch::reference();
    let g = Graph::new(&arch);
    let (w, h) = (1920u32, 1088u32);
    let (least, at) = g.least_live_bytes(w, h, 16);
    assert_eq!(g.nodes[at].name, "d1.l2.0");
    let level = |l: u32, channels: u64| (w >> l) as u64 * (h >> l) as u64 * channels.div_ceil(4) * 16;
    let deeper: u64 = g.hidden.iter().skip(1).map(|&(c, l)| level(l as u32, c as u64)).sum();
    assert_eq!(least, 3 * level(0, 32) + deeper);
    // The arenas reach it: the deeper levels' values take the cells of the first level's.
    let held = rae_core::denoiser::activation_bytes(&g, w, h, rae_core::Precision::F32, false);
    assert!(least <= held && held <= least + least / 20, "{held} bytes held, the floor {least}");
    // With the paper's skips (every shipped model's) the pooled values die young: the floor.
    let mut paper = arch.clone();
    paper.skip = rae_core::model::Skip::Prepool;
    let prepool = Graph::new(&paper);
    assert_eq!(rae_core::denoiser::activation_bytes(&prepool, w, h, rae_core::Precision::F32, false), prepool.least_live_bytes(w, h, 16).0);
    assert_eq!(g.least_live_bytes(w, h, 8).0 * 2, least, "f16 halves it");
}

#[test]
fn truncated_file_is_an_error() {
    let bytes = std::fs::read(fixture(TINY)).unwrap();
    for cut in [0, 7, 100, bytes.len() / 2, bytes.len() - 1] {
        let err = Weights::from_bytes(&bytes[..cut], "cut.safetensors").unwrap_err();
        assert!(matches!(err, Error::WeightsFormat { .. }), "cut at {cut}: {err}");
        assert!(err.to_string().contains("cut.safetensors"), "{err}");
    }
}

#[test]
fn missing_tensor_is_named() {
    let (mut t, meta) = parts(TINY);
    t.retain(|(n, ..)| n != "d3.l2.0.bias");
    let err = Weights::from_bytes(&build(&t, Some(meta)), "m.safetensors").unwrap_err();
    assert!(matches!(&err, Error::MissingTensor { name, .. } if name == "d3.l2.0.bias"), "{err}");
}

#[test]
fn wrong_shape_is_named() {
    let (mut t, meta) = parts(TINY);
    let e = t.iter_mut().find(|(n, ..)| n == "u2.l1.1.weight").unwrap();
    let (o, i) = (e.2[0], e.2[1]);
    e.2 = vec![i, o, 3, 3];
    let err = Weights::from_bytes(&build(&t, Some(meta)), "s.safetensors").unwrap_err();
    assert!(matches!(&err, Error::TensorShape { name, .. } if name == "u2.l1.1.weight"), "{err}");
    assert!(err.to_string().contains("u2.l1.1.weight"));
}

#[test]
fn mislabelled_file_is_refused() {
    // A tensor under a name the architecture does not have.
    let (mut t, meta) = parts(TINY);
    t.push(("d9.l1.0.bias".into(), Dtype::F32, vec![1], vec![0; 4]));
    let err = Weights::from_bytes(&build(&t, Some(meta.clone())), "x.safetensors").unwrap_err();
    assert!(matches!(&err, Error::UnexpectedTensor { name, .. } if name == "d9.l1.0.bias"), "{err}");
    // Weights of one network declared as another.
    let (t, _) = parts(TINY);
    let full = parts("weights_full.safetensors").1;
    let err = Weights::from_bytes(&build(&t, Some(full)), "y.safetensors").unwrap_err();
    assert!(matches!(err, Error::TensorShape { .. } | Error::MissingTensor { .. }), "{err}");
}

#[test]
fn unusable_dtype_and_non_finite_values_are_named() {
    let (mut t, meta) = parts(TINY);
    let e = t.iter_mut().find(|(n, ..)| n == "d1.l1.0.bias").unwrap();
    e.1 = Dtype::I32;
    let err = Weights::from_bytes(&build(&t, Some(meta.clone())), "d.safetensors").unwrap_err();
    assert!(matches!(&err, Error::TensorDtype { name, .. } if name == "d1.l1.0.bias"), "{err}");

    let (mut t, _) = parts(TINY);
    let e = t.iter_mut().find(|(n, ..)| n == "d1.l1.0.bias").unwrap();
    e.3[..4].copy_from_slice(&f32::NAN.to_le_bytes());
    let err = Weights::from_bytes(&build(&t, Some(meta)), "n.safetensors").unwrap_err();
    assert!(matches!(&err, Error::NonFiniteTensor { name, .. } if name == "d1.l1.0.bias"), "{err}");
}

#[test]
fn f16_weights_are_widened() {
    let (t, meta) = parts(TINY);
    let halves: Vec<_> = t
        .iter()
        .map(|(n, _, s, b)| {
            let h: Vec<u8> =
                b.chunks_exact(4).flat_map(|c| half::f16::from_f32(f32::from_le_bytes(c.try_into().unwrap())).to_le_bytes()).collect();
            (n.clone(), Dtype::F16, s.clone(), h)
        })
        .collect();
    let w16 = Weights::from_bytes(&build(&halves, Some(meta)), "h.safetensors").unwrap();
    let w32 = Weights::load(fixture(TINY)).unwrap();
    let (a, b) = (&w16.get("d2.l2.2.weight").unwrap().data, &w32.get("d2.l2.2.weight").unwrap().data);
    assert!(a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-3 * y.abs().max(1e-2)));
}

#[test]
fn missing_or_bad_architecture_is_an_error() {
    let (t, meta) = parts(TINY);
    let err = Weights::from_bytes(&build(&t, None), "a.safetensors").unwrap_err();
    assert!(matches!(err, Error::Arch { .. }), "{err}");
    let mut bad = meta.clone();
    let json = bad["rae.arch"].replace("\"color\"]", "\"color\", \"sparkle\"]");
    bad.insert("rae.arch".into(), json);
    let err = Weights::from_bytes(&build(&t, Some(bad)), "b.safetensors").unwrap_err();
    assert!(matches!(err, Error::Arch { .. }) && err.to_string().contains("sparkle"), "{err}");
    let mut bad = meta;
    let json = bad["rae.arch"].replace("\"version\": 1", "\"version\": 7");
    bad.insert("rae.arch".into(), json);
    let err = Weights::from_bytes(&build(&t, Some(bad)), "c.safetensors").unwrap_err();
    assert!(err.to_string().contains("version 7"), "{err}");
}
