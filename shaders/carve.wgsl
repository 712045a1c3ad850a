// Where a value carved into the cells of an arena keeps channel block `layer` (rae-core
// graph::Place, kernels::Carve): an arena layer holds the 4^level cells of a level-`level`
// value, a 2^level x 2^level grid of images of the level's size in Morton order (cell k's
// column is k's even bits, its row its odd bits). Appended to the modules that read or write
// carved values (kernels::conv_module_source).

// A carve: x the first cell, y the level, z and w the level's width and height.
// Returns the cell's top-left texel (x, y) and its arena layer (z).
fn carved(c: vec4<u32>, layer: u32) -> vec3<u32> {
    let cell = c.x + layer;
    let shift = 2u * c.y;
    let k = cell & ((1u << shift) - 1u);
    return vec3<u32>(even_bits(k) * c.z, even_bits(k >> 1u) * c.w, cell >> shift);
}

// The even bits of k, packed: bit 2i becomes bit i.
fn even_bits(k: u32) -> u32 {
    var v = k & 0x55555555u;
    v = (v | (v >> 1u)) & 0x33333333u;
    v = (v | (v >> 2u)) & 0x0f0f0f0fu;
    v = (v | (v >> 4u)) & 0x00ff00ffu;
    return (v | (v >> 8u)) & 0x0000ffffu;
}
