"""Fixtures shared by the discrepancy tests (the model twin as the robot: ``twin_case``)."""

from __future__ import annotations

from typing import Any

import pytest
from rss6 import identify
from twin_case import KP


@pytest.fixture(scope="module")
def truth() -> tuple[Any, tuple[float, float, float]]:
    """Table 5.2's truth: (dynamics, drive gains)."""
    return identify.table_5_2_truth()


@pytest.fixture(scope="module")
def excitation() -> identify.Excitation:
    """The random excitation the discrepancy tests run (seed 1)."""
    return identify.random_excitation(KP, seed=1)
