"""How far a hidden backlash moves the plant's stick–slip loop bias (issue 14, docs/discrepancy.md
"The refreshed bias iterated").

    python benches/python/refresh_bias_shift.py [--seeds 0 1] [--magnitude 1] [--model-error]

For the benchmark's backlash case on the rapier plant (implicit friction law; the model as the
truth, or with ``--model-error`` drawn from its prior), on the validation run as the workflow
replays it (recorded commands, the benchmark's 16 replicates and seeds): the RMS over the run of
the change of the mean noisy replay's bias from the model as given to the model with the backlash
at its hidden width, per pose axis in units of the loop's noise floor; and the same for the mesh
alone (width 0). The workflow's default takes the bias once, for the model as given; the opt-in
refresh takes it at the candidate.
"""

from __future__ import annotations

import argparse

import numpy as np
from rss6.discrepancy import benchmark as bm
from rss6.discrepancy._refresh import loop_bias
from rss6.discrepancy._steps import _calibrate, _named_run, _Part, _Sim
from rss6.discrepancy.model import AppliedEffect


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1])
    ap.add_argument("--magnitude", type=float, default=1.0)
    ap.add_argument("--model-error", action="store_true")
    args = ap.parse_args()
    k = 16  # the benchmark's replicates
    print("bias change / loop noise floor, RMS over the validation run (x y z α β γ)")
    for seed in args.seeds:
        spec = {
            "robot": "plant",
            "friction_law": "implicit",
            "effect": "backlash",
            "magnitude": args.magnitude,
            "seed": seed,
        }
        if args.model_error:
            spec["model_error"] = "prior"
        case = bm.hidden_case(spec)
        model = case.model
        run = _named_run("validation", case.validation, model, "recorded")
        held = _Part(run, slice(0, len(run.t)))
        sim = _Sim(2)
        try:
            _calibrate([held], model, k, sim, 7919 + seed)
            assert held.calibration is not None
            if held.bias is None:
                print(f"seed {seed}: the replays' mean is not away from the clean replay (no bias)")
                continue
            sigma = held.calibration.noise.sigma[:6]
            width = case.params["backlash"]["width"]
            for label, w in (
                ("mesh alone (width 0)", 0.0),
                (f"width {1e3 * width:.3f} mrad", width),
            ):
                m = model.with_effects(
                    [*model.applied(), AppliedEffect("backlash", "all joints", {"width": w})]
                )
                b = loop_bias(m, held, k, sim, 7919 + seed)
                d = (b - held.bias)[held.rows][:, :6]
                rms = np.sqrt(np.mean(d * d, axis=0)) / sigma
                print(f"seed {seed}, {label}: " + " ".join(f"{v:.2f}" for v in rms), flush=True)
        finally:
            sim.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
