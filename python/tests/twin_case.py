"""Shared by the discrepancy tests: the model twin as the robot (Table 5.2's truth, the drives'
derivative filter, smoothed friction), its runs, and the model that is its truth without hidden
effects."""

from __future__ import annotations

import re
from typing import Any

import rss6
from rss6 import identify
from rss6.discrepancy.model import Model

KP = rss6.KinematicParams.nominal()
T_F, EPS = 5e-3, 1.0


def robot(truth: Any, seed: int, hidden: dict[str, dict[str, float]] | None, **kw: Any) -> Any:
    """The model twin with ``hidden`` effects in its truth."""
    dp, pid = truth
    return rss6.ModelSim(
        KP,
        dp,
        pid=pid,
        seed=seed,
        drive_derivative_filter=T_F,
        friction_smoothing=EPS,
        effects=hidden,
        **kw,
    )


def collect(twin: Any, exc: identify.Excitation, **kw: Any) -> identify.IdentificationData:
    """One identification run of ``twin`` on ``exc`` through its true camera poses."""
    tr = twin.truth()
    return identify.collect(
        twin,
        exc,
        kp_model=KP,
        sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
        **kw,
    )


def model(
    truth: Any, twin: Any, effects: tuple[Any, ...] = (), *, stick_slip: bool = False
) -> Model:
    """The truth as a discrepancy model (with ``effects``); ``stick_slip``: with the implicit
    stick–slip friction law of :func:`stick_slip_robot` instead of smoothing."""
    dp, pid = truth
    tr = twin.truth()
    friction: dict[str, Any] = (
        {"implicit_friction": True} if stick_slip else {"friction_smoothing": EPS}
    )
    return Model(
        KP,
        dp,
        pid,
        tr["sensor_in_base"],
        tr["target_in_effector"],
        effects=effects,
        derivative_filter=T_F,
        **friction,
    )


def stick_slip_robot(truth: Any, seed: int) -> Any:
    """The model twin with the plant's implicit stick–slip friction law instead of smoothing."""
    dp, pid = truth
    return rss6.ModelSim(
        KP, dp, pid=pid, seed=seed, drive_derivative_filter=T_F, implicit_friction=True
    )


def held_out_costs(note: str) -> tuple[float, float]:
    """The (before, after) held-out whitened costs a re-identification note gives."""
    m = re.search(r"held-out whitened cost ([0-9.e+-]+) → ([0-9.e+-]+)", note)
    assert m is not None, note
    return float(m.group(1)), float(m.group(2))
