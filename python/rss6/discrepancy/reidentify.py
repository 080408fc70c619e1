"""Re-identification with the named effects (step 4 of the discrepancy workflow): the effects as
the identification loop takes them, and CLOE of the friction and drive gains with them."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy.model import Model, replay
from rss6.errors import IdentificationError, InvalidInputError

F64 = NDArray[np.float64]

REIDENTIFY_DEFAULT: tuple[str, ...] = (
    *(f"fc{i}" for i in range(1, 7)),
    *(f"fv{i}" for i in range(1, 7)),
    "lp",
    "li",
    "ld",
)
"""What ``reidentify=True`` re-identifies: the friction and the drive gains (the quantities CLOE
sees best in this loop; docs/identification.md)."""


def loop_effects(model: Model) -> tuple[Any, tuple[float, float, float], dict[str, Any]]:
    """The model's effects as the identification loop takes them: (dynamics with the named
    friction, drive gains with the named mismatch, keyword arguments of
    :func:`rss6.identify.cloe` / :func:`rss6.identify.simulate`: camera latency, gravity of a
    tilted base, payload as a load, offset drift). Raises :class:`rss6.InvalidInputError` for an
    effect the identification loop cannot express (backlash)."""
    from scipy.spatial.transform import Rotation

    from rss6.discrepancy.model import dynamics_with

    c = model.change()
    dp = dynamics_with(model.dynamics, c)
    g0 = [float(g) for g in model.pid]
    pid = (g0[0] * (1 + c.gains[0]), g0[1] * (1 + c.gains[1]), g0[2] * (1 + c.gains[2]))
    kw: dict[str, Any] = {"camera_latency": model.camera_latency}
    for name, params in c.twin.items():
        if name == "camera_latency":
            kw["camera_latency"] += params["latency"]
        elif name == "base_tilt":
            r = Rotation.from_euler("XY", [params["roll"], params["pitch"]]).as_matrix()
            kw["gravity"] = r.T @ np.array([0.0, 0.0, -9.81])
        elif name == "payload":
            com = [params["x"], params["y"], params["z"]]
            kw["load"] = (params["mass"], com, np.eye(3) * params.get("inertia", 0.0))
        elif name == "joint_offset_drift":
            rate = np.zeros(6)
            if "joint" in params:
                rate[int(params["joint"])] = params["rate"]
            else:
                rate[:] = params["rate"]
            kw["offset_drift"] = rate
        else:
            raise InvalidInputError(
                f"the identification loop cannot express {name!r}: re-identify without it"
            )
    return dp, pid, kw


def _reidentify(model: Model, data: Any, which: bool | Sequence[str]) -> tuple[Model, str]:
    """CLOE of ``which`` (True: :data:`REIDENTIFY_DEFAULT`) on the fitting run with the named
    effects; the re-identified model (its named friction and gain mismatch folded into the
    dynamics and gains, the other effects kept) and a note."""
    from rss6 import identify

    default = isinstance(which, bool)
    names = list(REIDENTIFY_DEFAULT) if isinstance(which, bool) else list(which)
    dp, pid, kw = loop_effects(model)
    timing = ""
    t0 = float(data.t[0])
    if kw["camera_latency"] > 0 and t0 > 0 and t0 != kw["camera_latency"]:
        # The loop's frames must fall on the measured ones, which a latency delays: the first
        # arrives at t0 = the robot's latency on the tick. The pose fit's estimate is off by
        # its error (8.9 ms for 10 ms), which puts every model frame a tick away.
        timing = f"; the loop's latency {1e3 * t0:.4g} ms, the first frame's time"
        timing += f" (named {1e3 * kw['camera_latency']:.4g} ms)"
        kw["camera_latency"] = t0

    def cloe(names: list[str]) -> Any:
        return identify.cloe(
            data,
            model.kinematics,
            dp,
            pid,
            parameters=names,
            derivative_filter=model.derivative_filter,
            friction_smoothing=model.friction_smoothing,
            implicit_friction=model.implicit_friction,
            commands="recorded" if getattr(data, "theta_cmd", None) is not None else "simulated",
            torque_limit=model.torque_limit,
            **kw,
        )

    held = ""
    try:
        res = cloe(names)
    except IdentificationError as e:
        # The default set asks for every friction coefficient and gain; one the fitting run cannot
        # identify (a joint that hardly moves) is held at the model's value, and said so. Names
        # the caller chose are not dropped.
        missing = [n for n in getattr(e, "names", []) if n in names]
        if not default or not missing or len(missing) == len(names):
            raise
        names = [n for n in names if n not in missing]
        held = f" ({', '.join(missing)} not identifiable from the fitting run: held)"
        res = cloe(names)
    kept = [a for a in model.applied() if a.name not in ("joint_friction", "pid_gains")]
    out = model.with_effects(kept).with_dynamics(res.dynamics, res.pid)
    note = f"re-identified {len(names)} quantities in {res.iterations} CLOE iterations"
    return out, note + held + timing


def reidentify_on(
    model: Model,
    fit: Any,
    held: Any,
    cost: Callable[[F64], float],
    held_named: F64,
    which: bool | Sequence[str],
) -> tuple[Model, F64 | None, str]:
    """Step 10 of :func:`~rss6.discrepancy.diagnose`: CLOE of ``which`` on the fitting part
    ``fit`` with the named effects, judged on the held-out part ``held``. Returns the model to
    keep — the re-identified one only if its held-out ``cost`` (the whitened residual's sum of
    squares over every channel, poses and potentiometers) is not above ``held_named``'s, the
    residual with the named effects —, the re-identified model's held-out residual (None if it
    could not run) and a note."""
    from rss6 import identify

    last = fit.t[-1] + fit.run.dt
    per_tick: dict[str, Any] = {}
    if fit.run.commands is not None:
        ticks = min(len(fit.run.commands), round(float(last) / fit.run.dt) + 1)
        per_tick = {"tick_t": np.arange(ticks) * fit.run.dt, "theta_cmd": fit.run.commands[:ticks]}
    data = identify.IdentificationData(
        t=fit.t,
        reference=fit.run.reference,
        measured=fit.measured[:, :6],
        duration=float(last),
        dt=fit.run.dt,
        **per_tick,
    )
    try:
        model_re, note = _reidentify(model, data, which)
    except (InvalidInputError, IdentificationError) as e:
        return model, None, f"not re-identified: {e}"
    held_after = held.measured - held.baseline(replay(model_re, held.run))[held.rows]
    c_named, c_after = cost(held_named), cost(held_after)
    change = f"held-out whitened cost {c_named:.6g} → {c_after:.6g}"
    if c_after <= c_named:
        return model_re, held_after, f"{note}; {change}"
    return (
        model,
        held_after,
        f"{note}, not kept: {change}; the model is the one with the named effects",
    )
