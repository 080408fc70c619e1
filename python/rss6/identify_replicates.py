"""σ of CLOE's estimates from the loop's own noise: noisy replicate runs of the identified model.

On the model twin, whose model is exact, the σ CLOE reports (Wald and two sandwiches) understate
the spread of f_c1 and of the viscous coefficients over trajectories by ≈ 25 % (docs/
identification.md, "σ from noisy replicates"): the camera and potentiometer noise act through the
stick–slip drive in ways no within-run residual shows. This module runs the same excitation on the
model twin at the estimate (:class:`rss6.ModelSim`, the identified dynamics and gains, its own
camera and potentiometer noise, one seed per replicate), replays the model against each run as
CLOE does (the same commands, the same potentiometer-noise replay), and carries the whitened
residuals to the estimate through CLOE's linear map (``IdentificationResult.linear_map``):
δ_k = (GᵀG)⁻¹G_sᵀ r_k. Their spread is the estimate's σ under the loop's noise, linearised — the
parametric bootstrap without refitting."""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterator
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from rss6 import _rss6
from rss6.errors import IdentificationError, InvalidInputError

F64 = NDArray[np.float64]

if TYPE_CHECKING:
    from rss6.identify import IdentificationData, IdentificationResult


def weighted_residual(result: IdentificationResult, data: IdentificationData, chi_s: F64) -> F64:
    """(6F,): CLOE's residual layout — frame k's axis i at 6k + i, W·(χ_m − χ_s) with the
    whitening W of ``result`` (diag(1/σ) unless CLOE weighted by a frame covariance)."""
    if result.linear_map is None:
        raise InvalidInputError("this result carries no linear map (CLOE's σ was not computed)")
    w = np.asarray(result.linear_map[1])
    whiten = np.diag(w) if w.ndim == 1 else w
    d = (np.asarray(data.measured) - np.asarray(chi_s)) @ whiten.T
    return np.asarray(d.reshape(-1), dtype=np.float64)


def model_output(
    result: IdentificationResult,
    data: IdentificationData,
    *,
    params: tuple[_rss6.DynamicParams, tuple[float, float, float]] | None = None,
) -> F64:
    """χ_s (F, 6) of ``result``'s model (or its loop with other ``params`` = (dynamics, gains)) on
    ``data`` as CLOE simulates it: the run's own commands with ``commands="recorded"``, the same
    potentiometer-noise replay, the run's outer gains."""
    from rss6 import identify
    from rss6.identify_linear import replayed_noise

    m = result.model
    dp, pid = (result.dynamics, result.pid) if params is None else params
    return identify.simulate(
        m.kp,
        dp,
        pid,
        data.reference,
        times=data.t,
        torque_limit=m.torque_limit,
        camera_latency=m.camera_latency,
        dt=data.dt,
        derivative_filter=m.derivative_filter,
        friction_smoothing=m.friction_smoothing,
        implicit_friction=m.implicit_friction,
        commands=data.frame_commands() if m.commands == "recorded" else None,
        outer_gains=data.outer_gains,
        pot_dither=replayed_noise(data, m.pot_noise, result),
    )


def replicate_runs(
    result: IdentificationResult, data: IdentificationData, *, n: int, seed: int
) -> Iterator[IdentificationData]:
    """``n`` noisy runs of ``data``'s excitation (as many periods, the same outer gains) by the model
    twin at ``result``'s estimate (:class:`rss6.ModelSim` with its own camera and potentiometer
    noise, seeds ``seed`` …), each measured through the twin's own frames. Raises
    :class:`rss6.IdentificationError` for a run whose visual PID faulted."""
    from rss6 import identify

    if n < 2:
        raise InvalidInputError(f"n must be >= 2 replicates, got {n}")
    m = result.model
    periods = max(1, round(data.duration / data.reference.duration))
    for k in range(n):
        robot = _rss6.ModelSim(
            m.kp,
            result.dynamics,
            pid=result.pid,
            seed=seed + k,
            dt=data.dt,
            torque_limit=m.torque_limit,
            camera_latency=m.camera_latency,
            drive_derivative_filter=m.derivative_filter,
            friction_smoothing=m.friction_smoothing,
            implicit_friction=m.implicit_friction,
        )
        tr = robot.truth()
        rep = identify.collect(
            robot,
            data.reference,
            kp_model=m.kp,
            sensor_in_base=tr["sensor_in_base"],
            target_in_effector=tr["target_in_effector"],
            periods=periods,
            outer_gains=data.outer_gains,
        )
        if rep.fault is not None:
            raise IdentificationError(
                f"replicate {k}: the visual PID faulted at t = {rep.fault[0]:.3f} s"
            )
        yield rep


def replicate_deviations(
    result: IdentificationResult,
    data: IdentificationData,
    *,
    n: int = 16,
    seed: int = 10_000,
    progress: Callable[[int, int], Any] | None = None,
) -> F64:
    """(n, p): the linearised deviation of the estimated logs (``result.identified`` order) on
    ``n`` :func:`replicate_runs`, carried through ``result.linear_map``. A replicate whose frames
    are not ``data``'s (times within half a tick) raises :class:`rss6.IdentificationError`.
    ``progress(done, n)`` after each; raise in it (or Ctrl-C) to stop."""
    if result.linear_map is None or result.linear_map[0].shape[0] != len(result.identified):
        raise InvalidInputError("this result carries no linear map (CLOE's σ was not computed)")
    lmap = result.linear_map[0]
    if lmap.shape[1] != 6 * data.frames:
        raise InvalidInputError(
            f"the linear map is for {lmap.shape[1] // 6} frames; these data have {data.frames}"
        )
    out = np.zeros((n, lmap.shape[0]))
    for k, rep in enumerate(replicate_runs(result, data, n=n, seed=seed)):
        if rep.frames != data.frames or np.any(np.abs(rep.t - data.t) > 0.5 * data.dt):
            raise IdentificationError(
                f"replicate {k} has {rep.frames} frames at other times than the run's "
                f"{data.frames}: its residual cannot use CLOE's map"
            )
        out[k] = lmap @ weighted_residual(result, rep, model_output(result, rep))
        if progress is not None:
            progress(k + 1, n)
    return out


def bootstrap_deviations(
    result: IdentificationResult,
    data: IdentificationData,
    refit: Callable[[IdentificationData], IdentificationResult],
    *,
    n: int = 16,
    seed: int = 10_000,
    progress: Callable[[int, int], Any] | None = None,
) -> F64:
    """(n, p): log(estimate / ``result``'s) of each quantity ``result`` identified, on ``n``
    :func:`replicate_runs` each identified again by ``refit`` — the whole procedure (start, CLOE,
    stopping rule) on data whose truth is ``result``'s estimate: the parametric bootstrap. NaN
    where a replicate's fit did not estimate the quantity or raised
    :class:`rss6.IdentificationError` (not converged)."""
    from rss6.identify import parameter_names
    from rss6.identify_report import quantities

    names = parameter_names()
    cols = [names.index(q) for q in result.identified]
    base = quantities(result.dynamics, result.pid)[cols]
    out = np.full((n, len(cols)), np.nan)
    for k, rep in enumerate(replicate_runs(result, data, n=n, seed=seed)):
        try:
            r = refit(rep)
        except IdentificationError:
            continue
        est = quantities(r.dynamics, r.pid)[cols]
        seen = np.array([q in r.identified for q in result.identified])
        out[k, seen] = np.log(est[seen] / base[seen])
        if progress is not None:
            progress(k + 1, n)
    return out


def with_replicates(
    result: IdentificationResult,
    data: IdentificationData,
    *,
    n: int = 16,
    seed: int = 10_000,
    refit: Callable[[IdentificationData], IdentificationResult] | None = None,
    poor_std: float = 0.10,
    progress: Callable[[int, int], Any] | None = None,
    correct_bias: bool = False,
) -> IdentificationResult:
    """``result`` with ``relative_std`` the larger of CLOE's and the spread (sample standard
    deviation) over ``n`` noisy replicates — linearised (:func:`replicate_deviations`), or with
    ``refit`` each replicate identified again (:func:`bootstrap_deviations`; at least half of them
    must have estimated a quantity, else its spread is infinite) — kept in
    ``relative_std_replicates``, and ``poorly_identified`` (above ``poor_std``) updated.

    ``correct_bias``: the replicates' mean deviation is the procedure's bias at the estimate (their
    truth is the estimate); each identified log-quantity is moved by minus it (kept in
    ``replicate_bias``), its σ widened by that mean's own error (spread / √n), and ``rms_after``
    recomputed at the moved estimate (docs/identification.md, "Weighting by the frames'
    covariance")."""
    if refit is None:
        d = replicate_deviations(result, data, n=n, seed=seed, progress=progress)
    else:
        d = bootstrap_deviations(result, data, refit, n=n, seed=seed, progress=progress)
    ok = np.isfinite(d)
    rep = np.full(d.shape[1], np.inf)
    for j in range(d.shape[1]):
        if 2 * ok[:, j].sum() >= n and ok[:, j].sum() >= 2:
            rep[j] = float(np.std(d[ok[:, j], j], ddof=1))
    std = np.maximum(np.asarray(result.relative_std, dtype=np.float64), rep)
    if correct_bias:
        result, std = _bias_corrected(result, data, d, ok, std)
    poor = tuple(name for name, s in zip(result.identified, std, strict=True) if s > poor_std)
    return dataclasses.replace(
        result, relative_std=std, relative_std_replicates=rep, poorly_identified=poor
    )


def _bias_corrected(
    result: IdentificationResult, data: IdentificationData, d: F64, ok: Any, std: F64
) -> tuple[IdentificationResult, F64]:
    """``result`` moved by minus the replicates' mean deviation ``d`` (where ``ok``; none where
    fewer than two are), and ``std`` widened by that mean's standard error."""
    from rss6.identify import parameter_names

    count = ok.sum(axis=0)
    bias = np.array(
        [float(d[ok[:, j], j].mean()) if count[j] >= 2 else 0.0 for j in range(d.shape[1])]
    )
    se = np.array(
        [
            float(d[ok[:, j], j].std(ddof=1) / np.sqrt(count[j])) if count[j] >= 2 else 0.0
            for j in range(d.shape[1])
        ]
    )
    psi = np.array(_rss6.cloe_psi(result.dynamics, result.pid)[0], dtype=np.float64)
    cols = [parameter_names().index(q) for q in result.identified]
    psi[cols] -= bias
    _, dp, pid = _rss6.cloe_psi(result.dynamics, result.pid, list(psi))
    moved = dataclasses.replace(
        result, dynamics=dp, pid=(float(pid[0]), float(pid[1]), float(pid[2])), replicate_bias=bias
    )
    chi = model_output(moved, data)
    rms = np.sqrt(np.mean((np.asarray(data.measured) - chi) ** 2, axis=0))
    return dataclasses.replace(moved, rms_after=rms), np.hypot(std, se)
