//! Library error type: every failure names the file (and where possible the field) it came from.

use std::path::PathBuf;

/// Errors returned by the antiradiance library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: cannot read file: {source}")]
    Io {
        /// File that failed.
        path: PathBuf,
        /// Underlying I/O error.
        source: std::io::Error,
    },
    /// The scene description is syntactically or semantically invalid.
    #[error("{path}: {message}")]
    Scene {
        /// Scene (TOML) file.
        path: PathBuf,
        /// What is wrong, naming the field.
        message: String,
    },
    /// A mesh (OBJ/MTL) is invalid.
    #[error("{path}: {message}")]
    Mesh {
        /// Mesh file.
        path: PathBuf,
        /// What is wrong, naming the face or vertex.
        message: String,
    },
    /// A solver or discretization setting is out of range.
    #[error("invalid setting `{field}`: {message}")]
    Setting {
        /// Setting name as written in the scene's `[solver]` table.
        field: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The requested discretization would need more memory than allowed.
    #[error("{what} need {needed_bytes} bytes, more than the {limit_bytes} bytes available; use fewer bins or a larger element size")]
    TooLarge {
        /// Which resource.
        what: String,
        /// Estimated size.
        needed_bytes: u64,
        /// Allowed size.
        limit_bytes: u64,
    },
    /// Linking would make more links than the link budget (`--max-links`); the plan
    /// ([`crate::engine::Prepared::new`]) coarsens the refinement and tries again.
    #[error("more than {budget} links (the link budget, --max-links, or what this machine's memory holds) for {elements} elements at τ = {oracle}; use a larger --max-links, solver.oracle or element size, or fewer bins")]
    LinkBudget {
        /// The budget.
        budget: u64,
        /// Leaf elements.
        elements: usize,
        /// The oracle's threshold τ.
        oracle: f64,
        /// Links this τ would make, as far as known (a sample's estimate, or a lower bound
        /// where linking stopped at the budget): fitting jumps τ by it.
        estimate: f64,
    },
    /// The GPU layer failed (a Vulkan call, named by its operation).
    #[error(transparent)]
    Gpu(#[from] crate::gpu::error::GpuError),
    /// The Vulkan device or driver lacks something the GPU solver needs.
    #[error("Vulkan device: {0}")]
    Device(String),
    /// An output file could not be written (or an image file read).
    #[error("{path}: {message}")]
    Output {
        /// File.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
    /// The solve produced values that cannot be trusted and no fallback recovered.
    #[error("numerical failure: {0}")]
    Numerical(String),
    /// A run option (command-line argument or API parameter) is out of range or inconsistent.
    #[error("{0}")]
    Invalid(String),
    /// A GLSL shader failed to compile; the message names the file and line.
    #[error("shader {file}: {message}")]
    Shader {
        /// Shader file under `glsl/`.
        file: String,
        /// Compiler output (`file:line: error: ...`).
        message: String,
    },
}

/// Result alias for the library.
pub type Result<T> = std::result::Result<T, Error>;
