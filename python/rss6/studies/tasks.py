"""The tasks of the three studies: one spec in, one flat record out (run on Dask workers)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["calibration_task", "discrepancy_task", "identification_task"]

_AXES = "xyzabg"


def calibration_task(spec: Mapping[str, Any]) -> dict[str, Any]:
    """One random robot of the §4.4.3 study (seed ``seed``; the analytic generator or, with
    ``plant``, the rapier plant): RMS relative pose errors per axis uncalibrated / implicit / RPBA,
    parameter errors and residuals, and whether each method met Table 4.5 on every axis."""
    from rss6 import _rss6, thesis

    rows = _rss6.calibration_study(
        np.asarray(spec["rpba_thetas"], dtype=np.float64),
        np.asarray(spec["implicit_thetas"], dtype=np.float64),
        robots=1,
        seed=int(spec["seed"]),
        dwell=float(spec.get("dwell", 2.0)),
        stroke=tuple(spec["stroke"]),
        plant=bool(spec.get("plant", False)),
        noise=str(spec.get("noise", "table")),
    )
    r = rows[0]
    rec: dict[str, Any] = {"seed": int(spec["seed"]), "plant": bool(spec.get("plant", False))}
    for key, name in (
        ("rms_uncalibrated", "uncalibrated"),
        ("rms_implicit", "implicit"),
        ("rms_rpba", "rpba"),
    ):
        v = np.asarray(r[key], dtype=np.float64)
        for i, a in enumerate(_AXES):
            rec[f"{name}_{a}"] = float(v[i])
    for name, t in (("implicit", "implicit"), ("rpba", "RPBA")):
        table = np.asarray(thesis.TABLE_4_5[t], dtype=np.float64)
        got = np.array([rec[f"{name}_{a}"] for a in _AXES])
        rec[f"{name}_met"] = bool(np.all(got <= table))
        rec[f"{name}_worst_axis"] = _AXES[int(np.argmax(got / table))]
        rec[f"{name}_worst_ratio"] = float(np.max(got / table))
        pe = r[f"{name}_param_error"]
        rec[f"{name}_param_error_after"] = float(pe[1])
        rec[f"{name}_residual_after"] = float(r[f"{name}_residual"][1])
    return rec


def quantities(dynamics: Any, pid: Any) -> dict[str, float]:
    """CLOE's positive quantities (exp ψ) by name (``rss6.identify.parameter_names``): what the
    study records for each estimate and compares with the Table 5.2 truth."""
    import rss6
    from rss6 import identify

    phi = np.exp(np.asarray(rss6._rss6.cloe_psi(dynamics, pid)[0]))
    return {n: float(v) for n, v in zip(identify.parameter_names(), phi, strict=True)}


def identification_task(spec: Mapping[str, Any]) -> dict[str, Any]:
    """One identification on a random trajectory (seed ``seed``) of the robot whose truth is
    Table 5.2 (``robot``: "plant" or "twin"): CLOE from Table 5.1 and the nominal gains
    (:func:`rss6.identify_sim.estimate_from_initial`; ``friction_law`` "tanh" or "implicit"; the
    plant at ``solver_iterations`` when given), the estimates by name and the RMS before and after
    on the trajectory."""
    import rss6
    from rss6 import identify, identify_sim
    from rss6.errors import IdentificationError

    kp = rss6.KinematicParams.nominal()
    quick = bool(spec.get("quick", False))
    harmonics, f0 = (3, 0.5) if quick else (5, 0.1)
    seed = int(spec["seed"])
    dp_true, pid_true = identify.table_5_2_truth()
    plant_cls: Any = getattr(rss6, "Plant", None)
    cls: Any = plant_cls if spec.get("robot", "plant") == "plant" and plant_cls else rss6.ModelSim
    t_f, eps = identify_sim.DRIVE_DERIVATIVE_FILTER, identify_sim.FRICTION_SMOOTHING
    law = str(spec.get("friction_law", "implicit"))
    kw: dict[str, Any] = {"friction_smoothing": eps} if cls is rss6.ModelSim else {}
    if law == "implicit":
        kw = {"implicit_friction": True}
        if cls is not rss6.ModelSim:
            kw["solver_iterations"] = identify_sim.IMPLICIT_PLANT_ITERATIONS
    if "solver_iterations" in spec and cls is not rss6.ModelSim:
        kw["solver_iterations"] = int(spec["solver_iterations"])
    robot = cls(kp, dp_true, pid=pid_true, seed=seed, drive_derivative_filter=t_f, **kw)
    tr = robot.truth()
    amplitude = (0.002, 0.01) if quick else (0.001, 0.005)
    exc = identify.random_excitation(kp, harmonics=harmonics, f0=f0, seed=seed, amplitude=amplitude)
    data = identify.collect(
        robot,
        exc,
        kp_model=kp,
        sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
    )
    rec: dict[str, Any] = {"seed": seed, "robot": cls.__name__, "friction_law": law}
    if data.fault is not None:
        rec.update(status="faulted", error=f"visual PID fault at {data.fault[0]:.2f} s")
        return rec

    def fit(d: Any) -> Any:
        return identify_sim.estimate_from_initial(
            d,
            kp,
            friction_law=law,
            lp=pid_true[0],
            parameters=spec.get("parameters", "base"),
            max_iterations=int(
                spec.get("iterations", (10 if quick else 20) * (1 + (law == "implicit")))
            ),
            derivative_filter=t_f,
            friction_smoothing=eps,
            pot_noise=str(spec.get("pot_noise", "recorded")),
            noise=spec.get("noise"),
        )

    res = fit(data)
    for name, v in quantities(res.dynamics, res.pid).items():
        rec[f"est_{name}"] = v
    if spec.get("profile"):
        rec.update(_profiles(spec, data, kp, res, law, pid_true[0]))
    if int(spec.get("replicates", 0)) >= 2:
        # Replicates by the model twin at the estimate: linearised, or each identified again.
        # A replicate that cannot run keeps the estimate and CLOE's σ; the record says why.
        refit = fit if spec.get("bootstrap", False) else None
        try:
            res = identify.with_replicates(
                res, data, n=int(spec["replicates"]), refit=refit,
                correct_bias=bool(spec.get("replicate_bias", False)),
            )  # fmt: skip
        except IdentificationError as e:
            rec["error"] = f"σ from CLOE alone: the noisy replicates failed ({e})"
        else:
            for name, sd in zip(res.identified, res.relative_std_replicates, strict=True):
                rec[f"rep_{name}"] = float(sd)
            if len(res.replicate_bias):  # the estimates moved by minus the replicates' mean
                for name, v in quantities(res.dynamics, res.pid).items():
                    rec[f"est_{name}"] = v
    for name, sd in zip(res.identified, res.relative_std, strict=True):
        rec[f"std_{name}"] = float(sd)
    for name, sd in zip(res.identified, res.relative_std_wald, strict=True):
        rec[f"wald_{name}"] = float(sd)
    rec["iterations"] = int(res.iterations)
    rec["converged_by"] = res.converged_by
    for i, a in enumerate(_AXES):
        rec[f"rms_before_{a}"] = float(res.rms_before[i])
        rec[f"rms_after_{a}"] = float(res.rms_after[i])
    return rec


def _profiles(
    spec: Mapping[str, Any], data: Any, kp: Any, res: Any, law: str, lp: float
) -> dict[str, Any]:
    """The 95 % profile-likelihood interval (:func:`rss6.identify_profile.profile`) of each of
    ``spec["profile"]`` that CLOE estimated, on CLOE's own result (before any replicates): the
    bounds ``prof_lo_`` / ``prof_hi_`` (0 / inf where Φ never rose enough within e^±3), or
    ``prof_error`` naming the point whose refit did not converge."""
    from rss6 import identify_profile, identify_sim
    from rss6.errors import IdentificationError

    quick = bool(spec.get("quick", False))
    guess, kw = identify_sim.cloe_settings(
        data, kp, friction_law=law, lp=lp,
        max_iterations=int(spec.get("iterations", (10 if quick else 20) * (1 + (law == "implicit")))),
        parameters=spec.get("parameters", "base"), pot_noise=str(spec.get("pot_noise", "recorded")),
        noise=spec.get("noise"),
    )  # fmt: skip
    out: dict[str, Any] = {}
    for name in spec["profile"]:
        if name not in res.identified:
            continue
        try:
            p = identify_profile.profile(data, kp, *guess, res, name, **kw)
        except IdentificationError as e:
            out["prof_error"] = str(e)
            continue
        out[f"prof_lo_{name}"], out[f"prof_hi_{name}"] = p.interval
    return out


def discrepancy_task(spec: Mapping[str, Any]) -> dict[str, Any]:
    """One hidden-effect case of the discrepancy benchmark
    (:func:`rss6.discrepancy.benchmark.benchmark_case`)."""
    from rss6.discrepancy.benchmark import benchmark_case

    return benchmark_case(spec)
