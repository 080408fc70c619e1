#!/usr/bin/env bash
# Installs everything rss6 needs on a fresh machine of this kind (Debian + Rust toolchain + CPython):
# the Python packages the analysts' module and its tests use, then the rss6 package itself from this
# checkout (maturin builds the Rust extension). Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
python3 -m pip install --quiet --upgrade pip >/dev/null 2>&1 || true
python3 -m pip install --quiet -r python/requirements-dev.txt
python3 -m pip install --quiet .
