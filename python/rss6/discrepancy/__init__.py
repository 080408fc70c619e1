"""Discrepancy workflow (issue 14): where and why a model disagrees with the robot.

Built so far — the statistical core, the data model and the report (docs/discrepancy.md):

* :mod:`~rss6.discrepancy.noise` — the noise model (σ and AR colour per axis; given, from repeated
  periods or runs, or from first differences);
* :mod:`~rss6.discrepancy.stats` — energy, window, whiteness and cross-correlation tests, Holm,
  parametric bootstrap, score test, Fisher correlation and ambiguity, confidence intervals;
* :func:`detect` — the Detect step on a residual, however it was simulated;
* :mod:`~rss6.discrepancy.report` — :class:`DiscrepancyReport` (``.table()``, ``.save(dir)``),
  :class:`NamedEffect`, :func:`from_detection`.

Not built: the effect library (``CANDIDATES``) and :func:`diagnose`, which replay the model in the
closed loop with effects — that simulation is to come from the Rust side. :func:`diagnose` raises
``NotImplementedError`` until then; :class:`Model` is the model description it will take.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from rss6.discrepancy import stats
from rss6.discrepancy.detect import (
    AXES,
    Detection,
    TestRow,
    Window,
    detect,
    reference_signatures,
)
from rss6.discrepancy.noise import (
    NoiseModel,
    noise_from_differences,
    noise_from_periods,
    noise_from_repeats,
)
from rss6.discrepancy.report import (
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
    "AXES",
    "Ambiguity",
    "CandidateRow",
    "Detection",
    "DiscrepancyReport",
    "HeldOut",
    "Model",
    "NamedEffect",
    "NoiseModel",
    "TestRow",
    "Unexplained",
    "Window",
    "ambiguities",
    "detect",
    "diagnose",
    "from_detection",
    "noise_from_differences",
    "noise_from_periods",
    "noise_from_repeats",
    "reference_signatures",
    "stats",
    "unexplained",
]


@dataclass(frozen=True)
class Model:
    """The model a discrepancy search replays in the closed loop (issue 14): kinematics
    (:class:`rss6.KinematicParams`), dynamics (:class:`rss6.DynamicParams`), the drive ``pid``
    gains, ᴼχ_C ``sensor_in_base`` and ᴱχ_t ``target_in_effector`` (6,), and the ``effects`` it
    already includes (names with parameters). A description only: nothing simulates it yet."""

    kinematics: Any
    dynamics: Any
    pid: Any
    sensor_in_base: Any
    target_in_effector: Any
    effects: Sequence[Any] = ()


def diagnose(
    measured: Any,
    model: Model,
    *,
    validation: Any = None,
    candidates: Sequence[Any] | None = None,
    alpha: float = 0.01,
    progress: Callable[..., Any] | None = None,
) -> DiscrepancyReport:
    """Not built yet: the full workflow needs the closed-loop simulation of ``model`` with effects
    (replay, residual Jacobians of every candidate, refits) from the Rust side. Use :func:`detect`
    on a residual you computed and :func:`from_detection` for its report."""
    raise NotImplementedError(
        "rss6.discrepancy.diagnose needs the closed-loop simulation with effects and the effect "
        "library (CANDIDATES), which are not built yet; detect() and from_detection() work on a "
        "residual you computed (docs/discrepancy.md)"
    )
