"""Hops out of the local minima of a stick–slip CLOE cost (:func:`rss6.identify.cloe`'s ``hops``).

Closed-loop output error sees Ξ and the drive gains only up to one common factor, so one quantity
is held (e.g. l_p). Moving every *other* quantity by the same log-factor δ is then the same as
moving the held one alone by −δ: a point whose output differs from the estimate's in exactly the
direction the data pin through the held quantity. With stick–slip friction LM stops in local minima
along that direction (gains and Coulomb frictions too large together); a new CLOE from the moved
estimate leaves them (docs/identification.md, "Multi-start with stick–slip").
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from rss6 import _rss6
from rss6.errors import IdentificationError, InvalidInputError

if TYPE_CHECKING:
    from rss6.identify import IdentificationResult

__all__ = ["check", "hopped"]


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
