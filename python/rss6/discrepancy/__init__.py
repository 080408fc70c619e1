"""Discrepancy workflow (issue 14): where and why a model disagrees with the robot.

Built so far — the statistical core, the data model and the report (docs/discrepancy.md):

* :mod:`~rss6.discrepancy.noise` — the noise model (σ and AR colour per axis; given, from repeated
  periods or runs, or from first differences);
* :mod:`~rss6.discrepancy.stats` — energy, window, whiteness and cross-correlation tests, Holm,
  parametric bootstrap, score test, Fisher correlation and ambiguity, confidence intervals;
* :func:`detect` — the Detect step on a residual, however it was simulated;
* :mod:`~rss6.discrepancy.report` — :class:`DiscrepancyReport` (``.table()``, ``.save(dir)``),
  :class:`NamedEffect`, :func:`from_detection`.

and the workflow itself:

* :mod:`~rss6.discrepancy.effects` — the effect library, one file per effect (:data:`CANDIDATES`);
* :mod:`~rss6.discrepancy.model` — :class:`Model` (with its effects, saved as TOML),
  :class:`Run`, :func:`replay` (the model twin in the run's closed loop);
* :mod:`~rss6.discrepancy.nominal` — the model's friction and drive gains refitted inside its
  uncertainty (:data:`NOMINAL_SPREAD`) before the search and after each named effect;
* :func:`diagnose` — detect, name, add, show the gap shrink on a held-out run
  (:mod:`~rss6.discrepancy.diagnose`, numerics in :mod:`~rss6.discrepancy.search`).
"""

from __future__ import annotations

from rss6.discrepancy import stats
from rss6.discrepancy.benchmark import benchmark_case
from rss6.discrepancy.detect import (
    AXES,
    Detection,
    TestRow,
    Window,
    detect,
    reference_signatures,
)
from rss6.discrepancy.diagnose import diagnose
from rss6.discrepancy.effects import CANDIDATES, EFFECTS
from rss6.discrepancy.model import AppliedEffect, Model, Run, replay, run_of
from rss6.discrepancy.noise import (
    NoiseModel,
    noise_from_differences,
    noise_from_periods,
    noise_from_repeats,
)
from rss6.discrepancy.nominal import NOMINAL_NAMES, NOMINAL_SPREAD, nominal_from
from rss6.discrepancy.report import (
    AMBIGUOUS,
    NEARLY_AMBIGUOUS,
    Ambiguity,
    CandidateRow,
    DiscrepancyReport,
    HeldOut,
    NamedEffect,
    Unexplained,
    ambiguities,
    from_detection,
    unexplained,
)

__all__ = [
    "AMBIGUOUS",
    "AXES",
    "CANDIDATES",
    "EFFECTS",
    "NEARLY_AMBIGUOUS",
    "NOMINAL_NAMES",
    "NOMINAL_SPREAD",
    "Ambiguity",
    "AppliedEffect",
    "CandidateRow",
    "Detection",
    "DiscrepancyReport",
    "HeldOut",
    "Model",
    "NamedEffect",
    "NoiseModel",
    "Run",
    "TestRow",
    "Unexplained",
    "Window",
    "ambiguities",
    "benchmark_case",
    "detect",
    "diagnose",
    "from_detection",
    "noise_from_differences",
    "noise_from_periods",
    "noise_from_repeats",
    "nominal_from",
    "reference_signatures",
    "replay",
    "run_of",
    "stats",
    "unexplained",
]
