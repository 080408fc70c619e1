#!/usr/bin/env bash
# Runs every criterion bench target in benches/ (short measurement times) and prints a Markdown table
# of medians, then the mean FK iteration counts of both FK methods on the same pose sets and the time
# per call of the kinematic hot paths in short rounds (criterion's long samples absorb other processes'
# time slices on a loaded machine; short rounds mostly run undisturbed).
#
#   scripts/bench.sh                 # all benches
#   scripts/bench.sh kinematics/fk   # only benchmarks whose id matches the criterion filter
#
# Environment: BENCH_WARM_UP (s, default 1), BENCH_MEASUREMENT (s, default 2).
# A new bench file only needs its `[[bench]] name = ... harness = false` entry in benches/Cargo.toml;
# a speed target is added as one line in TARGETS_NS below (criterion id → median bound in ns).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never

WARM_UP=${BENCH_WARM_UP:-1}
MEASUREMENT=${BENCH_MEASUREMENT:-2}
TARGET_DIR=$(cargo metadata --format-version 1 --no-deps | python3 -c 'import json,sys; print(json.load(sys.stdin)["target_directory"])')
CRITERION_DIR="$TARGET_DIR/criterion"

# Speed targets (median, ns); benchmarks without an entry are reported without a verdict.
TARGETS_NS='
kinematics/ik 300
kinematics/fk_warm 1000
kinematics/fk_cold 3000
dynamics/inverse_dynamics 2000
plant_tick_4_iterations 50000
control/camera_step 5000
'

mkdir -p "$CRITERION_DIR"
MARKER="$CRITERION_DIR/.bench-sh-start"
touch "$MARKER"
sleep 1 # file times have 1 s resolution on some filesystems

# --bench '*': every bench target, not the lib's libtest harness (it would reject criterion's flags).
cargo bench -p rss6-benches --bench '*' -- --warm-up-time "$WARM_UP" --measurement-time "$MEASUREMENT" \
    --noplot "$@" >&2

echo
echo "Medians (criterion, warm-up ${WARM_UP} s, measurement ${MEASUREMENT} s; $(nproc) cores, $(uname -m);"
echo "load average $(cut -d' ' -f1-3 /proc/loadavg) — wall-clock medians grow with other load):"
echo
find "$CRITERION_DIR" -path '*/new/estimates.json' -newer "$MARKER" -print0 | sort -z |
    TARGETS_NS="$TARGETS_NS" python3 -c '
import json, os, sys
targets = {}
for line in os.environ["TARGETS_NS"].strip().splitlines():
    name, bound = line.split()
    targets[name] = float(bound)
def fmt(ns):
    return f"{ns / 1000:.3f} µs" if ns >= 1000 else f"{ns:.1f} ns"
rows = []
for path in sys.stdin.read().split("\0"):
    if not path:
        continue
    with open(path) as f:
        est = json.load(f)
    with open(os.path.join(os.path.dirname(path), "benchmark.json")) as f:
        bid = json.load(f)["full_id"]
    med = est["median"]
    ci = med["confidence_interval"]
    verdict = ""
    if bid in targets:
        ok = med["point_estimate"] <= targets[bid]
        verdict = ("meets" if ok else "MISSES") + " ≤ " + fmt(targets[bid])
    lo, hi = fmt(ci["lower_bound"]), fmt(ci["upper_bound"])
    rows.append((bid, fmt(med["point_estimate"]), lo + " – " + hi, verdict))
print("| benchmark | median | 95 % CI of median | target |")
print("|---|---|---|---|")
for r in sorted(rows):
    print("| " + " | ".join(r) + " |")
if not rows:
    print("| (no benchmark ran) | | | |")
'

echo
echo "FK iteration counts (same pose sets for both methods):"
echo
cargo run --release -q -p rss6-benches --example fk_iterations

echo
echo "Time per call of the kinematic hot paths in short rounds (median and fastest of 400 rounds of 256"
echo "calls; a round is shorter than a scheduler time slice, so this is robust to other load):"
echo
cargo run --release -q -p rss6-benches --example kin_cpu
