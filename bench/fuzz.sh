#!/usr/bin/env bash
# Long fuzzing campaigns: every harness (or those named) for FUZZ_TIME seconds each (default 600),
# printing executions, exec/s, coverage (edges), corpus size and findings per target. Findings
# are kept in FUZZ_OUT (default bench-fuzz-findings.XXXXXX under /tmp, printed at the end).
# Usage: bash bench/fuzz.sh [TARGET...]
set -euo pipefail
cd "$(dirname "$0")/.."
export FUZZ_TIME=${FUZZ_TIME:-600}
export FUZZ_OUT=${FUZZ_OUT:-$(mktemp -d "${TMPDIR:-/tmp}/bench-fuzz-findings.XXXXXX")}
echo "bench/fuzz.sh: $FUZZ_TIME s per target, findings kept in $FUZZ_OUT"
rc=0
bash scripts/fuzz.sh "$@" || rc=$?
echo "bench/fuzz.sh: findings folder $FUZZ_OUT"
exit $rc
