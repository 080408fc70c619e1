"""An identification run read back from its MCAP log (:func:`rss6.identify.collect` with ``mcap=``):
:meth:`rss6.identify.IdentificationData.from_mcap` is :func:`read`.

The log holds the camera frames, the per-tick potentiometers, commands, desired and (simulated
robots) true poses, and metadata: f0, harmonics, duration, the reference's coefficients and the
visual PID's gains when they were not the thesis's (both since 2026-11-28; older logs have the
reference refitted from the logged desired poses), and the visual PID's first fault if it had one.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rss6 import _rss6
from rss6.errors import InvalidInputError, TruncatedLogError

if TYPE_CHECKING:
    from rss6.identify import IdentificationData

F64 = NDArray[np.float64]

#: The metadata ``kind`` of an identification run's log.
KIND = "rss6.identify.collect"


def read(path: str | Path, *, kinematics: Any = None, partial: bool = False) -> IdentificationData:
    """The :class:`rss6.identify.IdentificationData` logged at ``path`` (module docs).
    ``kinematics`` (default nominal) checks the reference's feasibility. A run that did not finish
    — a truncated file (its writer stopped: no footer) or one that ended on an exception such as
    Ctrl-C — is refused (:class:`rss6.TruncatedLogError`, :class:`rss6.InvalidInputError`) unless
    ``partial``: then its recorded part is returned, ``duration`` cut to its last whole tick (the
    reference must then be in the metadata: a refit from a part of a period is not exact). A fault
    of the visual PID is returned in ``fault``, as :func:`rss6.identify.collect` returns it."""
    import rss6
    from rss6 import identify, logs

    p = Path(path)
    if not p.is_file():
        raise InvalidInputError(f"no such MCAP file: {p}")
    log = logs.read_log(p)
    meta = log.metadata
    if meta.get("kind") != KIND:
        raise InvalidInputError(
            f"{p} is not an identification run (metadata kind {meta.get('kind')!r})"
        )
    try:
        f0, n, duration = float(meta["f0"]), int(meta["harmonics"]), float(meta["duration"])
        t_f, frames = (np.asarray(a, dtype=np.float64) for a in log.streams["camera_pose"])
        tick_t, desired = (np.asarray(a, dtype=np.float64) for a in log.streams["desired_pose"])
        kappa = np.asarray(log.streams["kappa"][1], dtype=np.float64)
        theta_cmd = np.asarray(log.streams["theta_cmd"][1], dtype=np.float64)
    except KeyError as e:
        raise InvalidInputError(f"{p} lacks {e.args[0]!r} (not an identification run?)") from None
    if len(t_f) == 0:
        raise InvalidInputError(f"{p} has no camera frames")
    true = log.streams.get("true_pose")
    true_pose = None if true is None else np.asarray(true[1], dtype=np.float64)
    status = str(meta.get("status", "finished"))
    unfinished = log.truncated or status.startswith("failed")
    coefficients = _floats(meta.get("coefficients"), p, "coefficients")
    if unfinished and not (partial and coefficients is not None):
        what = log.truncation if log.truncated else f"status {status!r}"
        msg = (
            f"{p}: the run did not finish ({what}): its camera frames end at "
            f"t = {float(t_f[-1]):.3f} s of its {duration:g} s"
            + (
                "; IdentificationData.from_mcap(path, partial=True) returns that part"
                if coefficients is not None
                else "; its log has no reference coefficients, so its part cannot be rebuilt"
            )
        )
        raise TruncatedLogError(msg) if log.truncated else InvalidInputError(msg)
    dt = float(tick_t[1] - tick_t[0]) if len(tick_t) > 1 else 1e-3
    if unfinished:
        # The recorded part: whole ticks of every per-tick stream, the frames before the last.
        ticks = min(len(tick_t), len(kappa), len(theta_cmd), len(desired))
        if true_pose is not None:
            ticks = min(ticks, len(true_pose))
        if ticks < 2:
            raise InvalidInputError(f"{p}: the run did not finish and holds under two ticks")
        duration = float(tick_t[ticks - 1]) + dt
        keep = t_f < tick_t[ticks - 1]
        t_f, frames = t_f[keep], frames[keep]
        tick_t, desired = tick_t[:ticks], desired[:ticks]
        kappa, theta_cmd = kappa[:ticks], theta_cmd[:ticks]
        true_pose = None if true_pose is None else true_pose[:ticks]
        if len(t_f) == 0:
            raise InvalidInputError(f"{p}: the run did not finish before its first camera frame")
    width = 2 * n + 1
    if coefficients is not None:
        if coefficients.size != 6 * width:
            raise InvalidInputError(
                f"{p}: {coefficients.size} reference coefficients for 6 axes × {width}"
            )
        coef = coefficients.reshape(6, width)
    else:
        coef = _refit(p, f0, n, tick_t, desired)
    kp = kinematics if kinematics is not None else rss6.KinematicParams.nominal()
    exc = identify.Excitation.from_coefficients(kp, coef, f0)
    gains = _floats(meta.get("outer_gains"), p, "outer_gains")
    if gains is not None and gains.size != 3:
        raise InvalidInputError(f"{p}: outer_gains has {gains.size} values, not 3")
    return identify.IdentificationData(
        t=t_f,
        reference=exc,
        measured=frames,
        duration=duration,
        dt=dt,
        tick_t=tick_t,
        kappa=kappa,
        theta_cmd=theta_cmd,
        reference_pose=desired,
        true_pose=true_pose,
        fault=_fault(meta.get("fault")),
        outer_gains=None if gains is None else (float(gains[0]), float(gains[1]), float(gains[2])),
    )


def _floats(text: Any, path: Path, key: str) -> F64 | None:
    if text is None:
        return None
    try:
        v = np.array([float(x) for x in str(text).split(",")], dtype=np.float64)
    except ValueError:
        raise InvalidInputError(f"{path}: metadata {key!r} is not a list of numbers") from None
    if not np.all(np.isfinite(v)):
        raise InvalidInputError(f"{path}: metadata {key!r} holds NaN or infinity")
    return v


def _refit(path: Path, f0: float, n: int, tick_t: F64, desired: F64) -> F64:
    """The reference's coefficients (6, 2n + 1) refitted exactly from the logged desired poses (a
    log without them): a Fourier series of f0 with n harmonics (eq. 5.11), fitted on basis
    functions evaluated by the series itself (unit coefficients)."""
    pick = np.unique(np.linspace(0, len(tick_t) - 1, min(len(tick_t), 600)).astype(int))
    basis = np.empty((len(pick), 2 * n + 1))
    for j in range(2 * n + 1):
        unit = np.zeros((6, 2 * n + 1))
        unit[0, j] = 1.0
        basis[:, j] = [_rss6.excitation_at(f0, unit, float(t))[0][0] for t in tick_t[pick]]
    coef, *_ = np.linalg.lstsq(basis, desired[pick], rcond=None)
    err = float(np.max(np.abs(basis @ coef - desired[pick])))
    if err > 1e-9:
        raise InvalidInputError(
            f"{path}: the logged reference is not a Fourier series of f0 = {f0} Hz with {n} "
            f"harmonics (refit error {err:.3g})"
        )
    return np.asarray(coef.T, dtype=np.float64)


def _fault(text: Any) -> tuple[float, str] | None:
    """The visual PID's first fault as the log holds it ("t = 4.323 s: reason")."""
    if text is None:
        return None
    head, sep, reason = str(text).partition(" s: ")
    try:
        t = float(head.removeprefix("t = "))
    except ValueError:
        return (float("nan"), str(text))
    return (t, reason) if sep else (t, str(text))
