"""Exciting trajectories for dynamic identification (thesis §5.4), re-exported by
:mod:`rss6.identify`.

An exciting trajectory is a finite Fourier series per pose axis (eq. 5.11) with n harmonics of f0 that
starts and ends at rest at a chosen pose. :func:`excitation` maximises the observability index O_in
(eq. 5.13) of the stacked regressor of the identifiable parameters over the trajectories that meet the
limits on a dense sampling (IK, stroke with a margin, type I/II singularities, eq. 4.22, joint rates,
accelerations) with scipy's differential evolution — seeded, the population evaluated in parallel in
Rust. The thesis used a genetic algorithm (324 iterations, O_in 0.38 → 1.345 in its units).

>>> import rss6
>>> from rss6 import identify
>>> exc = identify.excitation(rss6.KinematicParams.nominal(), maxiter=3, popsize=4, seed=1)
>>> exc.coefficients.shape, exc.duration
((6, 11), 10.0)
>>> pose, rate, acc = exc.sample(0.0)
>>> bool(abs(rate).max() < 1e-12)
True
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6 import _checks, _rss6
from rss6.errors import IdentificationError, InvalidInputError

__all__ = [
    "Excitation",
    "LoopObservability",
    "best_for_loop",
    "excitation",
    "focus_rms",
    "loop_observability",
    "random_excitation",
]

F64 = NDArray[np.float64]


@dataclass(frozen=True)
class Excitation:
    """A feasible exciting trajectory.

    ``coefficients`` (6, 2n + 1): per pose axis [s¹, c¹, …, sⁿ, cⁿ, χ0] of eq. 5.11; ``f0`` (Hz);
    ``duration`` = 1/f0 (s, one period: it starts and ends at rest at the same pose); ``observability``
    O_in (eq. 5.13) and ``condition`` (cond of the stacked regressor of the identifiable parameters);
    ``columns``: the identifiable columns of Ξ."""

    coefficients: F64
    f0: float
    duration: float
    observability: float
    condition: float
    columns: tuple[int, ...]

    def sample(self, t: float) -> tuple[F64, F64, F64]:
        """(χ, χ̇, χ̈) at time ``t`` (s)."""
        return _rss6.excitation_at(self.f0, self.coefficients, float(t))

    @classmethod
    def from_coefficients(
        cls, kp: _rss6.KinematicParams, coefficients: ArrayLike, f0: float, **limits: Any
    ) -> Excitation:
        """The trajectory with these coefficients (6, 2n + 1) and ``f0`` (Hz) after checking it
        against the limits (keyword arguments of :class:`rss6._rss6.ExcitationProblem`); raises
        :class:`rss6.IdentificationError` naming the violated constraint and its time."""
        c = np.asarray(coefficients, dtype=np.float64)
        if c.ndim != 2 or c.shape[0] != 6 or c.shape[1] < 5 or c.shape[1] % 2 == 0:
            raise InvalidInputError(
                f"coefficients must have shape (6, 2n + 1), n >= 2; got {c.shape}"
            )
        n = (c.shape[1] - 1) // 2
        problem = _rss6.ExcitationProblem(kp, harmonics=n, f0=f0, **limits)
        return _finish(problem, c, f0)


@dataclass(frozen=True)
class LoopObservability:
    """What the camera sees of A through the closed loop on one trajectory
    (:func:`loop_observability`): ``o_in`` (eq. 5.13 on the noise-weighted output sensitivity
    ∂(χ_s/σ)/∂log q: dimensionless, so masses, inertias, friction and gains count alike) and
    ``condition`` of its identifiable columns, the ``identifiable`` quantities' names, the
    camera ``frames`` simulated and ``relative_std`` {name: σ}: the relative standard deviation
    each estimate would have from these frames with white noise of the given σ (the Cramér–Rao
    bound, √diag((GᵀG)⁻¹) of the log; CLOE's Wald σ at this point). ``o_in`` is not comparable in
    value with :attr:`Excitation.observability`, which is in the torque regressor's units:
    compare rankings of trajectories."""

    o_in: float
    condition: float
    identifiable: tuple[str, ...]
    frames: int
    relative_std: dict[str, float]


def loop_observability(
    exc: Excitation,
    kp: _rss6.KinematicParams,
    dynamics: _rss6.DynamicParams,
    pid: tuple[float, float, float],
    *,
    torque_limit: float = 30.0,
    derivative_filter: float = 0.0,
    friction_smoothing: float = 0.0,
    implicit_friction: bool = False,
    hold: Sequence[str] = ("lp",),
    noise: tuple[float, float] | None = None,
    threshold: float = 1e-3,
    periods: int = 1,
) -> LoopObservability:
    """The closed loop's observability of A on ``exc`` (``periods`` periods from rest at its start)
    at the model (``kp``, ``dynamics``, drive gains ``pid``) — what CLOE works with, where
    :attr:`Excitation.observability` is the torque regressor's that :func:`excitation` maximises
    (issue 13 asks for both). One simulation of the loop with its sensitivities (≈ 0.7 s for 10 s
    on two cores). ``hold``: quantities left out (default l_p: the loop sees Ξ and the gains only up
    to a common factor, docs/identification.md); ``noise`` (position m, angle rad): the weights
    (default Table 4.1); ``threshold``: the pivoted QR's relative |R_ii|; the loop settings as for
    :func:`rss6.identify.simulate`."""
    if int(periods) < 1:
        raise InvalidInputError(f"periods must be >= 1, got {periods}")
    o_in, cond, names, frames, std = _rss6.loop_observability(
        kp,
        dynamics,
        (float(pid[0]), float(pid[1]), float(pid[2])),
        exc.f0,
        exc.coefficients,
        start=exc.sample(0.0)[0],
        duration=int(periods) * exc.duration,
        torque_limit=torque_limit,
        derivative_filter=derivative_filter,
        friction_smoothing=friction_smoothing,
        implicit_friction=implicit_friction,
        noise=noise,
        hold=list(hold),
        identifiability_threshold=threshold,
    )
    return LoopObservability(
        float(o_in),
        float(cond),
        tuple(names),
        int(frames),
        {str(n): float(v) for n, v in zip(names, std, strict=True)},
    )


def best_for_loop(
    kp: _rss6.KinematicParams,
    dynamics: _rss6.DynamicParams,
    pid: tuple[float, float, float],
    *,
    candidates: int = 20,
    seed: int = 0,
    include: Sequence[Excitation] = (),
    harmonics: int = 5,
    f0: float = 0.1,
    amplitude: tuple[float, float] = (0.001, 0.005),
    focus: Sequence[str] = (),
    progress: Callable[[int, float], Any] | None = None,
    **loop: Any,
) -> tuple[Excitation, LoopObservability]:
    """The trajectory the closed loop shows A best through, at the model (``kp``, ``dynamics``,
    drive gains ``pid``): of ``include`` and ``candidates`` random feasible trajectories (seeds
    ``seed``·1000 + k, :func:`random_excitation` with ``harmonics``, ``f0``, ``amplitude``), the
    one with the most identifiable quantities and, among those, the largest O_in of
    :func:`loop_observability` (keywords ``loop`` go there). A random search on the loop's own
    objective: each candidate costs one simulation with sensitivities (≈ 0.6 s for 10 s on two
    cores), so no population optimiser. The loop's O_in depends on the model it is evaluated at
    (docs/identification.md): use a model near the robot, e.g. a first identification's estimate,
    then collect and identify again on the result. ``progress(done, best O_in)`` after each.

    ``focus``: quantity names or name prefixes (``"fc"`` is fc1 … fc6) to choose for instead of
    O_in — the trajectory on which the most of them are identifiable and, among those, their
    relative σ (:attr:`LoopObservability.relative_std`) has the smallest root mean square (an
    A-criterion on their logs). O_in, a D-criterion over every identifiable quantity, is dominated
    by the poorly seen masses and can trade the friction terms against each other
    (docs/identification.md)."""
    if int(candidates) < 0 or (int(candidates) == 0 and not include):
        raise InvalidInputError("candidates must be >= 0, with at least one trajectory in all")
    focused = _focused(focus, loop.get("hold", ("lp",)))
    best: tuple[tuple[int, float], Excitation, LoopObservability] | None = None
    pool = list(include)
    for k in range(int(candidates) + len(pool)):
        exc = (
            pool[k]
            if k < len(pool)
            else random_excitation(
                kp, harmonics=harmonics, f0=f0, seed=int(seed) * 1000 + k - len(pool),
                amplitude=amplitude,
            )
        )  # fmt: skip
        seen = loop_observability(exc, kp, dynamics, pid, **loop)
        key = (len(seen.identifiable), seen.o_in) if not focused else _focus_key(seen, focused)
        if best is None or key > best[0]:
            best = (key, exc, seen)
        if progress is not None:
            progress(k + 1, best[2].o_in)
    assert best is not None
    return best[1], best[2]


def _focused(focus: Sequence[str], hold: Sequence[str]) -> tuple[str, ...]:
    """The quantity names ``focus`` (names or prefixes) stands for, ``hold`` left out."""
    if isinstance(focus, str):
        focus = (focus,)
    names = [n for n in _rss6.cloe_parameter_names() if n not in set(hold)]
    out: list[str] = []
    for f in focus:
        hit = [n for n in names if n == f or (n.startswith(f) and n[len(f) :].isdigit())]
        if not hit:
            raise InvalidInputError(
                f"focus {f!r} names no quantity the loop estimates (held: {list(hold)})"
            )
        out += [n for n in hit if n not in out]
    return tuple(out)


def focus_rms(seen: LoopObservability, focus: Sequence[str]) -> float:
    """Root mean square of the relative σ of the identifiable quantities among ``focus`` (names or
    prefixes, as :func:`best_for_loop`'s; ``inf`` if none is identifiable)."""
    focused = _focused(focus, ())
    s = [seen.relative_std[n] for n in focused if n in seen.relative_std]
    return float(np.sqrt(np.mean(np.square(s)))) if s else float("inf")


def _focus_key(seen: LoopObservability, focused: tuple[str, ...]) -> tuple[int, float]:
    n = sum(1 for q in focused if q in seen.relative_std)
    return n, -focus_rms(seen, focused)


def _finish(problem: _rss6.ExcitationProblem, c: F64, f0: float) -> Excitation:
    violation = problem.check(c)
    if violation is not None:
        constraint, time, excess = violation
        raise IdentificationError(
            f"infeasible exciting trajectory: {constraint} violated at t = {time:.3f} s "
            f"(by {excess:.3g})"
        )
    o_in, cond = problem.observability(c)
    return Excitation(
        coefficients=c,
        f0=float(f0),
        duration=1.0 / float(f0),
        observability=float(o_in),
        condition=float(cond),
        columns=tuple(problem.columns),
    )


#: The limits :func:`excitation` and :func:`random_excitation` take as keywords.
LIMITS = ("start", "stroke", "stroke_margin", "max_joint_rate", "samples", "rank_threshold")


def _problem(
    kp: _rss6.KinematicParams, harmonics: int, f0: float, seed: int, limits: dict[str, Any]
) -> Any:
    """The Rust problem for these options; :class:`rss6.InvalidInputError` for an unknown limit,
    a harmonics count that is not an int ≥ 2 or a seed outside numpy's [0, 2³² − 1]."""
    unknown = sorted(set(limits) - set(LIMITS))
    if unknown:
        raise InvalidInputError(
            f"unknown limit(s) {', '.join(unknown)}; known: {', '.join(LIMITS)}"
        )
    try:
        n = operator.index(harmonics)
    except TypeError:
        raise InvalidInputError(f"harmonics must be an int, got {harmonics!r}") from None
    if n < 2:
        raise InvalidInputError(f"harmonics must be >= 2, got {n}")
    _checks.seed(seed)
    return _rss6.ExcitationProblem(kp, harmonics=n, f0=f0, **limits)


def excitation(
    kp: _rss6.KinematicParams,
    *,
    harmonics: int = 5,
    f0: float = 0.1,
    seed: int = 0,
    progress: Callable[[int, float], Any] | None = None,
    maxiter: int = 60,
    popsize: int = 8,
    amplitude: tuple[float, float] = (0.002, 0.01),
    **limits: Any,
) -> Excitation:
    """An exciting trajectory for ``kp`` maximising O_in (eq. 5.13), by differential evolution.

    ``harmonics`` n and ``f0`` (Hz, thesis: 5 and 0.1); ``seed`` makes the search repeatable;
    ``progress(generation, best O_in)`` after each generation; ``maxiter`` generations of ``popsize`` ×
    dimension candidates; ``amplitude`` bounds the free coefficients (rates, m/s and rad/s) for
    translations and rotations — the limits decide what is feasible inside it (the default doubled
    in the ninth session: O_in 1.4× and, on the plant, the friction's errors a third to a half
    smaller, docs/identification.md; at 2.5·10⁻³, 1.25·10⁻² 3 seeds of 10 found no feasible
    trajectory in 30 generations); other keywords set the limits (``start``, ``stroke``,
    ``stroke_margin``, ``max_joint_rate``, ``samples``). Raises :class:`rss6.IdentificationError` if no
    feasible trajectory was found.
    """
    from scipy.optimize import Bounds, differential_evolution

    problem = _problem(kp, harmonics, f0, seed, limits)
    d = problem.dimension
    k = d // 6
    half = np.array([amplitude[0] if j // k < 3 else amplitude[1] for j in range(d)])
    bounds = Bounds(-half, half)
    generation = 0

    def scores(x: F64) -> F64:
        # vectorized: x has shape (dimension, S); Rust evaluates the S candidates in parallel.
        return np.asarray(
            problem.objectives(np.ascontiguousarray(np.asarray(x).T)), dtype=np.float64
        )

    objective: Any = scores  # scipy's stubs type the scalar form only

    def callback(intermediate_result: Any) -> None:
        nonlocal generation
        generation += 1
        if progress is not None:
            progress(generation, float(-intermediate_result.fun))

    res = differential_evolution(
        objective,
        bounds,
        seed=seed,
        maxiter=maxiter,
        popsize=popsize,
        vectorized=True,
        updating="deferred",
        polish=False,
        init="sobol",
        callback=callback,
    )
    if not res.fun < 0:
        raise IdentificationError(
            f"no feasible exciting trajectory found in {maxiter} generations (best score {res.fun:.3g}:"
            " 1 + the excess over the first violated limit); lower `amplitude` or relax the limits"
        )
    return _finish(problem, np.asarray(problem.coefficients(res.x), dtype=np.float64), f0)


def random_excitation(
    kp: _rss6.KinematicParams,
    *,
    harmonics: int = 5,
    f0: float = 0.1,
    seed: int = 0,
    amplitude: tuple[float, float] = (0.001, 0.005),
    batch: int = 64,
    attempts: int = 50,
    **limits: Any,
) -> Excitation:
    """A random feasible trajectory (validation, §5.5): free coefficients drawn uniformly within
    ``amplitude`` (as in :func:`excitation`) with ``seed``, the first of ``batch`` candidates that meets
    every limit. Raises :class:`rss6.IdentificationError` after ``attempts`` batches without one."""
    problem = _problem(kp, harmonics, f0, seed, limits)
    d = problem.dimension
    k = d // 6
    half = np.array([amplitude[0] if j // k < 3 else amplitude[1] for j in range(d)])
    rng = np.random.default_rng(seed)
    for _ in range(attempts):
        x = rng.uniform(-1.0, 1.0, size=(batch, d)) * half
        scores = np.asarray(problem.objectives(x))
        ok = np.flatnonzero(scores < 0)
        if ok.size:
            c = np.asarray(problem.coefficients(x[ok[0]]), dtype=np.float64)
            return _finish(problem, c, f0)
    raise IdentificationError(
        f"no feasible random trajectory in {attempts * batch} draws; lower `amplitude`"
    )
