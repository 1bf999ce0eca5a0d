//! Every WGSL kernel against its CPU mirror, on the adapter the machine has (lavapipe in CI).
//! These tests never skip: a machine without any Vulkan adapter fails them, and
//! `tools/test.sh` installs lavapipe so that CI always has one.
//!
//! One module per kernel family, named as the kernels in `wgsl/` (`tests/wgsl.rs` checks that
//! each kernel names its parity tests here); `common` holds what they share.

mod apply_moves;
mod backstop_filter;
mod brush_frame;
mod common;
mod deform;
mod dispatch_args;
mod gate;
mod hash_table;
mod moving_entries;
mod overlay;
mod proximity;
mod select;
mod vertex_normals;
