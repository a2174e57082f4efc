//! antiradiance: global illumination with implicit visibility (Dachsbacher, Stamminger,
//! Drettakis, Durand, SIGGRAPH 2007).
//!
//! The rendering equation is rewritten with unoccluded transport **U** and a propagated
//! antiradiance that cancels light wrongly sent through occluders (eqs. 11–14), solved on a
//! hierarchy of finite elements with directional bins (§3). See the README for the map from the
//! paper's equations and passes to modules.

#![warn(missing_docs)]
// `!(x > 0.0)` is how the input checks reject NaN along with the out-of-range values; the
// lint would have them rewritten as partial_cmp matches that read worse.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod animate;
pub mod backend;
pub mod bins;
pub mod bound;
pub mod brdf;
pub mod clusters;
pub mod elements;
pub mod engine;
pub mod error;
pub mod filter;
pub mod frame;
pub mod gpu;
pub mod hierarchy;
pub mod info;
pub mod linker;
pub mod meshed;
pub mod methods;
pub mod metrics;
pub mod plan;
pub mod profile;
pub mod progress;
pub mod raycast;
pub mod reference;
pub mod scene;
pub mod settings;
pub mod solids;
pub mod solver;
pub mod study;
pub mod system;
pub mod trace;

pub use engine::{Engine, Options};
pub use error::{Error, Result};
pub use scene::Scene;
pub use settings::{BackendKind, Method, Precision, Scheme};
pub use solver::CpuSolver;
pub use system::System;
