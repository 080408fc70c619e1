"""CLOE weighted by the camera frames' noise covariance (``identify.cloe(noise="frames")``).

The simulated camera's pose noise is correlated between axes (x with β, y with α: |ρ| ≈ 0.9), which
Table 4.1's per-axis weights ignore. Whitened by the covariance of a first fit's residual, CLOE's
errors and σ shrink several times; on the model twin without potentiometer noise the σ still
describe the errors (docs/identification.md, "Weighting by the frames' covariance")."""

from __future__ import annotations

import re

import numpy as np
import pytest
import rss6
from rss6 import identify, identify_profile, identify_sim
from rss6.errors import InvalidInputError, ShapeError
from rss6.studies.tasks import quantities


@pytest.fixture(scope="module")
def clean_twin_run():
    """A 10 s thesis-size random excitation on the stick–slip twin, potentiometers without noise
    (the case where the camera is the only noise), and CLOE's settings for it."""
    kp = rss6.KinematicParams.nominal()
    dp_true, pid_true = identify.table_5_2_truth()
    robot = rss6.ModelSim(
        kp, dp_true, pid=pid_true, seed=0, implicit_friction=True, potentiometer_noise=0.0,
        drive_derivative_filter=identify_sim.DRIVE_DERIVATIVE_FILTER,
    )  # fmt: skip
    tr = robot.truth()
    exc = identify.random_excitation(kp, harmonics=5, f0=0.1, seed=0, amplitude=(0.001, 0.005))
    data = identify.collect(
        robot, exc, kp_model=kp, sensor_in_base=tr["sensor_in_base"],
        target_in_effector=tr["target_in_effector"],
    )  # fmt: skip
    guess, kw = identify_sim.cloe_settings(data, kp, lp=pid_true[0], pot_noise="none")
    return kp, data, guess, kw, quantities(dp_true, pid_true)


def test_whitening_by_the_frames_covariance_shrinks_the_errors_and_keeps_the_sigmas_honest(
    clean_twin_run,
):
    kp, data, guess, kw, truth = clean_twin_run
    per_axis = identify.cloe(data, kp, *guess, **kw)
    frames = identify.cloe(data, kp, *guess, **{**kw, "noise": "frames"})
    w = frames.linear_map[1]
    assert w.shape == (6, 6) and np.allclose(w, np.tril(w))
    cov = np.linalg.inv(w.T @ w)
    rho = cov[0, 4] / np.sqrt(cov[0, 0] * cov[4, 4])
    # The camera's x and β: ρ measured −0.88 on this run's residual.
    assert rho < -0.5, rho
    # The whitened output error is χ² with the residual's own covariance: reduced χ² measured
    # 0.85 (0.79–0.87 on four seeds), against 3.6 with Table 4.1's weights.
    assert 0.5 < frames.reduced_chi2 < 1.3, frames.reduced_chi2
    assert per_axis.reduced_chi2 > 2.0, per_axis.reduced_chi2
    names = [n for n in frames.identified if re.fullmatch(r"f[cv]\d|l[id]", n)]
    assert len(names) == 14, names  # f_c, f_v of six joints, l_i, l_d (l_p is held)
    q, q0 = quantities(frames.dynamics, frames.pid), quantities(per_axis.dynamics, per_axis.pid)
    ratio = np.median([frames.std(n) / per_axis.std(n) for n in names])
    err = np.sqrt(np.mean([np.log(q[n] / truth[n]) ** 2 for n in names]))
    err0 = np.sqrt(np.mean([np.log(q0[n] / truth[n]) ** 2 for n in names]))
    z = np.sqrt(np.mean([(np.log(q[n] / truth[n]) / frames.std(n)) ** 2 for n in names]))
    # Measured on this run: σ 0.21× the per-axis ones (median), RMS log error 0.020 against 0.064,
    # z RMS 0.66 (0.66–0.82 on four seeds, benches/python/frame_weighting.py; 0.81 per axis). Bounds: the gain must show (ratio < 0.5, error
    # smaller) and the σ must describe the errors (z RMS < 1.8, 3× the measured).
    assert ratio < 0.5, ratio
    assert err < err0, (err, err0)
    assert z < 1.8, z
    # Both passes are counted, and the residual is the second's.
    assert frames.iterations > per_axis.iterations
    assert frames.residual.shape == (len(data.t), 6)
    # The noisy replicates go through the whitened map.
    rep = identify.with_replicates(frames, data, n=4)
    assert np.all(np.isfinite(rep.relative_std_replicates))
    assert np.all(rep.relative_std_replicates > 0)


def test_a_profile_of_a_whitened_fit_keeps_the_fits_covariance(clean_twin_run):
    """Each profile point is weighted by the fit's own frame covariance (a second estimate per
    point would change Φ's scale between points): the refit at the estimate reproduces Φ."""
    kp, data, guess, kw = clean_twin_run[:4]
    kw = {**kw, "noise": "frames"}
    fit = identify.cloe(data, kp, *guess, **kw)
    p = identify_profile.profile(data, kp, *guess, fit, "li", **kw)
    assert p.bounded() and p.interval[0] < p.estimate < p.interval[1]
    assert abs(p.delta[list(p.offsets).index(0.0)]) < 0.1


def test_a_noise_option_cloe_cannot_use_is_refused(clean_twin_run):
    kp, data, guess, kw = clean_twin_run[:4]
    with pytest.raises(InvalidInputError, match="'frames'"):
        identify.cloe(data, kp, *guess, **{**kw, "noise": "frame"})
    with pytest.raises(ShapeError, match=r"\(6, 6\)"):
        identify.cloe(data, kp, *guess, **{**kw, "noise": (1e-5, 1e-4, 1.0)})
    with pytest.raises(InvalidInputError, match="positive definite"):
        identify.cloe(data, kp, *guess, **{**kw, "noise": -np.eye(6)})
