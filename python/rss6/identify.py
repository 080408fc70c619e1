"""Dynamic identification (thesis ch. 5): exciting trajectories (§5.4, :mod:`rss6.excitation`), the
identification loop of Fig. 5.1 on a robot (:func:`collect`; its logs: :mod:`rss6.identify_log`)
and on the model (:func:`simulate`), CLOE (§5.3, :func:`cloe`), validation (§5.5, :func:`validate`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6 import _checks, _rss6, identify_hops, identify_linear, identify_log
from rss6.errors import IdentificationError, InvalidInputError, NonFiniteError, ShapeError
from rss6.excitation import Excitation, excitation, random_excitation
from rss6.identify_linear import (
    SETTLE_STEPS,
    LinearGuess,
    check_options,
    effect_kwargs,
    linear_guess,
    lowpass_measured,
    model_noise_passes,
    potentiometer_noise,
    replayed_noise,
    requested_names,
    table_5_2_truth,
)

__all__ = [
    "Excitation",
    "IdentificationData",
    "IdentificationResult",
    "LinearGuess",
    "LoopModel",
    "Validation",
    "cloe",
    "collect",
    "excitation",
    "linear_guess",
    "parameter_names",
    "potentiometer_noise",
    "random_excitation",
    "replicate_deviations",
    "simulate",
    "table_5_2_truth",
    "validate",
    "variation",
    "with_replicates",
]

F64 = NDArray[np.float64]


def parameter_names() -> list[str]:
    """Names of the quantities CLOE estimates: logs of ``platform.m``, the platform's second moments
    ``platform.Sxx``/``Syy``/``Szz``, ``wrench<i>.m``, ``wrench<i>.Iz``, ``link<i>.m``, the transverse
    ``link<i>.It``, ``fc<i>``, ``fv<i>``, and the drive gains ``lp``, ``li``, ``ld`` (43)."""
    return list(_rss6.cloe_parameter_names())


@dataclass(frozen=True)
class IdentificationData:
    """What the identification loop measured.

    ``t`` (F,): times (s from the start) of the camera frames the visual PID consumed; ``measured``
    (F, 6): χ_E of those frames (m, rad); ``reference``: the exciting trajectory the loop followed
    (from rest at ``start`` = its pose at t = 0); ``duration`` (s) of the run; ``dt`` (s) the joint
    tick. When collected on a robot also per tick: ``tick_t``, ``kappa`` (potentiometers, bit),
    ``theta_cmd`` (commands, drive convention, rad), ``reference_pose`` (χ_d) and ``true_pose`` (NaN
    rows on a real robot), ``fault`` (None or (t, reason) of the visual PID's first fault) and
    ``outer_gains`` (k_p, k_i, k_d) of the visual PID that ran (None: the thesis's)."""

    t: F64
    reference: Excitation
    measured: F64
    duration: float
    dt: float = 1e-3
    tick_t: F64 | None = None
    kappa: F64 | None = None
    theta_cmd: F64 | None = None
    reference_pose: F64 | None = None
    true_pose: F64 | None = None
    fault: tuple[float, str] | None = None
    outer_gains: tuple[float, float, float] | None = None

    @property
    def start(self) -> F64:
        """The pose the run starts at rest at (6,)."""
        return self.reference.sample(0.0)[0]

    @property
    def frames(self) -> int:
        """Number of camera frames."""
        return int(self.t.shape[0])

    def before_fault(self) -> IdentificationData:
        """The data up to the visual PID's first fault (frames before it; per-tick arrays cut at
        the same time), or ``self`` without a fault. After a fault the robot's command is held, so
        later frames no longer follow the loop :func:`cloe` simulates."""
        if self.fault is None:
            return self
        tf = float(self.fault[0])
        keep = self.t < tf
        if not np.any(keep):
            raise IdentificationError(f"no camera frames before the fault at t = {tf:.3f} s")

        def cut(a: F64 | None) -> F64 | None:
            return None if a is None or self.tick_t is None else a[self.tick_t < tf]

        return IdentificationData(
            t=self.t[keep],
            reference=self.reference,
            measured=self.measured[keep],
            duration=tf,
            dt=self.dt,
            tick_t=cut(self.tick_t),
            kappa=cut(self.kappa),
            theta_cmd=cut(self.theta_cmd),
            reference_pose=cut(self.reference_pose),
            true_pose=cut(self.true_pose),
            fault=None,
        )

    def frame_commands(self) -> F64:
        """(F, 6): the joint command (drive convention, rad) the robot's visual PID issued at each
        consumed frame (from ``theta_cmd`` at the frame's tick): the input of :func:`cloe` with
        ``commands="recorded"``. Raises :class:`rss6.InvalidInputError` without per-tick commands."""
        if self.theta_cmd is None or self.tick_t is None:
            raise InvalidInputError(
                "these data carry no per-tick commands (theta_cmd): collect() records them"
            )
        tick_t = np.asarray(self.tick_t)
        k = np.clip(np.searchsorted(tick_t, self.t - 0.5 * self.dt), 0, tick_t.size - 1)
        if tick_t.size == 0 or np.any(np.abs(tick_t[k] - self.t) > 0.5 * self.dt):
            raise InvalidInputError("a frame time has no tick with a command")
        return np.asarray(self.theta_cmd)[k]

    @classmethod
    def from_arrays(
        cls,
        t: ArrayLike,
        reference: Excitation,
        measured: ArrayLike,
        *,
        duration: float | None = None,
        dt: float = 1e-3,
    ) -> IdentificationData:
        """Data from arrays: frame times ``t`` (F,) s, strictly increasing, ≥ 0; the trajectory
        ``reference``; ``measured`` χ_E (F, 6) at those times. ``duration`` defaults to the last
        frame time plus one tick. Raises :class:`rss6.ShapeError`, :class:`rss6.NonFiniteError`,
        :class:`rss6.InvalidInputError` (t not increasing, not an Excitation) or
        :class:`rss6.IdentificationError` (no frames)."""
        if not isinstance(reference, Excitation):
            raise InvalidInputError(
                f"reference must be an rss6.identify.Excitation, got {type(reference).__name__}"
            )
        tt = np.asarray(t, dtype=np.float64)
        if tt.ndim != 1:
            raise ShapeError(f"t must have shape (F,), got {tt.shape}")
        if tt.size == 0:
            raise IdentificationError("no camera frames: t is empty")
        if not np.all(np.isfinite(tt)):
            raise NonFiniteError(
                f"t contains NaN or infinity at index [{np.argmin(np.isfinite(tt))}]"
            )
        m = np.asarray(measured, dtype=np.float64)
        if m.shape != (tt.size, 6):
            raise ShapeError(f"measured must have shape ({tt.size}, 6) like t, got {m.shape}")
        if not np.all(np.isfinite(m)):
            bad = np.argwhere(~np.isfinite(m))[0]
            raise NonFiniteError(f"measured contains NaN or infinity at [{bad[0]}, {bad[1]}]")
        if tt[0] < 0 or np.any(np.diff(tt) <= 0):
            raise InvalidInputError("t must be >= 0 and strictly increasing")
        if not (np.isfinite(dt) and dt > 0):
            raise InvalidInputError(f"dt must be finite and > 0 s, got {dt}")
        dur = float(tt[-1] + dt) if duration is None else float(duration)
        if not (np.isfinite(dur) and dur > tt[-1]):
            raise InvalidInputError(f"duration must exceed the last frame time, got {dur}")
        return cls(t=tt, reference=reference, measured=m, duration=dur, dt=float(dt))

    @classmethod
    def from_mcap(cls, path: str | Path, **options: Any) -> IdentificationData:
        """The run :func:`collect` logged at ``path`` (``mcap=``): :func:`rss6.identify_log.read`."""
        return identify_log.read(path, **options)


def collect(
    robot: Any,
    excitation: Excitation,
    *,
    kp_model: _rss6.KinematicParams,
    sensor_in_base: ArrayLike,
    target_in_effector: ArrayLike,
    periods: int = 1,
    mcap: str | Path | None = None,
    progress: Callable[[float, float], Any] | None = None,
    segment: float = 1.0,
    commands: ArrayLike | None = None,
    outer_gains: tuple[float, float, float] | None = None,
) -> IdentificationData:
    """Runs the identification loop of Fig. 5.1 on ``robot`` (:class:`rss6.Plant`,
    :class:`rss6.ModelSim` or any :class:`rss6.types.Robot`, e.g. ``rss6.can.simulated_robot(...)``):
    the robot is reset at rest at the trajectory's start (if it has ``reset``), then for ``periods``
    periods of ``excitation`` the visual PID (eq. 5.4, thesis gains, ``kp_model``'s J_θ) turns each
    camera frame (through ``sensor_in_base`` ᴼχ_C and ``target_in_effector`` ᴱχ_t) into joint
    commands the drive's PID tracks. ``progress(done_s, total_s)`` every ``segment`` s of robot time
    (raise in it, or Ctrl-C, to stop: the exception propagates); ``mcap``: log every tick there as the
    run goes. ``commands`` (T, 6): joint commands (drive convention, one per tick, e.g. a recorded
    run's :attr:`IdentificationData.theta_cmd`) sent instead of the visual PID's — the run replayed
    with the robot's own inputs (frames are still measured; T must cover every tick).
    ``outer_gains`` (k_p, k_i 1/s, k_d s): the visual PID's gains on every axis (None: the thesis's
    0.3, 2.4, 0.001; §5.6.3 validates on other gains too). Raises
    :class:`rss6.IdentificationError` if no camera frame arrived."""
    if not isinstance(excitation, Excitation):
        raise InvalidInputError("excitation must be an rss6.identify.Excitation")
    if int(periods) < 1:
        raise InvalidInputError(f"periods must be >= 1, got {periods}")
    duration = int(periods) * excitation.duration
    if hasattr(robot, "reset"):
        robot.reset(excitation.sample(0.0)[0])
    raw = _rss6.identification_run(
        robot,
        excitation.f0,
        excitation.coefficients,
        duration,
        kp_model,
        np.asarray(sensor_in_base, dtype=np.float64),
        np.asarray(target_in_effector, dtype=np.float64),
        segment=segment,
        progress=progress,
        mcap=None if mcap is None else str(mcap),
        commands=None if commands is None else np.asarray(commands, dtype=np.float64),
        outer_gains=outer_gains,
    )
    if int(raw["frames"]) == 0 or raw["frame_t"].size == 0:
        raise IdentificationError(
            f"no camera frames in {duration:.3f} s of identification run (target never seen)"
        )
    dt = float(raw["t"][1] - raw["t"][0]) if raw["t"].size > 1 else 1e-3
    return IdentificationData(
        t=np.asarray(raw["frame_t"]),
        reference=excitation,
        measured=np.asarray(raw["measured"]),
        duration=duration,
        dt=dt,
        tick_t=np.asarray(raw["t"]),
        kappa=np.asarray(raw["kappa"]),
        theta_cmd=np.asarray(raw["theta_cmd"]),
        reference_pose=np.asarray(raw["reference"]),
        true_pose=np.asarray(raw["true_pose"]),
        fault=None if raw["fault"] is None else (float(raw["fault"][0]), str(raw["fault"][1])),
        outer_gains=outer_gains,
    )


@dataclass(frozen=True)
class LoopModel:
    """What the simulated loop assumes besides A: the kinematics ``kp``, the drive's ``torque_limit``
    (N·m), the camera latency (s), the drive's ``derivative_filter`` T_f (s) and the model's
    Coulomb ``friction_smoothing`` ε (rad/s; 0 = sign), or ``implicit_friction``: Coulomb + viscous
    friction stepped implicitly per tick (stick–slip; the law of the twin and of the plant built
    with ``implicit_friction=True``). ``commands``: "simulated" (the outer loop closed on the
    model's frames, eq. 5.4) or "recorded" (the robot's own commands held, see :func:`cloe`)."""

    kp: _rss6.KinematicParams
    torque_limit: float = 30.0
    camera_latency: float = 0.0
    derivative_filter: float = 0.0
    friction_smoothing: float = 0.0
    implicit_friction: bool = False
    commands: str = "simulated"
    pot_noise: str = "none"


def simulate(
    kp: _rss6.KinematicParams,
    dynamics: _rss6.DynamicParams,
    pid: tuple[float, float, float],
    excitation: Excitation,
    *,
    times: ArrayLike,
    torque_limit: float = 30.0,
    camera_latency: float = 0.0,
    dt: float = 1e-3,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    commands: ArrayLike | None = None,
    gravity: ArrayLike | None = None,
    load: tuple[float, ArrayLike, ArrayLike] | None = None,
    offset_drift: ArrayLike | None = None,
    outer_gains: tuple[float, float, float] | None = None,
    pot_dither: ArrayLike | None = None,
) -> F64:
    """χ_s (len(times), 6) of the model (``kp``, ``dynamics``, drive gains ``pid``) in the loop of
    Fig. 5.1 following ``excitation`` from rest at its start (drive ``derivative_filter`` T_f s,
    Coulomb ``friction_smoothing`` ε rad/s; 0: as printed; or ``implicit_friction``, see
    :class:`LoopModel`). ``commands`` (F, 6): the robot's joint commands at its frames
    (:meth:`IdentificationData.frame_commands`), held instead of the model's visual PID output. Effects the model can express:
    ``gravity`` (3,) m/s² in the base frame (a tilted base), ``load`` = (mass kg, centre of mass (3,)
    m in ΣE, inertia (3, 3) kg·m² about it) fixed to the platform, ``offset_drift`` (6,) rad/s of the
    potentiometer offsets; ``outer_gains``: the visual PID's (k_p, k_i, k_d) (None: the thesis's);
    ``pot_dither`` (T, 6) rad: potentiometer noise added to the model's readings, one row per tick
    (:func:`rss6.identify.potentiometer_noise`). Returns the model's camera frames at ``times``
    (each must be a frame time of the loop within half a tick, e.g. :attr:`IdentificationData.t`;
    otherwise :class:`rss6.IdentificationError` names the first one that is not)."""
    tt = np.asarray(times, dtype=np.float64).reshape(-1)
    if tt.size == 0 or not np.all(np.isfinite(tt)) or np.any(np.diff(tt) <= 0):
        raise InvalidInputError("times must be non-empty, finite and strictly increasing")
    ts, chi, _, _ = _rss6.simulate_identification(
        kp,
        dynamics,
        _checks.gains3(pid, "pid"),
        excitation.f0,
        excitation.coefficients,
        start=excitation.sample(0.0)[0],
        duration=float(tt.max() + dt),
        torque_limit=torque_limit,
        camera_latency=camera_latency,
        dt=dt,
        derivative_filter=derivative_filter,
        friction_smoothing=friction_smoothing,
        implicit_friction=implicit_friction,
        commands=None if commands is None else np.asarray(commands, dtype=np.float64),
        outer_gains=outer_gains,
        pot_dither=None if pot_dither is None else np.asarray(pot_dither, dtype=np.float64),
        **effect_kwargs(gravity, load, offset_drift),
    )
    ts = np.asarray(ts)
    k = np.clip(np.searchsorted(ts, tt), 0, max(ts.size - 1, 0))
    km = np.clip(k - 1, 0, max(ts.size - 1, 0))
    best = np.where(np.abs(ts[km] - tt) < np.abs(ts[k] - tt), km, k) if ts.size else k
    if ts.size == 0 or np.any(np.abs(ts[best] - tt) > 0.5 * dt):
        bad = tt[0] if ts.size == 0 else tt[np.argmax(np.abs(ts[best] - tt) > 0.5 * dt)]
        raise IdentificationError(
            f"no camera frames: the model's loop has no frame at t = {bad:.4f} s"
        )
    return np.asarray(chi)[best]


@dataclass(frozen=True)
class IdentificationResult:
    """What :func:`cloe` returns.

    ``dynamics`` (:class:`rss6.DynamicParams`) and ``pid`` (l_p, l_i, l_d): the estimate
    (unidentifiable quantities at the guess); ``identified``: names of the estimated quantities (see
    :func:`parameter_names`) and ``relative_std`` (same order) their relative standard deviations
    (the larger of the Wald value ``relative_std_wald``, which assumes white residuals, and a
    Newey–West sandwich that also sees residuals correlated in time);
    ``poorly_identified``: those above 10 %; ``unidentifiable``: quantities the data cannot see;
    ``rms_before``/``rms_after`` (6,): RMS of χ_m − χ_s per axis (m, rad) at the guess and at the
    estimate; ``cost_history``: Φ at the guess and after every accepted step; ``iterations``;
    ``converged_by``: the stopping rule that ended it — ``"tolerances"`` (eq. 5.9),
    ``"invisible"`` (Φ fell by < 10⁻² residual variances twice), ``"settled"`` (over the last
    ``settle_steps`` steps Φ fell by < 1 residual variance, no quantity moved by half its σ: creeping
    along a stick–slip cost's kinks) or ``"stationary"`` (no step lowers Φ, first-order optimum);
    ``hops``: with :func:`cloe`'s ``hops``, the reduced χ² of the first run and after each hop
    (``iterations`` and ``simulations`` then count every run); ``restarts``: with ``restarts``, the
    reduced χ² of every run and ``start_spread`` the largest |log change| of each identified
    quantity between equally good runs (a floor under ``relative_std``); ``reduced_chi2`` = Φ/(N −
    p) (≈ 1 when the residual is the camera noise); ``inexact_friction_ticks``: ticks of the loop at
    the estimate whose implicit friction solve stopped at its sweep bound (0 expected; otherwise χ_s
    is approximate there); ``aliases``: for each unidentifiable quantity, the estimated ones that
    absorb it — {name: ({estimated: c}, residual)}: a relative change δ of it moves the output at
    the guess as relative changes c·δ of those do (|c| ≥ 0.05, at most 4), ``residual`` the relative
    misfit of that combination (≈ 0: it combines into them; near 1: the output hardly sees it);
    :meth:`alias_text` says it in words. ``guess`` and ``model`` keep what :func:`validate` needs.
    ``linear_map`` (map (p, 6F), whitening W (6, 6)): δψ = map · δr for a change δr of the
    residual whitened frame by frame (W·(χ_m − χ_s)); ``residual`` (F, 6): χ_m − χ_s at the estimate
    ; :func:`with_replicates` carries noisy replicate runs through it to ``relative_std_replicates``
    (and ``replicate_bias``, the shift ``correct_bias=True`` applied; docs/identification.md)."""

    dynamics: _rss6.DynamicParams
    pid: tuple[float, float, float]
    identified: tuple[str, ...]
    unidentifiable: tuple[str, ...]
    relative_std: F64
    poorly_identified: tuple[str, ...]
    rms_before: F64
    rms_after: F64
    cost_history: F64
    iterations: int
    reduced_chi2: float
    simulations: int
    guess: tuple[_rss6.DynamicParams, tuple[float, float, float]]
    model: LoopModel
    inexact_friction_ticks: int = 0
    aliases: dict[str, tuple[dict[str, float], float]] = field(default_factory=dict)
    relative_std_wald: F64 = field(default_factory=lambda: np.zeros(0))
    converged_by: str = "tolerances"
    hops: tuple[float, ...] = ()
    restarts: tuple[float, ...] = ()
    start_spread: F64 = field(default_factory=lambda: np.zeros(0))
    linear_map: tuple[F64, F64] | None = None
    relative_std_replicates: F64 = field(default_factory=lambda: np.zeros(0))
    residual: F64 = field(default_factory=lambda: np.zeros((0, 6)))
    replicate_bias: F64 = field(default_factory=lambda: np.zeros(0))

    def alias_text(self) -> list[str]:
        """One line per unidentifiable quantity: what it combines into (relative coefficients)."""
        out = []
        for name, (like, res) in self.aliases.items():
            terms = " ".join(f"{c:+.2f}·{n}" for n, c in like.items()) or "nothing estimated"
            how = "combines into" if res < 0.1 else "partly like" if res < 0.9 else "unseen; like"
            out.append(f"{name} {how} {terms} (misfit {res:.1e})")
        return out

    def std(self, name: str) -> float:
        """Relative standard deviation of the identified quantity ``name``."""
        try:
            return float(self.relative_std[self.identified.index(name)])
        except ValueError:
            raise InvalidInputError(f"{name!r} was not identified") from None


def cloe(
    data: IdentificationData,
    kp: _rss6.KinematicParams,
    dp_guess: _rss6.DynamicParams,
    pid_guess: tuple[float, float, float],
    *,
    parameters: str | Sequence[str] = "base",
    hold: Sequence[str] = (),
    consistent: bool = True,
    max_iterations: int = 20,
    progress: Callable[[int, float], Any] | None = None,
    torque_limit: float = 30.0,
    camera_latency: float = 0.0,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    commands: str = "simulated",
    noise: tuple[float, float] | ArrayLike | str | None = None,
    per_tick_jacobians: bool = False,
    tol_cost: float = 1e-6,
    tol_step: float = 1e-5,
    prior_log_std: float | None = 1.0,
    gravity: ArrayLike | None = None,
    load: tuple[float, ArrayLike, ArrayLike] | None = None,
    offset_drift: ArrayLike | None = None,
    measured_cutoff: float | None = None,
    pot_noise: str | ArrayLike = "none",
    settle_steps: int = SETTLE_STEPS,
    hops: Sequence[float] = (),
    restarts: int = 0,
    restart_spread: float = 0.3,
    initial: tuple[_rss6.DynamicParams, tuple[float, float, float]] | None = None,
) -> IdentificationResult:
    """Closed-loop output-error identification (thesis §5.3, eq. 5.6–5.9) of Ξ and the drive gains
    from ``data``, starting from (``dp_guess``, ``pid_guess``), by Levenberg–Marquardt on the
    simulated loop (model kinematics ``kp``, ``torque_limit`` N·m, ``camera_latency`` s, the drive's
    ``derivative_filter`` T_f s and the model's Coulomb ``friction_smoothing`` ε rad/s — 0: as printed,
    non-smooth — or ``implicit_friction``, stick–slip stepped implicitly as the twin and the plant
    step it, see :class:`LoopModel`) and its exact sensitivities. ``commands="recorded"`` holds the
    robot's own joint commands (:meth:`IdentificationData.frame_commands`) instead of simulating the
    outer visual PID: the output error of the drive + dynamics loop (with stick–slip the camera
    noise fed back moves the robot by more than the noise: docs/identification.md).

    ``parameters``: ``"base"`` estimates every quantity the data identify (QR with column pivoting
    at the guess, relative threshold 10⁻³), a list of names (:func:`parameter_names`) only those
    (the others stay at the guess); ``hold``: names kept at the guess as known — closed-loop output
    error sees Ξ and the drive gains only up to one common factor, so with ``"base"`` one known
    quantity (e.g. ``"lp"`` from the drive's data sheet) fixes the scale; ``consistent``: the estimator works on logs of physical quantities,
    so every iterate is a physical robot (the only parametrisation implemented: ``False`` is refused).
    ``noise`` (position m, angle rad): the residual weights' σ (default Table 4.1); a (6, 6) frame
    covariance: the residual whitened by it; ``"frames"``: a second pass whitened by the first's
    residual covariance (:func:`rss6.identify_linear.frame_noise_passes`).
    ``prior_log_std``: σ of a Gaussian prior on every estimated log-quantity centred at the guess
    (keeps quantities the run hardly sees near it); ``None``: the pure output error of eq. 5.7.
    ``cost_history`` includes the prior's term. ``gravity``, ``load``, ``offset_drift``: effects of
    the model, as for :func:`simulate` (re-identification with named effects).
    ``measured_cutoff`` (Hz): low-pass χ_m first (zero-phase 4th-order Butterworth, scipy
    ``filtfilt``) below the camera's Nyquist frequency; ``None``: no filter, as the weights assume
    white noise (docs/identification.md, "Filtering χ_m").
    ``pot_noise``: noise the model's drive adds to its potentiometer readings — ``"none"``
    (default); ``"recorded"``: :func:`potentiometer_noise` of the data (needs per-tick data; with
    stick–slip the noise breaks sticking joints free earlier); ``"model"``: that, then a second
    pass replaying the readings minus the first estimate's angles (:func:`rss6.identify_linear.
    model_noise_passes`); an array (T, 6) rad: that noise (this run only; docs/identification.md).
    ``per_tick_jacobians``: iterate on cheaper sensitivities (state Jacobians once per tick, ≈ 10⁻³);
    a stop is checked on the exact ones (iterations go on with them if their step would lower Φ by
    more than one residual variance), and the σ always come from the exact ones.
    ``settle_steps``: the *settled* rule's look-back in accepted steps (0 turns it off). ``hops``:
    after converging, CLOE again from the estimate with every quantity but the held ones moved by
    the log-factor δ, for each δ, keeping the lowest χ² (:func:`rss6.identify_hops.hopped`).
    ``restarts``: as many more runs (hops included) from the guess with each identified quantity
    moved by a seeded factor in [1 − ``restart_spread``, 1 + ``restart_spread``], the best kept and
    its σ widened to the spread over equally good runs (:func:`rss6.identify_hops.restarted`);
    ``initial`` (dynamics, gains): where LM starts instead of the guess (which centres the prior).
    ``progress(iteration, cost)`` after every accepted step (iteration 0: the guess); raise in it (or
    Ctrl-C) to stop. Raises :class:`rss6.IdentificationError`: a requested name is not identifiable
    (``.names``), no convergence (``.iterations``, ``.cost_history``), frames the model's loop does
    not produce, a faulted run (:meth:`IdentificationData.before_fault`). σ from the loop's own
    noise too: :func:`with_replicates`."""
    call = dict(locals())
    if hops:
        identify_hops.check(hops, parameters, hold)
    identify_hops.check_restarts(restarts, restart_spread)
    if isinstance(pot_noise, str) and pot_noise == "model":
        return model_noise_passes(data, lambda g: cloe(**{**call, **g}))
    if isinstance(noise, str):
        return identify_linear.frame_noise_passes(noise, lambda g: cloe(**{**call, **g}))
    if data.fault is not None:
        raise IdentificationError(
            f"the identification run faulted at t = {data.fault[0]:.3f} s ({data.fault[1]}); "
            "frames after it do not follow the loop: use data.before_fault()"
        )
    check_options(consistent, settle_steps, commands, max_iterations, tol_cost, tol_step)
    names = requested_names(parameters, parameter_names())
    held = data.frame_commands() if commands == "recorded" else None
    dither = replayed_noise(data, pot_noise)
    pid = _checks.gains3(pid_guess, "pid_guess")
    measured = data.measured if measured_cutoff is None else lowpass_measured(data, measured_cutoff)
    r = _rss6.cloe_identify(
        data.t,
        measured,
        data.reference.f0,
        data.reference.coefficients,
        kp,
        dp_guess,
        pid,
        start=data.start,
        duration=data.duration,
        parameters=names,
        hold=[str(h) for h in hold] or None,
        max_iterations=max_iterations,
        torque_limit=torque_limit,
        camera_latency=camera_latency,
        dt=data.dt,
        derivative_filter=derivative_filter,
        friction_smoothing=friction_smoothing,
        implicit_friction=implicit_friction,
        commands=held,
        per_tick_jacobians=per_tick_jacobians,
        tol_cost=tol_cost,
        tol_step=tol_step,
        prior_log_std=0.0 if prior_log_std is None else float(prior_log_std),
        progress=progress,
        outer_gains=data.outer_gains,
        pot_dither=dither,
        settle_steps=settle_steps,
        initial=initial,
        **effect_kwargs(gravity, load, offset_drift),
        **identify_linear.noise_kwargs(noise),
    )
    lp, li, ld = r["pid"]
    result = IdentificationResult(
        dynamics=r["dynamics"],
        pid=(float(lp), float(li), float(ld)),
        identified=tuple(r["identified"]),
        unidentifiable=tuple(r["unidentifiable"]),
        aliases={
            str(n): ({str(k): float(c) for k, c in like}, float(res))
            for n, like, res in r["aliases"]
        },
        relative_std=np.asarray(r["relative_std"]),
        relative_std_wald=np.asarray(r["relative_std_wald"]),
        linear_map=(np.asarray(r["estimator_map"]), np.asarray(r["residual_whitening"])),
        residual=np.asarray(r["residual"]),
        poorly_identified=tuple(r["poorly_identified"]),
        rms_before=np.asarray(r["rms_before"]),
        rms_after=np.asarray(r["rms_after"]),
        cost_history=np.asarray(r["cost_history"]),
        iterations=int(r["iterations"]),
        converged_by=str(r["converged_by"]),
        reduced_chi2=float(r["reduced_chi2"]),
        inexact_friction_ticks=int(r["inexact_friction_ticks"]),
        simulations=int(r["simulations"]),
        guess=(dp_guess, pid),
        model=LoopModel(
            kp=kp,
            torque_limit=torque_limit,
            camera_latency=camera_latency,
            derivative_filter=derivative_filter,
            friction_smoothing=friction_smoothing,
            implicit_friction=implicit_friction,
            commands=commands,
            # An array is this run's noise: other runs (validation) replay none.
            pot_noise=pot_noise if isinstance(pot_noise, str) else "none",
        ),
    )
    if hops:
        once = {"hops": (), "restarts": 0, "initial": None}
        result = identify_hops.hopped(
            result, hops, lambda g: cloe(**{**call, **g, **once}), parameters, hold
        )
    if restarts:
        rerun = lambda g: cloe(**{**call, **g, "restarts": 0})  # noqa: E731
        result = identify_hops.restarted(result, restarts, restart_spread, rerun, hold, data)
    return result


# Validation, Table 5.5 and the replicates' σ live in their modules (they use the names above).
from rss6.identify_replicates import replicate_deviations, with_replicates  # noqa: E402
from rss6.identify_validate import Validation, validate, variation  # noqa: E402
