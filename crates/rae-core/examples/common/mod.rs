//! What the conv examples (compile_cost, pad_cost) share: tile names on the command line and
//! the activation textures a conv is bound to.

use rae_core::kernels::{self, Tile, blocks};

/// The tile a name on the command line stands for: wino4lanesRxB, winolanesRxB, lanesRxB (two
/// columns), winoRxB, directRxB, mmaC or mmasC (C channels).
pub fn parse_tile(s: &str) -> Tile {
    if let Some(c) = s.strip_prefix("mmas") {
        return Tile::mma_split(c.parse().unwrap()).expect("an mma split tile");
    }
    if let Some(c) = s.strip_prefix("mma") {
        return Tile::mma(c.parse().unwrap()).expect("an mma tile");
    }
    let (method, rest) =
        ["wino4lanes", "winolanes", "lanes", "wino", "direct"].iter().find_map(|m| s.strip_prefix(m).map(|r| (*m, r))).expect("tile kind");
    let (r, b) = rest.split_once('x').expect("RxB");
    let (r, b): (u32, u32) = (r.parse().unwrap(), b.parse().unwrap());
    match method {
        "wino4lanes" => Tile::winograd4_lanes(r, b),
        "winolanes" => Tile::winograd_lanes(r, b),
        "wino" => Tile::winograd(r, b),
        "direct" => Tile::new(r, b),
        _ => Tile::lanes(r, b, 2),
    }
    .expect("a tile the kernels have")
}

/// A `w` x `h` activation texture of `channels`, viewed as the array a conv binds.
pub fn activation_view(device: &wgpu::Device, w: u32, h: u32, channels: usize) -> wgpu::TextureView {
    let t = device.create_texture(&wgpu::TextureDescriptor {
        label: None,
        size: wgpu::Extent3d { width: w, height: h, depth_or_array_layers: blocks(channels) },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: kernels::ACTIVATION_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
        view_formats: &[],
    });
    t.create_view(&wgpu::TextureViewDescriptor { dimension: Some(wgpu::TextureViewDimension::D2Array), ..Default::default() })
}
