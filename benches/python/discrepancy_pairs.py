"""Which candidates of the discrepancy library the excitation confounds: every effect × scope's
signature at its null value on the benchmark's fitting run (no hidden effect), whitened with the
noise the workflow learns, and for every pair the largest canonical correlation of their columns
(for one-parameter candidates, their |ρ| in the Fisher information; the workflow's ambiguity
uses the fitted direction's mimicry, which this bounds from above). Prints the pairs above
``--show`` on any excitation, with their value per excitation.

    python benches/python/discrepancy_pairs.py [--robot twin|plant] [--commands recorded|simulated]
        [--seeds 0 1 2] [--harmonics 5] [--show 0.8]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from rss6.discrepancy._steps import _calibrate, _named_run, _Part, _screen_all, _Sim
from rss6.discrepancy.benchmark import hidden_case
from rss6.discrepancy.effects import candidates


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--robot", choices=("twin", "plant"), default="twin")
    ap.add_argument("--commands", choices=("recorded", "simulated"), default="recorded")
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--harmonics", type=int, default=5)
    ap.add_argument("--show", type=float, default=0.8)
    args = ap.parse_args()
    found: dict[tuple[str, str], list[float]] = {}
    for seed in args.seeds:
        t0 = time.perf_counter()
        spec = {
            "seed": seed,
            "robot": args.robot,
            "commands": args.commands,
            "harmonics": args.harmonics,
        }
        case = hidden_case(spec)
        run = _named_run("measured", case.fit, case.model, args.commands)
        part = _Part(run, slice(0, len(run.t)))
        sim = _Sim(2)
        try:
            (clean,) = _calibrate([part], case.model, 16, sim, 7)
            cal = part.calibration
            assert cal is not None
            rw = cal.whitener.vec(part.measured - clean[part.rows])
            screens = _screen_all(candidates(None), case.model, part, clean, rw, cal, sim, None, 0)
        finally:
            sim.close()
        bases = [np.linalg.qr(s.columns)[0] for s in screens]
        labels = [f"{s.effect.name} ({s.scope})" for s in screens]
        for a in range(len(bases)):
            for b in range(a + 1, len(bases)):
                cc = float(np.linalg.svd(bases[a].T @ bases[b], compute_uv=False)[0])
                found.setdefault((labels[a], labels[b]), []).append(cc)
        print(f"excitation of seed {seed}: {time.perf_counter() - t0:.0f} s", flush=True)
    rows = sorted(found.items(), key=lambda kv: -max(kv[1]))
    print(
        f"\n{args.robot}, {args.commands} commands, {args.harmonics} harmonics: pairs whose "
        f"canonical correlation exceeds {args.show:g} on some excitation (seeds "
        f"{' '.join(map(str, args.seeds))})"
    )
    for (a, b), v in rows:
        if max(v) < args.show:
            break
        flag = "  confounded on every excitation" if min(v) > 0.9 else ""
        print(f"  {a:32s} {b:32s} " + " ".join(f"{x:.3f}" for x in v) + flag)


if __name__ == "__main__":
    main()
