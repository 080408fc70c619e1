"""The discrepancy report: the structured result of issue 14 and its directory (markdown + PNG).

:class:`DiscrepancyReport` holds the Detect step's :class:`~rss6.discrepancy.detect.Detection` on
the fitting run, the named effects, the ambiguous sets, the unexplained remainder and the gaps
(residual RMS per axis) on the held-out run. Its one-line :attr:`~DiscrepancyReport.verdict` is one
of "no missing effect", "named: …", "ambiguous: …", "unexplained discrepancy: axes …, spectral peak …
Hz, correlated with …" (joined by "; " when several apply). :func:`from_detection` builds the report
of a run that has been tested but not explained (the candidate search needs the closed-loop
simulation with effects, not built yet).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from rss6.discrepancy import figures, stats
from rss6.discrepancy.detect import AXES, Detection
from rss6.errors import ShapeError

__all__ = [
    "AMBIGUOUS",
    "NEARLY_AMBIGUOUS",
    "Ambiguity",
    "CandidateRow",
    "DiscrepancyReport",
    "HeldOut",
    "NamedEffect",
    "Unexplained",
    "ambiguities",
    "from_detection",
    "unexplained",
]

F64 = NDArray[np.float64]
#: |ρ| above which two candidates that both pass a round's screen are reported as ambiguous.
AMBIGUOUS = 0.9
#: |ρ| from which a named effect's closest mimic is mentioned in the verdict (docs/discrepancy.md,
#: "Confounded pairs": at the threshold the noise decides between "named" and "ambiguous").
NEARLY_AMBIGUOUS = 0.85
_UNITS = (1e3, 1e3, 1e3, 1e3, 1e3, 1e3)  # m → mm, rad → mrad


@dataclass(frozen=True)
class NamedEffect:
    """An effect that passed selection on the fitting run and is claimed on the held-out run:
    ``name`` and ``scope`` (e.g. "coulomb friction", "joint 3"), fitted ``params`` {name: value}
    (SI), ``ci`` {name: (low, high)} (95 %), Holm-adjusted bootstrap ``p_value``, ``gap_after``
    (6,): held-out residual RMS per axis with the effects named so far (m, rad); ``se`` {name:
    standard error} of ``params`` from the fitting run alone (the larger of Wald and the
    sandwiches); ``heldout`` {name: (value, standard error)}: the held-out run's own refit, empty
    when it could not run (``ci`` combines the two runs: docs/discrepancy.md, "Intervals");
    ``closest_mimic`` (label, |ρ|): of the candidates that also passed the round's screen, the one
    whose signature it shares most (None when it passed alone) — at |ρ| ≥
    :data:`NEARLY_AMBIGUOUS` the verdict says so: a second excitation would confirm the name;
    ``nominal_se`` {name: standard error}: what the model's own uncertainty (the nominal refit's
    prior) adds to ``ci``, empty when the nominal quantities are held."""

    name: str
    scope: str
    params: dict[str, float]
    ci: dict[str, tuple[float, float]]
    p_value: float
    gap_after: F64
    se: dict[str, float] = field(default_factory=dict)
    heldout: dict[str, tuple[float, float]] = field(default_factory=dict)
    closest_mimic: tuple[str, float] | None = None
    nominal_se: dict[str, float] = field(default_factory=dict)

    @property
    def nearly_ambiguous(self) -> bool:
        """Named, but its closest mimic's |ρ| is within reach of :data:`AMBIGUOUS` (≥
        :data:`NEARLY_AMBIGUOUS`): on another excitation or noise draw the pair may be reported
        ambiguous instead."""
        return self.closest_mimic is not None and self.closest_mimic[1] >= NEARLY_AMBIGUOUS


@dataclass(frozen=True)
class CandidateRow:
    """One effect × scope candidate of the search: its Δlog-likelihood on the fitting run, Holm-
    adjusted p, estimates with 95 % intervals, held-out ΔRMSE per axis (m, rad; < 0 is better) and
    whether it belongs to an ambiguous set."""

    effect: str
    scope: str
    delta_loglik: float
    p_adjusted: float
    estimate: dict[str, float]
    ci: dict[str, tuple[float, float]]
    heldout_drmse: F64
    ambiguous: bool


@dataclass(frozen=True)
class Ambiguity:
    """Candidates the data cannot tell apart: |ρ| of their Fisher information above 0.9.
    ``separate``: what excitation would (the samples where their signatures differ most)."""

    candidates: tuple[str, ...]
    correlation: float
    separate: str


@dataclass(frozen=True)
class Unexplained:
    """What is left after the best library model: the ``axes`` that still disagree, the residual's
    ``spectral_peak`` (Hz, the worst axis) and the signatures it follows (``correlated_with``,
    strongest first, with the axis)."""

    axes: tuple[str, ...]
    spectral_peak: float
    correlated_with: tuple[str, ...]

    def text(self) -> str:
        """ "unexplained discrepancy: axes …, spectral peak … Hz, correlated with …"."""
        corr = ", ".join(self.correlated_with) if self.correlated_with else "no signature"
        return (
            f"unexplained discrepancy: axes {', '.join(self.axes)}, spectral peak "
            f"{self.spectral_peak:.3g} Hz, correlated with {corr}"
        )


@dataclass(frozen=True)
class HeldOut:
    """Residuals (N, 6) on the held-out (validation) run at times ``time`` (N,) s: of the original
    model, with the named effects, after re-identification (None where not computed)."""

    time: F64
    before: F64
    named: F64 | None = None
    after: F64 | None = None


def unexplained(detection: Detection, top: int = 3) -> Unexplained | None:
    """The signature of a residual that still disagrees (None if nothing was detected): its axes,
    the spectral peak of the axis with the largest RMS/σ, the ``top`` signatures by |z|."""
    if not detection.detected:
        return None
    idx = [AXES.index(a) for a in detection.axes if a in AXES] or [0]
    worst = max(
        idx,
        key=lambda k: np.sqrt(np.mean(detection.residual[:, k] ** 2)) / detection.noise.sigma[k],
    )
    peak = stats.spectral_peak(detection.residual[:, worst], detection.rate)
    rows = detection.signatures()
    names: list[str] = []
    for r in rows:
        label = f"{r.test.removeprefix('xcorr ')} ({r.axis}, {r.detail})"
        if len(names) < top:
            names.append(label)
    return Unexplained(detection.axes, peak, tuple(names))


def _named_text(e: NamedEffect) -> str:
    text = f"{e.name} ({e.scope})"
    if e.nearly_ambiguous and e.closest_mimic is not None:
        other, rho = e.closest_mimic
        text += f" (nearly ambiguous with {other}, |ρ| {rho:.2f})"
    return text


def _rms(r: F64) -> F64:
    return np.asarray(np.sqrt(np.mean(r * r, axis=0)), dtype=np.float64)


@dataclass(frozen=True)
class DiscrepancyReport:
    """Structured result of the discrepancy workflow (issue 14).

    ``detected``: the Detect step on the fitting run; ``named``, ``ambiguous``, ``unexplained``:
    what the search concluded; ``gap_before``, ``gap_named``, ``gap_after``, ``noise_floor`` (6,):
    held-out residual RMS per axis of the original model, with the named effects, after
    re-identification, and σ (m, rad); ``model``: the final model; ``candidates``: the candidate
    table; ``held_out``: the residual traces; ``signatures``: what the residual was binned by; ``notes``: what the
    workflow dropped or could not do (e.g. an effect the identification loop cannot express)."""

    detected: Detection
    named: list[NamedEffect]
    ambiguous: list[Ambiguity]
    unexplained: Unexplained | None
    gap_before: F64
    gap_named: F64
    gap_after: F64
    noise_floor: F64
    model: Any = None
    candidates: list[CandidateRow] = field(default_factory=list)
    held_out: HeldOut | None = None
    signatures: dict[str, F64] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def verdict(self) -> str:
        """One line: "no missing effect", "named: …", "ambiguous: …", "unexplained discrepancy: …"."""
        parts = []
        if self.named:
            parts.append("named: " + ", ".join(_named_text(e) for e in self.named))
        if self.ambiguous:
            parts.append(
                "ambiguous: "
                + "; ".join("{" + ", ".join(a.candidates) + "}" for a in self.ambiguous)
            )
        if self.unexplained is not None:
            parts.append(self.unexplained.text())
        return "; ".join(parts) if parts else "no missing effect"

    def table(self) -> str:
        """The report as text: verdict, gaps per axis, the Detect step's rejected tests, the
        candidate table, the ambiguous sets."""
        lines = [f"verdict: {self.verdict}", ""]
        head = f"{'axis':6s}" + "".join(
            f"{n:>12s}" for n in ("before", "named", "after", "noise σ", "before/σ")
        )
        lines += ["residual RMS per axis (mm, mrad):", head, "-" * len(head)]
        for k, a in enumerate(AXES):
            vals = [self.gap_before[k], self.gap_named[k], self.gap_after[k], self.noise_floor[k]]
            ratio = self.gap_before[k] / self.noise_floor[k]
            lines.append(
                f"{a:6s}" + "".join(f"{v * _UNITS[k]:12.4g}" for v in vals) + f"{ratio:12.3g}"
            )
        det = self.detected
        lines += [
            "",
            (
                f"Detect ({det.noise.source} noise model, family-wise α = {det.alpha:g}, "
                f"{len(det.tests)} tests, Holm): {det.summary()}"
            ),
        ]
        for r in det.tests:
            if r.rejected:
                lines.append(
                    f"  {r.axis:3s} {r.test:28s} stat {r.statistic:10.4g}  p_adj {r.p_adjusted:9.3g}  {r.detail}"
                )
        for w in det.windows:
            lines.append(f"  window {w.axis}: {w.start:.2f}–{w.end:.2f} s, RMS/σ {w.ratio:.3g}")
        if self.candidates:
            lines += ["", "candidates:"]
            lines.append(
                f"  {'effect':22s} {'scope':12s} {'ΔlogL':>9s} {'p_adj':>9s} {'held-out ΔRMSE/σ (min)':>24s}  estimate ± CI"
            )
            for c in self.candidates:
                best = float(np.min(c.heldout_drmse / self.noise_floor))
                est = ", ".join(
                    f"{k}={v:.4g} [{c.ci[k][0]:.4g}, {c.ci[k][1]:.4g}]"
                    if k in c.ci
                    else f"{k}={v:.4g}"
                    for k, v in c.estimate.items()
                )
                flag = " (ambiguous)" if c.ambiguous else ""
                lines.append(
                    f"  {c.effect:22s} {c.scope:12s} {c.delta_loglik:9.3g} {c.p_adjusted:9.3g} {best:24.3g}  {est}{flag}"
                )
        if self.named:
            lines += [
                "",
                (
                    "named (estimate on the fitting run, 95 % interval from both runs and the "
                    "model's own uncertainty; in brackets the held-out run's own refit and what "
                    "the model's uncertainty alone spans, ±1.96σ):"
                ),
            ]
            for e in self.named:
                est = ", ".join(
                    f"{k}={v:.4g} [{e.ci[k][0]:.4g}, {e.ci[k][1]:.4g}]"
                    + (f" (held-out {e.heldout[k][0]:.4g})" if k in e.heldout else "")
                    + (
                        f" (model ±{1.96 * e.nominal_se[k]:.2g})"
                        if e.nominal_se.get(k, 0.0) > 0
                        else ""
                    )
                    if k in e.ci
                    else f"{k}={v:.4g}"
                    for k, v in e.params.items()
                )
                mimic = (
                    f"; closest mimic {e.closest_mimic[0]} (|ρ| {e.closest_mimic[1]:.2f})"
                    if e.closest_mimic is not None
                    else ""
                )
                lines.append(f"  {e.name} ({e.scope}): {est}; held-out p = {e.p_value:.3g}{mimic}")
        if self.notes:
            lines += ["", "notes:", *(f"  {n}" for n in self.notes)]
        for amb in self.ambiguous:
            lines.append(
                f"ambiguous {{{', '.join(amb.candidates)}}}: |ρ| = {amb.correlation:.3f}; "
                f"{amb.separate}"
            )
        return "\n".join(lines)

    def save(self, directory: str | PathLike[str]) -> list[Path]:
        """Writes ``report.md`` and its PNG figures into ``directory`` (created); returns the paths."""
        out = Path(directory)
        out.mkdir(parents=True, exist_ok=True)
        files = {
            "residuals": out / "residuals.png",
            "binned": out / "binned.png",
            "acf": out / "acf.png",
            "xcorr": out / "xcorr.png",
        }
        figures.residuals(self.detected, files["residuals"])
        figures.binned(self.detected, _binning(self.signatures), files["binned"])
        figures.acf(self.detected, files["acf"])
        figures.xcorr(self.detected, files["xcorr"])
        if self.held_out is not None:
            curves = {"original model": self.held_out.before}
            if self.held_out.named is not None:
                curves["with named effects"] = self.held_out.named
            if self.held_out.after is not None:
                curves["re-identified"] = self.held_out.after
            files["overlay"] = out / "overlay.png"
            figures.overlay(self.held_out.time, curves, self.noise_floor, files["overlay"])
        files["gaps"] = out / "gaps.png"
        reidentified = self.held_out is not None and self.held_out.after is not None
        gap_rows = {"before": self.gap_before, "named": self.gap_named}
        if reidentified:
            gap_rows["re-identified"] = self.gap_after
        figures.gaps(
            gap_rows,
            self.noise_floor,
            files["gaps"],
            "the held-out run" if self.held_out is not None else "the fitting run",
        )
        captions = {
            "residuals": "Residual per axis over time on the fitting run, with the noise floor.",
            "binned": "Residual binned by velocity sign, gravity load, workspace region.",
            "acf": "Autocorrelation of the prewhitened residual, 99 % band.",
            "xcorr": "Cross-correlation with the physical signatures, 99 % band.",
            "overlay": "Held-out run: residual of the original model, with the named effects"
            + (", after re-identification." if reidentified else " (not re-identified)."),
            "gaps": "Residual RMS per axis on the held-out run beside the noise floor.",
        }
        md = [
            "# Discrepancy report",
            "",
            f"**Verdict:** {self.verdict}",
            "",
            "```",
            self.table(),
            "```",
            "",
        ]
        for key, path in files.items():
            md += [f"## {key}", "", captions[key], "", f"![{key}]({path.name})", ""]
        (out / "report.md").write_text("\n".join(md), encoding="utf-8")
        return [out / "report.md", *files.values()]


def _binning(signatures: Mapping[str, F64]) -> dict[str, F64]:
    """The signatures the residual is binned by: velocity sign, gravity load, workspace region
    (those present; else whatever was given, at most three)."""
    keys = [k for k in ("velocity sign", "gravity load", "workspace radius") if k in signatures]
    keys = keys or list(signatures)[:3]
    return {k: np.asarray(signatures[k], dtype=np.float64) for k in keys}


def from_detection(
    detection: Detection,
    *,
    signatures: Mapping[str, ArrayLike] | None = None,
    held_out: HeldOut | None = None,
    model: Any = None,
) -> DiscrepancyReport:
    """The report of a run tested by :func:`~rss6.discrepancy.detect.detect` with no effect
    library searched: nothing named; "no missing effect" if nothing was detected, else an
    unexplained discrepancy with its signature. Gaps are on ``held_out`` if given (else on the
    fitting run); the named/after gaps equal the original's (no change was made)."""
    r = held_out.before if held_out is not None else detection.residual
    gap = _rms(r)
    sig = {k: np.asarray(v, dtype=np.float64) for k, v in (signatures or {}).items()}
    return DiscrepancyReport(
        detected=detection,
        named=[],
        ambiguous=[],
        unexplained=unexplained(detection),
        gap_before=gap,
        gap_named=gap.copy(),
        gap_after=gap.copy(),
        noise_floor=detection.noise.sigma.copy(),
        model=model,
        held_out=held_out,
        signatures=sig,
    )


def ambiguities(
    names: Sequence[str],
    corr: ArrayLike,
    among: Sequence[str],
    columns: Mapping[str, ArrayLike],
    *,
    sigma: ArrayLike | None = None,
    nuisance: ArrayLike | None = None,
    describe: Callable[[int], str] | None = None,
    threshold: float = AMBIGUOUS,
) -> list[Ambiguity]:
    """The ambiguous sets among the candidates ``among`` (:func:`stats.ambiguous_groups`), each with
    the largest |ρ| inside it (the Fisher correlations ``corr`` of ``names``) and where the first two
    differ most (their ``columns``, weighted and with the ``nuisance`` columns projected out as in
    :func:`stats.score_test`): ``describe(index)`` names a residual element (e.g. "axis z near
    t = 4.2 s"); by default its index."""
    c = np.abs(np.asarray(corr, dtype=np.float64))
    if c.shape != (len(names), len(names)):
        raise ShapeError(f"corr must be ({len(names)}, {len(names)}) like names; got {c.shape}")
    out = []
    for group in stats.ambiguous_groups(names, c, among, threshold):
        idx = [list(names).index(g) for g in group]
        rho = max(c[i, j] for i in idx for j in idx if i != j)
        diff = stats.separation(
            columns[group[0]], columns[group[1]], sigma=sigma, nuisance=nuisance
        )
        where = int(np.argmax(np.abs(diff)))
        label = describe(where) if describe is not None else f"residual element {where}"
        out.append(
            Ambiguity(group, float(rho), f"excite where their signatures differ most: {label}")
        )
    return out
