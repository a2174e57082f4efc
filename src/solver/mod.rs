//! The f64 CPU solver: the specification of the discrete system the GPU passes run.
//!
//! One iteration is the four operations of §4.2 in order: [`global`] (eq. 16, the unoccluded
//! transport U over all links), [`push`] (interior nodes' gathered radiance down to the leaves),
//! [`local`] (eq. 18 reflection K and eq. 19 antiradiance J at the leaves) and [`pull`] (leaf
//! intensities summed into every ancestor). `I_ex` holds `I_L` in each leaf's front bins and
//! `-I_A` in its back bins (Fig. 6a), so one table carries radiance and antiradiance.

pub mod convergence;
pub mod extrapolate;
pub mod global;
pub mod local;
pub mod pull;
pub mod push;

use crate::scene::Scheme;
use crate::system::System;
use glam::DVec3;
use std::sync::Arc;

/// A table with one row per node and one RGB texel per bin (the layout of §4.1).
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// Bins per row.
    pub bins: usize,
    /// Texels, row-major: `data[row * bins + bin]`.
    pub data: Vec<DVec3>,
}

impl Table {
    /// A zero table of `rows × bins`.
    pub fn zeros(rows: usize, bins: usize) -> Self {
        Self {
            bins,
            data: vec![DVec3::ZERO; rows * bins],
        }
    }

    /// One row.
    pub fn row(&self, r: usize) -> &[DVec3] {
        &self.data[r * self.bins..(r + 1) * self.bins]
    }

    /// One row, mutable.
    pub fn row_mut(&mut self, r: usize) -> &mut [DVec3] {
        &mut self.data[r * self.bins..(r + 1) * self.bins]
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.len() / self.bins
    }
}

/// Which hemisphere a local pass updates (the asymmetric scheme alternates them).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LocalMode {
    /// Reflection (front bins) and antiradiance (back bins): the symmetric scheme.
    Both,
    /// Reflection only, eq. 13 (antiradiance frozen).
    Reflect,
    /// Antiradiance only, eq. 14 (radiance frozen).
    Antiradiance,
}

/// The CPU solver's tables and iteration record, without the system they belong to: what an
/// engine keeps between frames while the system may change (moving objects).
#[derive(Debug, Clone)]
pub struct CpuState {
    /// Exitant intensity `I_ex = I_L - I_A` per node and bin.
    pub i_ex: Table,
    /// Incident radiance gathered by the global pass, per node (before push).
    pub l_in: Table,
    /// Incident radiance after push: each row plus all its ancestors' rows.
    pub l_push: Table,
    /// Display intensity: front-bin intensity reflected from light arriving through links and
    /// the environment (emission and the first bounce of direct light are drawn per pixel).
    pub i_total: Table,
    /// Incident radiance from direct light (shadow-mapped, reflected but creating no
    /// antiradiance); set with [`CpuState::set_direct_in`].
    direct_in: Option<Table>,
    /// Its first bounce ([`local::direct_exitant`]), which the local pass adds to I_ex.
    direct_ex: Option<Table>,
    /// Incident environment radiance per leaf and bin, shadowed
    /// ([`crate::frame::environment::environment_in_table`]): reflected, creating no
    /// antiradiance; set with [`CpuState::set_environment_in`].
    environment_in: Option<Arc<Table>>,
    /// Its first bounce ([`local::direct_exitant`]), which the local pass adds to I_ex and
    /// I_total (the frame draws no environment light per pixel).
    environment_ex: Option<Table>,
    /// Relative change of `I_ex` at every iteration.
    pub residuals: Vec<f64>,
    /// Total exitant flux (W, mean of channels) of the leaves' front bins after every iteration.
    pub energies: Vec<f64>,
    /// Global passes run so far.
    pub propagations: usize,
    /// Whether antiradiance is computed ([`crate::plan::Features::antiradiance`]): off, the
    /// back bins stay zero and the asymmetric scheme runs only its reflection step.
    pub antiradiance: bool,
    /// Whether emission enters the bins ([`crate::plan::Features::emission`]): off where the
    /// area emitters' light comes from shadow-mapped samples as direct light (§3.3).
    pub emission: bool,
    /// Weight ω of a symmetric iteration's new iterate: `I_ex ← I_ex + ω (F(I_ex) − I_ex)`
    /// (1: the plain iteration). Damping keeps the fixed point and turns an eigenvalue λ of
    /// the iteration into `1 − ω(1 − λ)`: a scene whose antiradiance overshoots in alternating
    /// sign (λ < −1, a deep stack of boards) converges with ω < 2/(1 − λ).
    pub damping: f64,
}

impl CpuState {
    /// Sets the direct incident table (or none) and computes its first bounce
    /// ([`local::direct_exitant`]) once, for every local pass that follows.
    pub fn set_direct_in(&mut self, sys: &System, direct: Option<Table>) {
        self.direct_ex = direct.as_ref().map(|t| local::direct_exitant(sys, t));
        self.direct_in = direct;
    }

    /// Sets the shadowed environment's incident table (or none) and computes its first bounce
    /// once, as [`CpuState::set_direct_in`] does for direct light.
    pub fn set_environment_in(&mut self, sys: &System, environment: Option<Arc<Table>>) {
        self.environment_ex = environment.as_ref().map(|t| local::direct_exitant(sys, t));
        self.environment_in = environment;
    }

    /// The environment's first bounce per node and bin ([`CpuState::set_environment_in`]).
    pub fn environment_exitant(&self) -> Option<&Table> {
        self.environment_ex.as_ref()
    }

    /// The direct incident table, per node and bin ([`CpuState::set_direct_in`]).
    pub fn direct_in(&self) -> Option<&Table> {
        self.direct_in.as_ref()
    }

    /// The leaves' first bounce of the direct light ([`local::direct_exitant`]).
    pub fn direct_exitant(&self) -> Option<&Table> {
        self.direct_ex.as_ref()
    }

    /// Zero tables for `sys`, no light yet.
    pub fn new(sys: &System) -> Self {
        let (n, m) = (sys.rows(), sys.bins.count);
        Self {
            i_ex: Table::zeros(n, m),
            l_in: Table::zeros(n, m),
            l_push: Table::zeros(n, m),
            i_total: Table::zeros(n, m),
            direct_in: None,
            direct_ex: None,
            environment_in: None,
            environment_ex: None,
            residuals: Vec::new(),
            energies: Vec::new(),
            propagations: 0,
            antiradiance: true,
            emission: true,
            damping: 1.0,
        }
    }
}

/// The CPU solver: a [`CpuState`] operated on with the [`System`] it belongs to. Its fields
/// are the state's (through `Deref`).
#[derive(Debug, Clone)]
pub struct CpuSolver<'a> {
    /// The discretized scene.
    pub sys: &'a System,
    /// Tables and iteration record.
    pub state: CpuState,
}

impl std::ops::Deref for CpuSolver<'_> {
    type Target = CpuState;
    fn deref(&self) -> &CpuState {
        &self.state
    }
}

impl std::ops::DerefMut for CpuSolver<'_> {
    fn deref_mut(&mut self) -> &mut CpuState {
        &mut self.state
    }
}

impl<'a> CpuSolver<'a> {
    /// A solver with no light yet; call [`CpuSolver::set_environment`] and/or
    /// [`CpuSolver::set_direct`] before [`CpuSolver::initialize`].
    pub fn new(sys: &'a System) -> Self {
        Self::resume(sys, CpuState::new(sys))
    }

    /// Continues from `state` (made for `sys` or a system of the same shape). Its direct-light
    /// tables belong to the system they were set for: after a move, set them again
    /// ([`CpuState::set_direct_in`]), as the engine does.
    pub fn resume(sys: &'a System, state: CpuState) -> Self {
        Self { sys, state }
    }

    /// Sets the environment's shadowed incident radiance per leaf and bin
    /// ([`crate::frame::environment::environment_in_table`]): reflected, no antiradiance (§3.3).
    pub fn set_environment(&mut self, table: Option<Table>) {
        let sys = self.sys;
        self.state.set_environment_in(sys, table.map(Arc::new));
    }

    /// Hook for direct light (§3.3): `f(leaf_index, bin)` returns the incident radiance from
    /// analytic lights in that bin, already shadowed; it is reflected but creates no antiradiance.
    pub fn set_direct(&mut self, f: impl Fn(usize, usize) -> DVec3) {
        let mut t = Table::zeros(self.sys.rows(), self.sys.bins.count);
        for (li, leaf) in self.sys.leaves.iter().enumerate() {
            for (b, v) in t.row_mut(leaf.node as usize).iter_mut().enumerate() {
                *v = f(li, b);
            }
        }
        let sys = self.sys;
        self.state.set_direct_in(sys, Some(t));
    }

    /// Initial state: emission, reflected direct light and environment (a local pass with
    /// nothing gathered yet), then pull.
    pub fn initialize(&mut self) {
        self.l_in.data.fill(DVec3::ZERO);
        self.l_push.data.fill(DVec3::ZERO);
        local::local(self, LocalMode::Both);
        pull::pull(&self.sys.hierarchy, &mut self.state.i_ex);
        self.residuals.clear();
        self.energies.clear();
        self.propagations = 0;
    }

    /// One propagation: global, push, local (in `mode`), pull.
    pub fn propagate(&mut self, mode: LocalMode) {
        let st = &mut self.state;
        global::global(self.sys, &st.i_ex, &mut st.l_in);
        push::push(self.sys, &st.l_in, &mut st.l_push);
        local::local(self, mode);
        pull::pull(&self.sys.hierarchy, &mut self.state.i_ex);
        self.state.propagations += 1;
    }

    /// One iteration of `scheme`: symmetric = one propagation updating both hemispheres;
    /// asymmetric = one reflection step then `antiradiance_steps` antiradiance steps (eqs. 13–14).
    /// Records the residual and energy.
    pub fn iterate(&mut self, scheme: Scheme, antiradiance_steps: usize) {
        let before = self.i_ex.clone();
        match scheme {
            Scheme::Symmetric => {
                self.propagate(LocalMode::Both);
                let w = self.damping;
                if w != 1.0 {
                    // Clusters too: pull is linear, so this is the pull of the damped leaves.
                    for (x, b) in self.state.i_ex.data.iter_mut().zip(&before.data) {
                        *x = *b + (*x - *b) * w;
                    }
                }
            }
            Scheme::Asymmetric => {
                self.propagate(LocalMode::Reflect);
                let steps = if self.antiradiance {
                    antiradiance_steps
                } else {
                    0
                };
                for _ in 0..steps {
                    self.propagate(LocalMode::Antiradiance);
                }
            }
        }
        let r = convergence::change(self.sys, &before, &self.i_ex).relative;
        let e = self.exitant_flux();
        self.residuals.push(r);
        self.energies.push(e);
    }

    /// Initializes and runs `iterations` iterations of `scheme`.
    pub fn solve(&mut self, scheme: Scheme, iterations: usize, antiradiance_steps: usize) {
        self.initialize();
        for _ in 0..iterations {
            self.iterate(scheme, antiradiance_steps);
        }
    }

    /// Flux leaving all leaves through their front bins (mean of RGB).
    pub fn exitant_flux(&self) -> f64 {
        convergence::exitant_flux(self.sys, &self.i_ex)
    }

    /// Irradiance arriving at the front of leaf `li` (index into `sys.leaves`) from links,
    /// environment and direct light, as the local pass sees it.
    pub fn irradiance(&self, li: usize) -> DVec3 {
        let leaf = &self.sys.leaves[li];
        let n = leaf.node as usize;
        let mut e = DVec3::ZERO;
        for (b, c) in self.sys.bins.centers.iter().enumerate() {
            let cos = -c.dot(leaf.normal);
            if cos > 0.0 {
                let mut l = self.l_push.row(n)[b];
                for t in [self.direct_in.as_ref(), self.environment_in.as_deref()]
                    .into_iter()
                    .flatten()
                {
                    l += t.row(n)[b];
                }
                e += l * cos;
            }
        }
        e * self.sys.bins.omega * leaf.cos_norm
    }

    /// Outgoing radiance of leaf `li` in bin `b` (front bins; zero behind), emission included.
    pub fn radiance(&self, li: usize, b: usize) -> DVec3 {
        let leaf = &self.sys.leaves[li];
        let cos = self.sys.bins.centers[b].dot(leaf.normal);
        if cos <= 0.0 {
            return DVec3::ZERO;
        }
        self.i_ex.row(leaf.node as usize)[b] / (leaf.area * leaf.cos_norm * cos)
    }

    /// Radiosity (W/m²) leaving leaf `li`, from its front-bin intensities.
    pub fn radiosity(&self, li: usize) -> DVec3 {
        let leaf = &self.sys.leaves[li];
        let row = self.i_ex.row(leaf.node as usize);
        let s: DVec3 = self
            .sys
            .bins
            .centers
            .iter()
            .zip(row)
            .filter(|(c, _)| c.dot(leaf.normal) > 0.0)
            .map(|(_, v)| *v)
            .sum();
        s * self.sys.bins.omega / leaf.area
    }
}
