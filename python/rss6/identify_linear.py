"""A linear initial guess for CLOE from what the drives did: inverse dynamics on the recorded
commands and potentiometers (docs/identification.md, "A linear start"); and the filters of the
recorded signals CLOE can use (the potentiometer noise to replay, a low-pass of χ_m).

CLOE's cost with stick–slip friction is piecewise smooth, and Levenberg–Marquardt started from the
thesis's initial model (Table 5.1, no friction) stops in local minima far from the truth. This
estimate needs no simulation: every quantity it uses was recorded.

* The drive torque of joint i is eq. 5.5 on what the drive saw, τ_i = l_p e_i + l_i ∫e_i + D_i with
  e = U_θ − θ_pot (drive convention) and the derivative filter D_k = (T_f D_{k−1} + l_d Δe)/(T_f + Δt):
  linear in (l_p, l_i, l_d) given the recorded commands and potentiometer readings.
* The pose χ by forward kinematics of the potentiometer angles (model convention); χ, e, ∫e and
  D/l_d are low-passed alike with a zero-phase Butterworth filter (scipy ``filtfilt``), χ̇ and χ̈ by
  central differences.
* Rows Γ_i(χ, χ̇, χ̈) Ξ = τ_i (eq. 5.1; `rss6.regressor`) for joints moving faster than ``min_rate``
  × their own peak rate: a joint at rest holds any friction torque in [−f_c, f_c], which sign(θ̇)
  does not describe.
* Unknowns: some of the 43 quantities CLOE estimates (:func:`rss6.identify.parameter_names`,
  exp ψ), to which Ξ is affine; by default the joint friction and l_i, l_d — what a CAD model does
  not give —, the masses and inertias staying at the prior. l_p is known: the equations are
  homogeneous in (Ξ, gains), so one quantity must be (the same scale direction CLOE cannot see).
  Bounded least squares (scipy ``lsq_linear``, every quantity ≥ 10⁻³ × its prior, so the result is
  physically consistent) with a ridge pulling each toward the prior by relative weight ``ridge``.
  Estimating the masses and inertias too (``names=None``) leaves them wild along the torque
  regressor's null space (structural rank 31 of 64; measured: link masses 0.001–17× the truth), and
  CLOE keeps what it cannot identify at its start.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy import optimize, signal

from rss6 import _checks, _rss6
from rss6.errors import IdentificationError, InvalidInputError, NonFiniteError, ShapeError

if TYPE_CHECKING:
    from rss6.identify import IdentificationData, IdentificationResult

__all__ = [
    "LinearGuess",
    "effect_kwargs",
    "linear_guess",
    "model_noise_passes",
    "model_potentiometer_noise",
    "potentiometer_noise",
    "replayed_noise",
]

_N_Q = 43
_LP, _LI, _LD = 40, 41, 42
_DEFAULT_NAMES = (*(f"f{k}{i}" for k in "cv" for i in range(1, 7)), "li", "ld")


@dataclass(frozen=True)
class LinearGuess:
    """What :func:`linear_guess` returns: the estimate (``dynamics``, ``pid``), the number of torque
    equations used (``rows``) and left out because the joint was near rest (``excluded``), the RMS
    drive torque over the rows and the RMS residual of the fit (N·m); ``at_bound``: quantities the
    fit pushed onto its lower bound (10⁻³ of the prior: the data asked for ≤ 0), returned at the
    prior instead and the rest refitted with them held there."""

    dynamics: _rss6.DynamicParams
    pid: tuple[float, float, float]
    rows: int
    excluded: int
    torque_rms: float
    residual_rms: float
    at_bound: tuple[str, ...] = ()


def _affine_map(
    dp: _rss6.DynamicParams, pid: tuple[float, float, float]
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q0 = exp ψ of the prior, and L, c with A = L q + c (A: the 67 entries of Ξ and the gains)."""
    psi0, _, _ = _rss6.cloe_psi(dp, pid)
    q0 = np.exp(np.asarray(psi0))

    def a_of(q: np.ndarray) -> np.ndarray:
        _, d, p = _rss6.cloe_psi(dp, pid, list(np.log(q)))
        return np.concatenate([np.asarray(d.to_vector()), np.asarray(p)])

    a0 = a_of(q0)
    lin = np.zeros((a0.size, _N_Q))
    for j in range(_N_Q):
        q = q0.copy()
        q[j] *= 2.0
        lin[:, j] = (a_of(q) - a0) / q0[j]
    return q0, lin, a0 - lin @ q0


def linear_guess(
    data: IdentificationData,
    kp: _rss6.KinematicParams,
    dp_prior: _rss6.DynamicParams,
    pid_prior: tuple[float, float, float],
    *,
    lp: float,
    derivative_filter: float = 0.0,
    drive: _rss6.KinematicParams | None = None,
    cutoff: float = 10.0,
    min_rate: float = 0.05,
    ridge: float = 1e-3,
    stride: int = 4,
    edge: float = 0.2,
    names: Sequence[str] | None = _DEFAULT_NAMES,
) -> LinearGuess:
    """The linear estimate (module docs) from ``data`` collected with per-tick commands and
    potentiometers (:func:`rss6.identify.collect`), with the model kinematics ``kp``, the prior
    (``dp_prior``, ``pid_prior``: the ridge's centre), the known ``lp`` and the drive's
    ``derivative_filter`` T_f (s). ``drive``: the drive's joint convention (default nominal);
    ``cutoff`` (Hz) of the low-pass; ``min_rate``: fraction of each joint's peak rate below which its
    equation is left out; ``stride``: ticks between equations; ``edge`` (s) left out at both ends
    (filter transients); ``names``: the quantities estimated (default friction, l_i, l_d; None:
    every one but l_p), the others kept at the prior.

    Raises :class:`rss6.InvalidInputError` (no per-tick data, bad options) and
    :class:`rss6.IdentificationError` (a faulted run, too few equations, a fit worse than no model)."""
    if data.kappa is None or data.theta_cmd is None or data.tick_t is None:
        raise InvalidInputError(
            "the linear guess needs per-tick potentiometers and commands: collect() records them"
        )
    if data.fault is not None:
        raise IdentificationError(
            f"the run faulted at t = {data.fault[0]:.3f} s: use data.before_fault()"
        )
    if not (np.isfinite(lp) and lp > 0):
        raise InvalidInputError(f"lp must be finite and > 0, got {lp}")
    dt = float(data.dt)
    if not (0 < cutoff < 0.5 / dt) or not (0 <= min_rate < 1) or stride < 1 or ridge < 0:
        raise InvalidInputError("cutoff must be in (0, Nyquist), min_rate in [0, 1), stride ≥ 1")
    drive = _rss6.KinematicParams.nominal() if drive is None else drive
    kappa = np.asarray(data.kappa, dtype=np.float64)
    cmd = np.asarray(data.theta_cmd, dtype=np.float64)
    n = kappa.shape[0]
    if n < 4 * int(edge / dt) + 50:
        raise IdentificationError(f"{n} ticks are too few for the linear guess")
    e = cmd - drive.theta_from_reading(kappa)
    integral = np.cumsum(e, axis=0) * dt
    # The drive's derivative D_k = (T_f D_{k−1} + Δe_k)/(T_f + dt), D_0 = 0 (Δe/dt unfiltered).
    de = np.diff(e, axis=0, prepend=e[:1])
    t_f = derivative_filter
    d_unit = (
        signal.lfilter([1.0 / (t_f + dt)], [1.0, -t_f / (t_f + dt)], de, axis=0)
        if t_f > 0
        else de / dt
    )
    theta = kp.theta_from_reading(kappa)
    poses = np.asarray(_rss6.fk_batch(kp, theta, data.start))
    b, a = signal.butter(4, cutoff * 2.0 * dt)
    pose = signal.filtfilt(b, a, poses, axis=0)
    pose_dot = np.gradient(pose, dt, axis=0)
    pose_ddot = np.gradient(pose_dot, dt, axis=0)
    e_f, int_f, d_f = (signal.filtfilt(b, a, x, axis=0) for x in (e, integral, d_unit))

    q0, lin, c = _affine_map(dp_prior, pid_prior)
    ticks = np.arange(int(edge / dt), n - int(edge / dt), stride)
    rates = np.array([_rss6.jacobian_theta(kp, pose[k]) @ pose_dot[k] for k in ticks])
    peak = np.abs(rates).max(axis=0)
    # One equation per tick and moving joint i: Γ_i (L q + c)_Ξ − l_i ∫e_i − l_d D_i = l_p e_i.
    gamma = np.array([_rss6.regressor(kp, pose[k], pose_dot[k], pose_ddot[k]) for k in ticks])
    moving = np.abs(rates) >= min_rate * peak
    excluded = int(moving.size - moving.sum())
    g_rows = gamma[moving]  # (rows, 64), tick-major as the ticks and joints are
    tick_of = np.broadcast_to(ticks[:, None], moving.shape)[moving]
    joint_of = np.broadcast_to(np.arange(6), moving.shape)[moving]
    a_mat = g_rows @ lin[:64]
    a_mat[:, _LI] -= int_f[tick_of, joint_of]
    a_mat[:, _LD] -= d_f[tick_of, joint_of]
    a_mat[:, _LP] = 0.0
    y = lp * e_f[tick_of, joint_of] - g_rows @ c[:64]
    terms = np.stack([e_f, int_f, d_f], axis=-1)[tick_of, joint_of]
    if len(y) < 3 * _N_Q:
        raise IdentificationError(
            f"only {len(y)} torque equations with moving joints (at least {3 * _N_Q} needed)"
        )
    all_names = list(_rss6.cloe_parameter_names())
    if names is None:
        free = [j for j in range(_N_Q) if j != _LP]
    else:
        unknown = [n for n in names if n not in all_names or n == "lp"]
        if unknown or not names:
            raise InvalidInputError(f"names must be quantities other than lp, got {unknown}")
        free = sorted({all_names.index(n) for n in names})
    q, at_bound = _bounded_fit(a_mat, y, q0, free, ridge)
    q[_LP] = lp
    residual = float(np.sqrt(np.mean((a_mat @ q - y) ** 2)))
    torque = float(np.sqrt(np.mean((terms @ q[[_LP, _LI, _LD]]) ** 2)))
    if residual >= torque:
        raise IdentificationError(
            f"the linear fit explains nothing (residual {residual:.3g} N·m ≥ torque {torque:.3g} N·m)"
        )
    _, dp, pid = _rss6.cloe_psi(dp_prior, pid_prior, list(np.log(q)))
    return LinearGuess(
        dynamics=dp,
        pid=(float(pid[0]), float(pid[1]), float(pid[2])),
        rows=len(y),
        excluded=excluded,
        torque_rms=torque,
        residual_rms=residual,
        at_bound=tuple(all_names[j] for j in at_bound),
    )


def _bounded_fit(
    a_mat: np.ndarray, y: np.ndarray, q0: np.ndarray, free: list[int], ridge: float
) -> tuple[np.ndarray, list[int]]:
    """q with the ``free`` entries fitted to a_mat q ≈ y by BVLS in units of the prior ``q0``
    (bounds [10⁻³, ∞) of it, a ridge towards it), the rest at ``q0``; and the indices held at the
    prior because the fit put them on the lower bound.

    A quantity on the lower bound is one the data want ≤ 0: it is held at the prior and the rest is
    refitted. Left at 10⁻³ of the prior, CLOE's log-prior would centre there, and a viscous term that
    small hardly moves the output, so CLOE could not leave it (3 of 40 plant runs did that). When
    every quantity ends on its bound the start is the prior itself, all of it named."""
    free = list(free)
    at_bound: list[int] = []
    q = q0.copy()
    while free:
        fixed = [j for j in range(len(q0)) if j not in free]
        y_free = y - a_mat[:, fixed] @ q0[fixed]
        scaled = a_mat[:, free] * q0[free]  # unknowns u = q / q0
        reg = np.eye(len(free)) * ridge * float(np.linalg.norm(scaled, axis=0).mean())
        fit = optimize.lsq_linear(
            np.vstack([scaled, reg]),
            np.concatenate([y_free, reg @ np.ones(len(free))]),
            bounds=(1e-3, np.inf),
            method="bvls",
        )
        if fit.status < 1:
            raise IdentificationError(f"the bounded least squares did not converge: {fit.message}")
        low = [free[k] for k in np.flatnonzero(fit.active_mask < 0)]
        if not low:
            q[free] = fit.x * q0[free]
            break
        at_bound += low
        free = [j for j in free if j not in low]
    return q, at_bound


def potentiometer_noise(
    data: IdentificationData,
    *,
    cutoff: float = 100.0,
    drive: _rss6.KinematicParams | None = None,
) -> np.ndarray:
    """(T, 6) rad: an estimate of the noise on the potentiometer readings the drive saw at each tick
    (drive convention): the recorded samples (where the held reading changes) minus their zero-phase
    low-pass (4th-order Butterworth at ``cutoff`` Hz, scipy ``filtfilt``), held between samples as
    the drive holds its reading. White noise spreads up to the samples' Nyquist frequency (250 Hz
    at 500 Hz), so this keeps the noise above ``cutoff`` (at 100 Hz ≈ 60 % of its variance) and
    the motion's content above it — which is not small: stick–slip and the 30 Hz command steps put
    kinks in the joint angles. Measured on the twin, RMS of (estimate − noise) / noise: 0.61 on a
    fast 2 s trajectory and 0.60 on a thesis-size one at 100 Hz; at 50 Hz 0.54 on the slow one but
    1.06 — worse than no estimate — on the fast one. :func:`rss6.identify.cloe` with
    ``pot_noise="recorded"`` replays it in the model's drive (docs/identification.md, "Replaying the
    potentiometer noise"). ``drive``: the drive's joint convention (default nominal).

    Raises :class:`rss6.InvalidInputError` without per-tick potentiometers, for a cutoff outside
    (0, Nyquist) or too few ticks to filter."""
    if data.kappa is None or data.tick_t is None:
        raise InvalidInputError(
            "the potentiometer noise needs per-tick potentiometers: collect() records them"
        )
    kappa = np.asarray(data.kappa, dtype=np.float64)
    if kappa.ndim != 2 or kappa.shape[0] < 50:
        raise InvalidInputError(f"{kappa.shape[0]} ticks are too few to filter")
    # The drive's readings are held between samples: filter the samples (a staircase's steps are
    # motion, θ̇·Δt/2 ≈ the noise itself on a fast joint), then hold the estimate likewise.
    fresh = _fresh_samples(kappa)
    period = float(np.median(np.diff(fresh))) * float(data.dt) if fresh.size > 1 else 0.0
    if fresh.size < 50 or not period > 0.0:
        raise InvalidInputError(f"{fresh.size} potentiometer samples are too few to filter")
    if not (np.isfinite(cutoff) and 0.0 < cutoff < 0.5 / period):
        raise InvalidInputError(
            f"cutoff must be in (0, {0.5 / period:.4g}) Hz, the samples' Nyquist frequency; "
            f"got {cutoff}"
        )
    drive = _rss6.KinematicParams.nominal() if drive is None else drive
    theta = drive.theta_from_reading(kappa[fresh])
    b, a = signal.butter(4, cutoff * 2.0 * period)
    est = theta - signal.filtfilt(b, a, theta, axis=0)
    return _held(est, fresh, kappa.shape[0])


def _fresh_samples(kappa: np.ndarray) -> np.ndarray:
    """The ticks at which the drive's held potentiometer reading (T, 6) changed: a new sample
    (tick 0 counts as one)."""
    return np.concatenate(([0], 1 + np.flatnonzero(np.any(kappa[1:] != kappa[:-1], axis=1))))


def _held(est: np.ndarray, fresh: np.ndarray, ticks: int) -> np.ndarray:
    """(ticks, 6): the per-sample values ``est`` at the sample ticks ``fresh``, held between
    samples as the drive holds its reading (before the first sample: the first value)."""
    held = np.searchsorted(fresh, np.arange(ticks), side="right") - 1
    return np.asarray(est[np.maximum(held, 0)], dtype=np.float64)


def replayed_noise(
    data: IdentificationData, pot_noise: object, result: Any = None
) -> np.ndarray | None:
    """The potentiometer noise :func:`rss6.identify.cloe` replays for ``pot_noise``: ``"none"``
    (None), ``"recorded"`` (:func:`potentiometer_noise` of ``data``), ``"model"``
    (:func:`model_potentiometer_noise` against ``result``, which it needs) or an array (T, 6) rad.
    Raises :class:`rss6.InvalidInputError`, :class:`rss6.ShapeError`, :class:`rss6.NonFiniteError`."""
    if isinstance(pot_noise, str):
        if pot_noise == "model" and result is not None:
            return model_potentiometer_noise(data, result)
        if pot_noise not in ("none", "recorded"):
            raise InvalidInputError(
                f"pot_noise must be 'none', 'recorded' or 'model', got {pot_noise!r}"
            )
        return None if pot_noise == "none" else potentiometer_noise(data)
    x = np.asarray(pot_noise, dtype=np.float64)
    if x.ndim != 2 or x.shape[1] != 6:
        raise ShapeError(f"pot_noise must have shape (T, 6), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise NonFiniteError("pot_noise contains NaN or infinity")
    return x


def lowpass_measured(data: IdentificationData, cutoff: float) -> np.ndarray:
    """χ_m through a zero-phase 4th-order Butterworth low-pass at ``cutoff`` Hz (scipy filtfilt)."""
    t = np.asarray(data.t, dtype=np.float64)
    if len(t) < 2:
        raise InvalidInputError("filtering χ_m needs at least two camera frames")
    nyquist = 0.5 / float(np.median(np.diff(t)))
    if not (np.isfinite(cutoff) and 0.0 < cutoff < nyquist):
        raise InvalidInputError(
            f"measured_cutoff must be in (0, {nyquist:.3g}) Hz, the camera's Nyquist frequency; "
            f"got {cutoff}"
        )
    b, a = signal.butter(4, cutoff / nyquist)
    pad = 3 * max(len(a), len(b))
    if len(t) <= pad:
        raise InvalidInputError(f"filtering χ_m needs more than {pad} frames, got {len(t)}")
    return np.asarray(signal.filtfilt(b, a, data.measured, axis=0), dtype=np.float64)


def effect_kwargs(
    gravity: ArrayLike | None,
    load: tuple[float, ArrayLike, ArrayLike] | None,
    offset_drift: ArrayLike | None,
) -> dict[str, Any]:
    """The model effects as the bindings take them (arrays of float64; None: absent)."""

    def f64(a: ArrayLike | None) -> NDArray[np.float64] | None:
        return None if a is None else np.asarray(a, dtype=np.float64)

    return {
        "gravity": f64(gravity),
        "load": None if load is None else (float(load[0]), f64(load[1]), f64(load[2])),
        "offset_drift": f64(offset_drift),
    }


def requested_names(parameters: str | Sequence[str], known: Sequence[str]) -> list[str] | None:
    """:func:`rss6.identify.cloe`'s ``parameters`` checked: ``None`` for ``"base"``, else the names.
    Raises :class:`rss6.InvalidInputError` for another string or a name not in ``known``."""
    if isinstance(parameters, str):
        if parameters != "base":
            raise InvalidInputError(
                f"parameters must be 'base' or a list of names, got {parameters!r}"
            )
        return None
    names = [str(n) for n in parameters]
    unknown = [n for n in names if n not in set(known)]
    if unknown:
        raise InvalidInputError(
            f"unknown parameter(s) {', '.join(unknown)}; see rss6.identify.parameter_names()"
        )
    return names


#: Default of :func:`rss6.identify.cloe`'s ``settle_steps``: ``rss6_ident::SETTLE_STEPS`` (3; 5 until
#: the fourteenth session: docs/identification.md "A shorter look-back for the settled rule").
SETTLE_STEPS: int = _rss6.SETTLE_STEPS


def check_options(
    consistent: bool,
    settle_steps: int,
    commands: str,
    max_iterations: int = 20,
    tol_cost: float = 0.0,
    tol_step: float = 0.0,
) -> None:
    """Raises :class:`rss6.InvalidInputError` for :func:`rss6.identify.cloe` options it refuses."""
    _checks.count(max_iterations, "max_iterations")
    for name, tol in (("tol_cost", tol_cost), ("tol_step", tol_step)):
        if not (math.isfinite(tol) and tol >= 0):
            raise InvalidInputError(f"{name} must be finite and ≥ 0, got {tol!r}")
    if not consistent:
        raise InvalidInputError(
            "consistent=False is not implemented: CLOE estimates logs of physical quantities"
        )
    _checks.count(settle_steps, "settle_steps")
    if commands not in ("simulated", "recorded"):
        raise InvalidInputError(f"commands must be 'simulated' or 'recorded', got {commands!r}")


def model_potentiometer_noise(
    data: IdentificationData, result: IdentificationResult, *, cutoff: float | None = 20.0
) -> np.ndarray:
    """(T, 6) rad: the robot's potentiometer noise estimated against a model — the robot's readings
    (drive convention) at its sampling ticks minus the noise-free potentiometer angles of
    ``result``'s model (:class:`rss6.identify.IdentificationResult`: its estimate and loop) run on
    the robot's recorded commands while replaying :func:`potentiometer_noise` of ``data``,
    high-passed at ``cutoff`` Hz (zero-phase 4th-order Butterworth, scipy ``filtfilt``; ``None``:
    unfiltered) to drop the slow part of the model's error, held between samples. Unlike the
    high-pass of :func:`potentiometer_noise` it keeps the noise below 100 Hz and removes the
    motion's kinks: on the twin (thesis-size trajectory, seed 0) RMS of (estimate − true noise) /
    noise 0.36 at 20 Hz against 0.60 (docs/identification.md, "Replaying the potentiometer
    noise"). Raises :class:`rss6.InvalidInputError` without per-tick potentiometers or recorded
    commands, and what the loop raises."""
    if data.kappa is None or data.tick_t is None:
        raise InvalidInputError(
            "the potentiometer noise needs per-tick potentiometers: collect() records them"
        )
    m = result.model
    kappa = np.asarray(data.kappa, dtype=np.float64)
    fresh = _fresh_samples(kappa)
    step = max(round(float(np.median(np.diff(fresh)))), 1) if fresh.size > 1 else 1
    _, _, _, ang = _rss6.simulate_identification(
        m.kp, result.dynamics, result.pid, data.reference.f0, data.reference.coefficients,
        start=data.start, duration=data.duration, torque_limit=m.torque_limit,
        camera_latency=m.camera_latency, dt=data.dt, derivative_filter=m.derivative_filter,
        friction_smoothing=m.friction_smoothing, implicit_friction=m.implicit_friction,
        commands=data.frame_commands(), outer_gains=data.outer_gains,
        pot_dither=potentiometer_noise(data),
    )  # fmt: skip
    ang = np.asarray(ang)
    # The model samples at every `step`-th tick from tick 0; readings that did not change are
    # missing from `fresh` and held over.
    fresh = fresh[(fresh % step == 0) & (fresh // step < len(ang))]
    drive = _rss6.KinematicParams.nominal()
    est = drive.theta_from_reading(kappa[fresh]) - ang[fresh // step]
    if cutoff is not None:
        nyquist = 0.5 / (step * float(data.dt))
        if not (np.isfinite(cutoff) and 0.0 < cutoff < nyquist):
            raise InvalidInputError(f"cutoff must be in (0, {nyquist:.4g}) Hz, got {cutoff}")
        b, a = signal.butter(4, cutoff / nyquist)
        est = est - signal.filtfilt(b, a, est, axis=0)
    return _held(est, fresh, kappa.shape[0])


def model_noise_passes(
    data: IdentificationData, rerun: Callable[[dict[str, Any]], IdentificationResult]
) -> IdentificationResult:
    """:func:`rss6.identify.cloe` with ``pot_noise="model"``: ``rerun`` (the same CLOE with some
    arguments replaced) first replaying :func:`potentiometer_noise`, then from that estimate
    (``initial``; the same guess, so the same prior) replaying :func:`model_potentiometer_noise`
    against it. The second result, with both passes' iterations and simulations, the first's
    ``rms_before`` and ``model.pot_noise == "model"`` (validation runs estimate theirs likewise).
    Both passes run the call's ``hops`` and ``restarts``: the noise is estimated against the first
    pass's model, which must not sit in a local minimum either."""
    first = rerun({"pot_noise": "recorded"})
    est = model_potentiometer_noise(data, first)
    second = rerun({"pot_noise": est, "initial": (first.dynamics, first.pid)})
    return _both_passes(first, second, model=dataclasses.replace(second.model, pot_noise="model"))


def _both_passes(
    first: IdentificationResult, second: IdentificationResult, **changes: Any
) -> IdentificationResult:
    """The second pass's result counting both passes' iterations and simulations, with the first's
    ``rms_before`` (the guess's) and ``changes``."""
    return dataclasses.replace(
        second,
        iterations=first.iterations + second.iterations,
        simulations=first.simulations + second.simulations,
        rms_before=first.rms_before,
        **changes,
    )


def noise_kwargs(noise: Any) -> dict[str, Any]:
    """The binding's keyword for :func:`rss6.identify.cloe`'s ``noise``: None (Table 4.1), a
    (position m, angle rad) pair of σ, or a (6, 6) frame covariance (the residual whitened by it)."""
    if noise is None:
        return {}
    a = np.asarray(noise, dtype=np.float64)
    if a.shape == (2,):
        return {"noise": (float(a[0]), float(a[1]))}
    if a.shape == (6, 6):
        return {"noise_covariance": a}
    raise ShapeError(
        f"noise must be (position, angle), a (6, 6) frame covariance or 'frames', got shape {a.shape}"
    )


def frame_noise_passes(
    noise: str, rerun: Callable[[dict[str, Any]], IdentificationResult]
) -> IdentificationResult:
    """:func:`rss6.identify.cloe` with ``noise="frames"``: ``rerun`` (the same CLOE with some
    arguments replaced) first with Table 4.1's per-axis weights, then from that estimate
    (``initial``; the same guess, so the same prior) with the residual whitened by the frames'
    covariance there, Σ = (1/F) Σ_k d_k d_kᵀ — a camera's pose noise is correlated between axes
    (x with β, y with α: |ρ| ≈ 0.9 on the simulated camera), which per-axis weights ignore
    (docs/identification.md, "Weighting by the frames' covariance"). The second result, with both
    passes' iterations and simulations and the first's ``rms_before``."""
    if noise != "frames":
        raise InvalidInputError(
            f"noise must be (position, angle), a (6, 6) covariance or 'frames', got {noise!r}"
        )
    first = rerun({"noise": None})
    d = first.residual
    cov = d.T @ d / max(len(d), 1)
    second = rerun({"noise": cov, "initial": (first.dynamics, first.pid)})
    return _both_passes(first, second)


def table_5_2_truth() -> tuple[_rss6.DynamicParams, tuple[float, float, float]]:
    """The documented simulated truth shaped like Table 5.2 (``rss6_ident::table_5_2_truth``): the
    table's identified masses and inertias, its friction × 40 (drive units to N·m) and the tuned
    drive gains moved by its identified/initial ratios. Returns (dynamics, (l_p, l_i, l_d))."""
    dp, pid = _rss6.table_5_2_truth_params()
    return dp, (float(pid[0]), float(pid[1]), float(pid[2]))
