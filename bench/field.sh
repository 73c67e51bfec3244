#!/usr/bin/env bash
# Benchmark of the equipotential surfaces (issue 16, item 6; the streamline half is added
# beside): the high-resolution phantom (thorax phantom --resolution high, surfaces, mesh
# --no-heart: about 1.8 million tetrahedra), a 300-frame beat solved with thorax forward --volume;
#  - three equipotential surfaces (25%, 50%, 75% of frame 193's range) by thorax
#    (thx_field_isosurface, in memory: bench/field_iso.c) and by VTK's vtkContour3DLinearGrid and
#    vtkContourFilter on the very same mesh and potentials (the .vtu of thorax export, read once;
#    the filter's Update alone: bench/field_vtk.py), best of 10 each, with triangle counts, areas
#    and the ratio;
#  - thorax on 1 thread and on all (OMP_NUM_THREADS);
#  - the whole command, thorax field ... -o iso.vtp (reading the solution, writing the file);
#  - a 300-frame loop of three equipotential surfaces (geometry only, no rendering).
# Prints figures; never fails on time. FIELD_BENCH_DIR=DIR keeps the prepared model and solution
# there for the next run.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
ISO=${ISO:-$PWD/build/bin/field_iso}
PY=${PY:-/usr/bin/python3}
[ -x "$THORAX" ] && [ -x "$ISO" ] || { echo "build first (make)"; exit 1; }
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
if [ -n "${FIELD_BENCH_DIR:-}" ]; then
    W=$FIELD_BENCH_DIR
    mkdir -p "$W"
else
    W=$(mktemp -d)
    trap 'rm -rf "$W"' EXIT
fi
FRAME=${FRAME:-193}
SPEC=${SPEC:-25%,50%,75%}
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ ! -f "$W/sol/solution.json" ]; then
    t0=$(date +%s.%N)
    "$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$W/m" -q
    "$THORAX" mesh "$W/m" --no-heart -q
    "$THORAX" beat "$W/m" -o "$W/beat.raw" --frames 300 -q
    "$THORAX" forward "$W/m" --epicardial "$W/beat.raw" --volume -o "$W/sol" -q
    echo "prepared the high phantom and its 300-frame volume solution in $(echo "$(date +%s.%N) - $t0" | bc) s"
fi
[ -f "$W/vtu/volume_$(printf %04d "$FRAME").vtu" ] ||
    "$THORAX" export "$W/m" --solution "$W/sol" --format vtu --frames "$FRAME" -o "$W/vtu" -q
echo "--- equipotential surfaces $SPEC of frame $FRAME"
OMP_NUM_THREADS=1 "$ISO" "$W/sol" "$FRAME" "$SPEC" 10 | tee "$W/thx1.log"
"$ISO" "$W/sol" "$FRAME" "$SPEC" 10 | head -1 | sed 's/^thorax:/thorax (all threads):/' | tee "$W/thxn.log"
vals=$(grep '^thorax value' "$W/thx1.log" | awk '{print $3}' | sed 's/:$//' | paste -sd,)
"$PY" bench/field_vtk.py "$W/vtu/volume_$(printf %04d "$FRAME").vtu" "$vals" 10 | tee "$W/vtk.log"
t1=$(grep -o 'best of 10 [0-9.]* s' "$W/thx1.log" | awk '{print $4}')
tn=$(grep -o 'best of 10 [0-9.]* s' "$W/thxn.log" | awk '{print $4}')
tv=$(grep 'vtkContour3DLinearGrid' "$W/vtk.log" | grep -o 'best of 10 [0-9.]* s' | awk '{print $4}')
tc=$(grep 'vtkContourFilter' "$W/vtk.log" | grep -o 'best of 10 [0-9.]* s' | awk '{print $4}')
echo "ratio: vtkContour3DLinearGrid / thorax = $(echo "scale=1; $tv / $t1" | bc) (1 thread), $(echo "scale=1; $tv / $tn" | bc) (all threads); vtkContourFilter / thorax = $(echo "scale=1; $tc / $t1" | bc) (1 thread)"
"$PY" - "$W/thx1.log" "$W/vtk.log" <<'EOF'
import sys, re
a = {m[0]: (int(m[1]), float(m[2])) for m in re.findall(r"thorax value (\S+): (\d+) triangles, area (\S+)", open(sys.argv[1]).read())}
b = {m[0]: (int(m[1]), float(m[2])) for m in re.findall(r"vtk value (\S+): (\d+) triangles, area (\S+)", open(sys.argv[2]).read())}
for v in a:
    print("value %s: triangles thorax %d VTK %d, area relative difference %.1e" % (v, a[v][0], b[v][0], abs(a[v][1] - b[v][1]) / b[v][1]))
EOF
echo "--- the whole command (read the solution, cut, write the .vtp)"
/usr/bin/time -f "thorax field: %e s wall, %M KB peak" "$THORAX" field "$W/sol" --isosurface "$SPEC" --frame "$FRAME" -o "$W/iso.vtp" -q
echo "--- 300 frames x three equipotential surfaces (geometry only)"
OMP_NUM_THREADS=1 "$ISO" "$W/sol" "$FRAME" "$SPEC" 1 300 "$SPEC" | tail -1 | sed 's/^thorax loop:/thorax loop (1 thread):/'
"$ISO" "$W/sol" "$FRAME" "$SPEC" 1 300 "$SPEC" | tail -1 | sed 's/^thorax loop:/thorax loop (all threads):/'
