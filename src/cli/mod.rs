//! The binary's parts: argument definitions, progress bars, the `animate` command and the
//! viewer's window.

pub mod animate;
pub mod args;
pub mod progress;
pub mod view;
