//! The binary's parts: argument definitions and progress bars.

pub mod args;
pub mod progress;
