"""The nominal parameters refitted inside the model's own uncertainty (issue 14, step 3: "adding
effects forward and refitting the nominal parameters each time").

An identified model is never exact: CLOE leaves the friction a few per cent off (docs/
identification.md). Such an error moves the potentiometers and the commands far more than the
poses, so without a refit the friction candidates rank first on every scope and hide a real
effect behind a chain of refusals. Here the model's Coulomb and viscous coefficients per joint and
its three drive gains are refitted to the fitting run by bounded least squares, each inside a box
of relative half-width ``spread`` around its value (what the identification vouches for, e.g. 3×
its relative σ). What is left outside the box is a missing effect; what is inside is the model's
own uncertainty. The refit decides what the search screens (the residual against the refitted
model ranks the candidates) and enters the final model; the candidates are fitted, and their
claims made, on the model as given with the named effects (a refit before anything is named takes
up part of a real effect: a 15 kg payload was fitted as 9.6 kg beside a drive-gain change when
its fit started from the refitted model)."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np
from numpy.typing import NDArray

import rss6
from rss6.discrepancy.model import Model, replay
from rss6.errors import InvalidInputError, Rss6Error

F64 = NDArray[np.float64]

__all__ = [
    "NOMINAL_NAMES",
    "NOMINAL_SPREAD",
    "PRIOR_SIGMAS",
    "NominalFit",
    "held_sensitivity",
    "nominal_difference",
    "nominal_from",
    "nominal_variance",
    "refit_nominal",
    "refit_step",
    "sensitivity",
    "spreads",
]

NOMINAL_NAMES: tuple[str, ...] = (
    *(f"fc{i}" for i in range(1, 7)),
    *(f"fv{i}" for i in range(1, 7)),
    "lp",
    "li",
    "ld",
)
"""The refitted quantities, in CLOE's names (:func:`rss6.identify.parameter_names`)."""

PRIOR_SIGMAS = 3.0
"""The box's half-width in prior standard deviations: the refit is the maximum a posteriori under a
Gaussian prior N(model's value, (spread/3)²) per quantity, inside the box."""

NOMINAL_SPREAD: dict[str, float] = {"coulomb": 0.10, "viscous": 0.25, "gains": 0.05}
"""Default relative half-widths of the box: ≈ 3× the relative σ CLOE reports on the plant
(Coulomb ≤ 3 %, viscous ≤ 8 %; docs/identification.md) and the 5 % the gains are identified to."""


def spreads(nominal: Mapping[str, float] | None) -> F64:
    """The 15 relative half-widths from ``nominal``: keys "coulomb", "viscous", "gains" (every
    joint / gain) or CLOE names ("fc3", "lp", …), the latter overriding; missing ones are 0
    (held). Raises :class:`rss6.InvalidInputError` for an unknown key or a width outside [0, 1)."""
    out = np.zeros(len(NOMINAL_NAMES))
    if not nominal:
        return out
    groups = {"coulomb": range(6), "viscous": range(6, 12), "gains": range(12, 15)}
    for key in sorted(nominal, key=lambda k: k in NOMINAL_NAMES):
        w = float(nominal[key])
        if not np.isfinite(w) or not 0.0 <= w < 1.0:
            raise InvalidInputError(f"nominal spread {key!r} must be in [0, 1), got {w}")
        if key in groups:
            out[list(groups[key])] = w
        elif key in NOMINAL_NAMES:
            out[NOMINAL_NAMES.index(key)] = w
        else:
            raise InvalidInputError(
                f"unknown nominal quantity {key!r}: use coulomb, viscous, gains or one of "
                + ", ".join(NOMINAL_NAMES)
            )
    return out


def nominal_from(
    result: Any, *, sigmas: float = PRIOR_SIGMAS, cap: float = 0.5
) -> dict[str, float]:
    """The spreads from an identification (:class:`rss6.identify.IdentificationResult`): ``sigmas``
    × the relative σ CLOE reports for each quantity it identified (at most ``cap``), and
    :data:`NOMINAL_SPREAD`'s group value for those it did not (held at the guess, or not asked
    for)."""
    if not 0 < cap < 1 or not sigmas > 0:
        raise InvalidInputError(f"need sigmas > 0 and cap in (0, 1); got {sigmas}, {cap}")
    if not (hasattr(result, "identified") and hasattr(result, "relative_std")):
        raise InvalidInputError(
            "nominal_from needs an identification result (.identified, .relative_std); got "
            f"{type(result).__name__}"
        )
    identified = tuple(result.identified)
    std = np.asarray(result.relative_std, dtype=np.float64)
    if len(identified) != len(std):
        raise InvalidInputError(
            f"the result names {len(identified)} quantities but gives {len(std)} relative σ"
        )
    out: dict[str, float] = {}
    for i, name in enumerate(NOMINAL_NAMES):
        group = "coulomb" if i < 6 else "viscous" if i < 12 else "gains"
        if name in identified:
            w = float(std[identified.index(name)]) * sigmas
            out[name] = min(w, cap) if np.isfinite(w) else NOMINAL_SPREAD[group]
        else:
            out[name] = NOMINAL_SPREAD[group]
    return out


def _values(model: Model) -> F64:
    return np.concatenate(
        [
            np.asarray(model.dynamics.coulomb, dtype=np.float64),
            np.asarray(model.dynamics.viscous, dtype=np.float64),
            np.asarray([float(g) for g in model.pid], dtype=np.float64),
        ]
    )


def _with_values(model: Model, v: F64) -> Model:
    d = model.dynamics.to_dict()
    d["coulomb"], d["viscous"] = np.array(v[:6]), np.array(v[6:12])
    return model.with_dynamics(rss6.DynamicParams.from_dict(d), tuple(float(g) for g in v[12:]))


@dataclass(frozen=True)
class NominalFit:
    """The refit: the model with the refitted quantities, their relative changes (15, in
    :data:`NOMINAL_NAMES` order; 0 where held), which ended on their box, the fitting run's
    whitened cost before and after, whether the last step still lowered the cost by less than
    10⁻³ of it (else the iterations ran out) and how many quantities were free; ``sensitivity``
    (whitened data rows × 15: the residual's Jacobian at the start, 0 for held quantities) and
    ``prior_sigma`` (15: the prior's σ, 0 where held) — what :func:`nominal_variance` needs."""

    model: Model
    relative: F64
    at_bound: NDArray[np.bool_]
    cost_before: float
    cost_after: float
    converged: bool
    n_free: int
    sensitivity: F64 | None = None
    prior_sigma: F64 | None = None

    def summary(self, threshold: float = 1e-3) -> str:
        """The quantities that moved (relative change above ``threshold``), those on their box
        marked."""
        moved = [
            f"{n} {100 * r:+.2g} %" + (" (on its box)" if b else "")
            for n, r, b in zip(NOMINAL_NAMES, self.relative, self.at_bound, strict=True)
            if abs(r) > threshold
        ]
        return ", ".join(moved) if moved else "nothing moved"


def refit_nominal(
    model: Model,
    original: Model,
    spread: F64,
    residual: Callable[[Model], F64],
    many: Callable[[Sequence[Callable[[], F64]]], list[F64]],
    *,
    held: Sequence[int] = (),
    iterations: int = 2,
) -> NominalFit:
    """Bounded least squares of the whitened ``residual(model)`` and a Gaussian prior
    N(``original``'s value, (box/:data:`PRIOR_SIGMAS`)²) over the nominal quantities of ``model``
    inside ``original``'s values × (1 ± ``spread``) (``held`` indices and zero widths stay at
    ``model``'s values); the costs reported are the residual's alone.

    Gauss–Newton from ``model``'s values, at most ``iterations`` steps: the Jacobian by forward
    differences at a tenth of each box (the replays run together through ``many``), the step the
    bounded linear least squares inside the box (``scipy.optimize.lsq_linear``), halved up to
    twice if the cost does not fall. The problem is nearly linear inside the box: 15 + 1 replays a
    step, where a trust-region solver spent ≈ 6 Jacobians. Converged when a full step ends at the
    cost the linear model predicted (within 10⁻³ of it), lowers it by less than 10⁻³, or not at all
    (on the twin: one step, ``benches/python/nominal_refit.py``)."""
    from scipy.optimize import lsq_linear

    v0 = _values(model)
    ref = _values(original)
    width = np.abs(ref) * spread
    free = np.flatnonzero((width > 0) & ~np.isin(np.arange(len(v0)), list(held)))
    r0 = residual(model)
    c0 = float(r0 @ r0)
    if free.size == 0:
        return NominalFit(model, np.zeros(len(v0)), np.zeros(len(v0), bool), c0, c0, True, 0)
    lo, hi = ref[free] - width[free], ref[free] + width[free]
    h = 0.1 * width[free]
    # The prior: each quantity N(original, (box/3)²) — directions the run hardly sees stay at the
    # model's values instead of wandering to the box's edges.
    sigma = width[free] / PRIOR_SIGMAS

    def full(x: F64) -> F64:
        v = v0.copy()
        v[free] = x
        return v

    def res(x: F64) -> F64:
        return np.concatenate([residual(_with_values(model, full(x))), (x - ref[free]) / sigma])

    x = np.clip(v0[free], lo, hi)
    try:
        r = res(x) if np.any(x != v0[free]) else np.concatenate([r0, (x - ref[free]) / sigma])
        cost = float(r @ r)
        converged = False
        sens: F64 | None = None
        for _ in range(max(1, iterations)):
            steps = np.where(x + h <= hi, h, -h)
            pts = [x + np.eye(len(x))[i] * steps[i] for i in range(len(x))]
            cols = many([partial(res, p) for p in pts])
            jac = np.column_stack([(c - r) / st for c, st in zip(cols, steps, strict=True)])
            if sens is None:
                sens = np.zeros((len(r0), len(v0)))
                sens[:, free] = jac[: len(r0)]
            d = lsq_linear(jac, -r, bounds=(lo - x, hi - x), method="bvls").x
            lin = r + jac @ d
            predicted = float(lin @ lin)  # the cost the linear model expects after the full step
            for t in (1.0, 0.5, 0.25):
                xn = np.clip(x + t * d, lo, hi)
                rn = res(xn)
                cn = float(rn @ rn)
                if cn < cost:
                    break
            else:
                converged = True  # no step lowers the cost: at the optimum within the box
                break
            x, r, fell, cost = xn, rn, cost - cn, cn
            # Done when the step hardly lowers the cost, or ends where the linear model said (the
            # problem is linear there: the optimum of the linear model is the refit's).
            if fell < 1e-3 * cost or (t == 1.0 and abs(cn - predicted) <= 1e-3 * cn):
                converged = True
                break
    except Rss6Error as err:
        raise InvalidInputError(f"the nominal refit could not replay the model: {err}") from err
    v = full(x)
    n_data = len(r0)
    tol = 1e-3 * width[free]
    at = np.zeros(len(v0), dtype=bool)
    at[free] = (x <= lo + tol) | (x >= hi - tol)
    rel = np.where(ref != 0, v / np.where(ref != 0, ref, 1.0) - 1.0, 0.0)
    c_data = float(r[:n_data] @ r[:n_data])
    prior = np.zeros(len(v0))
    prior[free] = sigma
    return NominalFit(
        _with_values(model, v), rel, at, c0, c_data, converged, int(free.size), sens, prior
    )


def nominal_variance(j_effect: F64, nf: NominalFit | None, residual: F64 | None = None) -> F64:
    """What the model's own uncertainty adds to the variance of effect parameters fitted on the
    model as given (the nominal quantities held at the model's values). With J_e the fit's
    whitened Jacobian (M, n), r its whitened residual and J_n the nominal quantities' (``nf
    .sensitivity``) under their prior N(0, diag(``nf.prior_sigma``²)), the linearised joint fit
    of (effect, nominal) has covariance [J_eᵀJ_e, J_eᵀJ_n; J_nᵀJ_e, J_nᵀJ_n + Σ⁻¹]⁻¹: its effect
    block less (J_eᵀJ_e)⁻¹ — the variance a direction of the effect shares with the nominal
    quantities, as much of the prior as the data do not pin down — plus the square of the joint
    fit's one step from the estimate, Δ (what the nominal quantities the data do see would move it:
    the estimate is not corrected, its interval holds the correction). Friction on a joint beside
    the model's own friction of it carries the prior's σ; an effect the nominal quantities cannot
    mimic keeps its interval. Zeros (n,) when there is no refit or the layouts differ."""
    n = j_effect.shape[1]
    joint = _joint(j_effect, nf)
    if joint is None:
        return np.zeros(n)
    cov, jn = joint
    shared = np.maximum(np.diag(cov)[:n] - np.diag(np.linalg.pinv(j_effect.T @ j_effect)), 0.0)
    if residual is None or residual.shape[0] != j_effect.shape[0]:
        return np.asarray(shared)
    # Gauss–Newton on ‖r + J_e Δ + J_n δ‖² + ‖δ/σ‖² (the Jacobians are the residual's).
    step = -(cov @ np.concatenate([j_effect.T @ residual, jn.T @ residual]))[:n]
    return np.asarray(shared + step * step)


def _joint(j_effect: F64, nf: NominalFit | None) -> tuple[F64, F64] | None:
    """The linearised joint fit of (effect, nominal quantities under their prior) on the run of
    ``j_effect``: its covariance and the nominal quantities' Jacobian (the prior's held ones left
    out), or None without a refit or with a Jacobian of another run."""
    if nf is None or nf.sensitivity is None or nf.prior_sigma is None:
        return None
    jn, sig = nf.sensitivity, nf.prior_sigma
    keep = sig > 0
    if not keep.any() or jn.shape[0] != j_effect.shape[0]:
        return None
    jn = jn[:, keep]
    a = j_effect.T @ j_effect
    b = j_effect.T @ jn
    info = np.block([[a, b], [b.T, jn.T @ jn + np.diag(1.0 / sig[keep] ** 2)]])
    return np.linalg.pinv(info), jn


def nominal_difference(
    j_fit: F64, r_fit: F64, j_held: F64, jn_held: F64 | None, nf: NominalFit | None
) -> F64:
    """What the model's own uncertainty adds to the covariance of the difference between an
    effect's estimates on two runs, both fitted on the model as given: an error δ of the nominal
    quantities moves the estimate on run x by A_x δ, A_x = (J_xᵀJ_x)⁻¹J_xᵀJ_n,x (J_x the effect's
    whitened Jacobian on that run, J_n,x the nominal quantities'), so the difference carries
    (A_f − A_h)δ — zero only when both excitations see the model's error alike. δ is taken as
    the fitting run's joint fit says (``r_fit`` its residual at the estimate, ``nf`` the refit
    with the fitting run's J_n): its covariance (what the data do not pin) plus its one step
    squared, as :func:`nominal_variance`. ``jn_held``: J_n on the held-out run, every one of the
    15 quantities (:func:`sensitivity`). Zeros (n, n) when anything is missing."""
    n = j_fit.shape[1]
    joint = _joint(j_fit, nf)
    if joint is None or jn_held is None or nf is None or nf.prior_sigma is None:
        return np.zeros((n, n))
    if jn_held.shape != (j_held.shape[0], len(nf.prior_sigma)) or j_held.shape[1] != n:
        return np.zeros((n, n))
    cov, jn_f = joint
    jn_h = jn_held[:, nf.prior_sigma > 0]
    step = -(cov @ np.concatenate([j_fit.T @ r_fit, jn_f.T @ r_fit]))[n:]
    second = cov[n:, n:] + np.outer(step, step)
    a_f = np.linalg.pinv(j_fit.T @ j_fit) @ (j_fit.T @ jn_f)
    a_h = np.linalg.pinv(j_held.T @ j_held) @ (j_held.T @ jn_h)
    d = a_f - a_h
    return np.asarray(d @ second @ d.T)


def sensitivity(
    model: Model,
    prior_sigma: F64,
    residual: Callable[[Model], F64],
    r0: F64,
    many: Callable[[Sequence[Callable[[], F64]]], list[F64]],
) -> F64:
    """The whitened ``residual``'s Jacobian (rows × 15) in the nominal quantities of ``model``
    whose ``prior_sigma`` is positive (0 for the others), by forward differences of 0.3 σ (a tenth
    of the box, the steps of :func:`refit_nominal`) from ``r0`` = ``residual(model)``: J_n on
    another run than the refit's."""
    v0 = _values(model)
    out = np.zeros((len(r0), len(v0)))
    free = np.flatnonzero(prior_sigma > 0)
    steps = 0.1 * PRIOR_SIGMAS * prior_sigma[free]

    def moved(i: int, h: float) -> F64:
        v = v0.copy()
        v[i] += h
        return residual(_with_values(model, v))

    cols = many([partial(moved, int(i), float(h)) for i, h in zip(free, steps, strict=True)])
    for i, h, c in zip(free, steps, cols, strict=True):
        out[:, i] = (c - r0) / h
    return out


def held_sensitivity(
    model: Model,
    held: Any,
    baseline: F64,
    nf: NominalFit | None,
    many: Callable[[Sequence[Callable[[], F64]]], list[F64]],
) -> F64 | None:
    """J_n on the held-out run for :func:`_consistency`: the whitened residual's Jacobian in the
    nominal quantities ``nf`` holds uncertain, at ``model`` (whose held-out replay is
    ``baseline``); None without a refit or when a replay fails (the test then knows only the
    noise)."""
    if nf is None or nf.prior_sigma is None or held.calibration is None:
        return None
    white = held.calibration.whitener

    def residual(m: Model) -> F64:
        return np.asarray(white.vec(held.measured - held.baseline(replay(m, held.run))[held.rows]))

    r0 = np.asarray(white.vec(held.measured - baseline[held.rows]))
    try:
        return sensitivity(model, nf.prior_sigma, residual, r0, many)
    except Rss6Error:
        return None


def refit_step(
    model: Model,
    original: Model,
    spread: F64,
    fit: Any,
    held: Any,
    current: tuple[F64, F64],
    many: Callable[[Sequence[Callable[[], F64]]], list[F64]],
) -> tuple[Model, F64 | None, F64 | None, str, NominalFit | None]:
    """One refit of the nominal quantities of ``model`` (with its named effects), from
    ``original``'s values, on the fitting part ``fit``, judged on the held-out part ``held`` like
    a re-identification: kept only if the held-out whitened cost over every channel does not grow
    against the current baselines ``current`` (fitting run, held-out run: ``model``'s replays).
    Returns the model to keep, its new fitting and held-out baselines (None if not kept), a note
    and the refit itself (None if it could not run), whose sensitivities give the intervals the
    model's uncertainty (:func:`nominal_variance`) whether or not it is kept."""
    cal, hcal = fit.calibration, held.calibration
    current_fit, current_held = current
    # From the model's own values: what an earlier refit took up of an effect named since (the
    # first refit runs before anything is named) is given back.
    start = _with_values(model, _values(original))
    # Replays by the quantities' values: the start's is the current baseline when the model holds
    # the original's values, and the accepted step's is the new one.
    baselines: dict[bytes, F64] = {}
    if np.array_equal(_values(model), _values(original)):
        baselines[_values(start).tobytes()] = current_fit

    def residual(m: Model) -> F64:
        key = _values(m).tobytes()
        if key not in baselines:
            baselines[key] = fit.baseline(replay(m, fit.run))
        return np.asarray(cal.whitener.vec(fit.measured - baselines[key][fit.rows]))

    try:
        nf = refit_nominal(start, original, spread, residual, many)
    except (InvalidInputError, Rss6Error) as err:
        return model, None, None, f"nominal quantities not refitted: {err}", None
    if nf.n_free == 0:
        return model, None, None, "", None
    new_held = held.baseline(replay(nf.model, held.run))
    c_old = float(np.sum(hcal.whitener.vec(held.measured - current_held[held.rows]) ** 2))
    c_new = float(np.sum(hcal.whitener.vec(held.measured - new_held[held.rows]) ** 2))
    text = (
        f"nominal refit inside the model's uncertainty ({nf.summary()}): fitting cost "
        f"{nf.cost_before:.6g} → {nf.cost_after:.6g}, held-out {c_old:.6g} → {c_new:.6g}"
    )
    if not nf.converged:
        text += " (its steps ran out before the cost settled)"
    if c_new > c_old:
        return model, None, None, text + "; not kept (the held-out run does not agree)", nf
    new_fit = baselines.get(_values(nf.model).tobytes())
    if new_fit is None:
        new_fit = fit.baseline(replay(nf.model, fit.run))
    return nf.model, new_fit, new_held, text, nf
