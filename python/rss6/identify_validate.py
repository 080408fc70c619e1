"""Validation of an identified model on fresh trajectories (thesis §5.5, Tables 5.3–5.5) and the
variation measure over re-identifications; re-exported by :mod:`rss6.identify`."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6 import _rss6
from rss6.errors import InvalidInputError
from rss6.excitation import Excitation, random_excitation
from rss6.identify import (
    IdentificationData,
    IdentificationResult,
    collect,
    parameter_names,
)
from rss6.identify_replicates import model_output

__all__ = ["Validation", "validate", "variation"]

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Validation:
    """What :func:`validate` returns: ``rms`` (n, 6) RMS of χ_m − χ_s per axis (m, rad) with the
    identified model on each fresh trajectory, ``rms_initial`` (n, 6) the same with the initial
    model (the guess), ``excitations`` and ``data`` of each trajectory. On a simulated robot also
    ``rms_true`` and ``rms_true_initial`` (n, 6): the same RMS against the robot's noise-free pose
    at the frame times instead of the camera's χ_m — the model's own error, without the camera
    noise that bounds ``rms`` from below (None on a real robot)."""

    rms: F64
    rms_initial: F64
    excitations: tuple[Excitation, ...]
    data: tuple[IdentificationData, ...]
    rms_true: F64 | None = None
    rms_true_initial: F64 | None = None

    @property
    def ratio(self) -> F64:
        """rms / rms_initial (n, 6): the thesis's criterion is ≤ 1/3."""
        return np.asarray(self.rms / self.rms_initial)

    @property
    def ratio_true(self) -> F64 | None:
        """rms_true / rms_true_initial (n, 6), or None without a noise-free pose."""
        if self.rms_true is None or self.rms_true_initial is None:
            return None
        return np.asarray(self.rms_true / self.rms_true_initial)

    @property
    def faulted(self) -> tuple[int, ...]:
        """Indices of the trajectories whose run on the robot faulted (their RMS compares the
        model with a robot that left the loop)."""
        return tuple(i for i, d in enumerate(self.data) if d.fault is not None)


def validate(
    result: IdentificationResult,
    robot: Any,
    *,
    n: int = 10,
    seed: int = 0,
    kp_model: _rss6.KinematicParams | None = None,
    sensor_in_base: ArrayLike | None = None,
    target_in_effector: ArrayLike | None = None,
    harmonics: int = 5,
    f0: float = 0.1,
    amplitude: tuple[float, float] = (0.001, 0.005),
    mcap_dir: str | Path | None = None,
    progress: Callable[[int, int], Any] | None = None,
    outer_gains: tuple[float, float, float] | None = None,
    **limits: Any,
) -> Validation:
    """Validation on fresh trajectories (thesis §5.5, Tables 5.3–5.5): ``n`` random feasible
    trajectories (:func:`random_excitation`, seeds ``seed``, ``seed`` + 1, …, same limits), each
    collected on ``robot`` (:func:`collect`), then the identified model and the initial one
    (``result.guess``) simulated in the loop at the frame times. ``kp_model`` defaults to the model's
    kinematics; ``sensor_in_base``/``target_in_effector`` to the robot's truth (simulated robots).
    ``mcap_dir``: one log per trajectory (``validation_<i>.mcap``). ``progress(done, n)``.
    ``outer_gains`` (k_p, k_i, k_d): the visual PID's gains on the robot and in the model (None: the
    thesis's) — the thesis also validates with gains other than the identification run's."""
    kp = result.model.kp if kp_model is None else kp_model
    if sensor_in_base is None or target_in_effector is None:
        if not hasattr(robot, "truth"):
            raise InvalidInputError(
                "sensor_in_base and target_in_effector are needed for this robot"
            )
        truth = robot.truth()
        sensor_in_base = truth["sensor_in_base"] if sensor_in_base is None else sensor_in_base
        target_in_effector = (
            truth["target_in_effector"] if target_in_effector is None else target_in_effector
        )
    rms = np.zeros((n, 6))
    rms0 = np.zeros((n, 6))
    true = np.full((n, 6), np.nan)
    true0 = np.full((n, 6), np.nan)
    excs: list[Excitation] = []
    datas: list[IdentificationData] = []
    for i in range(n):
        exc = random_excitation(
            kp, harmonics=harmonics, f0=f0, seed=seed + i, amplitude=amplitude, **limits
        )
        mcap = None if mcap_dir is None else Path(mcap_dir) / f"validation_{i}.mcap"
        d = collect(
            robot,
            exc,
            kp_model=kp,
            sensor_in_base=sensor_in_base,
            target_in_effector=target_in_effector,
            mcap=mcap,
            outer_gains=outer_gains,
        )
        at_frames = _true_at_frames(d)
        for out, out_true, params in (
            (rms, true, (result.dynamics, result.pid)),
            (rms0, true0, result.guess),
        ):
            chi = model_output(result, d, params=params)
            out[i] = np.sqrt(np.mean((d.measured - chi) ** 2, axis=0))
            if at_frames is not None:
                out_true[i] = np.sqrt(np.mean((at_frames - chi) ** 2, axis=0))
        excs.append(exc)
        datas.append(d)
        if progress is not None:
            progress(i + 1, n)
    has_truth = bool(np.all(np.isfinite(true)))
    return Validation(
        rms=rms,
        rms_initial=rms0,
        excitations=tuple(excs),
        data=tuple(datas),
        rms_true=true if has_truth else None,
        rms_true_initial=true0 if has_truth else None,
    )


def _true_at_frames(d: IdentificationData) -> F64 | None:
    """The robot's noise-free pose at the frame times (the ticks the frames were consumed at), or
    None without one (a real robot, a log without it, or a frame time that is no tick's)."""
    if d.true_pose is None or d.tick_t is None:
        return None
    true_pose, tick_t = np.asarray(d.true_pose), np.asarray(d.tick_t)
    idx = np.searchsorted(tick_t, d.t)
    if np.any(idx >= len(tick_t)) or not np.array_equal(tick_t[idx], d.t):
        return None
    at = true_pose[idx]
    return at if bool(np.all(np.isfinite(at))) else None


def variation(
    estimates: Sequence[tuple[_rss6.DynamicParams, tuple[float, float, float]]],
) -> dict[str, float]:
    """Variation measure (thesis Table 5.5) of each quantity CLOE estimates
    (:func:`parameter_names`) over several identifications (dynamics, pid): standard deviation over
    |mean| (fraction). Needs at least two estimates."""
    if len(estimates) < 2:
        raise InvalidInputError("variation needs at least two estimates")
    phi = np.array([np.exp(np.asarray(_rss6.cloe_psi(dp, pid)[0])) for dp, pid in estimates])
    v = phi.std(axis=0, ddof=1) / np.abs(phi.mean(axis=0))
    return dict(zip(parameter_names(), (float(x) for x in v)))
