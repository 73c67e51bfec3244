#!/usr/bin/env bash
# The demo (make demo): the whole pipeline on the built-in phantom, timed stage by
# stage (one line a stage on the terminal; every command's output in OUT/demo.log),
# and OUT/index.html, the results page (scripts/demo_report.py): the figures at a
# glance, the interactive page (page.html), the 12-lead ECG on ECG paper, the electrodes on the torso, the maps, the
# volume mesh and the conductivity table, the checks and the timings.
set -euo pipefail
T=${THORAX:-build/bin/thorax}
O=${OUT:-out/demo}
mkdir -p "$O"
TIMES="$O/timings.txt"
LOG="$O/demo.log"   # every command and everything it printed
: > "$TIMES"
: > "$LOG"
# One line a stage on the terminal: its name and time. A stage that fails prints what it said
# (stderr and stdout) and stops the demo with its exit status.
stage() { # NAME CMD...
    local name=$1; shift
    local t0 t1 rc=0 err="$O/.stage.err" out="$O/.stage.out"
    printf '+ %s\n' "$*" >> "$LOG"
    t0=$(date +%s.%N)
    "$@" > "$out" 2> "$err" || rc=$?
    t1=$(date +%s.%N)
    cat "$out" "$err" >> "$LOG"
    if [ "$rc" -ne 0 ]; then
        printf 'demo: stage "%s" failed (exit %d): %s\n' "$name" "$rc" "$*" >&2
        cat "$out" "$err" >&2
        rm -f "$out" "$err"
        exit "$rc"
    fi
    rm -f "$out" "$err"
    awk -v n="$name" -v a="$t0" -v b="$t1" 'BEGIN { printf "%s\t%.2f\n", n, b - a }' >> "$TIMES"
    awk -v n="$name" -v a="$t0" -v b="$t1" 'BEGIN { printf "  %-46s %7.1f s\n", n, b - a }'
}
QRS=193   # the QRS peak of the phantom's beat (frame 193 = 192 ms)
# The pipeline opens at the scan (paper 3.1): the phantom as a label map (what a segmentation tool writes) and as a
# simulated CT; the label map traced plane by plane into the contours (10 mm apart, nodes 11 mm apart: the paper's
# scale), the contours laced into surfaces.
LABELS=(--label 1,2,3,4,5,6=torso:outer --label 2,3,4,5,6=fat:fat --label 3,4,5,6=muscle:muscle
        --label 4=lung_r:lung --label 5=lung_l:lung --label 6=heart:heart)
stage "scan: label map (thorax phantom --image)" "$T" phantom --image "$O/labels.nii.gz" --voxel 2 --modality labels -q
stage "scan: simulated CT" "$T" phantom --image "$O/ct.nii.gz" --voxel 2 --modality ct --noise 20 --seed 1 -q
stage "contours (thorax digitize)" sh -c "'$T' digitize '$O/labels.nii.gz' ${LABELS[*]} --spacing 10 --node-spacing 11 -o '$O/contours.txt' > '$O/digitize.txt'"
stage "surfaces" "$T" surfaces "$O/contours.txt" -o "$O/model" -q
HIDE=(--surface torso=hidden --surface fat=hidden --surface muscle=hidden --surface lung_r=hidden --surface lung_l=hidden
      --surface heart=hidden)
stage "the scan with its contours" "$T" render "$O/model" --image "$O/ct.nii.gz" --image-plane z=100 --contours "$O/contours.txt" \
    "${HIDE[@]}" --view superior --size 800x600 --orientation -o "$O/scan.png" -q
stage "volume mesh" sh -c "'$T' mesh '$O/model' --no-heart --stats > '$O/mesh.txt'"
stage "checks" sh -c "'$T' check '$O/model' --json > '$O/check.json'"
stage "electrodes" "$T" electrodes "$O/model" -q
stage "heartbeat (500 frames)" sh -c "'$T' beat '$O/model' -o '$O/beat.raw' > '$O/beat.out' && sed -n 2p '$O/beat.out' > '$O/beat.label'"
stage "forward solution (500 frames)" "$T" forward "$O/model" --epicardial "$O/beat.raw" -o "$O/solution" --currents $QRS --volume -q
stage "12-lead ECG and its plot" "$T" leads "$O/solution" --plot "$O/ecg12.svg" -q
R=(--solution "$O/solution" --size 800x900 --colorbar --orientation --label --trace II --only torso --only heart)
stage "interactive page (thorax export --format html)" "$T" export --solution "$O/solution" --format html -o "$O/page.html" \
    --only torso --only heart --size 640x720 --frame $QRS --title "thorax demo: the phantom's heartbeat" -q
stage "anterior map" "$T" render "${R[@]}" --frame $QRS --view anterior -o "$O/anterior.png" -q
stage "posterior map" "$T" render "${R[@]}" --frame $QRS --view posterior -o "$O/posterior.png" -q
OPEN=(--view anterior --clip anterior:0.75 --no-clip heart)   # the chest opened, the heart whole
stage "heart through the clip plane" "$T" render "${R[@]}" --frame $QRS "${OPEN[@]}" -o "$O/heart.png" -q
stage "contours and bands" "$T" render --solution "$O/solution" --size 800x800 --frame $QRS --view left --style bands+contours --levels 16 --colorbar --orientation --label -o "$O/bands.png" -q
stage "current arrows" "$T" render --solution "$O/solution" --size 800x800 --frame $QRS --view anterior --clip anterior:0.55 --arrows --arrow-spacing 18 --surface torso=wire:0.15 --orientation -o "$O/currents.png" -q
stage "orientation check" "$T" render "$O/model" --size 900x600 --panels --mode orientation --orientation -o "$O/orientation.png" -q
E12=(--electrodes "$O/model/electrodes/12lead.txt")
stage "electrodes (anterior)" "$T" render --solution "$O/solution" --frame $QRS --size 700x800 --only torso "${E12[@]}" --orientation --view anterior -o "$O/electrodes_anterior.png" -q
stage "electrodes (left)" "$T" render --solution "$O/solution" --frame $QRS --size 700x800 --only torso "${E12[@]}" --orientation --view left -o "$O/electrodes_left.png" -q
stage "volume mesh picture" "$T" render "$O/model" --size 800x900 --mode hidden --tetrahedra --clip anterior:0.5 --orientation --view anterior -o "$O/tetrahedra.png" -q
stage "animation (300 frames + MP4)" "$T" animate "${R[@]}" --size 640x720 "${OPEN[@]}" --frames 101:400 --fps 30 -o "$O/frames" --mp4 "$O/beat.mp4" -q
# Inside the volume (paper 4.3): equipotential surfaces and slices of the volume potentials
ISO=(--solution "$O/solution" --isosurface 12%,30%,70%,88% --colorbar --orientation --label --only torso --only heart --only equipotentials)
stage "equipotential surfaces" "$T" render "${ISO[@]}" --size 800x900 --frame $QRS --view anterior -o "$O/equipotentials.png" -q
stage "slices with contour lines" "$T" render --solution "$O/solution" --size 800x800 --frame $QRS --view superior \
    --slice z=110 --surface heart=phong:0.35 --style continuous+contours --levels 16 --colorbar --orientation --label -o "$O/slices.png" -q
stage "current streamlines" "$T" render --solution "$O/solution" --size 800x900 --frame $QRS --view anterior \
    --streamlines density:220 --only torso --only heart --only streamlines --colorbar --orientation --label -o "$O/streamlines.png" -q
# RaySpray (paper 4.3): the picture ray traced (the heart through a glass torso, shadows, a sky), and the
# potential rendered inside the torso by emission and absorption
stage "ray traced: the heart through a glass torso" "$T" trace --solution "$O/solution" --size 800x900 --frame $QRS --view anterior \
    --material torso=glass --material fat=transparent:0.9 --material muscle=transparent:0.9 --environment sky --colorbar \
    --orientation --label -o "$O/traced.png" -q
stage "volume-rendered potential" "$T" trace --solution "$O/solution" --size 800x900 --frame $QRS --view anterior \
    --volume potential --volume-opacity 0:1,0.3:0,0.7:0,1:1 --volume-density 0.08 --only heart --colorbar --orientation \
    --label -o "$O/volume.png" -q
stage "equipotential animation (300 frames + MP4)" "$T" animate "${ISO[@]}" --size 480x540 --frames 101:400 --fps 30 \
    -o "$O/iso_frames" --mp4 "$O/equipotentials.mp4" -q
stage "camera flight round the torso (121 frames + MP4)" "$T" animate --solution "$O/solution" \
    --keys "$(dirname "$0")/demo_flight.keys" --only torso --only heart --colorbar --orientation --label \
    --size 480x540 --fps 30 -o "$O/flight_frames" --mp4 "$O/flight.mp4" -q
# Measured data, when the shared data folder is beside the checkout (it is in CI; elsewhere this part
# is left out): map3d's recordings drawn from their own files, no model needed.
MD=${MAP3D_DATA:-../shared/data/map3d}
if [ -f "$MD/data/tank/cool1-atdr-run1.mat" ] && [ -f "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" ]; then
    stage "measured: tank sock" "$T" render "$MD/geom/tank/25feb97_sock.pts" --data "$MD/data/tank/cool1-atdr-run1.mat" \
        --channels "$MD/geom/tank/sock128.channels" --frame 185 --scope frame --style continuous+contours --colorbar \
        --label --trace 60 --size 600x600 -o "$O/measured_tank.png" -q
    stage "measured: 490-lead sock" "$T" render "$MD/geom/socks/490sock.pts" --data "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" \
        --frame 277 --scope frame --style continuous+contours --colorbar --label --trace 245 --size 600x600 \
        -o "$O/measured_sock.png" -q
    stage "measured: sock animation (120 frames + MP4)" "$T" animate "$MD/geom/socks/490sock.pts" \
        --data "$MD/data/socks/10jan01/rsm10jan01-cs-0004.mat" --frames 231:350 --scope fixed:-10:10 --colorbar --style continuous+contours --label \
        --trace 245 --size 480x480 --fps 20 -o "$O/measured_frames" --mp4 "$O/measured_sock.mp4" -q
else
    rm -rf "$O/measured_tank.png" "$O/measured_sock.png" "$O/measured_sock.mp4" "$O/measured_frames"
fi
stage "VTK export" sh -c "'$T' export '$O/model' --format vtp -o '$O/vtk' -q && '$T' export '$O/model' --format vtu -o '$O/vtk' -q"
stage "ParaView time series (every 5th frame)" "$T" export "$O/model" --solution "$O/solution" --format vtp \
    --surface torso --surface heart --frames 1:500:5 -o "$O/paraview" -q

# the page: the figures at a glance, the ECG, the pictures, the tables (scripts/demo_report.py)
python3 "$(dirname "$0")/demo_report.py" "$O" $QRS
