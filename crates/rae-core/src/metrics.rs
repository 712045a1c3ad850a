//! Error metrics of the field (see ../shared/PAPER.md): relMSE on radiance; PSNR and SSIM on
//! tonemapped images ([`crate::io::tonemap`]); temporal error on frame differences. Images are
//! RGB, `width * height * 3`, top row first.

use crate::io::tonemap;

/// mean((x - r)^2 / (r^2 + 0.01)) over all values.
pub fn relmse(x: &[f32], r: &[f32]) -> f64 {
    x.iter().zip(r).map(|(&a, &b)| ((a - b) as f64).powi(2) / ((b as f64).powi(2) + 0.01)).sum::<f64>() / x.len() as f64
}

/// PSNR in dB of the tonemapped images (peak 1).
pub fn psnr(x: &[f32], r: &[f32]) -> f64 {
    let mse = x.iter().zip(r).map(|(&a, &b)| ((tonemap(a) - tonemap(b)) as f64).powi(2)).sum::<f64>() / x.len() as f64;
    if mse == 0.0 { f64::INFINITY } else { -10.0 * mse.log10() }
}

fn luma(img: &[f32]) -> Vec<f64> {
    img.chunks_exact(3).map(|c| 0.2126 * tonemap(c[0]) as f64 + 0.7152 * tonemap(c[1]) as f64 + 0.0722 * tonemap(c[2]) as f64).collect()
}

/// Separable 11-tap Gaussian blur (sigma 1.5), edges clamped.
fn blur(v: &[f64], w: usize, h: usize) -> Vec<f64> {
    let k: Vec<f64> = (-5..=5).map(|i: i32| (-(i * i) as f64 / (2.0 * 1.5 * 1.5)).exp()).collect();
    let s: f64 = k.iter().sum();
    let k: Vec<f64> = k.iter().map(|x| x / s).collect();
    let mut tmp = vec![0.0; v.len()];
    for y in 0..h {
        for x in 0..w {
            tmp[y * w + x] = (0..11).map(|i| k[i] * v[y * w + (x as i64 + i as i64 - 5).clamp(0, w as i64 - 1) as usize]).sum();
        }
    }
    let mut out = vec![0.0; v.len()];
    for y in 0..h {
        for x in 0..w {
            out[y * w + x] = (0..11).map(|i| k[i] * tmp[(y as i64 + i as i64 - 5).clamp(0, h as i64 - 1) as usize * w + x]).sum();
        }
    }
    out
}

/// Mean SSIM (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5) of the tonemapped luminance.
pub fn ssim(x: &[f32], r: &[f32], width: u32, height: u32) -> f64 {
    let (w, h) = (width as usize, height as usize);
    let (a, b) = (luma(x), luma(r));
    let mul = |p: &[f64], q: &[f64]| p.iter().zip(q).map(|(x, y)| x * y).collect::<Vec<_>>();
    let (ma, mb) = (blur(&a, w, h), blur(&b, w, h));
    let (saa, sbb, sab) = (blur(&mul(&a, &a), w, h), blur(&mul(&b, &b), w, h), blur(&mul(&a, &b), w, h));
    let (c1, c2) = (0.01f64.powi(2), 0.03f64.powi(2));
    let total: f64 = (0..w * h)
        .map(|i| {
            let (va, vb, cov) = (saa[i] - ma[i] * ma[i], sbb[i] - mb[i] * mb[i], sab[i] - ma[i] * mb[i]);
            ((2.0 * ma[i] * mb[i] + c1) * (2.0 * cov + c2)) / ((ma[i] * ma[i] + mb[i] * mb[i] + c1) * (va + vb + c2))
        })
        .sum();
    total / (w * h) as f64
}

/// mean |(x_t - x_{t-1}) - (r_t - r_{t-1})| between two consecutive frames of a result and
/// its reference, on tonemapped values (so a firefly does not dominate).
pub fn temporal_error(x_prev: &[f32], x: &[f32], r_prev: &[f32], r: &[f32]) -> f64 {
    let n = x.len();
    (0..n).map(|i| ((tonemap(x[i]) - tonemap(x_prev[i])) - (tonemap(r[i]) - tonemap(r_prev[i]))).abs() as f64).sum::<f64>() / n as f64
}

/// The median of `values` (the upper one of an even count; NaN when empty), sorting them.
pub fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values.get(values.len() / 2).copied().unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_images_are_perfect_and_noise_is_not() {
        let (w, h) = (24u32, 17u32);
        let r: Vec<f32> = (0..w * h * 3).map(|i| 0.5 + 0.4 * ((i as f32) * 0.1).sin()).collect();
        assert_eq!(relmse(&r, &r), 0.0);
        assert!(psnr(&r, &r).is_infinite());
        assert!((ssim(&r, &r, w, h) - 1.0).abs() < 1e-9);
        let noisy: Vec<f32> = r.iter().enumerate().map(|(i, v)| v + if i % 7 == 0 { 0.5 } else { 0.0 }).collect();
        assert!(relmse(&noisy, &r) > 0.0 && psnr(&noisy, &r) < 40.0 && ssim(&noisy, &r, w, h) < 0.99);
        assert_eq!(temporal_error(&r, &r, &noisy, &noisy), 0.0, "equal motion in result and reference");
        assert!(temporal_error(&r, &noisy, &r, &r) > 0.0);
    }
}
