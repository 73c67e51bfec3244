#!/usr/bin/env bash
# Benchmark of the interactive viewer (issue 13, item 10; paper 3.4: "interactive manipulation of
# the large meshes ... proved to be particularly taxing"): the high-resolution phantom's torso and
# heart with their potentials, 1280x800, on this machine's Mesa llvmpipe under Xvfb —
#   rotate:     360 drawings, each turned 1 degree, one after another (the time between finished
#               drawings, what a user dragging the mouse sees);
#   frame-step: 299 frame steps of the potentials;
#   pick:       100 picks over a grid of the window;
#   rotate again with the colour bar and the time label (a map3d user's picture: the annotations
#   drawn over the scene read back, and what they changed uploaded), with each draw's phases
#   (scene, readback, annotations, their upload; each finished) and the load average beside it:
#   the step's time grows with the machine's load through the scene's rasterization (Mesa llvmpipe's
#   threads), docs/design/view.md "Responsiveness under load";
#   peak memory of the process;
# then VTK 9 (bench/vtk_view.py) drawing the same meshes and data in an on-screen window of the same
# size, in the same run, and the ratios; then bench/digitize.sh (tracing a scan: the livewire beside
# OpenCV's, plane steps in the slice pane, the model after a loop edit). Prints figures; never fails on time.
#   DATA=DIR   reuse DIR/m (model) and DIR/sol (solution) instead of making them (about 3 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ -n "${DATA:-}" ]; then
    M=$DATA/m S=$DATA/sol
else
    M=$W/m S=$W/sol
    "$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$M" -q 2> /dev/null
    "$THORAX" mesh "$M" --no-heart -q
    "$THORAX" electrodes "$M" -q
    "$THORAX" beat "$M" -o "$W/beat.raw" --frames 300 -q
    "$THORAX" forward "$M" --epicardial "$W/beat.raw" -o "$S" -q
fi
/usr/bin/python3 - "$M" <<'EOF'
import json, sys
m = json.load(open(sys.argv[1] + '/model.json'))
s = [x for x in m['surfaces'] if x['name'] in ('torso', 'heart')]
print('scene: torso and heart, %d nodes, %d triangles, potentials coloured per pixel (Gouraud), 1280x800' % (
    sum(x['n_nodes'] for x in s), sum(x['n_tris'] for x in s)))
EOF
cat > "$W/bench.txt" <<EOF
--solution $S
--size 1280x800
--only torso
--only heart
--frame 1
action bench-rotate 360
action bench-frames 299
action bench-pick 100
--colorbar
--label
action bench-rotate 360
quit
EOF
xvfb-run -a -s "-screen 0 1600x1100x24" "$THORAX" view --script "$W/bench.txt" 2> "$W/view.err" | tee "$W/ours.txt"
xvfb-run -a -s "-screen 0 1600x1100x24" /usr/bin/python3 bench/vtk_view.py --model "$M" --solution "$S" 2> "$W/vtk.err" | tee "$W/vtk.txt" | tail -3
/usr/bin/python3 - "$W/ours.txt" "$W/vtk.txt" <<'EOF'
import re, sys
ours, vtk = open(sys.argv[1]).read(), open(sys.argv[2]).read()
def num(pat, text):
    m = re.search(pat, text)
    return float(m.group(1)) if m else float('nan')
o_rot = num(r'rotate \d+ steps in [\d.]+ s: ([\d.]+) per second', ours)
o_rot_ms = num(r'rotate .*?median ([\d.]+) ms a step', ours)
o_fs = num(r'frame-step \d+ steps in [\d.]+ s: ([\d.]+) per second', ours)
o_fs_ms = num(r'frame-step .*?median ([\d.]+) ms a step', ours)
o_pick = num(r'pick \d+ picks, median ([\d.]+) ms', ours)
rots = re.findall(r'rotate \d+ steps in [\d.]+ s: [\d.]+ per second; median ([\d.]+) ms a step', ours)
o_rot_ann = float(rots[1]) if len(rots) > 1 else float('nan')
ph = re.findall(r'rotate phases: scene ([\d.]+) ms, readback ([\d.]+) ms, annotations ([\d.]+) ms, their upload ([\d.]+) ms', ours)
o_peak = max(float(x) for x in re.findall(r'peak (\d+) MB', ours)) if 'peak' in ours else float('nan')
v_rot_ms = num(r'vtk: rotate ([\d.]+) ms/frame', vtk)
v_fs_ms = num(r'frame-step ([\d.]+) ms', vtk)
v_peak = num(r'peak ([\d.]+) MB', vtk)
print()
print('%-26s %16s %16s %10s' % ('1280x800, llvmpipe', 'thorax view', 'VTK 9', 'VTK/thorax'))
print('%-26s %10.1f ms %3.0f/s %10.1f ms %3.0f/s %9.1fx' % ('rotate (a frame)', o_rot_ms, o_rot, v_rot_ms, 1000 / v_rot_ms, v_rot_ms / o_rot_ms))
print('%-26s %10.1f ms %3.0f/s %10.1f ms %3.0f/s %9.1fx' % ('frame step', o_fs_ms, o_fs, v_fs_ms, 1000 / v_fs_ms, v_fs_ms / o_fs_ms))
print('%-26s %10.1f ms %3.0f/s %16s' % ('rotate, bar and label', o_rot_ann, 1000 / o_rot_ann, '-'))
if len(ph) > 1:
    print('%-26s scene %s ms, readback %s, annotations %s, upload %s' % ('  its phases (a draw)', *ph[1]))
print('%-26s %13.2f ms %16s' % ('pick (median)', o_pick, '-'))
print('%-26s %13.0f MB %13.0f MB' % ('peak memory', o_peak, v_peak))
print('targets: >= 30 frames a second rotating and stepping, picks < 50 ms')
print('load average after: %s' % open('/proc/loadavg').read().split(' ', 3)[:3])
EOF
# tracing a scan (issue 26 item 8): the livewire beside OpenCV's, plane steps, the model after an edit
echo
bash bench/digitize.sh
