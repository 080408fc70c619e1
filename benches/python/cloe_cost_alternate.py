"""Issue 13's "Jacobian ≤ 3× one simulation" figure for two or more builds, run alternately so the
machine's drift hits each alike: each round runs every build's `cloe_cost` example once
(`10 --implicit --per-tick-only --repeat R`) and reads its simulation and exact-Jacobian times
(medians of R). Prints, per build, the fastest and the median simulation and exact Jacobian over
the rounds and the ratio of the fastest exact run to the fastest simulation.

Build the binaries first, e.g. at two commits::

    cargo build --release -p rss6-ident --example cloe_cost
    cp target/release/examples/cloe_cost /tmp/cloe_cost_new   # and /tmp/cloe_cost_old at the other

    python benches/python/cloe_cost_alternate.py /tmp/cloe_cost_new /tmp/cloe_cost_old --rounds 8

Run on an idle machine: another job on the two cores inflates the simulation and the Jacobian
differently, so the ratio moves with the load.
"""

from __future__ import annotations

import argparse
import re
import statistics
import subprocess

LINE = re.compile(r"simulation ([0-9.]+) s;.*exact ones from a recording ([0-9.]+) s")


def one_run(binary: str, repeat: int) -> tuple[float, float]:
    """(simulation, exact Jacobian) seconds of one `--per-tick-only` run of `binary`."""
    out = subprocess.run(
        [binary, "10", "--implicit", "--per-tick-only", "--repeat", str(repeat)],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    m = LINE.search(out)
    if m is None:
        raise SystemExit(f"{binary}: unexpected output {out!r}")
    return float(m.group(1)), float(m.group(2))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("binaries", nargs="+", help="cloe_cost example binaries")
    ap.add_argument("--rounds", type=int, default=8)
    ap.add_argument("--repeat", type=int, default=3, help="cloe_cost's --repeat")
    args = ap.parse_args()
    if args.rounds < 1 or args.repeat < 1:
        raise SystemExit("--rounds and --repeat must be at least 1")
    sims: dict[str, list[float]] = {b: [] for b in args.binaries}
    exact: dict[str, list[float]] = {b: [] for b in args.binaries}
    for r in range(args.rounds):
        for b in args.binaries:
            t_sim, t_exact = one_run(b, args.repeat)
            sims[b].append(t_sim)
            exact[b].append(t_exact)
        print(f"round {r + 1}/{args.rounds} done", flush=True)
    for b in args.binaries:
        s, e = sims[b], exact[b]
        print(
            f"{b}: simulation min {min(s):.4f} median {statistics.median(s):.4f} s; "
            f"exact Jacobian min {min(e):.4f} median {statistics.median(e):.4f} s; "
            f"fastest exact / fastest simulation {min(e) / min(s):.2f}x"
        )


if __name__ == "__main__":
    main()
