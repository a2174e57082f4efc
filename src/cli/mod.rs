//! The binary's parts: argument definitions, progress bars and the `animate` command.

pub mod animate;
pub mod args;
pub mod progress;
