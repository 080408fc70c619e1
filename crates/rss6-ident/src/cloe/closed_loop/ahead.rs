//! Stages evaluated ahead, on all cores.
//!
//! A stage's derivatives (F_χ, F_χ̇, M̃⁻¹J_θᵀ, −M̃⁻¹J_θᵀΓ: most of the sensitivities' cost) depend
//! on the primal trajectory only, not on the sensitivities carried through the loop. So a primal
//! run (no sensitivities, one simulation's cost) records every stage call; helper threads then
//! evaluate the calls chunk by chunk, while the sensitivity run takes its stages from the chunks
//! instead of evaluating them in turn. The loop's own thread shares the work: whenever the chunk it
//! needs is not ready it evaluates the next unclaimed chunk itself instead of waiting, so one
//! helper per further core keeps every core busy without a third thread competing for two cores
//! (before the twenty-seventh session a producer thread fed a rayon pool of all cores, block by
//! block: three busy threads on two cores). Helpers stay at most [`LOOKAHEAD`] chunks ahead of the
//! loop (bounded memory). The same function evaluates a stage either way, so the result is bit for
//! bit the one of the sequential run; a call whose inputs differ from the recorded one (which the
//! loop's determinism rules out, checked anyway) is evaluated in turn.

use super::recording::{StageKnown, TickFriction};
use super::stages::{Stage, StageModel};
use super::{Lean, StateJacobians};
use crate::cloe::config::LoopRun;
use crate::cloe::friction::sim_err;
use crate::error::Result;
use rss6_core::{
    rk4_step_implicit_friction_observed, ForwardJacobians, FrictionStep, Mat6, ModelState, Vec6,
};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard, PoisonError};
use std::time::Duration;

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

/// Stage calls per chunk (≈ 5 KB each with 67 columns; ≈ 0.5 ms of one core for the exact
/// Jacobian's 49 columns).
pub(super) const CHUNK: usize = 64;

/// Chunks a helper may evaluate ahead of the one the loop is on (≈ 5 MB with 67 columns).
pub(super) const LOOKAHEAD: usize = 16;

/// One chunk of evaluated stages.
type Block = Vec<Option<Result<Stage>>>;

/// Evaluates one chunk of calls. The state Jacobians of a frozen stage are zero (the consumer puts
/// the tick's in).
/// `known`: the calls' recorded angles and accelerations (as many, or none).
fn evaluate(
    model: &StageModel,
    fj: &mut ForwardJacobians,
    calls: &[StageCall],
    known: &[Option<StageKnown>],
) -> Block {
    calls
        .iter()
        .enumerate()
        .map(|(k, c)| {
            let state = c.first || model.cfg.state_jacobians == StateJacobians::Exact;
            let frozen = (!state).then(|| (Mat6::zeros(), Mat6::zeros()));
            let known = known.get(k).and_then(Option::as_ref);
            Some(model.stage(fj, &c.p, &c.v, &c.tau, c.t, frozen, c.free_rates, known))
        })
        .collect()
}

/// What the loop and its helpers share: the recorded calls, the chunks evaluated and not yet taken,
/// the next chunk to claim and the chunk the loop is on.
pub(super) struct Shared {
    calls: Arc<[StageCall]>,
    known: Arc<[Option<StageKnown>]>,
    slots: Vec<Mutex<Option<Block>>>,
    next: AtomicUsize,
    consumed: AtomicUsize,
    stop: AtomicBool,
    /// A helper panicked: the chunk it claimed never comes, so the loop evaluates in turn.
    failed: AtomicBool,
    lock: Mutex<()>,
    changed: Condvar,
}

/// A poisoned lock only means another thread panicked; the data (an `Option`) is still whole.
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

impl Shared {
    pub(super) fn new(calls: Arc<[StageCall]>, known: Arc<[Option<StageKnown>]>) -> Arc<Self> {
        let n = calls.len().div_ceil(CHUNK);
        Arc::new(Shared {
            calls,
            known,
            slots: (0..n).map(|_| Mutex::new(None)).collect(),
            next: AtomicUsize::new(0),
            consumed: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
            failed: AtomicBool::new(false),
            lock: Mutex::new(()),
            changed: Condvar::new(),
        })
    }

    /// Chunk k's calls and their recorded angles and accelerations (none if not recorded).
    fn chunk(&self, k: usize) -> (&[StageCall], &[Option<StageKnown>]) {
        let end = ((k + 1) * CHUNK).min(self.calls.len());
        (
            self.calls.get(k * CHUNK..end).unwrap_or(&[]),
            self.known.get(k * CHUNK..end).unwrap_or(&[]),
        )
    }

    /// The next unclaimed chunk within [`LOOKAHEAD`] of the loop, claimed; `None` if there is none.
    fn claim(&self) -> Option<usize> {
        loop {
            let k = self.next.load(Ordering::Acquire);
            let limit = self.consumed.load(Ordering::Acquire) + LOOKAHEAD;
            if k >= self.slots.len() || k >= limit {
                return None;
            }
            if self
                .next
                .compare_exchange(k, k + 1, Ordering::AcqRel, Ordering::Acquire)
                .is_ok()
            {
                return Some(k);
            }
        }
    }

    /// Wakes every waiting thread (under the lock, so a thread that checked and is about to wait
    /// cannot miss it).
    fn notify(&self) {
        drop(lock(&self.lock));
        self.changed.notify_all();
    }

    fn put(&self, k: usize, block: Block) {
        if let Some(slot) = self.slots.get(k) {
            *lock(slot) = Some(block);
        }
        self.notify();
    }

    /// Waits until `ready` holds or another thread signals a change (at most 1 ms: a bound, not
    /// a poll).
    fn wait_unless(&self, ready: impl Fn() -> bool) {
        let guard = lock(&self.lock);
        if !ready() {
            let _ = self.changed.wait_timeout(guard, Duration::from_millis(1));
        }
    }

    /// Stops the helpers (the loop is done or gone).
    pub(super) fn stop(&self) {
        self.stop.store(true, Ordering::Release);
        self.notify();
    }
}

/// Marks the helpers failed if a helper unwinds (a panic), so the loop does not wait for its chunk.
struct Unwinding<'s>(&'s Shared);

impl Drop for Unwinding<'_> {
    fn drop(&mut self) {
        if std::thread::panicking() {
            self.0.failed.store(true, Ordering::Release);
            self.0.notify();
        }
    }
}

/// A helper thread: evaluates chunks until every chunk is claimed or the loop stops.
pub(super) fn help(model: &StageModel, shared: &Shared) {
    let _guard = Unwinding(shared);
    let mut fj = ForwardJacobians::default();
    while !shared.stop.load(Ordering::Acquire) {
        if let Some(k) = shared.claim() {
            let (calls, known) = shared.chunk(k);
            let block = evaluate(model, &mut fj, calls, known);
            shared.put(k, block);
        } else {
            let next = shared.next.load(Ordering::Acquire);
            if next >= shared.slots.len() {
                return;
            }
            shared.wait_unless(|| {
                shared.stop.load(Ordering::Acquire)
                    || next < shared.consumed.load(Ordering::Acquire) + LOOKAHEAD
            });
        }
    }
}

/// The loop's side: the chunk it is on and the stages taken.
pub(super) struct Ahead {
    shared: Arc<Shared>,
    /// The recorded run's friction steps, and the next one's index.
    friction: Arc<[TickFriction]>,
    next_friction: usize,
    /// Friction steps taken from the recording.
    pub(super) friction_taken: usize,
    next: usize,
    /// Index of `ready[0]`.
    start: usize,
    ready: Block,
    /// Stages taken from the chunks.
    pub(super) taken: usize,
}

impl Drop for Ahead {
    fn drop(&mut self) {
        self.shared.stop();
    }
}

impl Ahead {
    pub(super) fn new(shared: Arc<Shared>, friction: Arc<[TickFriction]>) -> Self {
        Ahead {
            shared,
            friction,
            next_friction: 0,
            friction_taken: 0,
            next: 0,
            start: 0,
            ready: Vec::new(),
            taken: 0,
        }
    }

    /// The recorded run's next friction step, if it was solved at this state (χ, χ̇) and drive
    /// torque (bit for bit; the loop's determinism makes it so while the runs agree). The
    /// sensitivity run then need not solve it again.
    pub(super) fn take_friction(
        &mut self,
        p: &Vec6,
        v: &Vec6,
        drive: &Vec6,
    ) -> Option<FrictionStep> {
        let k = self.next_friction;
        self.next_friction += 1;
        let step = self
            .friction
            .get(k)
            .filter(|f| f.p == *p && f.v == *v && f.drive == *drive)
            .map(|f| f.step);
        self.friction_taken += usize::from(step.is_some());
        step
    }

    /// The stage of the loop's next call `call`, from the chunks evaluated ahead; while the chunk
    /// it needs is not ready, the loop evaluates unclaimed chunks itself with `model` (the same
    /// function the helpers use). `None` if `call` is not the recorded one.
    pub(super) fn take(
        &mut self,
        call: &StageCall,
        model: &StageModel,
        fj: &mut ForwardJacobians,
    ) -> Option<Result<Stage>> {
        let idx = self.next;
        self.next += 1;
        let sh = &self.shared;
        if sh.calls.get(idx) != Some(call) {
            return None;
        }
        let c = idx / CHUNK;
        while idx >= self.start + self.ready.len() {
            if sh.failed.load(Ordering::Acquire) {
                return None;
            }
            let got = sh.slots.get(c).and_then(|s| lock(s).take());
            if let Some(block) = got {
                (self.start, self.ready) = (c * CHUNK, block);
                sh.consumed.store(c, Ordering::Release);
                sh.notify();
            } else if let Some(k) = sh.claim() {
                let (calls, known) = sh.chunk(k);
                let block = evaluate(model, fj, calls, known);
                if k == c {
                    (self.start, self.ready) = (c * CHUNK, block);
                    sh.consumed.store(c, Ordering::Release);
                    sh.notify();
                } else {
                    sh.put(k, block);
                }
            } else {
                sh.wait_unless(|| sh.slots.get(c).is_none_or(|s| lock(s).is_some()));
            }
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
            let mut rec = rec.borrow_mut();
            rec.calls.push(call);
            rec.known.push(None);
        }
        let frozen = match state {
            StateJac::Compute => None,
            StateJac::Frozen(j) => Some(j.unwrap_or_else(|| (Mat6::zeros(), Mat6::zeros()))),
        };
        if let Some(ahead) = &self.ahead {
            let taken = {
                let mut fj = self.scratch.borrow_mut();
                ahead.borrow_mut().take(&call, &self.model, &mut fj)
            };
            if let Some(stage) = taken {
                let mut stage = stage?;
                if let (Some(jac), Some((fp, fv))) = (stage.jac.as_deref_mut(), frozen) {
                    (jac.fp, jac.fv) = (fp, fv);
                }
                return Ok(stage);
            }
        }
        let mut fj = self.scratch.borrow_mut();
        self.model
            .stage(&mut fj, p, v, tau, t, frozen, free_rates, None)
    }

    /// One tick of a primal run with implicit friction:
    /// [`rss6_core::rk4_step_implicit_friction_observed`] from IK(χ) `theta` when known. The same
    /// arithmetic as the implicit branch of [`Self::run`] (`friction::solve`, then [`Self::rk4`]
    /// with its first stage), errors at the same times; a recording run records the same four
    /// stage calls that branch makes.
    pub(super) fn lean_tick(
        &mut self,
        tau: &Vec6,
        t: f64,
        theta: Option<&Vec6>,
        out: &mut LoopRun,
    ) -> Result<()> {
        let cfg = self.cfg;
        let state = ModelState {
            pose: self.pose,
            pose_dot: self.pose_dot,
        };
        let env = cfg.environment();
        let mut stages = [(Vec6::zeros(), Vec6::zeros(), (Vec6::zeros(), Vec6::zeros())); 4];
        let mut k = 0;
        let (next, f) = rk4_step_implicit_friction_observed(
            &cfg.kp,
            &self.dp,
            &state,
            tau,
            cfg.dt,
            &env,
            theta,
            |p, v, theta, a| {
                if let Some(s) = stages.get_mut(k) {
                    *s = (*p, *v, (*theta, *a));
                }
                k += 1;
            },
        )
        .map_err(|e| sim_err(t, e))?;
        out.count_friction(f.exact, f.stuck.iter().filter(|&&b| b).count());
        if let Some(rec) = &self.record {
            // As `friction::solve` and `Self::rk4` call `Self::stage`: the first stage with its
            // state Jacobians and free rates, all under τ_a − τ_f.
            let net = tau - f.torque;
            let mut rec = rec.borrow_mut();
            rec.friction.push(TickFriction {
                p: self.pose,
                v: self.pose_dot,
                drive: *tau,
                step: f,
            });
            rec.calls
                .extend(stages.iter().enumerate().map(|(i, &(p, v, _))| StageCall {
                    p,
                    v,
                    tau: net,
                    t,
                    first: i == 0,
                    free_rates: i == 0,
                }));
            rec.known.extend(stages.iter().map(|s| Some(s.2)));
        }
        self.set_state(next.pose, next.pose_dot, t + cfg.dt)
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
        // Every tick's friction step from the recording too, bit for bit the one solved in turn.
        assert_eq!((run.friction_ahead, seq.friction_ahead), (300, 0));
        assert!(run.chi == plain.chi && run.chi == seq.chi);
        assert!(run.jacobian == seq.jacobian);
        // So are the first-stage sensitivities CLOE iterates on, whose other three stages take
        // only the recorded acceleration, and the exact ones (each stage's IK angles and
        // acceleration taken from the recording too).
        for jacobians in [
            crate::StateJacobians::FirstStage,
            crate::StateJacobians::Exact,
        ] {
            let mut with = cfg.clone();
            with.state_jacobians = jacobians;
            let (_, rec) = simulate_recorded(&cfg, &a, &exc, None, None, true).unwrap();
            let (ahead, _) = simulate_recorded(&with, &a, &exc, Some(&cols), rec, false).unwrap();
            with.parallel_stages = false;
            let seq = simulate(&with, &a, &exc, Some(&cols)).unwrap();
            assert_eq!((ahead.stages_ahead, seq.stages_ahead), (1200, 0));
            assert!(ahead.chi == plain.chi && ahead.chi == seq.chi);
            assert!(ahead.jacobian.is_some() && ahead.jacobian == seq.jacobian);
        }
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
        // Its friction steps were solved with the other viscous friction: none is taken.
        assert_eq!(run.friction_ahead, 0);
        assert!(run.jacobian == seq.jacobian);
    }
}
