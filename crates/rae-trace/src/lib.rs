//! rae-trace: a unidirectional path tracer (next-event estimation, multiple importance
//! sampling, Russian roulette, GGX materials, a BVH) that renders noisy frames with auxiliary
//! buffers, motion vectors and references for rae, and shows how to embed rae-core.

pub mod geometry;
pub mod material;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod scenes;
pub mod texture;

pub use render::{Aux, FrameBuffers, Settings, render_frame};
pub use scene::Scene;
