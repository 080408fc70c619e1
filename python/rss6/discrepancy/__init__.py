"""Discrepancy workflow (issue 14), the statistical core: detect where a residual disagrees with
the noise, test candidates at their null value, report."""

from __future__ import annotations

from rss6.discrepancy import stats
from rss6.discrepancy.detect import (
    AXES,
    Detection,
    TestRow,
    Window,
    detect,
    reference_signatures,
)
from rss6.discrepancy.noise import NoiseModel, noise_from_differences, noise_from_periods

__all__ = [
    "AXES",
    "Detection",
    "NoiseModel",
    "TestRow",
    "Window",
    "detect",
    "noise_from_differences",
    "noise_from_periods",
    "reference_signatures",
    "stats",
]
