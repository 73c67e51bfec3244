#!/usr/bin/env bash
# Benchmark of the surface build (paper 3.1-3.2) on the high-resolution phantom:
# wall time and peak memory of `thorax surfaces`, per-stage times, and VTK's
# contour-to-surface filters on the same contours, run side by side.
# Prints figures; never passes or fails on time. Target: < 1 s and < 200 MB.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-build/bin/thorax}
RUNS=${RUNS:-5}
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
command -v /usr/bin/time > /dev/null || { echo "needs /usr/bin/time (scripts/deps.sh)"; exit 1; }

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), OMP_NUM_THREADS=${OMP_NUM_THREADS:-default}"
"$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
echo "input: high-resolution phantom, $(grep -c '^layer' "$W/c.txt") layers, $(grep -c '^loop' "$W/c.txt") loops, $(grep -cE '^-?[0-9]' "$W/c.txt") digitized points"
echo

times=()
for i in $(seq "$RUNS"); do
    /usr/bin/time -f "%e %M" -o "$W/time" "$THORAX" surfaces "$W/c.txt" -o "$W/m" --stats > "$W/out" 2>&1
    read -r wall rss < "$W/time"
    times+=("$wall $rss")
done
best=$(printf '%s\n' "${times[@]}" | sort -n | head -1)
median=$(printf '%s\n' "${times[@]}" | sort -n | sed -n "$(( (RUNS + 1) / 2 ))p")
echo "thorax surfaces (whole command: read, build, write), $RUNS runs:"
echo "  wall  best $(echo "$best" | cut -d' ' -f1) s   median $(echo "$median" | cut -d' ' -f1) s      (target < 1 s)"
echo "  peak memory $(( $(echo "$median" | cut -d' ' -f2) / 1024 )) MB                  (target < 200 MB)"
grep -E '^total' "$W/out" | awk '{printf "  output: %s nodes, %s triangles (paper: 42,000 / 85,000)\n", $2, $3}'
echo "  last run, per stage:"
grep -E '^stage times' "$W/out" | sed 's/^stage times (s): /    /; s/, /\n    /g'
grep -E '^(lacing|orientation):' "$W/out" | sed 's/^/  /'
echo
echo "single thread:"
OMP_NUM_THREADS=1 /usr/bin/time -f "%e %M" -o "$W/time1" "$THORAX" surfaces "$W/c.txt" -o "$W/m1" -q
read -r wall1 rss1 < "$W/time1"
echo "  wall $wall1 s, peak memory $(( rss1 / 1024 )) MB"
echo
echo "thorax check on the result:"
/usr/bin/time -f "%e %M" -o "$W/timec" "$THORAX" check "$W/m" -q && echo "  all surfaces pass" || echo "  CHECK FAILED"
read -r wallc rssc < "$W/timec"
echo "  wall $wallc s, peak memory $(( rssc / 1024 )) MB"
echo
echo "peer on the same contours (VTK $( /usr/bin/python3 -c 'import vtk; print(vtk.vtkVersion.GetVTKVersion())'), in-process times):"
/usr/bin/python3 bench/peer_vtk_contours.py "$W/c.txt" 5
echo "  (vtkRuledSurfaceFilter laces the raw digitized points: no spline, no caps, no concave"
echo "   handling, no orientation; vtkVoxelContoursToSurfaceFilter gives a staircase surface"
echo "   at the layer spacing.)"
