#!/usr/bin/env bash
# The whole test suite, exactly as CI runs it (.ci/run calls this script).
set -euo pipefail
cd "$(dirname "$0")/.."
export CARGO_TERM_COLOR=never
# Each step says when it started (minutes into the run): where CI's time goes is in every log.
step() { printf '\n==> [%d:%02d] %s\n' $((SECONDS / 60)) $((SECONDS % 60)) "$*"; }

step "cargo fmt --all --check"
cargo fmt --all --check
step "cargo clippy --workspace --all-targets -- -D warnings"
cargo clippy --workspace --all-targets -- -D warnings
step "offline estimation builds without the physics engine (rss6-exp, rss6-sim without 'rapier')"
cargo check -p rss6-exp -p rss6-sim --no-default-features
step "cargo doc --no-deps (warnings are errors)"
RUSTDOCFLAGS="-D warnings" cargo doc --no-deps --workspace --exclude rss6-py
step "cargo test --workspace (rss6-py is tested through pytest below)"
cargo test --workspace --exclude rss6-py
step "install the Python package from this checkout"
bash scripts/setup.sh
step "ruff check python/rss6 python/tests"
python3 -m ruff check python/rss6 python/tests
step "mypy python/rss6 (settings in pyproject.toml)"
python3 -m mypy python/rss6
step "mypy stubtest rss6._rss6 (every runtime name must be in the stub)"
python3 -m mypy.stubtest rss6._rss6
step "pytest (pytest-xdist: one worker per core)"
python3 -m pytest python/tests -q -n auto --dist worksteal
step "done"
