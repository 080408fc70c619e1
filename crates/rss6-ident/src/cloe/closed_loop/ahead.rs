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
    /// Whether the stage evaluates its own state Jacobians ([`StateJac::Compute`]).
    pub(super) state: bool,
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
                let frozen = (!c.state).then(|| (Mat6::zeros(), Mat6::zeros()));
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
