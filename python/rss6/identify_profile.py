"""Profile-likelihood intervals for CLOE's estimates (:func:`profile`).

CLOE's σ comes from the Jacobian at the estimate: the curvature of the output error Φ there. With
stick–slip friction Φ is far from quadratic along poorly identified quantities. On a 2 s run a
crank mass came out ×17 the truth with σ 33 %, and Φ at the truth was only 6 residual variances
higher: the Wald interval said 8.7 σ (docs/identification.md, "Multi-start with stick–slip"). A
profile asks the data directly. The quantity is held at points away from the estimate, every other
estimated quantity is refitted by CLOE at each point, and the interval is where Φ stays below the
level's χ²₁ quantile (in residual variances, scaled like the reported σ). Each point costs one CLOE
from the estimate, so profile what matters, not every flagged quantity of a long run.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray
from scipy import stats

from rss6 import _rss6
from rss6.errors import IdentificationError, InvalidInputError

if TYPE_CHECKING:
    from rss6.identify import IdentificationData, IdentificationResult

__all__ = ["Profile", "profile"]

F64 = NDArray[np.float64]

#: A refit at the estimate itself may end this many residual variances above the fit's Φ before
#: the profile refuses the settings as not the fit's own (measured ≤ 0.02 on the test's run).
REPRODUCE = 1.0


@dataclass(frozen=True)
class Profile:
    """The profile of one estimated quantity. ``offsets``: log(value / estimate) of the points,
    sorted; ``delta``: Φ there minus the lowest Φ seen (the estimate's, unless a point fitted
    better), in residual variances; ``threshold``: the level's χ²₁ quantile scaled by (σ / Wald σ)²,
    so a quadratic Φ gives the reported interval; ``interval``: the values where ``delta`` crosses
    it (linear between points), 0 or ∞ where it does not within ``max_log_offset``; ``wald``: the
    reported interval, estimate·e^(∓zσ); ``lower_minimum``: a point fitted better than the estimate
    by more than the threshold (the estimate is a local minimum); ``runs``: CLOE runs spent."""

    name: str
    estimate: float
    offsets: F64
    delta: F64
    threshold: float
    interval: tuple[float, float]
    wald: tuple[float, float]
    level: float
    lower_minimum: bool
    runs: int

    def bounded(self) -> bool:
        """Whether both ends of the interval were found."""
        return self.interval[0] > 0.0 and math.isfinite(self.interval[1])


def _crossing(offsets: list[float], deltas: list[float], threshold: float) -> float | None:
    """The offset where ``deltas`` (walking outward from offset 0) first reaches ``threshold``,
    linear between the two points around it; None if it never does."""
    for k in range(1, len(offsets)):
        if deltas[k] >= threshold:
            d0, d1 = deltas[k - 1], deltas[k]
            w = 1.0 if d1 == d0 else (threshold - d0) / (d1 - d0)
            return offsets[k - 1] + min(max(w, 0.0), 1.0) * (offsets[k] - offsets[k - 1])
    return None


def profile(
    data: IdentificationData,
    kp: _rss6.KinematicParams,
    dp_guess: _rss6.DynamicParams,
    pid_guess: tuple[float, float, float],
    result: IdentificationResult,
    name: str,
    *,
    level: float = 0.95,
    max_log_offset: float = 3.0,
    progress: Callable[[int, float, float], Any] | None = None,
    **cloe_kwargs: Any,
) -> Profile:
    """The profile-likelihood interval of ``name`` in ``result``, which :func:`rss6.identify.cloe`
    fitted from (``dp_guess``, ``pid_guess``) on ``data`` with ``cloe_kwargs`` (pass the same
    ones: the loop's law, ``commands``, ``prior_log_std``, …; ``hops`` and ``restarts`` are not
    used for the points). On each side the quantity is held at estimate·e^(±cσ), c = 1, 2, 4, …,
    until Φ rises past the threshold or |log offset| reaches ``max_log_offset``; the others start
    from the estimate and keep the fit's prior. ``progress(points, offset, delta)`` after each point.

    Raises :class:`rss6.InvalidInputError` for a name the fit did not estimate, a level outside
    (0, 1), a ``max_log_offset`` that is not finite and > 0, or settings that do not reproduce the
    fit (a refit at the estimate ends > 1 residual variance above its Φ);
    :class:`rss6.IdentificationError` when a point's CLOE does not converge (naming the point)."""
    from rss6 import identify

    if name not in result.identified:
        raise InvalidInputError(
            f"{name!r} was not estimated; estimated: {', '.join(result.identified)}"
        )
    if not 0.0 < level < 1.0:
        raise InvalidInputError(f"level must lie in (0, 1), got {level}")
    if not (math.isfinite(max_log_offset) and max_log_offset > 0.0):
        raise InvalidInputError(f"max_log_offset must be finite and > 0, got {max_log_offset}")
    names = identify.parameter_names()
    j = names.index(name)
    k = result.identified.index(name)
    sigma = float(result.relative_std[k])
    wald_sigma = float(result.relative_std_wald[k]) if len(result.relative_std_wald) else sigma
    s2 = float(result.reduced_chi2)
    phi_hat = float(result.cost_history[-1])
    threshold = float(stats.chi2.ppf(level, 1)) * (sigma / wald_sigma) ** 2
    prior = cloe_kwargs.get("prior_log_std", 1.0)
    psi_guess, _, _ = _rss6.cloe_psi(dp_guess, pid_guess)
    psi_est, _, _ = _rss6.cloe_psi(result.dynamics, result.pid)
    others = [n for n in result.identified if n != name]
    kw = {**cloe_kwargs, "parameters": others, "hops": (), "restarts": 0}
    kw.pop("initial", None)
    if isinstance(kw.get("noise"), str) and result.linear_map is not None:
        # noise="frames": every point is weighted by the fit's own frame covariance, Σ = (WᵀW)⁻¹.
        w = np.asarray(result.linear_map[1])
        kw["noise"] = np.linalg.inv(w.T @ w)

    def at(offset: float) -> float:
        held = psi_est[j] + offset
        g = np.array(psi_guess, dtype=float)
        g[j] = held
        _, dpg, pidg = _rss6.cloe_psi(dp_guess, pid_guess, list(g))
        s = np.array(psi_est, dtype=float)
        s[j] = held
        _, dps, pids = _rss6.cloe_psi(dp_guess, pid_guess, list(s))
        try:
            r = identify.cloe(data, kp, dpg, pidg, initial=(dps, pids), **kw)
        except IdentificationError as e:
            raise IdentificationError(
                f"the profile of {name} at log offset {offset:+.3g} did not converge: {e}"
            ) from e
        phi = float(r.cost_history[-1])
        if prior:
            phi += ((held - psi_guess[j]) / float(prior)) ** 2
        return (phi - phi_hat) / s2

    runs = 0

    def point(offset: float) -> float:
        nonlocal runs
        d = at(offset)
        runs += 1
        if progress is not None:
            progress(runs, offset, d)
        return d

    d0 = point(0.0)
    if d0 > REPRODUCE:
        raise InvalidInputError(
            f"a refit at the estimate ends {d0:.2f} residual variances above the fit's Φ: pass "
            "the data, guess and settings the fit used"
        )
    sides: dict[int, tuple[list[float], list[float]]] = {}
    for side in (-1, 1):
        offs, ds = [0.0], [d0]
        c = 1.0
        while True:
            off = side * min(c * max(sigma, 1e-3), max_log_offset)
            offs.append(off)
            ds.append(point(off))
            if ds[-1] - min(0.0, d0) >= threshold or abs(off) >= max_log_offset:
                break
            c *= 2.0
        sides[side] = (offs, ds)
    lowest = min(min(ds) for _, ds in sides.values())
    est = math.exp(float(psi_est[j]))  # ψ is the log of the physical quantity
    bounds = []
    for side in (-1, 1):
        offs, ds = sides[side]
        x = _crossing([abs(o) for o in offs], [d - lowest for d in ds], threshold)
        bounds.append(None if x is None else est * math.exp(side * x))
    all_off = sorted({o for offs, _ in sides.values() for o in offs})
    by_off = {o: d for offs, ds in sides.values() for o, d in zip(offs, ds, strict=True)}
    z = float(stats.norm.ppf(0.5 + level / 2.0))
    return Profile(
        name=name,
        estimate=est,
        offsets=np.array(all_off),
        delta=np.array([by_off[o] - lowest for o in all_off]),
        threshold=threshold,
        interval=(
            bounds[0] if bounds[0] is not None else 0.0,
            bounds[1] if bounds[1] is not None else math.inf,
        ),
        wald=(est * math.exp(-z * sigma), est * math.exp(z * sigma)),
        level=level,
        lower_minimum=lowest < -threshold,
        runs=runs,
    )
