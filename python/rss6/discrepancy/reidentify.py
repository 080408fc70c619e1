"""Re-identification with the named effects (step 4 of the discrepancy workflow): the effects as
the identification loop takes them, and CLOE of the friction and drive gains with them."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from rss6.discrepancy.model import Model
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
    return out, f"re-identified {len(names)} quantities in {res.iterations} CLOE iterations{held}"
