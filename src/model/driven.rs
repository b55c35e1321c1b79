//! A model under a drive: the [`HybridSystem`] the integrators step.

use std::marker::PhantomData;

use nalgebra::SVector;

use crate::drive::Excitation;
use crate::ode::HybridSystem;

use super::{Mode, Model};

/// A model of dimension `N` driven by the base acceleration `drive` (see [`super`]).
#[derive(Debug, Clone)]
pub struct Driven<'m, M, E, const N: usize> {
    /// The model.
    pub model: &'m M,
    /// The base acceleration.
    pub drive: E,
    dim: PhantomData<[(); N]>,
}

impl<'m, M: Model<N>, E, const N: usize> Driven<'m, M, E, N> {
    /// `model` under `drive`.
    pub fn new(model: &'m M, drive: E) -> Self {
        Self {
            model,
            drive,
            dim: PhantomData,
        }
    }

    /// The same model under another drive.
    pub fn with_drive<F>(&self, drive: F) -> Driven<'m, M, F, N> {
        Driven::new(self.model, drive)
    }
}

impl<M: Model<N>, E: Excitation, const N: usize> HybridSystem for Driven<'_, M, E, N> {
    type State = SVector<f64, N>;
    type Mode = Mode;

    #[inline(always)]
    fn guard_count(&self) -> usize {
        self.model.guard_count()
    }

    #[inline(always)]
    fn rhs(&self, mode: Mode, t: f64, y: &SVector<f64, N>) -> SVector<f64, N> {
        self.model.rhs(mode, y, self.drive.accel(t))
    }

    #[inline(always)]
    fn guards(&self, mode: Mode, t: f64, y: &SVector<f64, N>, g: &mut [f64]) {
        self.model.guards(mode, y, || self.drive.accel(t), g)
    }

    #[inline]
    fn switch(&self, mode: Mode, index: usize, t: f64, y: &mut SVector<f64, N>) -> Mode {
        self.model.switch(mode, index, y, self.drive.accel(t))
    }

    #[inline(always)]
    fn next_breakpoint(&self, t: f64) -> f64 {
        self.drive.next_breakpoint(t)
    }

    fn check_state(&self, mode: Mode, t: f64, y: &SVector<f64, N>) -> Result<(), String> {
        self.model
            .check_state(mode, y)
            .map_err(|m| format!("at t = {t:e} s: {m}"))
    }
}
