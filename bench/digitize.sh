#!/usr/bin/env bash
# Benchmark of tracing a scan in the viewer (issue 26 item 8), in one run:
#   1. the livewire between two clicks on a 512 x 512 plane: ours (bench/livewire.c, wall clock)
#      beside OpenCV's intelligent scissors (bench/digitize_opencv.py: the same costs, the whole plane's
#      Dijkstra at each seed) on the same synthetic plane; target under 50 ms;
#   2. plane scrolling in the slice pane (bench-trace-scroll: a plane step, the plane sampled, its grey
#      levels, the loops drawn; the pane 560 x 800): on the InVesalius CT (256 x 256) and on a
#      512 x 512 x 300 label map (bench/torso_labels.py); target under 30 ms;
#   3. the model's update after a loop edit at the high phantom's resolution (its contours, layers and
#      nodes 5 mm apart, loaded onto its MR with 5 mm planes): bench-trace-edit moves a point and
#      builds and checks that surface again; target under 1 s;
#   4. the livewire inside the viewer: two clicks 130 mm apart along the 512 x 512 map's outline,
#      each `trace point` line's time (-v).
# Prints figures; never fails on time. Usage: bench/digitize.sh (build first).
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
PY=/usr/bin/python3
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
XV=(xvfb-run -a -s "-screen 0 1600x1100x24")

echo; echo "== 1. livewire between two clicks, 512 x 512 =="
LIVEWIRE_WALL=1 build/bin/livewire_bench 15
$PY bench/digitize_opencv.py 15 || echo "(OpenCV: python3-opencv missing)"

echo; echo "== 2. plane scrolling in the slice pane =="
INV=/usr/share/doc/invesalius-examples/examples/Cranium.inv3
if [ -r "$INV" ]; then
    $PY -B tests/inv3_to_nifti.py "$INV" "$W/ct.nii.gz" > /dev/null
    printf -- '--image %s\n--size 800x800\naction trace surface head:outer\naction bench-trace-scroll 200\nquit\n' "$W/ct.nii.gz" > "$W/ct.txt"
    "${XV[@]}" "$THORAX" view --script "$W/ct.txt" 2> /dev/null | grep bench- | sed 's/^/CT: /'
fi
$PY bench/torso_labels.py "$W/map.nii.gz" 512 512 300 > /dev/null
printf -- '--image %s\n--size 800x800\naction trace surface torso\naction bench-trace-scroll 200\nquit\n' "$W/map.nii.gz" > "$W/map.txt"
"${XV[@]}" "$THORAX" view --script "$W/map.txt" 2> /dev/null | grep bench- | sed 's/^/512 map: /'

echo; echo "== 3. the model's update after a loop edit, the high phantom =="
"$THORAX" phantom --resolution high --seed 1 -o "$W/high.txt" -q
"$THORAX" phantom --image "$W/mr.nii.gz" --modality mr --voxel 5 -q > /dev/null
# the contours' layers lie on multiples of 5 mm, the image's planes half a voxel off them: the image
# is moved 2.5 mm up (its grey levels do not matter here, only its planes)
$PY - "$W/mr.nii.gz" <<'EOF'
import sys, nibabel as nib, numpy as np
im = nib.load(sys.argv[1]); aff = im.affine.copy(); aff[2, 3] += 2.5
nib.save(nib.Nifti1Image(np.asarray(im.dataobj), aff), sys.argv[1])
EOF
cat > "$W/edit.txt" <<EOF
--image $W/mr.nii.gz
--contours $W/high.txt
--size 800x800
action trace surface torso
action trace plane z=135
action bench-trace-edit 20
action trace surface heart
action trace plane z=135
action bench-trace-edit 20
action trace surface lung_l
action trace plane z=135
action bench-trace-edit 20
quit
EOF
"${XV[@]}" "$THORAX" view --script "$W/edit.txt" 2> /dev/null | grep "bench-\|passes" | grep -v "^trace:" | sed 's/^/high phantom: /'

echo; echo "== 4. the livewire in the viewer, the 512 x 512 map =="
cat > "$W/lw.txt" <<EOF
--image $W/map.nii.gz
--size 800x800
action trace surface torso
action trace plane z=0
action trace tool livewire
action trace point 170 0
action trace point 120 100
action trace point 0 140
quit
EOF
"${XV[@]}" "$THORAX" view --script "$W/lw.txt" -v 2>&1 >/dev/null | grep "trace point" | sed 's/^thorax view: /512 map: /'
echo
echo "targets: livewire between two clicks < 50 ms; a plane step < 30 ms; the model after an edit < 1 s"
echo "load average after: $(cut -d' ' -f1-3 /proc/loadavg)"
