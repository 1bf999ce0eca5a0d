//! slayer — sculpting engine for detailed multi-layered materials.
//!
//! Layers of one triangle mesh are brushed together, collide instead of passing through each
//! other (sLayer, Algorithm 2), are remeshed to keep their detail uniform, and carry a per-vertex
//! BRDF. The hot loop runs as WGSL compute passes through wgpu, each mirrored on the CPU.
//!
//! Data flows one way: [`mesh`] ← [`grid`] ← [`collide`] ← the program.

pub mod abi;
pub mod app;
pub mod bench;
pub mod brush;
pub mod check;
pub mod codec;
pub mod collide;
pub mod cpu;
pub mod files;
pub mod geom;
pub mod gpu;
pub mod grid;
pub mod grow;
pub mod io;
pub mod material;
pub mod memory;
pub mod mesh;
pub mod pipeline;
pub mod remesh;
pub mod render;
pub mod scene;
pub mod session;
pub mod tools;
pub mod topology;
