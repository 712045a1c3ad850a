//! rae-cli as a library: its command line and the `denoise` command, so that tools (the fuzz
//! harness in `fuzz/`) drive them as the binary does.

pub mod args;
pub mod denoise;
