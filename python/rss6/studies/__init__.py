"""Studies at scale on Dask (issue 16): Monte Carlo calibration, identification variation, the
discrepancy benchmark. Each study is a list of picklable specs mapped on a
``dask.distributed.Client`` (:mod:`rss6.studies.engine`: CSV records as tasks finish, resume,
retries); each returns a ``pandas.DataFrame`` of its records (one row per spec, with its
``spec_id``) and writes ``out``. ``summary_*`` turn the records into the study's tables.

How to run on a cluster: docs/studies.md.
"""

from __future__ import annotations

import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from rss6.errors import InvalidInputError
from rss6.studies.engine import probe_task, read_records, run_study
from rss6.studies.tasks import (
    calibration_task,
    discrepancy_task,
    identification_task,
    quantities,
)

__all__ = [
    "calibration_study",
    "discrepancy_benchmark",
    "identification_variation",
    "probe_task",
    "read_records",
    "run_study",
    "summary_calibration",
    "summary_discrepancy",
    "summary_identification",
]

_AXES = "xyzabg"


def _frame(records: list[dict[str, str]]) -> Any:
    import pandas as pd

    df = pd.DataFrame.from_records(records)
    for c in df.columns:
        conv = pd.to_numeric(df[c], errors="coerce")
        if conv.notna().sum() == df[c].astype(bool).sum() and c not in ("spec_id",):
            df[c] = conv
    return df


def _study(
    task: Any,
    specs: list[dict[str, Any]],
    fields: list[str],
    out: Any,
    client: Any,
    workers: int,
    progress: Any,
) -> Any:
    """Runs a study (:func:`run_study`) and returns every record of ``out`` as a DataFrame."""
    recs, _ = run_study(
        task, specs, out=out, fields=fields, client=client, workers=workers, progress=progress
    )
    return _frame(recs)


def calibration_study(
    n_robots: int,
    *,
    out: str | Path,
    client: Any = None,
    seed: int = 0,
    workers: int = 2,
    plant: bool = False,
    dwell: float = 2.0,
    candidates: int = 5000,
    progress: Any = True,
    noise: str = "table",
) -> Any:
    """The §4.4.3 calibration study over ``n_robots`` random robots (seeds ``seed`` …), one task
    per robot: the configuration sets are selected once here (``candidates`` per set) and travel
    in the specs; ``plant``: the rapier plant and its stereo CMM instead of the analytic generator;
    ``noise``: ``"table"`` or ``"dwells"`` (both methods weighted by the camera covariance pooled
    from the dwells, :func:`rss6.calibrate.rpba`; the spec ids carry it)."""
    if noise not in ("table", "dwells"):
        raise InvalidInputError(f'noise must be "table" or "dwells", got {noise!r}')
    import rss6
    from rss6 import calibrate

    nominal = rss6.KinematicParams.nominal()
    lo, hi = calibrate.stroke(nominal)
    th_r = calibrate.select_configurations(
        nominal, "rpba", seed, candidates=candidates, stroke=(lo, hi)
    )
    th_i = calibrate.select_configurations(
        nominal, "implicit", seed, candidates=candidates, stroke=(lo, hi)
    )
    specs = [
        {
            "spec_id": f"calibration:{'plant' if plant else 'generator'}:{seed + r}"
            + ("" if noise == "table" else f":{noise}"),
            "seed": seed + r,
            "plant": plant,
            "noise": noise,
            "dwell": dwell,
            "stroke": (float(lo), float(hi)),
            "rpba_thetas": np.asarray(th_r).tolist(),
            "implicit_thetas": np.asarray(th_i).tolist(),
        }
        for r in range(n_robots)
    ]
    fields = ["seed", "plant"]
    for m in ("uncalibrated", "implicit", "rpba"):
        fields += [f"{m}_{a}" for a in _AXES]
    for m in ("implicit", "rpba"):
        fields += [
            f"{m}_met",
            f"{m}_worst_axis",
            f"{m}_worst_ratio",
            f"{m}_param_error_after",
            f"{m}_residual_after",
        ]
    return _study(calibration_task, specs, fields, out, client, workers, progress)


def identification_variation(
    n_trajectories: int,
    *,
    out: str | Path,
    client: Any = None,
    seed: int = 0,
    workers: int = 2,
    robot: str = "plant",
    quick: bool = False,
    parameters: Any = "base",
    progress: Any = True,
    friction_law: str = "implicit",
    pot_noise: str = "recorded",
    solver_iterations: int | None = None,
    replicates: int = 16,
    bootstrap: bool = False,
    profile: Sequence[str] = (),
    noise: str | None = None,
    replicate_bias: bool = False,
) -> Any:
    """Table 5.5 (variation of each identified quantity over trajectories) and Table 5.4 (RMS per
    trajectory): one CLOE per random trajectory (seeds ``seed`` …) on the robot whose truth is
    Table 5.2 (``robot``: "plant" or "twin"); ``quick``: 2 s trajectories, 10 iterations;
    ``friction_law``: "tanh" or "implicit" (stick–slip in robot and model, linear start, l_p
    known; :func:`rss6.identify_sim.estimate_from_initial`); ``pot_noise``: "recorded" (the
    model's drive replays the potentiometer noise estimated from the readings), "model" (then a
    second pass against the first estimate's model, ``identify.cloe(pot_noise="model")``) or "none";
    ``solver_iterations``: the plant's rapier iterations (default
    :data:`rss6.identify_sim.IMPLICIT_PLANT_ITERATIONS`; the spec ids then end in ":itN");
    ``replicates``: each σ also from that many noisy replicates on the model twin at the estimate
    (:func:`rss6.identify.with_replicates`; 0: CLOE's σ alone, as before 2026-11-29; spec ids
    then end in ":repN"), each
    identified again with ``bootstrap`` (the parametric bootstrap; ":bootN"); ``profile``: names
    (:func:`rss6.identify.parameter_names`) whose 95 % profile-likelihood interval each run also
    computes (:func:`rss6.identify_profile.profile`, ≈ 5–7 CLOE runs per name; ":prof-NAME+…");
    ``noise``: :func:`rss6.identify.cloe`'s — ``"frames"`` whitens the residual by the frames'
    covariance (a second pass; ":frames"); ``replicate_bias``: each estimate moved by minus its
    replicates' mean deviation (:func:`rss6.identify.with_replicates`'s ``correct_bias``; needs
    replicates; ":rbias")."""
    from rss6 import identify

    unknown = sorted(set(profile) - set(identify.parameter_names()))
    if unknown:
        raise InvalidInputError(
            f"cannot profile {', '.join(unknown)}: not among rss6.identify.parameter_names()"
        )

    if pot_noise not in ("recorded", "model", "none"):
        raise InvalidInputError(
            f"pot_noise must be 'recorded', 'model' or 'none', got {pot_noise!r}"
        )
    if solver_iterations is not None and solver_iterations < 1:
        raise InvalidInputError(f"solver_iterations must be >= 1, got {solver_iterations}")
    if replicates == 1 or replicates < 0:
        raise InvalidInputError(f"replicates must be 0 or >= 2, got {replicates}")
    it: dict[str, Any] = (
        {} if solver_iterations is None else {"solver_iterations": int(solver_iterations)}
    )
    if replicates:
        it.update(replicates=int(replicates), bootstrap=bool(bootstrap))
    if profile:
        it["profile"] = list(profile)
    if noise not in (None, "frames"):
        raise InvalidInputError(f"noise must be None or 'frames', got {noise!r}")
    if noise:
        it["noise"] = noise
    if replicate_bias and not replicates:
        raise InvalidInputError("replicate_bias needs replicates >= 2")
    if replicate_bias:
        it["replicate_bias"] = True
    specs = [
        {
            "spec_id": f"identification:{robot}:{friction_law}:{'quick' if quick else 'full'}:"
            f"pot-{pot_noise}:{seed + k}"
            + (f":it{solver_iterations}" if solver_iterations is not None else "")
            + (f":{'boot' if bootstrap else 'rep'}{replicates}" if replicates else "")
            + (f":prof-{'+'.join(profile)}" if profile else "")
            + (f":{noise}" if noise else "")
            + (":rbias" if replicate_bias else ""),
            "friction_law": friction_law,
            "pot_noise": pot_noise,
            "seed": seed + k,
            "robot": robot,
            "quick": quick,
            "parameters": parameters,
            **it,
        }
        for k in range(n_trajectories)
    ]
    fields = ["seed", "robot", "friction_law", "iterations"]
    fields += [f"est_{n}" for n in identify.parameter_names()]
    fields += [f"std_{n}" for n in identify.parameter_names()]
    fields += [f"wald_{n}" for n in identify.parameter_names()]
    fields += [f"rep_{n}" for n in identify.parameter_names()] if replicates else []
    fields += [f"rms_{w}_{a}" for w in ("before", "after") for a in _AXES]
    fields += ["converged_by"]
    fields += [f"prof_{b}_{n}" for n in profile for b in ("lo", "hi")]
    fields += ["prof_error"] if profile else []
    return _study(identification_task, specs, fields, out, client, workers, progress)


def discrepancy_benchmark(
    cases: Any,
    *,
    out: str | Path,
    client: Any = None,
    seed: int = 0,
    workers: int = 2,
    progress: Any = True,
) -> Any:
    """The discrepancy workflow's hidden-effect benchmark: ``cases`` is a list of specs
    (:func:`rss6.discrepancy.benchmark.cases`) or a number n: the library and out-of-library
    effects at 2× noise, two pairs, and n no-effect cases (seed ``seed``)."""
    from rss6.discrepancy import benchmark

    if isinstance(cases, int):
        specs = benchmark.cases(magnitudes=(2.0,), seeds=(seed,), n_null=max(0, cases))
    else:
        specs = list(cases)
    fields = [
        "robot",
        "friction",
        "seed",
        "kind",
        "hidden",
        "magnitude",
        "reached",
        "named",
        "verdict",
        "correct",
        "first_right",
        "ambiguous",
        "unexplained",
        "notes",
        "truth",
        "estimate",
        "ci",
    ]
    for p in ("gap_before", "gap_named", "gap_after", "noise"):
        fields += [f"{p}_{a}" for a in _AXES]
    fields += ["se", "heldout"]  # the two runs' errors behind the intervals (sixth session)
    fields += ["ambiguous_sets"]  # which candidates were ambiguous, with their |ρ| (eighth session)
    fields += ["nominal_se"]  # the model's own uncertainty in the intervals (thirty-second session)
    return _study(discrepancy_task, specs, fields, out, client, workers, progress)


def summary_calibration(df: Any) -> str:
    """Met / error counts per method, RMS per axis (mean, p95), worst cases with seeds."""
    ok = df[df["status"] == "ok"]
    lines = [f"{len(df)} robots: {len(ok)} ok, {int((df['status'] != 'ok').sum())} errors"]
    for m in ("implicit", "rpba"):
        met = ok[f"{m}_met"].astype(str).eq("True").sum()
        lines.append(f"{m}: met Table 4.5 on every axis {met}/{len(ok)}")
        for a in _AXES:
            v = ok[f"{m}_{a}"].astype(float)
            lines.append(f"  {a}: mean {v.mean():.4g}  p95 {np.percentile(v, 95):.4g}")
        worst = ok.sort_values(f"{m}_worst_ratio", ascending=False).head(3)
        lines.append(
            "  worst: "
            + ", ".join(
                f"seed {int(r['seed'])} ({r[f'{m}_worst_axis']} at {float(r[f'{m}_worst_ratio']):.2f}× Table 4.5)"
                for _, r in worst.iterrows()
            )
        )
    return "\n".join(lines)


def summary_identification(df: Any) -> str:
    """Table 5.5 (std/|mean| of each estimate) and Table 5.4 (RMS after per trajectory)."""
    from rss6 import identify

    ok = df[df["status"] == "ok"]
    est = [c for c in ok.columns if c.startswith("est_")]
    lines = [f"{len(df)} trajectories: {len(ok)} identified"]
    if "converged_by" in ok.columns and len(ok):
        rules = ok["converged_by"].astype(str).value_counts()
        lines[0] += " (stopping rule: " + ", ".join(f"{k} {v}" for k, v in rules.items()) + ")"
    # Every robot of the study has Table 5.2 as its truth (identification_task).
    truth = quantities(*identify.table_5_2_truth())
    if len(ok) >= 2:
        import pandas as pd
        from scipy.stats import chi2, norm

        # With a right σ, (n − 1)·spread²/σ² is χ²(n − 1): the range the ratio σ/spread falls in.
        dof = len(ok) - 1
        lo, hi = (float(np.sqrt(dof / chi2.ppf(q, dof))) for q in (0.975, 0.025))
        lines.append(
            "Table 5.5 (variation = std / |mean| over the trajectories; predicted: median relative "
            "σ CLOE reported, where it estimated the quantity — the larger of Wald and sandwich; "
            "Wald: white-residual σ alone; replicates: from noisy replicate runs, if asked; error: mean and RMS of log(estimate / Table 5.2 truth); "
            "covers: runs whose own 95 % interval holds the truth; RMS: the root mean square of the "
            "runs' σ against the spread of log(estimate), the comparison that holds when the "
            "trajectories' σ differ — the median of unequal σ is below what their spread is):"
        )
        # The same for the friction and drive gains all at once (Bonferroni over those with a σ):
        # one of 14 outside the first range is what right σ give in about half of all studies.
        m = sum(
            re.fullmatch(r"f[cv]\d+|l[pid]", c[4:]) is not None
            and f"std_{c[4:]}" in ok.columns
            and bool(ok[f"std_{c[4:]}"].replace("", np.nan).astype(float).notna().any())
            for c in est
        )
        a = 0.05 / max(m, 1)
        flo, fhi = (float(np.sqrt(dof / chi2.ppf(q, dof))) for q in (1 - a / 2, a / 2))
        lines.append(
            f"  (were every σ right and equal, predicted / spread would lie in [{lo:.2f}, {hi:.2f}] for 95 % "
            f"of studies of {len(ok)} trajectories, and that of all {m} friction and gain "
            f"quantities in [{flo:.2f}, {fhi:.2f}] for 95 %)"
        )
        for c in est:
            v = ok[c].astype(float)
            line = f"  {c[4:]:12s} {float(v.std(ddof=1) / abs(v.mean())):.3g}"
            spread = float(v.std(ddof=1) / abs(v.mean()))
            t = truth.get(c[4:], 0.0)
            if t > 0 and bool((v > 0).all()):
                e = np.log(v.to_numpy() / t)
                line += (
                    f"   error {100 * float(e.mean()):+.2f} % (RMS "
                    f"{100 * float(np.sqrt(np.mean(e * e))):.2f} %)"
                )
            cols = ((f"std_{c[4:]}", "predicted"), (f"wald_{c[4:]}", "Wald"))
            for col, label in (*cols, (f"rep_{c[4:]}", "replicates")):
                if col in ok.columns:
                    p = ok[col].replace("", np.nan).astype(float).dropna()
                    if len(p):
                        line += f"   {label} {float(p.median()):.3g}"
                        if label != "Wald" and spread > 0:
                            line += f" ({float(p.median()) / spread:.2f}× the spread)"
                        if label == "predicted" and t > 0 and bool((v > 0).all()):
                            both = pd.concat([np.log(v / t), p], axis=1, join="inner").to_numpy()
                            inside = np.abs(both[:, 0]) <= 1.96 * both[:, 1]
                            line += f" covers {int(inside.sum())}/{len(inside)}"
                            # Runs differ in σ, so the spread is their RMS, not their median.
                            rms = float(np.sqrt(np.mean(both[:, 1] ** 2)))
                            lsp = float(np.std(both[:, 0], ddof=1)) if len(both) > 1 else 0.0
                            if lsp > 0:
                                lo, hi = _rms_range(both[:, 1])
                                line += (
                                    f" RMS {rms:.3g} ({rms / lsp:.2f}× the log spread, "
                                    f"right σ: [{lo:.2f}, {hi:.2f}])"
                                )
            lines.append(line)
        # Issue 13: every estimate with a relative σ below 5 % within 10 % of the truth.
        # A σ near 5 % misses 10 % now and then even when right: the count right σ would give
        # (log(estimate / truth) normal with that σ) says whether the misses are too many.
        well, misses, expected = 0, [], 0.0
        for name, t in truth.items():
            col = f"std_{name}"
            if col not in ok.columns or t <= 0:
                continue
            sd = ok[col].replace("", np.nan).astype(float)
            for seed, est, s in zip(ok["seed"], ok[f"est_{name}"].astype(float), sd, strict=True):
                if s < 0.05:
                    well += 1
                    expected += float(norm.cdf(np.log(0.9) / s) + norm.sf(np.log(1.1) / s))
                    if abs(est / t - 1) >= 0.10:
                        misses.append(
                            f"{name} seed {seed} {100 * (est / t - 1):+.1f} % (σ {100 * s:.1f} %)"
                        )
        lines.append(
            f"  estimates with σ < 5 %: {well - len(misses)} of {well} within 10 % of the truth"
            f" (were their σ right, {expected:.1f} would miss on average)"
            + (f"; the others: {', '.join(misses)}" if misses else "")
        )
    lines += _profile_lines(ok, truth)
    lines.append("Table 5.4 (RMS after, mm / mrad):")
    for _, r in ok.iterrows():
        lines.append(
            f"  seed {int(r['seed'])}: "
            + " ".join(f"{1e3 * float(r[f'rms_after_{a}']):.4f}" for a in _AXES)
        )
    return "\n".join(lines)


def _profile_lines(ok: Any, truth: dict[str, float]) -> list[str]:
    """For each profiled quantity: how many runs' 95 % profile-likelihood interval holds the truth,
    beside the reported interval (estimate·e^(±1.96σ)) on the same runs."""
    lines = []
    for col in (c for c in ok.columns if c.startswith("prof_lo_")):
        name = col[len("prof_lo_") :]
        t = truth.get(name, 0.0)
        rows = ok[[col, f"prof_hi_{name}", f"est_{name}", f"std_{name}"]]
        rows = rows.replace("", np.nan).astype(float).dropna()
        if t <= 0 or not len(rows):
            continue
        lo, hi, est, sd = (rows[c].to_numpy() for c in rows.columns)
        prof = int(np.sum((lo <= t) & (t <= hi)))
        wald = int(np.sum(np.abs(np.log(est / t)) <= 1.96 * sd))
        lines.append(
            f"  {name}: the 95 % profile-likelihood interval holds the truth in {prof} of "
            f"{len(rows)} runs (the reported σ's interval: {wald} of {len(rows)})"
        )
    if "prof_error" in ok.columns:
        failed = int(ok["prof_error"].replace("", np.nan).notna().sum())
        if failed:
            lines.append(f"  {failed} runs' profiles stopped on a refit that did not converge")
    return lines


def _rms_range(sd: Any) -> tuple[float, float]:
    """Where RMS(σ) / spread falls for 95 % of studies when every σ is right but they differ: the
    spread's variance then has Satterthwaite's (Σσ²)² / Σσ⁴ degrees of freedom (fewer than the
    runs), less the mean's share. On 4000 synthetic studies of 40 or 120 runs with log-uniform σ
    over a factor e² or e⁴ it held 95–96 % of them; the equal-σ range 68–84 %
    (``python/tests/test_studies.py``). Equal σ: the χ² range of n − 1 degrees of freedom."""
    from scipy.stats import chi2

    v = np.asarray(sd, dtype=np.float64) ** 2
    n = len(v)
    nu = float(v.sum() ** 2 / np.sum(v * v)) * (n - 1) / n
    lo, hi = (float(np.sqrt(nu / chi2.ppf(q, nu))) for q in (0.975, 0.025))
    return lo, hi


def summary_discrepancy(df: Any) -> str:
    """The confusion matrix and the issue-14 figures (:func:`rss6.discrepancy.benchmark.summary`)."""
    from rss6.discrepancy.benchmark import summary

    rows = [
        {k: ("" if v != v else v) for k, v in r.items()}
        for r in df[df["status"] == "ok"].astype(str).to_dict("records")
    ]
    return summary(rows)
