"""``rss6 identify --simulate``: dynamic identification of a simulated robot, end to end (thesis §5.6).

1. An exciting trajectory (§5.4, :func:`rss6.identify.excitation`; thesis: 5 harmonics of 0.1 Hz).
2. The identification loop of Fig. 5.1 on the simulated "real robot" — the rapier plant when built,
   whose dynamics and drive gains are :func:`rss6.identify.table_5_2_truth` — logged to MCAP.
3. CLOE (§5.3) from the initial model: Table 5.1, the tuned drive gains (400, 2000, 4) and small
   positive friction (0.1 N·m, 0.1 N·m·s/rad: the log-parametrisation cannot start at the thesis's 0).
4. Tables 5.2 (initial, identified, truth, relative σ, flag > 10 %, beside the thesis's values), 5.3
   (RMS before/after), 5.4 (validation on fresh random feasible trajectories, RMS of the identified
   and initial models), 5.5 (variation over re-identifications on the validation runs); Figs.
   5.7–5.9 as PNG; an MCAP log per run.

If CLOE does not converge the report says so, shows its cost history and uses the last accepted
iterate (marked as such) for the tables and figures.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

import rss6
from rss6 import _rss6, identify, plots, thesis
from rss6.errors import IdentificationError

__all__ = ["IdentifyReport", "run"]

#: Friction of the initial model (N·m, N·m·s/rad).
INITIAL_FRICTION = (0.1, 0.1)
#: Drive gains of the initial model (rss6's tuned gains, PidGains::tuned).
INITIAL_PID = (400.0, 2000.0, 4.0)
#: Time constant (s) of the drive's derivative filter, on the plant and in the model.
DRIVE_DERIVATIVE_FILTER = 5e-3
#: ε (rad/s) of the model's smoothed Coulomb friction f_c tanh(θ̇/ε): 1 rad/s, what the multi-start
#: benchmark needs for ±30 % guesses of Table 5.2's friction (docs/identification.md).
FRICTION_SMOOTHING = 1.0

_AXES = ("x", "y", "z", "α", "β", "γ")


def initial_model() -> tuple[rss6.DynamicParams, tuple[float, float, float]]:
    """Table 5.1 with :data:`INITIAL_FRICTION`, and :data:`INITIAL_PID`."""
    d = rss6.DynamicParams.nominal().to_dict()
    d["coulomb"] = [INITIAL_FRICTION[0]] * 6
    d["viscous"] = [INITIAL_FRICTION[1]] * 6
    return rss6.DynamicParams.from_dict(d), INITIAL_PID


def _phi(dp: rss6.DynamicParams, pid: tuple[float, float, float]) -> np.ndarray:
    """The quantities CLOE estimates (see :func:`rss6.identify.parameter_names`) of a model."""
    psi, _, _ = _rss6.cloe_psi(dp, pid)
    return np.exp(np.asarray(psi))


def _thesis_columns() -> tuple[list[float], list[float]]:
    """Table 5.1/5.2 as the quantities CLOE estimates (printed units: friction and PID gains in the
    thesis's drive units)."""

    def bodies(
        platform: list[float], wrenches: list[list[float]], links: list[list[float]]
    ) -> list[float]:
        m, ix, iy, iz = platform
        out = [m, (iy + iz - ix) / 2, (ix + iz - iy) / 2, (ix + iy - iz) / 2]
        for w in wrenches:
            out += [w[0], w[-1]]
        for li in links:
            out += [li[0], (li[1] + li[2]) / 2]
        return out

    t51 = thesis.TABLE_5_1
    w0, l0 = list(t51["wrench"]), list(t51["link"])
    initial = bodies(list(t51["platform"]), [[w0[0], w0[3]]] * 6, [l0[:3]] * 6)
    initial += [0.0] * 12 + list(thesis.TABLE_5_2["pid_initial"])
    b = thesis.TABLE_5_2_BODIES
    ident = bodies(b["platform"], b["wrenches"], b["links"])
    ident += list(thesis.TABLE_5_2["coulomb"]) + list(thesis.TABLE_5_2["viscous"])
    ident += list(thesis.TABLE_5_2["pid_identified"])
    return initial, ident


def _loop_text(smooth: dict[str, float]) -> str:
    t_f, eps = smooth["derivative_filter"], smooth["friction_smoothing"]
    if t_f == 0 and eps == 0:
        return "loop as printed: unfiltered drive derivative, sign friction"
    return f"drive derivative filter {1e3 * t_f:g} ms, model friction tanh(θ̇/{eps:g} rad/s)"


@dataclass
class IdentifyReport:
    """Everything ``rss6 identify --simulate`` found and wrote."""

    plant: str
    excitation: identify.Excitation
    data: identify.IdentificationData
    names: list[str]
    initial: np.ndarray
    estimate: np.ndarray
    truth: np.ndarray
    converged: bool
    identified: tuple[str, ...]
    relative_std: dict[str, float]
    unidentifiable: tuple[str, ...]
    cost_history: np.ndarray
    iterations: int
    reduced_chi2: float
    rms_before: np.ndarray
    rms_after: np.ndarray
    validation: identify.Validation | None
    error: str = ""
    run_failed: str = ""
    loop: str = ""
    variation: dict[str, float] | None = None
    reidentified: tuple[int, int] = (0, 0)
    files: list[Path] = field(default_factory=list)
    elapsed: dict[str, float] = field(default_factory=dict)

    def table_5_2(self) -> str:
        """Table 5.2 analog: per estimated quantity the initial, identified and true value, the
        relative σ (flagged > 10 %), and the thesis's initial and identified values."""
        th0, th1 = _thesis_columns()
        head = (
            f"{'quantity':14s} {'initial':>11s} {'identified':>11s} {'truth':>11s} "
            f"{'rel. σ':>8s} {'':4s} {'thesis init':>11s} {'thesis id.':>11s}"
        )
        lines = [head, "-" * len(head)]
        for k, n in enumerate(self.names):
            if not self.converged:
                sig, flag = "    n/c", ""
            elif n in self.relative_std:
                s = self.relative_std[n]
                sig = f"{100 * s:7.2f}%"
                flag = " >10%" if s > 0.10 else ""
            else:
                sig, flag = "   fixed", ""
            lines.append(
                f"{n:14s} {self.initial[k]:11.4g} {self.estimate[k]:11.4g} {self.truth[k]:11.4g} "
                f"{sig:>8s} {flag:4s} {th0[k]:11.4g} {th1[k]:11.4g}"
            )
        lines.append(
            "(Sxx, Syy, Szz: the platform's second moments, I_x = Syy + Szz …; link It = (I_x + I_y)/2; "
            "thesis friction and PID gains in drive units, 1 unit = 40 N·m here; 'fixed': not "
            "identifiable from these data, kept at the initial value; 'n/c': CLOE did not converge, no σ)"
        )
        return "\n".join(lines)

    def table_5_3(self) -> str:
        """Table 5.3 analog: RMS of χ_m − χ_s on the identification trajectory (mm, mrad)."""
        t = thesis.TABLE_5_3
        lines = [
            f"{'axis':5s} {'before':>9s} {'after':>9s} {'thesis before':>14s} {'thesis after':>13s}"
        ]
        for i, a in enumerate(_AXES):
            lines.append(
                f"{a:5s} {1e3 * self.rms_before[i]:9.4f} {1e3 * self.rms_after[i]:9.4f} "
                f"{1e3 * t['before'][i]:14.3f} {1e3 * t['after'][i]:13.3f}"
            )
        lines.append("(mm for x, y, z; mrad for α, β, γ)")
        return "\n".join(lines)

    def table_5_4(self) -> str:
        """Table 5.4 analog: per validation trajectory the RMS of the identified model (and of the
        initial one), beside the thesis's row."""
        v = self.validation
        if v is None:
            return "(no validation)"
        lines = [
            "traj  model       " + " ".join(f"{a:>8s}" for a in _AXES) + "   max ratio",
        ]
        for j in range(v.rms.shape[0]):
            lines.append(
                f"{j + 1:4d}  identified  "
                + " ".join(f"{1e3 * x:8.4f}" for x in v.rms[j])
                + f"   {np.max(v.ratio[j]):.3f}"
            )
            fault = v.data[j].fault
            if fault is not None:
                lines.append(
                    f"      (the run on the robot failed at t = {fault[0]:.3f} s: {fault[1]})"
                )
            lines.append(
                "      initial     " + " ".join(f"{1e3 * x:8.4f}" for x in v.rms_initial[j])
            )
            if j < len(thesis.TABLE_5_4):
                lines.append(
                    "      thesis      " + " ".join(f"{1e3 * x:8.3f}" for x in thesis.TABLE_5_4[j])
                )
        good = [j for j in range(v.rms.shape[0]) if j not in v.faulted]
        ok = bool(good) and bool(np.all(v.ratio[good] <= 1 / 3))
        lines.append(
            f"(mm, mrad; ratio = identified/initial RMS, thesis criterion ≤ 1/3: "
            f"{'met' if ok else 'NOT met'} on every axis of the {len(good)} runs that did not fault"
            f"; {len(v.faulted)} faulted)"
        )
        return "\n".join(lines)

    def table_5_5(self) -> str:
        """Table 5.5 analog: variation (std/|mean|) of each estimated quantity over the
        identification run and the re-identifications on the validation runs, beside the thesis's
        where it names the same quantity."""
        if self.variation is None:
            return "(fewer than two identifications: no variation measure)"
        done, conv = self.reidentified
        names = list(self.identified) if self.identified else self.names
        lines = [f"{'quantity':14s} {'variation':>10s} {'thesis':>8s}"]
        for n in names:
            th = thesis.TABLE_5_5.get(n)
            ths = f"{100 * th:7.2f}%" if th is not None else "       —"
            lines.append(f"{n:14s} {100 * self.variation[n]:9.2f}% {ths}")
        lines.append(
            f"(over {done + 1} identifications: this run and {done} validation runs, {conv} of "
            "those converged — the others enter with their last iterate; the thesis's is over 10; "
            "'—': the thesis names moments (I_x, I_y), not Σ or It)"
        )
        return "\n".join(lines)

    def text(self) -> str:
        """What ``rss6 identify --simulate`` prints."""
        if self.run_failed:
            return "\n".join(
                [
                    f"rss6 identify --simulate on the {self.plant} (truth: table_5_2_truth)",
                    f"the identification run failed: {self.run_failed}",
                    (
                        f"({self.data.frames} frames before it; no identification from a robot "
                        "that left the loop — try another --seed)"
                    ),
                    f"files: {len(self.files)}",
                ]
            )
        status = (
            f"converged in {self.iterations} iterations, reduced χ² {self.reduced_chi2:.3g}"
            if self.converged
            else f"DID NOT CONVERGE ({self.error}); tables show the last accepted iterate"
        )
        e = self.excitation
        timing = ", ".join(f"{k} {v:.1f} s" for k, v in self.elapsed.items())
        hist = " → ".join(f"{c:.4g}" for c in self.cost_history)
        return "\n".join(
            [
                f"rss6 identify --simulate on the {self.plant} (truth: table_5_2_truth; {self.loop})",
                (
                    f"1. exciting trajectory: {e.coefficients.shape[1] // 2} harmonics of "
                    f"{e.f0} Hz, {e.duration:.1f} s, O_in {e.observability:.4g}, "
                    f"cond {e.condition:.4g}"
                ),
                f"2. identification loop: {self.data.frames} camera frames"
                + (f", visual-PID fault {self.data.fault}" if self.data.fault else ""),
                (
                    f"3. CLOE: {len(self.identified)} quantities estimated, "
                    f"{len(self.unidentifiable)} not identifiable; {status}"
                ),
                f"   cost history: {hist}",
                "",
                "Table 5.2 — identified parameters",
                self.table_5_2(),
                "",
                "Table 5.3 — RMS of the pose errors on the identification trajectory",
                self.table_5_3(),
                "",
                "Table 5.4 — validation trajectories",
                self.table_5_4(),
                "",
                "Table 5.5 — variation measure over re-identifications",
                self.table_5_5(),
                f"files: {len(self.files)} in {self.files[0].parent if self.files else '-'}; {timing}",
            ]
        )


def run(
    out: str | Path,
    *,
    quick: bool = False,
    seed: int = 0,
    plant: str = "auto",
    progress: Callable[[int, str], Any] | None = None,
    as_printed: bool = False,
    variation: bool = True,
) -> IdentifyReport:
    """Runs the study (see the module docs) and writes its files into ``out``. ``quick``: a 2 s
    trajectory (3 harmonics of 0.5 Hz, 5 generations), 10 CLOE iterations, 2 validation trajectories;
    otherwise 10 s (5 of 0.1 Hz, 30 generations), 20 iterations, 10 trajectories. ``plant``:
    "rapier", "model" or "auto". ``progress(total, desc)`` returns a context manager with
    ``update(n)`` (e.g. a tqdm bar) or None. The drive filters its derivative
    (:data:`DRIVE_DERIVATIVE_FILTER`) and the model smooths Coulomb friction
    (:data:`FRICTION_SMOOTHING`), unless ``as_printed``: eq. 5.5 unfiltered, sign friction.
    ``variation``: re-identify on every validation run for Table 5.5 (the slowest step of a full
    run: ≈ 10 min of 11 measured)."""
    outdir = Path(out)
    outdir.mkdir(parents=True, exist_ok=True)
    kp = rss6.KinematicParams.nominal()
    files: list[Path] = []
    elapsed: dict[str, float] = {}
    harmonics, f0, gens, iters, n_val = (3, 0.5, 5, 10, 2) if quick else (5, 0.1, 30, 20, 10)
    # Free-coefficient bounds (rates, m/s and rad/s). Larger ones make the visual-PID loop on the
    # rapier plant leave its workspace more often (docs/identification.md).
    amplitude = (0.002, 0.01) if quick else (0.001, 0.005)
    use_rapier = plant == "rapier" or (plant == "auto" and rss6.Plant is not None)
    t_f = 0.0 if as_printed else DRIVE_DERIVATIVE_FILTER
    eps = 0.0 if as_printed else FRICTION_SMOOTHING

    def frames(
        dp: rss6.DynamicParams,
        pid: tuple[float, float, float],
        reference: identify.Excitation,
        d: identify.IdentificationData,
    ) -> np.ndarray:
        """χ_s of the model (dp, pid) in this run's loop at the frames of `d`."""
        return identify.simulate(
            kp,
            dp,
            pid,
            reference,
            times=d.t,
            dt=d.dt,
            derivative_filter=t_f,
            friction_smoothing=eps,
        )

    smooth = {"derivative_filter": t_f, "friction_smoothing": eps}

    def bar(total: int, desc: str) -> Any:
        return None if progress is None else progress(total, desc)

    t0 = time.perf_counter()
    b = bar(gens, "excitation design")
    exc = identify.excitation(
        kp,
        harmonics=harmonics,
        f0=f0,
        seed=seed,
        maxiter=gens,
        popsize=5 if quick else 8,
        amplitude=amplitude,
        progress=None if b is None else (lambda g, o: b.update(1)),
    )
    if b is not None:
        b.close()
    elapsed["design"] = time.perf_counter() - t0
    tt = np.linspace(0.0, exc.duration, 500)
    plots.exciting_trajectory(
        tt,
        np.array([exc.sample(t)[0] for t in tt]),
        outdir / "fig5_7_excitation.png",
        "Exciting trajectory (Fig. 5.7)",
    )
    files.append(outdir / "fig5_7_excitation.png")

    dp_true, pid_true = identify.table_5_2_truth()

    def make_robot() -> Any:
        if use_rapier:
            return rss6.Plant(kp, dp_true, pid=pid_true, seed=seed, drive_derivative_filter=t_f)
        return rss6.ModelSim(kp, dp_true, pid=pid_true, seed=seed, drive_derivative_filter=t_f)

    robot = make_robot()
    truth = robot.truth()
    t0 = time.perf_counter()
    b = bar(int(np.ceil(exc.duration)), "identification run")
    done = [0.0]

    def tick(d: float, total: float) -> None:
        if b is not None:
            b.update(round(d) - round(done[0]))
        done[0] = d

    data = identify.collect(
        robot,
        exc,
        kp_model=kp,
        sensor_in_base=truth["sensor_in_base"],
        target_in_effector=truth["target_in_effector"],
        mcap=outdir / "identification.mcap",
        progress=tick,
    )
    if b is not None:
        b.close()
    files.append(outdir / "identification.mcap")
    elapsed["collect"] = time.perf_counter() - t0

    dp0, pid0 = initial_model()
    names = identify.parameter_names()
    if data.fault is not None:
        # The robot left the loop (the visual PID faulted and its command is held): nothing to
        # identify from; report it.
        phi0 = _phi(dp0, pid0)
        return IdentifyReport(
            plant="rapier plant" if use_rapier else "model twin",
            excitation=exc,
            data=data.before_fault(),
            names=names,
            initial=phi0,
            estimate=phi0,
            truth=_phi(dp_true, pid_true),
            converged=False,
            identified=(),
            relative_std={},
            unidentifiable=(),
            cost_history=np.zeros(0),
            iterations=0,
            reduced_chi2=float("nan"),
            rms_before=np.full(6, np.nan),
            rms_after=np.full(6, np.nan),
            validation=None,
            error="identification run failed",
            loop=_loop_text(smooth),
            run_failed=f"visual-PID fault at t = {data.fault[0]:.3f} s: {data.fault[1]}",
            files=files,
            elapsed=elapsed,
        )
    t0 = time.perf_counter()
    b = bar(iters, "CLOE")
    last = [0]

    def step(k: int, cost: float) -> None:
        if b is not None and k > last[0]:
            b.update(k - last[0])
            last[0] = k

    error = ""
    try:
        res = identify.cloe(
            data,
            kp,
            dp0,
            pid0,
            max_iterations=iters,
            per_tick_jacobians=True,
            progress=step,
            derivative_filter=t_f,
            friction_smoothing=eps,
        )
        converged = True
        est_dp, est_pid = res.dynamics, res.pid
        identified, rel, unid = res.identified, res.relative_std, res.unidentifiable
        hist, its, chi2 = res.cost_history, res.iterations, res.reduced_chi2
        rms_b, rms_a = res.rms_before, res.rms_after
        result = res
    except IdentificationError as e:
        if not hasattr(e, "last_dynamics"):
            raise
        converged = False
        error = f"{getattr(e, 'iterations', '?')} iterations"
        est_dp, est_pid = e.last_dynamics, e.last_pid  # type: ignore[attr-defined]
        hist = np.asarray(e.cost_history)  # type: ignore[attr-defined]
        its, chi2 = int(e.iterations), float("nan")  # type: ignore[attr-defined]
        identified, rel, unid = (), np.zeros(0), ()
        # The report's figures need these frames anyway (`sims` below).
        sims = {
            "initial": frames(dp0, pid0, exc, data),
            "identified": frames(est_dp, est_pid, exc, data),
        }
        rms_b = np.sqrt(np.mean((data.measured - sims["initial"]) ** 2, axis=0))
        rms_a = np.sqrt(np.mean((data.measured - sims["identified"]) ** 2, axis=0))
        result = identify.IdentificationResult(
            dynamics=est_dp,
            pid=est_pid,
            identified=(),
            unidentifiable=(),
            relative_std=np.zeros(0),
            poorly_identified=(),
            rms_before=rms_b,
            rms_after=rms_a,
            cost_history=hist,
            iterations=its,
            reduced_chi2=chi2,
            simulations=0,
            guess=(dp0, pid0),
            model=identify.LoopModel(kp=kp, derivative_filter=t_f, friction_smoothing=eps),
        )
    if b is not None:
        b.close()
    elapsed["cloe"] = time.perf_counter() - t0

    if converged:
        sims = {
            "initial": frames(dp0, pid0, exc, data),
            "identified": frames(est_dp, est_pid, exc, data),
        }
    plots.identification_fit(
        data.t,
        data.measured,
        sims,
        outdir / "fig5_8_identification.png",
        "Identification trajectory: measured, initial and identified model (Fig. 5.8)",
    )
    files.append(outdir / "fig5_8_identification.png")

    t0 = time.perf_counter()
    b = bar(n_val, "validation")
    val = identify.validate(
        result,
        make_robot(),
        n=n_val,
        seed=seed + 1000,
        harmonics=harmonics,
        f0=f0,
        amplitude=amplitude,
        mcap_dir=outdir,
        progress=None if b is None else (lambda d, n: b.update(1)),
    )
    if b is not None:
        b.close()
    files += [outdir / f"validation_{i}.mcap" for i in range(n_val)]
    elapsed["validation"] = time.perf_counter() - t0
    d1 = val.data[0]
    plots.identification_fit(
        d1.t,
        d1.measured,
        {"identified": frames(est_dp, est_pid, val.excitations[0], d1)},
        outdir / "fig5_9_validation.png",
        "Validation trajectory 1: measured and identified model (Fig. 5.9)",
    )
    files.append(outdir / "fig5_9_validation.png")

    # Table 5.5: identify again on every validation run that did not fault.
    good = [j for j in range(n_val) if j not in val.faulted] if variation else []
    estimates = [(est_dp, est_pid)]
    conv = 0
    t0 = time.perf_counter()
    b = bar(len(good), "re-identification")
    for j in good:
        try:
            r = identify.cloe(
                val.data[j],
                kp,
                dp0,
                pid0,
                max_iterations=iters,
                per_tick_jacobians=True,
                derivative_filter=t_f,
                friction_smoothing=eps,
            )
            estimates.append((r.dynamics, r.pid))
            conv += 1
        except IdentificationError as e:
            if not hasattr(e, "last_dynamics"):
                raise
            estimates.append((e.last_dynamics, e.last_pid))  # type: ignore[attr-defined]
        if b is not None:
            b.update(1)
    if b is not None:
        b.close()
    elapsed["re-identification"] = time.perf_counter() - t0
    var = identify.variation(estimates) if len(estimates) >= 2 else None

    return IdentifyReport(
        plant="rapier plant" if use_rapier else "model twin",
        excitation=exc,
        data=data,
        names=names,
        initial=_phi(dp0, pid0),
        estimate=_phi(est_dp, est_pid),
        truth=_phi(dp_true, pid_true),
        converged=converged,
        identified=tuple(identified),
        relative_std={n: float(s) for n, s in zip(identified, rel)},
        unidentifiable=tuple(unid),
        cost_history=np.asarray(hist),
        iterations=its,
        reduced_chi2=chi2,
        rms_before=np.asarray(rms_b),
        rms_after=np.asarray(rms_a),
        validation=val,
        error=error,
        files=files,
        elapsed=elapsed,
        variation=var,
        reidentified=(len(good), conv),
        loop=_loop_text(smooth),
    )
