//! The binary's parts: argument definitions, progress bars and the viewer's window.

pub mod args;
pub mod progress;
pub mod view;
