//! Stages evaluated ahead, on all cores.
//!
//! A stage's derivatives (F_χ, F_χ̇, M̃⁻¹J_θᵀ, −M̃⁻¹J_θᵀΓ: most of the sensitivities' cost) depend
//! on the primal trajectory only, not on the sensitivities carried through the loop. So a primal
//! run (no sensitivities, one simulation's cost) records every stage call; a producer thread then
//! evaluates the calls in blocks, each block in parallel (rayon), while the sensitivity run takes
//! its stages from the blocks instead of evaluating them in turn. The same function evaluates a
//! stage either way, so the result is bit for bit the one of the sequential run; a call whose
//! inputs differ from the recorded one (which the loop's determinism rules out, checked anyway)
//! is evaluated in turn.

use super::stages::{Stage, StageModel};
use super::{Lean, StateJacobians};
use crate::error::Result;
use rayon::prelude::*;
use rss6_core::{ForwardJacobians, Mat6, Vec6};
use std::sync::mpsc::{Receiver, SyncSender};
use std::sync::Arc;

/// How a stage gets its state Jacobians F_χ, F_χ̇.
// A stack temporary, passed once per stage: its 576 bytes are not worth a box.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy)]
pub(super) enum StateJac {
    /// Evaluated at the stage (exact).
    Compute,
    /// Taken from the tick's first stage ([`super::StateJacobians::PerTick`]); `None` when that
    /// stage has none (no sensitivities).
    Frozen(Option<(Mat6, Mat6)>),
}

/// The inputs of one stage call, as the loop made it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct StageCall {
    pub(super) p: Vec6,
    pub(super) v: Vec6,
    pub(super) tau: Vec6,
    pub(super) t: f64,
    /// The tick's first stage (the only one with its own state Jacobians under
    /// [`StateJacobians::PerTick`]).
    pub(super) first: bool,
    pub(super) free_rates: bool,
}

/// Stage calls per block (≈ 5 KB each with 67 columns).
pub(super) const BLOCK: usize = 512;

/// One block of evaluated stages.
pub(super) type Block = Vec<Option<Result<Stage>>>;

/// Evaluates `calls` block by block, each block in parallel, and sends the blocks in order until
/// the receiver is gone. The state Jacobians of a frozen stage are zero (the consumer puts the
/// tick's in).
pub(super) fn produce(model: &StageModel, calls: &[StageCall], tx: &SyncSender<Block>) {
    for chunk in calls.chunks(BLOCK) {
        let block: Block = chunk
            .par_iter()
            .map_init(ForwardJacobians::default, |fj, c| {
                let state = c.first || model.cfg.state_jacobians == StateJacobians::Exact;
                let frozen = (!state).then(|| (Mat6::zeros(), Mat6::zeros()));
                Some(model.stage(fj, &c.p, &c.v, &c.tau, c.t, frozen, c.free_rates))
            })
            .collect();
        if tx.send(block).is_err() {
            return;
        }
    }
}

/// The consumer's side: the recorded calls and the blocks received so far.
pub(super) struct Ahead {
    calls: Arc<[StageCall]>,
    rx: Receiver<Block>,
    next: usize,
    /// Index of `ready[0]`.
    start: usize,
    ready: Block,
    /// Stages taken from the blocks.
    pub(super) taken: usize,
}

impl Ahead {
    pub(super) fn new(calls: Arc<[StageCall]>, rx: Receiver<Block>) -> Self {
        Ahead {
            calls,
            rx,
            next: 0,
            start: 0,
            ready: Vec::new(),
            taken: 0,
        }
    }

    /// The stage of the loop's next call `call`, from the blocks evaluated ahead (waiting for
    /// the next block if needed); `None` if `call` is not the recorded one or the producer has
    /// stopped.
    pub(super) fn take(&mut self, call: &StageCall) -> Option<Result<Stage>> {
        let idx = self.next;
        self.next += 1;
        if self.calls.get(idx) != Some(call) {
            return None;
        }
        while idx >= self.start + self.ready.len() {
            let block = self.rx.recv().ok()?;
            self.start += self.ready.len();
            self.ready = block;
        }
        let stage = self.ready.get_mut(idx - self.start).and_then(Option::take);
        self.taken += usize::from(stage.is_some());
        stage
    }
}

impl Lean<'_> {
    /// One RK4 stage at (χ, χ̇) = (`p`, `v`) under `tau` ([`StageModel::stage`]; `first`: the
    /// tick's first stage): recorded in a primal run, taken from the stages evaluated ahead in a
    /// sensitivity run if there are any.
    pub(super) fn stage(
        &self,
        p: &Vec6,
        v: &Vec6,
        tau: &Vec6,
        t: f64,
        (first, state): (bool, StateJac),
        free_rates: bool,
    ) -> Result<Stage> {
        let call = StageCall {
            p: *p,
            v: *v,
            tau: *tau,
            t,
            first,
            free_rates,
        };
        if let Some(rec) = &self.record {
            rec.borrow_mut().push(call);
        }
        let frozen = match state {
            StateJac::Compute => None,
            StateJac::Frozen(j) => Some(j.unwrap_or_else(|| (Mat6::zeros(), Mat6::zeros()))),
        };
        if let Some(ahead) = &self.ahead {
            if let Some(stage) = ahead.borrow_mut().take(&call) {
                let mut stage = stage?;
                if let (Some(jac), Some((fp, fv))) = (stage.jac.as_mut(), frozen) {
                    (jac.fp, jac.fv) = (fp, fv);
                }
                return Ok(stage);
            }
        }
        let mut fj = self.scratch.borrow_mut();
        self.model.stage(&mut fj, p, v, tau, t, frozen, free_rates)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::super::{simulate, simulate_recorded, LoopConfig};
    use crate::cloe::truth::table_5_2_truth;
    use crate::excitation::Excitation;
    use rss6_core::{home_pose, KinematicParams};

    /// A plain run's recording (exact state Jacobians configured) serves the per-tick sensitivity
    /// run at the same parameters: every stage comes from the blocks and the result is the
    /// sequential one bit for bit. A recording from other parameters is never used wrongly.
    #[test]
    fn a_plain_runs_recording_serves_the_sensitivity_run_at_the_same_parameters() {
        let _ = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build_global();
        let free: Vec<f64> = (0..24).map(|k| 0.004 * ((k % 5) as f64 - 2.0)).collect();
        let exc = Excitation::at_rest(3, 0.5, &home_pose(), &free).unwrap();
        let mut cfg = LoopConfig::new(KinematicParams::nominal(), home_pose(), 0.3);
        (cfg.implicit_friction, cfg.derivative_filter) = (true, 5e-3);
        let a = table_5_2_truth();
        let cols = [0usize, 3, 33, 54, 61, 65];
        let (plain, rec) = simulate_recorded(&cfg, &a, &exc, None, None, true).unwrap();
        assert!(rec.is_some());
        let mut per_tick = cfg.clone();
        per_tick.state_jacobians = crate::StateJacobians::PerTick;
        let (run, _) = simulate_recorded(&per_tick, &a, &exc, Some(&cols), rec, false).unwrap();
        let mut in_turn = per_tick.clone();
        in_turn.parallel_stages = false;
        let seq = simulate(&in_turn, &a, &exc, Some(&cols)).unwrap();
        assert_eq!((run.stages_ahead, seq.stages_ahead), (1200, 0));
        assert!(run.chi == plain.chi && run.chi == seq.chi);
        assert!(run.jacobian == seq.jacobian);
        // Another viscous friction: the trajectory parts from the recording.
        let mut other = a;
        other.dynamics.viscous[2] *= 1.5;
        let (_, rec) = simulate_recorded(&cfg, &other, &exc, None, None, true).unwrap();
        let (run, _) = simulate_recorded(&per_tick, &a, &exc, Some(&cols), rec, false).unwrap();
        println!(
            "stages taken from another run's recording: {}",
            run.stages_ahead
        );
        assert!(run.stages_ahead < 1200);
        assert!(run.jacobian == seq.jacobian);
    }
}
