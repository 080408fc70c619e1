"""Hops and restarts out of the local minima of a stick–slip CLOE cost (:func:`rss6.identify.cloe`'s
``hops`` and ``restarts``).

Closed-loop output error sees Ξ and the drive gains only up to one common factor, so one quantity
is held (e.g. l_p). Moving every *other* quantity by the same log-factor δ is then the same as
moving the held one alone by −δ: a point whose output differs from the estimate's in exactly the
direction the data pin through the held quantity. With stick–slip friction LM stops in local minima
along that direction (gains and Coulomb frictions too large together); a new CLOE from the moved
estimate leaves them (docs/identification.md, "Multi-start with stick–slip"). Some local minima lie
elsewhere (a link mass several times the truth with σ < 10 %): restarts from moved guesses find a
lower one, and the spread of the estimates over equally good runs says what the local σ cannot.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

from rss6 import _checks, _rss6
from rss6.errors import IdentificationError, InvalidInputError

if TYPE_CHECKING:
    from rss6.identify import IdentificationResult

__all__ = ["EQUALLY_GOOD", "check", "check_restarts", "hopped", "restarted"]

#: Runs whose output error Φ exceeds the best one's by at most this many residual variances fit the
#: data as well: the 99 % quantile of χ² with one degree of freedom (a likelihood-ratio test).
EQUALLY_GOOD = 6.63
#: :func:`rss6.identify.cloe`'s bound on the relative σ of a well-identified quantity.
POOR_STD = 0.1


def check(hops: Sequence[float], parameters: object, hold: Sequence[str]) -> list[float]:
    """The hops as floats. Raises :class:`rss6.InvalidInputError` unless ``parameters == "base"``
    and something is held (otherwise the scale is free and a hop moves nothing the data see), or
    for a δ that is not finite with 0 < |δ| ≤ 1."""
    if parameters != "base" or not hold:
        raise InvalidInputError(
            "hops need parameters='base' and a held quantity (e.g. hold=['lp']): the common scale "
            "they move along is otherwise free"
        )
    deltas = [float(d) for d in hops]
    if not all(math.isfinite(d) and 0.0 < abs(d) <= 1.0 for d in deltas):
        raise InvalidInputError(f"every hop must be finite with 0 < |δ| ≤ 1, got {list(hops)}")
    return deltas


def hopped(
    result: IdentificationResult,
    hops: Sequence[float],
    rerun: Callable[[dict[str, Any]], IdentificationResult],
    parameters: object,
    hold: Sequence[str],
) -> IdentificationResult:
    """``result`` or a better one: for each δ of ``hops`` in turn, ``rerun({"dp_guess": …,
    "pid_guess": …})`` — the same CLOE from the best estimate so far with every quantity but the
    ``hold`` ones moved by the log-factor δ — kept when its reduced χ² is lower. A hop that does not
    converge is skipped (NaN in ``hops``). The result's ``hops`` holds the reduced χ² of the first
    run and of every hop; ``iterations`` and ``simulations`` count every run; ``guess`` and
    ``rms_before`` stay the first run's. Raises what :func:`check` raises."""
    deltas = check(hops, parameters, hold)
    names = _rss6.cloe_parameter_names()
    best, chi2 = result, [result.reduced_chi2]
    iterations, simulations = result.iterations, result.simulations
    for d in deltas:
        psi, _, _ = _rss6.cloe_psi(best.dynamics, best.pid)
        moved = [p if n in hold else p + d for n, p in zip(names, psi, strict=True)]
        _, dp, pid = _rss6.cloe_psi(best.dynamics, best.pid, moved)
        try:
            r = rerun({"dp_guess": dp, "pid_guess": pid})
        except IdentificationError:
            chi2.append(float("nan"))
            continue
        iterations, simulations = iterations + r.iterations, simulations + r.simulations
        chi2.append(r.reduced_chi2)
        if r.reduced_chi2 < best.reduced_chi2:
            best = r
    return dataclasses.replace(
        best,
        hops=tuple(chi2),
        iterations=iterations,
        simulations=simulations,
        guess=result.guess,
        rms_before=result.rms_before,
    )


def check_restarts(restarts: int, spread: float) -> None:
    """Raises :class:`rss6.InvalidInputError` unless ``restarts`` is an int ≥ 0 and
    0 < ``spread`` < 1."""
    _checks.count(restarts, "restarts")
    if not (math.isfinite(spread) and 0.0 < spread < 1.0):
        raise InvalidInputError(f"restart_spread must lie in (0, 1), got {spread!r}")


def restarted(
    result: IdentificationResult,
    restarts: int,
    spread: float,
    rerun: Callable[[dict[str, Any]], IdentificationResult],
    hold: Sequence[str],
    data: Any,
) -> IdentificationResult:
    """``result`` or a better one: ``restarts`` more runs ``rerun({"initial": (dp, pid)})`` — the
    same CLOE (same guess, so the same prior) started from the guess with every quantity ``result``
    identified, but the ``hold`` ones, moved by the log of a seeded factor in [1 − ``spread``,
    1 + ``spread``] — and the one with the lowest output error Φ = reduced χ² × (N − p) kept. Runs
    whose Φ exceeds that by at most :data:`EQUALLY_GOOD` kept residual variances fit ``data`` as
    well: each identified quantity's σ is raised to at least the largest |log difference| between
    such a run's estimate and the kept one (``start_spread``), and ``poorly_identified`` is redone.
    A restart that does not converge is skipped (NaN in ``restarts``). ``restarts`` holds every
    run's reduced χ², the first run's first; ``iterations`` and ``simulations`` count every run;
    ``guess`` and ``rms_before`` stay the first run's."""
    rng = np.random.default_rng(0)
    names = _rss6.cloe_parameter_names()
    psi_g, gdp, gpid = _rss6.cloe_psi(*result.guess)
    n_res = 6 * len(data.t)
    runs, chi2 = [result], [result.reduced_chi2]
    for _ in range(restarts):
        moved = list(psi_g)
        for n in result.identified:
            if n not in hold:
                moved[names.index(n)] += math.log1p(spread * rng.uniform(-1.0, 1.0))
        _, dp, pid = _rss6.cloe_psi(gdp, gpid, moved)
        try:
            r = rerun({"initial": (dp, pid)})
        except IdentificationError:
            chi2.append(float("nan"))
            continue
        runs.append(r)
        chi2.append(r.reduced_chi2)

    def phi(r: IdentificationResult) -> float:
        return r.reduced_chi2 * max(n_res - len(r.identified), 1)

    best = min(runs, key=phi)
    psi_b, _, _ = _rss6.cloe_psi(best.dynamics, best.pid)
    spread_k = np.zeros(len(best.identified))
    for r in runs:
        if phi(r) - phi(best) > EQUALLY_GOOD * best.reduced_chi2:
            continue
        psi_r, _, _ = _rss6.cloe_psi(r.dynamics, r.pid)
        for i, n in enumerate(best.identified):
            if n in r.identified:
                j = names.index(n)
                spread_k[i] = max(spread_k[i], abs(psi_r[j] - psi_b[j]))
    std = np.maximum(best.relative_std, spread_k)
    return dataclasses.replace(
        best,
        relative_std=std,
        poorly_identified=tuple(
            n for n, s in zip(best.identified, std, strict=True) if s > POOR_STD
        ),
        restarts=tuple(chi2),
        start_spread=spread_k,
        iterations=sum(r.iterations for r in runs),
        simulations=sum(r.simulations for r in runs),
        guess=result.guess,
        rms_before=result.rms_before,
    )
