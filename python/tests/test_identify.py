"""Exciting trajectories (thesis §5.4): rest at both ends, feasibility, seeded optimisation."""

from __future__ import annotations

import numpy as np
import pytest
import rss6
from rss6 import identify


@pytest.fixture(scope="module")
def kp() -> rss6.KinematicParams:
    return rss6.KinematicParams.nominal()


def test_an_optimised_excitation_is_feasible_at_rest_and_repeatable(
    kp: rss6.KinematicParams,
) -> None:
    seen: list[tuple[int, float]] = []
    a = identify.excitation(
        kp, maxiter=4, popsize=5, seed=3, progress=lambda g, o: seen.append((g, o))
    )
    b = identify.excitation(kp, maxiter=4, popsize=5, seed=3)
    assert np.array_equal(a.coefficients, b.coefficients)  # seeded
    assert a.coefficients.shape == (6, 11) and a.duration == pytest.approx(10.0)
    assert len(seen) == 4 and all(o > 0 for _, o in seen)
    # O_in never gets worse from one generation's best to the next (DE keeps the best).
    assert all(o2 >= o1 for (_, o1), (_, o2) in zip(seen, seen[1:]))
    for t in (0.0, a.duration):
        pose, rate, acc = a.sample(t)
        assert np.allclose(pose, rss6.home_pose(), atol=1e-12)
        assert np.abs(rate).max() < 1e-12 and np.abs(acc).max() < 1e-12
    assert (
        len(a.columns) == 31
    )  # identifiable columns of Ξ with vertical gravity (docs/dynamics.md)
    assert a.observability > 0 and a.condition >= 1


def test_an_infeasible_trajectory_is_refused_with_its_constraint_and_time(
    kp: rss6.KinematicParams,
) -> None:
    c = np.zeros((6, 11))
    c[:, -1] = rss6.home_pose()
    c[3, 0] = 2.0  # α̇ amplitude of 2 rad/s: far past the joint-rate limit
    with pytest.raises(rss6.IdentificationError, match=r"violated at t = \d"):
        identify.Excitation.from_coefficients(kp, c, 0.1)
    c[3, 0] = 0.0
    still = identify.Excitation.from_coefficients(kp, c, 0.1)
    assert still.coefficients.shape == (6, 11)
    with pytest.raises(rss6.InvalidInputError):
        identify.Excitation.from_coefficients(kp, np.zeros((5, 11)), 0.1)
