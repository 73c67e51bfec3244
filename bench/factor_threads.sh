#!/usr/bin/env bash
# The factorization's OpenBLAS threads on a busy machine (issue 28, item 4; docs/design/parallel.md,
# "CHOLMOD's BLAS threads under load"): thorax forward on a model, thorax's choice (as many BLAS
# threads as cores are free when the factorization starts) against the former fixed count
# (THORAX_FACTOR_THREADS=$(nproc)), runs alternated in pairs, first on the machine as it is, then
# with BUSY loops of other processes beside (two on this 2-core machine: load about 2 more). Prints
# the medians of the whole run's wall time and of the factorization (thorax forward -v), and the
# ratio ours / fixed. Never fails on time.
#   MODEL=DIR BEAT=FILE   the model and the epicardial series (required)
#   RUNS=N                pairs (default 3); BUSY=N busy loops (default: the cores)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
: "${MODEL:?MODEL=DIR (a meshed model)}" "${BEAT:?BEAT=FILE (epicardial potentials)}"
RUNS=${RUNS:-3}
BUSY=${BUSY:-$(nproc)}
W=$(mktemp -d)
PIDS=()
trap 'kill "${PIDS[@]}" 2> /dev/null || true; rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
# one run: wall seconds and the factorization's seconds and threads, appended to FILE
run() {
    local file=$1
    shift
    rm -rf "$W/out"
    local t0 t1
    t0=$(date +%s.%N)
    env "$@" "$THORAX" forward "$MODEL" --epicardial "$BEAT" -o "$W/out" -v > "$W/log" 2>&1
    t1=$(date +%s.%N)
    local f
    f=$(grep -o 'factorization [0-9.]* s ([^)]*)' "$W/log" | head -1)
    echo "$(echo "$t1 - $t0" | bc) $(echo "$f" | awk '{print $2}') $(echo "$f" | grep -o '[0-9]* BLAS thread' | awk '{print $1}')" >> "$file"
}
phase() {
    local name=$1
    : > "$W/ours" && : > "$W/fixed"
    for _ in $(seq "$RUNS"); do
        run "$W/ours" THORAX_BENCH=1
        run "$W/fixed" THORAX_FACTOR_THREADS="$(nproc)"
    done
    /usr/bin/python3 - "$name" "$W/ours" "$W/fixed" <<'PY'
import sys, statistics as S
name, a, b = sys.argv[1], [l.split() for l in open(sys.argv[2])], [l.split() for l in open(sys.argv[3])]
med = lambda rows, k: S.median(float(r[k]) for r in rows)
print('%-28s ours: wall %6.2f s, factorization %6.2f s (%s BLAS threads) | fixed: wall %6.2f s, factorization %6.2f s (%s) | ours/fixed wall %.2f' % (
    name, med(a, 0), med(a, 1), '/'.join(sorted({r[2] for r in a})), med(b, 0), med(b, 1), '/'.join(sorted({r[2] for r in b})),
    S.median(float(x[0]) / float(y[0]) for x, y in zip(a, b))))
PY
}
phase "as the machine is"
for _ in $(seq "$BUSY"); do sh -c 'while :; do :; done' & PIDS+=($!); done
sleep 1
phase "with $BUSY busy loops beside"
