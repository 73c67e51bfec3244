#!/usr/bin/env bash
# Benchmark of current streamlines (issue 16, item 3; the streamline half of bench/field.sh): 1,000
# seeds drawn by |J| density on the high-resolution phantom (about 1.8 million tetrahedra, the heart
# left out), one frame of thorax forward --volume, lines both ways, by thorax (thorax streamlines) and
# by VTK's vtkStreamTracer in the same run: RK2, RK4 and RK45 with the same seeds, the same step (mm),
# the same maximum length and terminal |J|, VTK given the same node-averaged field as point data on
# the volume thorax export writes (--format vtu). Prints the wall times (thorax: its field set-up,
# point locator included, plus tracing; VTK: vtkStreamTracer.Update(), its locator included), their
# ratio, and the accuracy: each tracer's largest distance from a reference (thorax RK4, step 0.02 mm)
# over the first 100 mm of each line, and the two tracers' distance from each other.
# Never fails on time. RES=medium for a quicker run; THREADS (1) for both tracers.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
PY=${PY:-/usr/bin/python3}
RES=${RES:-high}
THREADS=${THREADS:-1}
STEP=${STEP:-0.5}
MAXLEN=${MAXLEN:-300}
MINCUR=${MINCUR:-0.001}
N=${N:-1000}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
W=${KEEP:-$(mktemp -d)}
[ -n "${KEEP:-}" ] || trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
if [ ! -f "$W/sol/solution.json" ]; then
    "$THORAX" phantom --resolution "$RES" --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
    "$THORAX" mesh "$W/m" --no-heart -q
    "$THORAX" beat "$W/m" -o "$W/beat.raw" --frames 8 --dt 30 -q
    "$THORAX" forward "$W/m" --epicardial "$W/beat.raw" --volume -o "$W/sol" -q
    rm -rf "$W/vtu"
    "$THORAX" export "$W/m" --solution "$W/sol" --format vtu --frames 4 -o "$W/vtu" -q
fi
nt=$("$PY" -c "import json; print(json.load(open('$W/m/model.json'))['volume']['n_tets'])")
echo "$RES phantom: $nt tetrahedra (heart left out); frame 4 (120 ms) of the phantom's beat"
mkdir -p "$W/lines"
: > "$W/lines/times.txt"
run() { # NAME THREADS ARGS...: thorax streamlines, its field set-up + tracing seconds into times.txt
    local name=$1 th=$2; shift 2
    rm -f "$W/lines/$name.vtp"
    OMP_NUM_THREADS=$th "$THORAX" streamlines "$W/sol" --streamlines --frame 4 --seed density:$N --no-loops \
        --max-length "$MAXLEN" --min-current "$MINCUR" -o "$W/lines/$name.vtp" "$@" 2> "$W/log"
    "$PY" - "$W/log" "$name" >> "$W/lines/times.txt" <<'PYEOF'
import re, sys
t = open(sys.argv[1]).read()
m = re.search(r"(\d+) points.*field ([0-9.]+) s, tracing ([0-9.]+) s \((\d+) steps, (\d+) evaluations\)", t)
assert m, t
print(sys.argv[2], "%.3f" % (float(m.group(2)) + float(m.group(3))), "%s (field %s s + tracing %s s, %s steps, %s evaluations)" %
      (m.group(1), m.group(2), m.group(3), m.group(4), m.group(5)))
PYEOF
    tail -1 "$W/lines/times.txt"
}
run rk2 "$THREADS" --integrator rk2 --step-mm "$STEP"
run rk4 "$THREADS" --integrator rk4 --step-mm "$STEP"
run rk45 "$THREADS" --integrator rk45 --step-mm "$STEP" --tolerance 1e-6
run rk2_2threads 2 --integrator rk2 --step-mm "$STEP"
run ref 2 --integrator rk4 --step-mm 0.02 --max-steps 10000000
"$PY" bench/field_streamlines_vtk.py "$W/vtu/volume_0004.vtu" "$W/lines" "$STEP" "$MAXLEN" "$MINCUR" "$THREADS"
