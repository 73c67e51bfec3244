#!/usr/bin/env bash
# Benchmark of RaySpray, the ray tracer (issue 27 item 5), with the peers in the same run:
#   1. the high-resolution phantom's surfaces with the potentials at 1920 x 1080, a key light with
#      shadows, the heart a mirror: thorax trace (wall clock, median of 3; peak memory) beside
#      thorax render (OpenGL, Mesa's llvmpipe) of the same picture;
#   2. primary rays (one sample, the headlight, no bounces): rays a second of the shaded frame, and of
#      the id image alone (bench/trace_ids.c: the surface and triangle each pixel sees), beside Embree's
#      own viewer (embree-tools, its primID shader: one ray a pixel) on the same surfaces as OBJ;
#   3. the volume rendering of the potential inside the mesh at 1024 x 1024: thorax trace, a frame
#      and the next (no rebuild), beside VTK 9's unstructured-grid ray caster
#      (vtkUnstructuredGridVolumeRayCastMapper, bench/vtk_volume.py) on the same mesh and field;
# memory printed. Prints figures; never fails on time.
#   DATA=DIR   reuse DIR/m (model, meshed) and DIR/sol (solution with volume potentials)
#   KEEP=DIR   keep the pictures there (trace.png, opengl.png, primary.png, volume.png, vtk_volume.png)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
PY=/usr/bin/python3
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ -n "${DATA:-}" ]; then
    M=$DATA/m S=$DATA/sol
else
    M=$W/m S=$W/sol
    "$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$M" -q 2> /dev/null
    "$THORAX" mesh "$M" --no-heart -q
    "$THORAX" beat "$M" -o "$W/beat.raw" --frames 300 -q
    "$THORAX" forward "$M" --epicardial "$W/beat.raw" --volume -o "$S" -q
fi
$PY - "$M" <<'EOF'
import json, sys
m = json.load(open(sys.argv[1] + '/model.json'))
print('model: %d surfaces, %d nodes, %d triangles; %s tetrahedra' % (len(m['surfaces']), sum(x['n_nodes'] for x in m['surfaces']),
      sum(x['n_tris'] for x in m['surfaces']), m.get('volume', {}).get('n_tets', '?')))
EOF
peak() { sed -n 's/.*Maximum resident set size (kbytes): \([0-9]*\).*/\1/p' "$1" | awk '{printf "%.0f", $1 / 1024}'; }
median() { grep -o 'median [0-9.]* ms' "$1" | awk '{print $2}'; }

echo; echo "== 1. surfaces, 1920 x 1080, shadows and a mirror =="
/usr/bin/time -v "$THORAX" trace --solution "$S" --frame 193 --size 1920x1080 --samples 1 --ao 0 --material heart=mirror:0.3 \
    --repeat 3 -o "$W/t.png" > "$W/t.out" 2> "$W/t.time"
/usr/bin/time -v "$THORAX" render --solution "$S" --frame 193 --size 1920x1080 --repeat 3 -o "$W/g.png" > "$W/g.out" 2> "$W/g.time"
printf '%-34s %10s ms %8s MB\n' "thorax trace (shadows, mirror)" "$(median "$W/t.out")" "$(peak "$W/t.time")"
printf '%-34s %10s ms %8s MB\n' "thorax render (OpenGL, llvmpipe)" "$(median "$W/g.out")" "$(peak "$W/g.time")"

echo; echo "== 2. primary rays (the same perspective camera for both) =="
"$THORAX" trace "$M" --camera 0,1500,135:0,0,135:0,0,1:22 --size 1920x1080 --samples 1 --ao 0 --light head --depth 0 \
    --repeat 5 -o "$W/p.png" > "$W/p.out" 2> /dev/null
ms=$(median "$W/p.out")
$PY -c "print('%-34s %10.1f M rays/s (%s ms a frame of 2.07 M rays, shaded and coloured)' % ('thorax trace, primary rays', 1920 * 1080 / (float('$ms') / 1000) / 1e6, '$ms'))"
IDS=$(dirname "$THORAX")/trace_ids
if [ -x "$IDS" ]; then
    "$IDS" "$M" 1920 1080 0,1500,135 0,0,135 0,0,1 22 20 > "$W/i.out"
    $PY - "$W/i.out" <<'EOF'
import re, sys
m = re.search(r'median ([0-9.]+) ms of \d+, ([0-9.]+) M rays/s', open(sys.argv[1]).read())
print('%-34s %10.1f M rays/s (%s ms a frame; the id image, what the primID shader computes)' % ('thorax, primary rays alone', float(m.group(2)), m.group(1)))
EOF
fi
"$THORAX" export "$M" --format obj -o "$W/obj" -q
$PY bench/obj_merge.py "$W/obj" "$W/all.obj"
if command -v viewer > /dev/null; then
    viewer -i "$W/all.obj" --size 1920 1080 --shader primID --vp 0 1500 135 --vi 0 0 135 --vu 0 0 1 --fov 22 \
        --benchmark 2 10 --threads "$(nproc)" > "$W/e.out" 2>&1 || true
    mr=$(sed -n 's/^BENCHMARK_RENDER_MRAYPS_AVG //p' "$W/e.out")
    fps=$(sed -n 's/^BENCHMARK_RENDER_AVG //p' "$W/e.out")
    [ -n "$mr" ] && $PY -c "print('%-34s %10.1f M rays/s (%.1f ms a frame; its ISPC kernels, the primID shader)' % ('Embree 3 viewer (embree-tools)', $mr, 1000 / $fps))"
fi

echo; echo "== 3. volume rendering of the potential, 1024 x 1024 =="
/usr/bin/time -v "$THORAX" trace --solution "$S" --frame 193 --size 1024x1024 --samples 1 --ao 0 --volume potential --surface torso=hidden \
    --surface fat=hidden --surface muscle=hidden --surface lung_l=hidden --surface lung_r=hidden --repeat 3 -o "$W/v.png" \
    > "$W/v.out" 2> "$W/v.time" || true
printf '%-34s %10s ms %8s MB (median of 3; the first builds the mesh'"'"'s faces; the memory holds the whole series read)\n' \
    "thorax trace --volume potential" "$(median "$W/v.out")" "$(peak "$W/v.time")"
"$THORAX" export "$M" --solution "$S" --format vtu --frames 193:193 -o "$W/vtu" -q 2> /dev/null || true
if [ -d "$W/vtu" ]; then
    xvfb-run -a -s "-screen 0 1600x1200x24" /usr/bin/time -v $PY bench/vtk_volume.py "$W/vtu" 1024 2> "$W/vtk.err" | sed 's/^/VTK: /' ||
        echo "VTK: (failed: $(tail -2 "$W/vtk.err"))"
    [ -n "$(peak "$W/vtk.err")" ] && echo "VTK: peak memory $(peak "$W/vtk.err") MB (one frame's .vtu read)"
fi
if [ -n "${KEEP:-}" ]; then
    mkdir -p "$KEEP"
    for f in t:trace g:opengl p:primary v:volume; do [ -f "$W/${f%%:*}.png" ] && cp "$W/${f%%:*}.png" "$KEEP/${f#*:}.png"; done
    [ -f "$W/vtu/vtk_volume.png" ] && cp "$W/vtu/vtk_volume.png" "$KEEP/"
    echo "pictures kept in $KEEP"
fi
echo
echo "targets: surfaces 1920x1080 with shadows and reflections < 1 s; volume 1024^2 < 1 s and >= 3x VTK's ray caster"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
