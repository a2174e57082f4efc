//! The paper's method as a backend: the f64 CPU solver with a ray-cast frame ([`cpu`], the
//! specification) and the Vulkan raster passes with their raster frame ([`gpu`]).

pub mod cpu;
pub mod gpu;
