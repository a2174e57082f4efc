//! The binary's parts: argument definitions, one file per command (its flags and the call they
//! make), what the commands share, progress bars and the viewer's window.

pub mod animate;
pub mod args;
pub mod compare;
pub mod info;
pub mod output;
pub mod profile;
pub mod progress;
pub mod reference;
pub mod render;
pub mod study;
pub mod view;
