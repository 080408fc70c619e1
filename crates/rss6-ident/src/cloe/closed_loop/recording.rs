//! What a primal run records for the sensitivity run that follows it: its stage calls and its
//! ticks' implicit friction steps.

use super::ahead::StageCall;
use crate::cloe::config::LoopConfig;
use rss6_core::{DynamicParams, Environment, FrictionStep, KinematicParams, Vec6};
use std::sync::Arc;

/// The stage calls of a primal run ([`super::simulate_recording`]), and its ticks' implicit friction
/// steps, for a sensitivity run with the same configuration (but for `state_jacobians`),
/// parameters and reference ([`super::simulate_from`]).
#[derive(Clone)]
pub struct Recording {
    pub(super) calls: Arc<[StageCall]>,
    /// Each call's IK angles and acceleration when the run knew them (the implicit law's ticks).
    pub(super) known: Arc<[Option<StageKnown>]>,
    pub(super) friction: Arc<[TickFriction]>,
    /// What the friction steps were solved with besides the state and torque.
    pub(super) model: FrictionModel,
}

/// A stage call's joint angles θ = IK(χ) and acceleration χ̈ as the primal run computed them
/// (`rss6_core::rk4_step_implicit_friction_observed`): its derivatives need neither computed
/// again ([`rss6_core::JacobianRequest::theta`], [`rss6_core::JacobianRequest::pose_ddot`]).
pub(super) type StageKnown = (Vec6, Vec6);

/// What a tick's friction step depends on besides the state (χ, χ̇) and the drive torque: a
/// recording's steps serve a sensitivity run only if these are equal. (A stage call needs no
/// such check: the sensitivity run's own model evaluates it; its recorded θ and χ̈ depend on the
/// same model and take the same check.)
#[derive(Clone, Copy, PartialEq)]
pub(super) struct FrictionModel {
    kp: KinematicParams,
    dp: DynamicParams,
    env: Environment,
    dt: f64,
}

impl FrictionModel {
    pub(super) fn of(cfg: &LoopConfig, dp: &DynamicParams) -> Self {
        FrictionModel {
            kp: cfg.kp,
            dp: *dp,
            env: cfg.environment(),
            dt: cfg.dt,
        }
    }
}

impl std::fmt::Debug for Recording {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "Recording({} stage calls, {} friction steps)",
            self.calls.len(),
            self.friction.len()
        )
    }
}

/// What a primal run records: its stage calls and its ticks' friction steps.
pub(super) struct Recorder {
    pub(super) calls: Vec<StageCall>,
    pub(super) known: Vec<Option<StageKnown>>,
    pub(super) friction: Vec<TickFriction>,
}

impl Recorder {
    /// Room for the run's four stage calls per tick and, under the implicit law, one friction
    /// step per tick (≈ 1.8 KB per tick in all: no regrowth copies in the run).
    pub(super) fn for_run(cfg: &LoopConfig) -> Self {
        let ticks = (cfg.duration / cfg.dt).round() as usize + 1;
        Recorder {
            calls: Vec::with_capacity(4 * ticks),
            known: Vec::with_capacity(4 * ticks),
            friction: Vec::with_capacity(if cfg.implicit_friction { ticks } else { 0 }),
        }
    }
}

/// One tick's implicit friction step in a primal run, with the state (χ, χ̇) and drive torque τ_a
/// it was solved at.
#[derive(Debug, Clone, Copy)]
pub(super) struct TickFriction {
    pub(super) p: Vec6,
    pub(super) v: Vec6,
    pub(super) drive: Vec6,
    pub(super) step: FrictionStep,
}
