"""The report of ``rss6 identify --simulate`` (:mod:`rss6.identify_sim`): Tables 5.2–5.5 beside the
thesis's and the printed summary."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import rss6
from rss6 import _rss6, identify, thesis
from rss6.excitation import LoopObservability
from rss6.identify_linear import SETTLE_STEPS

__all__ = ["IdentifyReport", "loop_text", "quantities"]

_AXES = ("x", "y", "z", "α", "β", "γ")


def quantities(dp: rss6.DynamicParams, pid: tuple[float, float, float]) -> np.ndarray:
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


def loop_text(t_f: float, eps: float, implicit: bool = False) -> str:
    """One line on the loop's drive and friction law."""
    if implicit:
        drive = f"drive derivative filter {1e3 * t_f:g} ms" if t_f > 0 else "unfiltered drive"
        return (
            f"{drive}, stick–slip friction stepped implicitly in plant and model; linear start "
            "from the recorded commands and potentiometers (l_p known), CLOE on the recorded commands"
        )
    if t_f == 0 and eps == 0:
        return "loop as printed: unfiltered drive derivative, sign friction"
    return f"drive derivative filter {1e3 * t_f:g} ms, model friction tanh(θ̇/{eps:g} rad/s)"


#: What each CLOE stopping rule (``IdentificationResult.converged_by``) means, for the report.
_STOP_RULES = {
    "tolerances": "eq. 5.9: Φ and every quantity changed by less than the tolerances",
    "invisible": "Φ fell by < 1 % of a residual variance twice",
    "settled": f"settled: over the last {SETTLE_STEPS} steps Φ fell by < 1 residual variance and "
    "no quantity moved by half its σ",
    "stationary": "no step lowers Φ and the gradient vanishes",
}


def _periods(n: float) -> str:
    k = round(n)
    return f"{k} period" if k == 1 else f"{k} periods"


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
    converged_by: str = ""
    run_failed: str = ""
    loop: str = ""
    variation: dict[str, float] | None = None
    reidentified: tuple[int, int] = (0, 0)
    files: list[Path] = field(default_factory=list)
    elapsed: dict[str, float] = field(default_factory=dict)
    inexact_friction_ticks: int = 0
    #: Where the σ come from: CLOE's alone, or with the noisy replicates' spread (and why not).
    sigma_note: str = ""
    #: One validation run with the visual PID's gains at ``identify_sim.OTHER_OUTER_GAINS``.
    validation_other_gains: identify.Validation | None = None
    #: What each unidentifiable quantity combines into (IdentificationResult.alias_text()).
    aliases: list[str] = field(default_factory=list)
    #: O_in and cond of the loop's output sensitivity at the estimate (None: not converged).
    loop_observability: LoopObservability | None = None

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
        o = self.validation_other_gains
        if o is not None:
            from rss6.identify_sim import OTHER_OUTER_GAINS

            g = ", ".join(f"{x:g}" for x in OTHER_OUTER_GAINS)
            lines.append(
                "gains identified  "
                + " ".join(f"{1e3 * x:8.4f}" for x in o.rms[0])
                + f"   {np.max(o.ratio[0]):.3f}   (outer gains k_p, k_i, k_d = {g})"
            )
            lines.append(
                "      initial     " + " ".join(f"{1e3 * x:8.4f}" for x in o.rms_initial[0])
            )
            if o.ratio_true is not None:
                lines.append(
                    "      (against the noise-free pose: identified/initial "
                    f"{np.min(o.ratio_true[0]):.3f}–{np.max(o.ratio_true[0]):.3f})"
                )
            if o.faulted:
                lines.append("      (the run with these gains faulted on the robot)")
        good = [j for j in range(v.rms.shape[0]) if j not in v.faulted]
        ok = bool(good) and bool(np.all(v.ratio[good] <= 1 / 3))
        lines.append(
            f"(mm, mrad; ratio = identified/initial RMS, thesis criterion ≤ 1/3: "
            f"{'met' if ok else 'NOT met'} on every axis of the {len(good)} runs that did not fault"
            f"; {len(v.faulted)} faulted)"
        )
        rt, et = v.ratio_true, v.rms_true
        if rt is not None and et is not None and good:
            r, e = rt[good], et[good]
            lines.append(
                "(the model's own error, against the robot's noise-free pose at the frame times: "
                f"identified/initial RMS {np.min(r[:, :3]):.3f}–{np.max(r[:, :3]):.3f} on x, y, z, "
                f"{np.min(r[:, 3:]):.3f}–{np.max(r[:, 3:]):.3f} on α, β, γ: ≤ 1/3 "
                f"{'met' if bool(np.all(r <= 1 / 3)) else 'NOT met'} on every axis; identified "
                f"{1e3 * np.max(e[:, :3]):.4f} mm, {1e3 * np.max(e[:, 3:]):.4f} mrad at worst)"
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
            f"converged in {self.iterations} iterations "
            f"({_STOP_RULES.get(self.converged_by, self.converged_by or 'eq. 5.9')}), "
            f"reduced χ² {self.reduced_chi2:.3g}"
            if self.converged
            else f"DID NOT CONVERGE ({self.error}); tables show the last accepted iterate"
        )
        if self.sigma_note:
            status += f"; {self.sigma_note}"
        if self.inexact_friction_ticks:
            status += (
                f"; WARNING: {self.inexact_friction_ticks} ticks of the model's loop used an inexact "
                "friction solve"
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
                    f"cond {e.condition:.4g} (torque regressor)"
                    + (
                        ""
                        if self.loop_observability is None
                        else f"; through the loop at the estimate O_in "
                        f"{self.loop_observability.o_in:.4g}, cond "
                        f"{self.loop_observability.condition:.4g} (camera poses / noise)"
                    )
                ),
                f"2. identification loop: {self.data.frames} camera frames in "
                f"{self.data.duration:.0f} s ({_periods(self.data.duration / e.duration)})"
                + (f", visual-PID fault {self.data.fault}" if self.data.fault else ""),
                (
                    f"3. CLOE: {len(self.identified)} quantities estimated, "
                    f"{len(self.unidentifiable)} not identifiable; {status}"
                ),
                *(f"   {a}" for a in self.aliases),
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
