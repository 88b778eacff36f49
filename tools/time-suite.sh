#!/bin/sh
# The test suite as CI and a new user see it: a fresh clone of HEAD, its own .venv (`make setup`,
# timed apart), an empty drjit kernel cache, then `make test`, whose wall time it prints.
# Usage: sh tools/time-suite.sh [PYTEST_ARGS]
set -eu
root=$(cd "$(dirname "$0")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
git clone -q "$root" "$work/clone"
cd "$work/clone"
start=$(date +%s)
make setup >/dev/null
echo "time-suite: make setup: $(( $(date +%s) - start )) s"
start=$(date +%s)
status=0
DRJIT_CACHE_DIR="$work/kernels" MI_BRDFS_NO_PROGRESS=1 make test PYTEST_ARGS="${1:-}" || status=$?
echo "time-suite: make test on a fresh clone, empty kernel cache: $(( $(date +%s) - start )) s (exit $status)"
exit $status
