"""Bad input refused where it is given, naming what is wrong (docs/architecture.md, "Checking
input"): options that used to be clipped or ignored silently, or to end as an IndexError, an
OverflowError or a TypeError deep inside a call. The checks of each module's own objects stay in
that module's tests; these are the free functions' options."""

from __future__ import annotations

import numpy as np
import pytest
import rss6
from rss6 import discrepancy, identify

SIGMA = 1e-5  # Table 4.1-like pose noise (m)


@pytest.mark.parametrize(
    ("kw", "match"),
    [
        ({"harmonics": -1}, "harmonics must be >= 2, got -1"),
        ({"harmonics": 2.5}, "harmonics must be an int, got 2.5"),
        ({"seed": -1}, r"seed must be in \[0, 2\*\*32 - 1\], got -1"),
        ({"stroke_margn": 0.2}, "unknown limit.*stroke_margn; known: start, stroke, stroke_margin"),
    ],
)
def test_excitation_options_are_checked_before_the_search(
    kw: dict[str, object], match: str
) -> None:
    """A negative harmonics count or seed used to end as an OverflowError or a numpy ValueError,
    a misspelt limit as a TypeError from the binding's constructor."""
    for design in (identify.excitation, identify.random_excitation):
        with pytest.raises(rss6.InvalidInputError, match=match):
            design(rss6.KinematicParams.nominal(), **kw)


def test_detect_refuses_options_it_would_otherwise_bend() -> None:
    """A zero window or negative lag used to be clipped silently, zero Ljung–Box lags and a noise
    floor of the wrong length ended as numpy's IndexError or broadcast ValueError, a correlation
    matrix of the wrong size gave "nothing ambiguous"."""
    t = np.arange(900) / 30.0  # a 30 s run at 30 Hz
    ref = np.column_stack([0.01 * np.sin(2 * np.pi * 0.1 * t + k) for k in range(6)])
    sig = discrepancy.reference_signatures(t, ref)
    r = np.random.default_rng(3).standard_normal((900, 6)) * SIGMA
    for kw, match in (
        ({"window": 0.0}, "window must be finite and > 0"),
        ({"max_lag": -0.1}, "max_lag finite and >= 0"),
        ({"lb_lags": 0}, "lb_lags must be an int >= 1"),
    ):
        with pytest.raises(rss6.InvalidInputError, match=match):
            discrepancy.detect(t, r, sig, noise_floor=SIGMA, **kw)
    with pytest.raises(rss6.ShapeError, match=r"noise_floor must be one σ or one per axis"):
        discrepancy.detect(t, r, sig, noise_floor=np.full(3, SIGMA))
    assert not discrepancy.detect(t, r, sig, noise_floor=np.full(6, SIGMA)).detected
    with pytest.raises(rss6.ShapeError, match=r"corr must be \(2, 2\)"):
        discrepancy.ambiguities(["a", "b"], np.eye(3), ["a", "b"], {})
    with pytest.raises(rss6.InvalidInputError, match="needs an identification result"):
        discrepancy.nominal_from(None)
