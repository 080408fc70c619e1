"""The model a discrepancy search replays, the measured runs it compares with, and the replay.

A :class:`Model` is what a user has after calibration and identification (kinematics, dynamics,
drive gains, ᴼχ_C, ᴱχ_t, the loop's smoothing options) plus a list of named effects
(:class:`AppliedEffect`); ``save``/``load`` keep it as TOML files (``kinematics.toml``,
``dynamics.toml``, ``model.toml`` with the gains, the poses, the options and the effects list).

A :class:`Run` is one measured identification run (the loop of Fig. 5.1): its reference
(an :class:`~rss6.identify.Excitation`), the camera frames, and — when they were measured — the
potentiometers and the joint commands, averaged over each camera interval. Every channel is used.
With the robot's per-tick commands (``commands="recorded"``, the default when the run has them)
they are the replay's *input*: the model is driven by the commands the robot received, and the
channels compared are the poses (6) and potentiometers (6, bit). Without them (or with
``commands="simulated"``) the model's own visual PID closes the loop on its frames and the
commands are compared as well (6 more, rad).

:func:`replay` runs the model twin (``rss6.ModelSim``: the same reference and camera timing; every
library effect is one of its hidden effects) and returns the same channels at the run's frame
times; with a ``seed`` the twin's sensors are noisy (Table 4.1), which is how the noise is learnt.
Why recorded commands: with stick–slip friction the visual PID closed on noisy frames decides
where joints break away, so a closed-loop replay wanders from the robot by up to 0.69 mm on a
2 s run that its own commands reproduce exactly (docs/identification.md, "Stick–slip").
"""

from __future__ import annotations

import math
import sys
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

import rss6

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover - Python < 3.11
    import tomli as tomllib
from rss6 import _checks, identify
from rss6.discrepancy.effects import Change, get
from rss6.errors import InvalidInputError, ShapeError
from rss6.identify_linear import potentiometer_noise

__all__ = [
    "CHANNELS",
    "COMMAND_MODES",
    "MODEL_FORMAT",
    "POT_NOISE_MODES",
    "AppliedEffect",
    "Model",
    "Replay",
    "Run",
    "replay",
    "run_of",
    "simulate",
]

F64 = NDArray[np.float64]

CHANNELS: tuple[str, ...] = (
    *("x", "y", "z", "α", "β", "γ"),
    *(f"κ{i + 1}" for i in range(6)),
    *(f"θcmd{i + 1}" for i in range(6)),
)
"""The channels compared: camera pose χ_E (m, rad), potentiometers κ (bit), joint commands (rad;
only when the replay closes its own loop); joints numbered from 1."""

MODEL_FORMAT = 2
"""The ``format`` :meth:`Model.save` writes into ``model.toml``: 2 numbers joint scopes from 1;
files without the key (format 1) numbered them from 0 and are read in today's numbering."""

COMMAND_MODES: tuple[str, ...] = ("recorded", "simulated")
"""How a replay drives the model: the run's per-tick commands, or the model's own visual PID."""

POT_NOISE_MODES: tuple[str, ...] = ("none", "recorded")
"""What a replay driven by recorded commands does about the robot's potentiometer noise, which its
drive reacted to: nothing, or replay an estimate of it (:func:`run_of`)."""


@dataclass(frozen=True)
class AppliedEffect:
    """A library effect in a model: ``name`` (see :data:`rss6.discrepancy.CANDIDATES`), ``scope``
    and its parameters (SI; missing ones at their null value)."""

    name: str
    scope: str
    params: Mapping[str, float] = field(default_factory=dict)

    def change(self) -> Change:
        """What it does to the simulated model."""
        return get(self.name).apply(self.params, self.scope)


@dataclass(frozen=True)
class Model:
    """The model a discrepancy search replays in the closed loop (issue 14): ``kinematics``
    (:class:`rss6.KinematicParams`), ``dynamics`` (:class:`rss6.DynamicParams`), the drive ``pid``
    gains (l_p, l_i, l_d), ᴼχ_C ``sensor_in_base`` and ᴱχ_t ``target_in_effector`` (6,), the
    ``effects`` it includes (:class:`AppliedEffect` or (name, scope, params) tuples), and the
    loop's options: drive derivative filter T_f (s), Coulomb friction smoothing ε (rad/s) or the
    shared implicit stick–slip law (``implicit_friction``, ``rss6_core::implicit_friction``; the
    plant's with ``implicit_friction=True``), torque limit (N·m), camera latency (s)."""

    kinematics: Any
    dynamics: Any
    pid: Any
    sensor_in_base: Any
    target_in_effector: Any
    effects: Sequence[Any] = ()
    derivative_filter: float = 0.0
    friction_smoothing: float = 0.0
    implicit_friction: bool = False
    torque_limit: float = 30.0
    camera_latency: float = 0.0

    def __post_init__(self) -> None:
        # Checked here, so a wrong model fails where it is made (or loaded), not as an index error
        # or a run "without camera frames" deep inside a replay.
        _checks.gains3(self.pid, "pid", nonnegative=True)
        _checks.pose6(self.sensor_in_base, "sensor_in_base")
        _checks.pose6(self.target_in_effector, "target_in_effector")
        for name, positive in (
            ("derivative_filter", False),
            ("friction_smoothing", False),
            ("torque_limit", True),
            ("camera_latency", False),
        ):
            x = float(getattr(self, name))
            if not math.isfinite(x) or x < 0 or (positive and x == 0):
                raise InvalidInputError(
                    f"{name} must be finite and {'> 0' if positive else '>= 0'}, got {x}"
                )

    def applied(self) -> tuple[AppliedEffect, ...]:
        """The effects as :class:`AppliedEffect` (checked against the library)."""
        out = []
        for e in self.effects:
            a = e if isinstance(e, AppliedEffect) else AppliedEffect(*e)
            get(a.name).check(a.params, a.scope)
            out.append(a)
        return tuple(out)

    def change(self) -> Change:
        """All its effects' changes, merged."""
        c = Change()
        for a in self.applied():
            c = c.merged(a.change())
        return c

    def with_effects(self, effects: Sequence[AppliedEffect]) -> Model:
        """This model with ``effects`` instead of its own."""
        return replace(self, effects=tuple(effects))

    def with_dynamics(self, dynamics: Any, pid: Any) -> Model:
        """This model with other dynamics and gains (after a re-identification)."""
        return replace(self, dynamics=dynamics, pid=tuple(float(g) for g in pid))

    def save(self, directory: str | Path) -> list[Path]:
        """Writes ``kinematics.toml``, ``dynamics.toml`` and ``model.toml`` (gains, ᴼχ_C, ᴱχ_t,
        options and the effects list) into ``directory``; returns their paths."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        self.kinematics.to_toml(out / "kinematics.toml")
        self.dynamics.to_toml(out / "dynamics.toml")
        lines = [
            "# rss6 discrepancy model: parameters beside kinematics.toml and dynamics.toml",
            f"format = {MODEL_FORMAT}",
            f"pid = [{', '.join(repr(float(g)) for g in self.pid)}]",
            f"sensor_in_base = [{', '.join(repr(float(v)) for v in self.sensor_in_base)}]",
            f"target_in_effector = [{', '.join(repr(float(v)) for v in self.target_in_effector)}]",
            f"derivative_filter = {float(self.derivative_filter)!r}",
            f"friction_smoothing = {float(self.friction_smoothing)!r}",
            f"implicit_friction = {'true' if self.implicit_friction else 'false'}",
            f"torque_limit = {float(self.torque_limit)!r}",
            f"camera_latency = {float(self.camera_latency)!r}",
        ]
        for a in self.applied():
            lines += ["", "[[effects]]", f'name = "{a.name}"', f'scope = "{a.scope}"']
            lines.append(
                "params = { "
                + ", ".join(f"{k} = {float(v)!r}" for k, v in sorted(a.params.items()))
                + " }"
            )
        (out / "model.toml").write_text("\n".join(lines) + "\n", encoding="utf-8")
        return [out / "kinematics.toml", out / "dynamics.toml", out / "model.toml"]

    @classmethod
    def load(cls, directory: str | Path) -> Model:
        """The model :meth:`save` wrote into ``directory``. Raises
        :class:`rss6.InvalidInputError` naming a missing file or key or a wrong value."""
        d = Path(directory)
        for name in ("kinematics.toml", "dynamics.toml", "model.toml"):
            if not (d / name).is_file():
                raise InvalidInputError(f"model directory {d} has no {name}")
        try:
            doc = tomllib.loads((d / "model.toml").read_text(encoding="utf-8"))
        except tomllib.TOMLDecodeError as e:
            raise InvalidInputError(f"{d / 'model.toml'} is not valid TOML: {e}") from None
        fmt = doc.get("format", 1)
        if fmt not in (1, MODEL_FORMAT):
            raise InvalidInputError(
                f"{d / 'model.toml'} has format {fmt!r}; this rss6 reads formats 1 and "
                f"{MODEL_FORMAT}"
            )
        kinematics = rss6.KinematicParams.load(d / "kinematics.toml")
        dynamics = rss6.DynamicParams.load(d / "dynamics.toml")
        try:
            effects = tuple(
                AppliedEffect(
                    str(e["name"]), _scope_from(str(e["scope"]), fmt), dict(e.get("params", {}))
                )
                for e in doc.get("effects", [])
            )
            model = cls(
                kinematics=kinematics,
                dynamics=dynamics,
                pid=tuple(float(g) for g in doc["pid"]),
                sensor_in_base=np.asarray(doc["sensor_in_base"], dtype=np.float64),
                target_in_effector=np.asarray(doc["target_in_effector"], dtype=np.float64),
                effects=effects,
                derivative_filter=float(doc.get("derivative_filter", 0.0)),
                friction_smoothing=float(doc.get("friction_smoothing", 0.0)),
                implicit_friction=bool(doc.get("implicit_friction", False)),
                torque_limit=float(doc.get("torque_limit", 30.0)),
                camera_latency=float(doc.get("camera_latency", 0.0)),
            )
        except KeyError as e:
            raise InvalidInputError(f"{d / 'model.toml'} has no {e.args[0]!r}") from None
        except (TypeError, ValueError) as e:
            # InvalidInputError is a ValueError: the model's own checks land here too.
            raise InvalidInputError(f"{d / 'model.toml'}: {e}") from None
        model.applied()
        return model


def _scope_from(scope: str, fmt: int) -> str:
    """A saved effect's scope in today's numbering: format 1 (files without a ``format`` key,
    before the twenty-seventh session) numbered joint scopes from 0, format 2 from 1."""
    if fmt == 1 and scope.startswith("joint ") and scope[6:].isdigit():
        return f"joint {int(scope[6:]) + 1}"
    return scope


@dataclass(frozen=True)
class Run:
    """One measured run of the identification loop: the ``reference`` excitation, ``duration`` (s),
    frame times ``t`` (N,) s and ``channels`` (N, C) at them (:data:`CHANNELS`' first C: 6 without
    the per-tick channels, 12 with recorded ``commands``, 18 without), the joint tick ``dt`` (s),
    and ``commands`` (T, 6): the joint commands the robot received, one per tick from t = 0
    (drive convention, rad), which replays then send instead of closing the model's loop;
    ``pot_dither`` (T, 6) rad: an estimate of the potentiometer noise the robot's drive saw at each
    tick, which noise-free replays then add to their drive's readings (``run_of(pot_noise=...)``)."""

    reference: identify.Excitation
    duration: float
    t: F64
    channels: F64
    dt: float = 1e-3
    commands: F64 | None = None
    pot_dither: F64 | None = None

    @property
    def poses(self) -> F64:
        """The camera poses (N, 6)."""
        return self.channels[:, :6]

    @property
    def width(self) -> int:
        """Number of channels."""
        return int(self.channels.shape[1])


def _interval_means(tick_t: F64, values: F64, frame_t: F64) -> F64:
    """Mean of per-tick ``values`` over each camera interval (t_{k−1}, t_k] (the first: the ticks
    up to t_0), so the potentiometers' and commands' noise averages as the camera's frames do."""
    idx = np.searchsorted(tick_t, frame_t + 1e-9, side="right")
    idx = np.clip(idx, 1, len(tick_t))
    starts = np.r_[0, idx[:-1]]
    csum = np.vstack([np.zeros((1, values.shape[1])), np.cumsum(values, axis=0)])
    counts = np.maximum(idx - starts, 1)[:, None]
    return np.asarray((csum[idx] - csum[starts]) / counts, dtype=np.float64)


def run_of(
    data: Any, *, kinematics: Any = None, commands: str = "recorded", pot_noise: str = "none"
) -> Run:
    """A :class:`Run` from :class:`rss6.identify.IdentificationData` (every channel it has) or from
    an MCAP path written by :func:`rss6.identify.collect` (its reference is refitted from the
    logged desired poses with the logged f0 and harmonics; ``kinematics`` checks it).
    ``commands``: "recorded" — replays send the run's per-tick commands when it has them (the
    channels are then poses and potentiometers); "simulated" — replays close the model's visual
    PID and the commands are compared too. ``pot_noise`` (with recorded commands): "none" — the
    noise-free replays read noise-free potentiometers; "recorded" — they replay
    :func:`rss6.identify.potentiometer_noise` of the run in their drive (its motion then follows
    the robot's noise realisation as far as the estimate goes), and the noisy replays that learn
    the noise are compared with noise-free replays of their own estimate. A :class:`Run` is
    returned as it is."""
    if commands not in COMMAND_MODES:
        raise InvalidInputError(f"commands must be one of {COMMAND_MODES}, got {commands!r}")
    if pot_noise not in POT_NOISE_MODES:
        raise InvalidInputError(f"pot_noise must be one of {POT_NOISE_MODES}, got {pot_noise!r}")
    if isinstance(data, Run):
        if pot_noise == "recorded" and data.pot_dither is None:
            raise InvalidInputError(
                "pot_noise='recorded' needs the run's per-tick commands and potentiometers; this "
                "Run was made without them (build it with run_of(data, pot_noise='recorded'))"
            )
        return data
    if isinstance(data, (str, Path)):
        return _run_from_mcap(Path(data), kinematics, commands, pot_noise)
    if not isinstance(data, identify.IdentificationData):
        raise InvalidInputError(
            "measured data must be rss6.identify.IdentificationData, a Run or an MCAP path; "
            f"got {type(data).__name__}"
        )
    if data.fault is not None:
        raise InvalidInputError(
            f"the run's visual PID faulted at t = {data.fault[0]:.3f} s ({data.fault[1]}): the "
            "loop was open after it; use data.before_fault() or another run"
        )
    ch = [np.asarray(data.measured, dtype=np.float64)]
    recorded = dither = None
    if data.tick_t is not None and data.kappa is not None and data.theta_cmd is not None:
        tt = np.asarray(data.tick_t, dtype=np.float64)
        cmd = np.asarray(data.theta_cmd, dtype=np.float64)
        step = float(np.median(np.diff(tt))) if tt.size > 1 else float(data.dt)
        if not np.isclose(step, float(data.dt), rtol=1e-6):
            raise InvalidInputError(
                f"the run's per-tick records are {step:.6g} s apart but its dt is {data.dt} s"
            )
        ch.append(_interval_means(tt, np.asarray(data.kappa, dtype=np.float64), data.t))
        if commands == "recorded":
            ticks = round(float(data.duration) / float(data.dt))
            if cmd.shape[0] < ticks or abs(float(tt[0])) > 0.5 * float(data.dt):
                raise InvalidInputError(
                    f"the run has {cmd.shape[0]} per-tick commands from t = {tt[0]:.4f} s for "
                    f"{ticks} ticks from 0: not a whole run (use commands='simulated')"
                )
            recorded = cmd[:ticks]
            if pot_noise == "recorded":
                dither = potentiometer_noise(data)[:ticks]
        else:
            ch.append(_interval_means(tt, cmd, data.t))
    if pot_noise == "recorded" and dither is None:
        raise InvalidInputError(
            "pot_noise='recorded' replays the robot's potentiometer noise through its recorded "
            "per-tick commands: "
            + (
                "use commands='recorded'"
                if commands != "recorded"
                else "this run has no per-tick potentiometers and commands"
            )
        )
    return Run(
        data.reference,
        float(data.duration),
        np.asarray(data.t, dtype=np.float64),
        np.hstack(ch),
        float(data.dt),
        recorded,
        dither,
    )


def _run_from_mcap(path: Path, kinematics: Any, commands: str, pot_noise: str) -> Run:
    data = identify.IdentificationData.from_mcap(path, kinematics=kinematics)
    return run_of(data, commands=commands, pot_noise=pot_noise)


def dynamics_with(dp: Any, change: Change) -> Any:
    """``dp`` with the change's friction added to its Coulomb and viscous coefficients."""
    if not any(change.coulomb) and not any(change.viscous):
        return dp
    d = dp.to_dict()
    d["coulomb"] = np.asarray(d["coulomb"], dtype=np.float64) + np.asarray(change.coulomb)
    d["viscous"] = np.asarray(d["viscous"], dtype=np.float64) + np.asarray(change.viscous)
    return rss6.DynamicParams.from_dict(d)


@dataclass(frozen=True)
class Replay:
    """One simulated run at the model's own camera frames: ``frame_t`` (F,) s, ``poses`` (F, 6),
    the per-tick channels averaged over the measured run's camera intervals (N, 6 or 12) or None;
    for a replay driven by recorded commands also the model's true pose per tick (``tick_t``,
    ``true_pose``) and its total camera ``latency`` (s); a noisy replay of a run with
    ``pot_dither`` also the estimate of its own potentiometer noise (``dither``, T × 6 rad)."""

    frame_t: F64
    poses: F64
    ticks: F64 | None
    tick_t: F64 | None = None
    true_pose: F64 | None = None
    latency: float = 0.0
    dither: F64 | None = None

    def _index(self, run: Run) -> NDArray[np.int64] | None:
        """Frame k of the model for frame k of the run when both cameras capture on the same
        schedule and only their latencies differ (stamps apart by one constant, ≤ 1 frame more
        or less): the model's frame k shows the pose at the same capture time. None otherwise."""
        n, f = len(run.t), len(self.frame_t)
        m = min(n, f)
        if m < 2 or abs(n - f) > 1:
            return None
        d = self.frame_t[:m] - run.t[:m]
        if np.ptp(d) > 5e-4:
            return None
        return np.minimum(np.arange(n), f - 1)

    def at(self, run: Run) -> F64:
        """The channels (N, C) at the run's frames. Driven by recorded commands: the model's pose
        ``latency`` before each stamp (its true pose per tick, linear between ticks — noise-free
        frames are exactly that pose), so a latency shows as the lag between the frames and the
        commands and potentiometers. In a closed loop: the model's frame captured at the same time
        (frame by frame when the two cameras share their capture schedule and differ only in
        latency — their stamps then differ by a constant), else a cubic spline through the
        model's frames at the run's stamps."""
        out = np.empty_like(run.channels)
        idx = None if run.commands is not None else self._index(run)
        if run.commands is not None:
            if self.tick_t is None or self.true_pose is None:
                raise ShapeError("the replay has no per-tick poses")
            at = run.t - self.latency
            for j in range(6):
                out[:, j] = np.interp(at, self.tick_t, self.true_pose[:, j])
        elif idx is not None:
            out[:, :6] = self.poses[idx]
        else:
            from scipy.interpolate import CubicSpline

            out[:, :6] = CubicSpline(self.frame_t, self.poses, axis=0, extrapolate=True)(run.t)
        if run.width > 6:
            if self.ticks is None:
                raise ShapeError("the replay has no per-tick channels")
            out[:, 6:] = self.ticks
        return out

    def noise(self, clean: Replay, run: Run) -> F64:
        """This noisy replay minus the ``clean`` one at the model's own frames, taken at the frame
        nearest each of the run's times (N, C): the loop's noise, not smoothed by interpolation."""
        if self.frame_t.shape != clean.frame_t.shape:
            raise ShapeError("noisy and clean replays have different frames")
        idx = self._index(run)
        if idx is not None:
            k = idx
        else:
            k = np.clip(np.searchsorted(self.frame_t, run.t), 1, len(self.frame_t) - 1)
            k = np.where(
                np.abs(self.frame_t[k - 1] - run.t) <= np.abs(self.frame_t[k] - run.t), k - 1, k
            )
        out = np.empty_like(run.channels)
        out[:, :6] = (self.poses - clean.poses)[k]
        if run.width > 6:
            if self.ticks is None or clean.ticks is None:
                raise ShapeError("the replay has no per-tick channels")
            out[:, 6:] = self.ticks - clean.ticks
        return out


def replay(model: Model, run: Run, change: Change | None = None, *, seed: int | None = None) -> F64:
    """The model's noise-free replay of ``run`` (with its effects and ``change`` on top): the run's
    channels (N, C) at its frame times (:meth:`Replay.at`). See :func:`simulate`."""
    return simulate(model, run, change, seed=seed).at(run)


def simulate(
    model: Model, run: Run, change: Change | None = None, *, seed: int | None = None
) -> Replay:
    """The model (with its effects and ``change`` on top) in the run's loop from a fresh model twin
    at rest at the reference's start. Noise-free unless ``seed`` is given (then the twin's sensors
    add Table 4.1's noise with that seed); noise-free replays of a run with ``pot_dither`` add it
    to their drive's readings (sent as commands minus the dither: the drive's PID sees only their
    difference), noisy ones estimate their own (:attr:`Replay.dither`). Raises :class:`rss6.InvalidInputError` if the change is
    not physical (e.g. friction below 0) and :class:`rss6.IdentificationError` if the replay's
    visual PID faults."""
    c = model.change() if change is None else model.change().merged(change)
    dp = dynamics_with(model.dynamics, c)
    if np.any(np.asarray(dp.coulomb) < 0) or np.any(np.asarray(dp.viscous) < 0):
        raise InvalidInputError("friction below 0 after the effects: not a physical model")
    g0 = [float(g) for g in model.pid]
    pid = (g0[0] * (1 + c.gains[0]), g0[1] * (1 + c.gains[1]), g0[2] * (1 + c.gains[2]))
    if min(pid) <= 0:
        raise InvalidInputError(f"drive gains {pid} are not positive")
    quiet: dict[str, Any] = (
        {} if seed is not None else {"pixel_noise": 0.0, "potentiometer_noise": 0.0}
    )
    twin = rss6.ModelSim(
        model.kinematics,
        dp,
        pid=pid,
        effects=c.twin or None,
        seed=0 if seed is None else int(seed),
        dt=run.dt,
        sensor_in_base=np.asarray(model.sensor_in_base, dtype=np.float64),
        target_in_effector=np.asarray(model.target_in_effector, dtype=np.float64),
        torque_limit=model.torque_limit,
        camera_latency=model.camera_latency,
        drive_derivative_filter=model.derivative_filter,
        friction_smoothing=model.friction_smoothing,
        implicit_friction=model.implicit_friction,
        **quiet,
    )
    # Whole periods covering the run (a run read in part ends inside one); recorded commands are
    # held at their last value past the run's end, where no frame is compared.
    periods = max(1, math.ceil(run.duration / run.reference.duration - 1e-9))
    commands = run.commands
    if commands is not None:
        need = round(periods * run.reference.duration / run.dt)
        if seed is None and run.pot_dither is not None:
            commands = commands - run.pot_dither
        if commands.shape[0] < need:
            commands = np.vstack([commands, np.repeat(commands[-1:], need - len(commands), 0)])
    data = identify.collect(
        twin,
        run.reference,
        kp_model=model.kinematics,
        sensor_in_base=model.sensor_in_base,
        target_in_effector=model.target_in_effector,
        periods=periods,
        commands=commands,
    )
    if data.fault is not None:
        raise rss6.IdentificationError(
            f"the model's loop faulted at t = {data.fault[0]:.3f} s ({data.fault[1]})"
        )
    ticks = None
    if run.width > 6:
        if data.tick_t is None or data.kappa is None or data.theta_cmd is None:
            raise ShapeError("the replay has no per-tick channels")
        parts = [_interval_means(data.tick_t, data.kappa, run.t)]
        if run.width > 12:
            parts.append(_interval_means(data.tick_t, data.theta_cmd, run.t))
        ticks = np.hstack(parts)
    if run.commands is None:
        return Replay(np.asarray(data.t), np.asarray(data.measured), ticks)
    if data.true_pose is None or not np.all(np.isfinite(data.true_pose)):
        raise ShapeError("the model twin gave no true poses")
    latency = model.camera_latency + c.twin.get("camera_latency", {}).get("latency", 0.0)
    dither = None
    if seed is not None and run.pot_dither is not None:
        dither = potentiometer_noise(data)[: run.commands.shape[0]]
    return Replay(
        np.asarray(data.t),
        np.asarray(data.measured),
        ticks,
        np.asarray(data.tick_t, dtype=np.float64),
        np.asarray(data.true_pose, dtype=np.float64),
        float(latency),
        dither,
    )
