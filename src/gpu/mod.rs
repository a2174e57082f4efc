//! The GPU design of §4 on Vulkan: tables as float16 (or float32) images, links as line
//! primitives with additive blending, push as quads, local-pass fragment shaders on ping-pong
//! images, pull as lines. See the README for the module ↔ paper map.

pub mod barrier;
pub mod blend16;
pub mod cache;
pub mod context;
mod device;
pub mod diagnostics;
pub mod error;
pub mod frame;
pub mod handle;
pub mod layout;
pub mod links;
pub mod memory;
pub mod pack;
pub mod passes;
pub mod pipelines;
pub mod profiler;
pub mod reduce;
pub mod resources;
pub mod shaders;
pub mod solver;
pub mod staged;
pub mod tables;
pub mod validation;
pub mod work;

pub use context::{Context, ContextOptions, HostDevice, LineMode};
pub use error::GpuError;
pub use solver::{GpuOptions, GpuSolver};
