//! The output's temporal accumulation: rae-core's CPU reference against the vectors
//! weights-tool's is held to (tests/fixtures/accumulate_vectors.safetensors, written by
//! `python -m rae_weights golden`), and a denoiser built with it (shaders/accumulate.wgsl)
//! against its network's frames accumulated by the reference.

use rae_core::accumulate::{Accumulator, accumulate};
use rae_core::{Denoiser, FrameInputs, Options, Weights};
use safetensors::SafeTensors;

use crate::{fixture, gpu, vector_cases};

fn values(st: &SafeTensors, name: &str) -> (Vec<f32>, Vec<usize>) {
    let t = st.tensor(name).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(t.dtype(), safetensors::Dtype::F32, "{name}");
    (t.data().chunks_exact(4).map(|b| f32::from_le_bytes(b.try_into().unwrap())).collect(), t.shape().to_vec())
}

#[test]
fn accumulation_gives_the_shared_vectors_values() {
    let bytes = std::fs::read(fixture("accumulate_vectors.safetensors")).unwrap();
    let st = SafeTensors::deserialize(&bytes).unwrap();
    let cases = vector_cases(&st);
    assert!(cases.len() >= 4, "{cases:?}");
    for case in cases {
        let (current, shape) = values(&st, &format!("{case}.current"));
        let (previous, _) = values(&st, &format!("{case}.previous"));
        let (motion, _) = values(&st, &format!("{case}.motion"));
        let (expected, _) = values(&st, &format!("{case}.expected"));
        let (h, w) = (shape[0], shape[1]);
        let mut out = vec![f32::NAN; current.len()];
        accumulate(&current, &previous, &motion, w, h, &mut out);
        let mut kept = 0;
        for (i, (g, e)) in out.iter().zip(&expected).enumerate() {
            assert!((g - e).abs() <= 1e-5 * e.abs().max(1.0), "{case} value {i}: rae-core {g}, weights-tool {e}");
            kept += (g == &current[i]) as usize;
        }
        assert!(kept < out.len(), "{case}: some history is blended in");
    }
}

#[test]
fn a_denoiser_accumulates_its_frames_with_motion_and_starts_over_on_reset() {
    // The frames of a denoiser built with accumulation are its network's frames (a denoiser
    // without) accumulated by the CPU reference with their motion: frame 0 as it is, the next
    // ones blended; after a reset the history is gone. A frame without motion passes through.
    // The CPU and the GPU round differently: within 1e-5 of the larger of 1 and the value.
    let golden = crate::golden("golden_full_motion_64x64.safetensors");
    let weights = Weights::load(fixture(&golden.weights)).unwrap();
    let g = gpu();
    let (w, h) = (golden.width, golden.height);
    let build = |accumulate| {
        Denoiser::with_options(&g.device, &g.queue, &weights, w, h, Options { motion: true, accumulate, ..Default::default() }).unwrap()
    };
    let (mut plain, mut accumulating) = (build(false), build(true));
    assert_eq!(accumulating.gpu_bytes(), plain.gpu_bytes() + rae_core::denoiser::accumulate_bytes(w, h));
    let mut by_hand = Accumulator::new(w, h);
    assert!(golden.frames.len() >= 3 && golden.inputs(1).motion.is_some());
    // The second round's frame 1 has motion that is NaN, infinite, absurd and off screen at some
    // pixels: those keep the network's output.
    let mut hostile = golden.inputs(1).motion.unwrap().to_vec();
    for (k, v) in [f32::NAN, f32::INFINITY, -1e9, -100.0, 40.0].into_iter().enumerate() {
        hostile[2 * (k * 7 * w as usize + 3 * k) + k % 2] = v;
    }
    for round in 0..2 {
        for i in 0..3 {
            let frame = golden.inputs(i);
            let frame = match (round, i) {
                (_, 2) => FrameInputs { motion: None, ..frame },
                (1, 1) => FrameInputs { motion: Some(&hostile), ..frame },
                _ => frame,
            };
            let net = plain.denoise(&frame).unwrap();
            let mut want = net.clone();
            by_hand.apply(&mut want, frame.motion);
            let got = accumulating.denoise(&frame).unwrap();
            assert!(got.iter().all(|v| v.is_finite()), "round {round} frame {i}: finite");
            let worst = got.iter().zip(&want).map(|(g, w)| (g - w).abs() / w.abs().max(1.0)).fold(0.0f32, f32::max);
            assert!(worst <= 1e-5, "round {round} frame {i}: {worst:e} from the reference");
            // The first frame and a frame without motion pass through; frame 1 is blended.
            assert_eq!(got == net, i != 1, "round {round} frame {i}");
        }
        plain.reset();
        accumulating.reset();
        by_hand.reset();
    }
}
