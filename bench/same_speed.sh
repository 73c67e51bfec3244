#!/usr/bin/env bash
# Did a change that should change nothing (a refactoring) move the speed? Counts the instructions
# (valgrind --tool=callgrind: the same count for the same program and input, whatever else the
# machine is doing) of REV's thorax and of this tree's, on the same inputs, side by side:
# phantom contours, surfaces, surface checks, the volume mesh and its check (medium phantom),
# slicing, a model read and export, a time-series conversion and the forward transfer of the
# 12 leads. Prints both counts and their ratio per command; never fails on speed.
# Usage: bash bench/same_speed.sh [REV] [WORKDIR]   (REV's build is kept in WORKDIR, shared with
#        bench/same_outputs.sh; about 15 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
NAME=same_speed
. bench/old_thorax.sh "$@"
command -v valgrind > /dev/null || { echo "same_speed: needs valgrind" >&2; exit 1; }
D=$W/speed
rm -rf "$D"
mkdir -p "$D"
# inputs, made once by this tree's thorax (both read the same files)
"$NEW" phantom --resolution medium --seed 1 -o "$D/c.txt" -q
"$NEW" surfaces "$D/c.txt" -o "$D/m" -q
"$NEW" mesh "$D/m" -o "$D/mv" -q
"$NEW" electrodes "$D/mv" -q
"$NEW" beat "$D/mv" -o "$D/beat.raw" -q
echo "same_speed: $REV ($(git rev-parse --short "$REV")) against this tree ($(git rev-parse --short HEAD)$(git diff --quiet || echo ', with changes')): instructions (callgrind)"
printf '%-34s %15s %15s %8s\n' command old new new/old
count() { # BIN OUT ARGS...: instructions of one run
    local bin=$1 out=$2; shift 2
    rm -rf "$out"
    valgrind --tool=callgrind --callgrind-out-file="$D/cg.out" "$bin" "$@" > /dev/null 2> "$D/cg.err" || { echo "failed: $*" >&2; cat "$D/cg.err" >&2; return 1; }
    sed -n 's/^summary: //p' "$D/cg.out" | head -1
}
run() { # NAME OUTPUT-TO-CLEAR ARGS... (@OUT in ARGS is the output path)
    local name=$1 out=$2; shift 2
    local a=() b=()
    for x in "$@"; do a+=("${x//@OUT/$out.old}"); b+=("${x//@OUT/$out.new}"); done
    local o n
    o=$(count "$OLD" "$out.old" "${a[@]}")
    n=$(count "$NEW" "$out.new" "${b[@]}")
    awk -v c="$name" -v o="$o" -v n="$n" 'BEGIN { printf "%-34s %15.0f %15.0f %8.4f\n", c, o, n, n / o }'
}
run "phantom (medium)" "$D/p" phantom --resolution medium --seed 1 -o @OUT -q
run "surfaces (medium)" "$D/s" surfaces "$D/c.txt" -o @OUT -q
run "check (surfaces)" "$D/x" check "$D/m" -q
run "mesh (medium)" "$D/v" mesh "$D/m" -o @OUT -q
run "check (surfaces and volume)" "$D/x" check "$D/mv" -q
run "slice (5 mm)" "$D/sl" slice "$D/m" --spacing 5 -o @OUT -q
run "export vtu" "$D/e" export "$D/mv" --format vtu -o @OUT -q
run "series convert (raw -> mat)" "$D/b" series convert "$D/beat.raw" -o @OUT -q --format mat
run "forward transfer (12 leads)" "$D/t" forward "$D/mv" --transfer-out --rows "$D/mv/electrodes/12lead.txt" -o @OUT -q
