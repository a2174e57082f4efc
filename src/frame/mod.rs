//! Frames (§3.3 direct light, §4.3 indirect light on screen): what both backends share to turn a
//! solved scene into an image — the camera, shadow maps, direct light, the splat/vertex
//! interpolation of indirect light, the CPU image formation and image files.

pub mod camera;
pub mod cpu;
pub mod direct;
pub mod edges;
pub mod emitters;
pub mod environment;
pub mod image;
pub mod lights;
pub mod shading;
pub mod shadow;
pub mod splat;
pub mod surfaces;

pub use image::Image;
