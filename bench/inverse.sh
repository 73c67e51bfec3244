#!/usr/bin/env bash
# Benchmark of thorax inverse (issue 15, item 5): a 500-frame inverse with λ per frame on the
# medium phantom's transfer matrix (torso nodes x heart nodes). Prints the time of the standard
# form + SVD and of everything per frame (λ rule, filter factors, solutions, norms) separately;
# the target is under 1 s for the per-frame part. Never fails on time.
# Usage: bench/inverse.sh   (WORK=DIR keeps and reuses the model and matrix)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
W=${WORK:-$(mktemp -d)}
[ -n "${WORK:-}" ] || trap 'rm -rf "$W"' EXIT
mkdir -p "$W"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
if [ ! -d "$W/m" ]; then
    "$THORAX" phantom --resolution medium --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
    "$THORAX" mesh "$W/m" --no-heart -q
fi
[ -f "$W/beat500.raw" ] || "$THORAX" beat "$W/m" -o "$W/beat500.raw" --frames 500 -q
[ -d "$W/T" ] || "$THORAX" forward "$W/m" --transfer-out -o "$W/T" -q
[ -d "$W/F" ] || "$THORAX" forward "$W/m" --epicardial "$W/beat500.raw" --transfer "$W/T/transfer.raw" -o "$W/F" -q
for args in "tikhonov0 lcurve" "tikhonov0 gcv" "tikhonov0 creso" "tikhonov1 lcurve" "tikhonov2 gcv" "tsvd lcurve"; do
    set -- $args
    rm -rf "$W/inv"
    /usr/bin/time -f "%e %M" -o "$W/t" "$THORAX" inverse --transfer "$W/T/transfer.raw" --data "$W/F/torso.raw" \
        --method $1 --lambda $2 --lambda-per frame -o "$W/inv" -q
    read -r wall rss < "$W/t"
    /usr/bin/python3 - "$W/inv/inverse.json" "$1" "$2" "$wall" "$rss" <<'PY'
import json, sys
j = json.load(open(sys.argv[1]))
print("%-10s %-7s %d frames, %d x %d: standard form + SVD %.3f s, per-frame part %.3f s (%.2f ms/frame); "
      "wall %.2f s (reading, writing), peak %d MB" % (sys.argv[2], sys.argv[3], j['frames'], j['rows'], j['heart_nodes'],
      j['seconds_svd'], j['seconds_frames'], 1e3 * j['seconds_frames'] / j['frames'], float(sys.argv[4]), int(sys.argv[5]) // 1024))
PY
done
