//! Progress of the library's long steps (linking, iterations, path tracing), reported through a
//! trait the library calls and a front end implements (the CLI draws indicatif bars).

/// Progress of the long steps.
pub trait Progress {
    /// A step with `total` units of work begins.
    fn begin(&self, step: &str, total: u64);
    /// `n` more units are done.
    fn advance(&self, n: u64);
    /// The current step is done.
    fn end(&self);
}

/// Reports nothing.
pub struct Silent;

impl Progress for Silent {
    fn begin(&self, _: &str, _: u64) {}
    fn advance(&self, _: u64) {}
    fn end(&self) {}
}
