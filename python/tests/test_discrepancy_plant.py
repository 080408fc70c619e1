"""The discrepancy workflow's Name step where the model is not the robot (issue 14): the rapier plant
with the shared stick–slip law hides an effect at 5× the camera noise, and the model — the plant's
truth without the effect — differs from the plant by 0.1–0.6× the noise even with the effect added
(the plant's 48 constraint iterations — what a spec without "solver_iterations" gets; the
benchmark's grid and `rss6 diagnose --simulate` run at 100 since the twenty-ninth session;
docs/discrepancy.md, "The model is not the robot"). And an
out-of-library camera drift on the twin, which a joint's offset drift can mimic on x only.

Measured (seed 0, recorded commands, 16 replicates, the loop's bias refreshed at each candidate —
diagnose's default since the twenty-sixth session; 100–141 s a case on one thread, the grid's
`--null 0 --seeds 0 --magnitudes 2 5`): base tilt (0.3, 0.3) rad → (0.273, 0.300), pitch on its
bound (0.258 without the refresh; the one-step start had fitted (0.09, −0.24)); friction on joint 3
(1.839 N·m, 9.193 N·m·s/rad) → (1.809, 9.418) (1.774, 9.334 without); a 13.3 kg payload → 13.7 kg
at (0.014, −0.007, 0.006) m for (0.02, 0, 0) (14.0 kg at (0.011, −0.008, −0.001) without), from the
mass scan's start; camera drift at 5× (the twin) → "unexplained", the offset drift of joint 5
refused for making z worse."""

from __future__ import annotations

import json

import pytest
import rss6
from rss6.discrepancy import benchmark

pytestmark = pytest.mark.skipif(not hasattr(rss6, "Plant"), reason="built without the rapier plant")

PLANT = {"robot": "plant", "friction_law": "implicit", "magnitude": 5.0, "seed": 0}


def test_a_large_base_tilt_on_the_plant_is_fitted_from_a_global_start() -> None:
    rec = benchmark.benchmark_case({**PLANT, "effect": "base_tilt"})
    assert rec["first_right"], rec["verdict"] + " | " + rec["notes"]
    # The truth (0.3, 0.3) rad is on the tilt's bounds and the plant's data want more pitch: a
    # payload that overlaps the clipped tilt (canonical correlation 0.83) is not named beside it.
    assert rec["named"] == "base_tilt (base)", rec["notes"]
    assert "it would take up what that bound stops" in rec["notes"], rec["notes"]
    truth, est, ci = (json.loads(rec[k]) for k in ("truth", "estimate", "ci"))
    # The global start's minimum, not the wrong one at (0.14, −0.02): measured roll 0.273 (pitch
    # on its bound; 0.258 without the refreshed bias), bound ≈ 3× its error. With the payload
    # beside it (before the twenty-third session) the roll was 0.298: the payload took up the
    # plant's error the clipped pitch leaves.
    for k in ("roll", "pitch"):
        assert abs(est[k] - truth[k]) <= 0.08, (k, est, truth)
        assert ci[k][0] <= truth[k] <= ci[k][1], (k, ci, truth)


def test_model_error_on_the_plant_does_not_refuse_the_true_friction() -> None:
    rec = benchmark.benchmark_case({**PLANT, "effect": "joint_friction@joint 3"})
    assert rec["named"] == "joint_friction (joint 3)", rec["verdict"] + " | " + rec["notes"]
    # The two runs' estimates agree within the errors their intervals state (robust covariances):
    # no note of a difference. Against the noise replicates alone the held-out refit differed
    # (T² 33, p = 2e-4), and until the twenty-second session the friction was refused for it.
    assert "differs beyond" not in rec["notes"], rec["notes"]
    truth, est = json.loads(rec["truth"]), json.loads(rec["estimate"])
    # Measured relative error ≤ 2.5 % (≤ 3.6 % without the refreshed bias); bound ≈ 3×.
    for k in ("coulomb", "viscous"):
        assert abs(est[k] - truth[k]) <= 0.075 * abs(truth[k]), (k, est, truth)


def test_a_heavy_payload_on_the_plant_is_fitted_from_the_mass_scan() -> None:
    # 12.9 kg at 2 cm along x: the score test's one-step mass is 0.51 kg (stick–slip hides a small
    # load), and from it and the Sobol starts the fit ended on the COM bounds (cost 43 678 against
    # the base tilt's 22 163: "unexplained"). The payload's mass scan starts it at 16 kg: cost 3 772.
    rec = benchmark.benchmark_case({**PLANT, "effect": "payload"})
    assert rec["first_right"], rec["verdict"] + " | " + rec["notes"]
    truth, est = json.loads(rec["truth"]), json.loads(rec["estimate"])
    # Measured: mass +2.9 %, COM x 0.014 m for 0.02, |y|, |z| ≤ 0.0075 m (+5.2 %, 0.011, 0.009
    # without the refreshed bias); bounds ≈ 3×.
    assert abs(est["mass"] - truth["mass"]) <= 0.09 * truth["mass"], (est, truth)
    for k in ("x", "y", "z"):
        assert abs(est[k] - truth[k]) <= 0.022, (k, est, truth)


def test_a_camera_drift_is_not_named_a_joint_offset_drift() -> None:
    rec = benchmark.benchmark_case({"effect": "camera_drift", "magnitude": 5.0, "seed": 0})
    assert rec["named"] == "none", rec["verdict"]
    assert rec["unexplained"], rec["verdict"]
    assert "worse by" in rec["notes"] and "mimics something outside the library" in rec["notes"]


def test_a_start_the_model_cannot_run_is_no_start() -> None:
    # No effect on the plant (seed 10054 of the full grid): a Sobol start of the global stage drove
    # the model's legs out of reach, and its UnreachableError ended the study task. Such a start
    # now scores as infinitely bad and the workflow goes on.
    rec = benchmark.benchmark_case({**PLANT, "effect": None, "seed": 10_054})
    assert rec["verdict"] == "no missing effect", rec["verdict"] + " | " + rec["notes"]
