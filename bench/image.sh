#!/usr/bin/env bash
# Benchmark of label map -> contours -> surfaces (issue 25, item 6) beside CGAL Mesh_3's labeled-image
# mesher on the same label map, in one run. The map: bench/torso_labels.py, a 512 x 512 x 300
# torso of five tissues (fat, muscle/lean tissue, two lungs, heart, blood pools; 0.8 x 0.8 x 1.0 mm
# voxels; the values are in its header), written as .nii.gz.
#   thorax: `thorax surfaces MAP.nii.gz --label ...` (the image straight to the model; the target:
#     < 10 s on 2 cores, < 2 GB), and its two halves `thorax digitize` (-> contours) and `thorax
#     surfaces` (contours -> model); `thorax check` on the model; `thorax mesh` (MESH=0 skips) on a
#     model traced MESH_SPACING mm apart (planes and loop nodes; default 4 = CGAL's facet size: the
#     1 mm model's million triangles take thorax mesh over 10 minutes).
#   CGAL: bench/mesh3_labels.cpp (built here with g++ when libcgal-dev is installed, never by the
#     project's CMake): Labeled_mesh_domain_3 on the same voxels, facet angle 30, facet size /
#     facet distance / cell size from CGAL_CRITERIA (mm, default "4 1 8"; a fourth word `untimed`
#     lifts CGAL's default time limit on its sliver optimizers: slower, the same mesh every run),
#     cell radius-edge 3.
# For each: whole-process wall time, CPU time (user + system: the steadier figure on a shared machine)
# and peak memory (/usr/bin/time; thorax the median of RUNS runs, CGAL of CGAL_RUNS), surfaces / tetrahedra, the smallest dihedral angle (bench/tet_quality.py,
# one program for both meshes), and how far the interfaces lie from the label boundaries
# (bench/label_distance.py, one metric for both: thorax's surface nodes, CGAL's interface facets'
# vertices; the exact distance to the voxel faces between the labels on either side; mean, 95th
# percentile, max in mm). Prints figures; never passes or fails on time.
# Environment: SIZE (default 512x512x300; the body keeps its size, the voxels scale), ENDS (cut: the
# body cut flat near both ends of the volume, as a scan's field of view cuts it; closed: rounded ends,
# every tissue enclosed by the next), RUNS (3), MESH_TIMEOUT (600 s for thorax mesh), MESH_SPACING (4),
# CGAL_RUNS (1), CGAL_CRITERIA, MESH (1), THORAX_LABELS (the --label options), KEEP=1 keeps the
# work directory, MAP=FILE.nii.gz uses a map torso_labels.py wrote before (of SIZE and ENDS) instead of
# generating it.
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-build/bin/thorax}
PY=/usr/bin/python3
SIZE=${SIZE:-512x512x300}
ENDS=${ENDS:-cut}
MESH_TIMEOUT=${MESH_TIMEOUT:-600}
MESH_SPACING=${MESH_SPACING:-4}
RUNS=${RUNS:-3}
CGAL_RUNS=${CGAL_RUNS:-1}
CGAL_CRITERIA=${CGAL_CRITERIA:-4 1 8}
MESH=${MESH:-1}
# surface NAME = boundary of the union of these labels (the model's nesting: the torso is every label)
# (--holes keep: the lungs wrap around the diaphragm's dome, a hole in their planes; filled, the lung's
# surface would close over the dome, up to 9.5 mm off its label: docs/design/image.md)
THORAX_LABELS=${THORAX_LABELS:---label 1,2,3,4,5=torso:outer --label 2,3,4,5=fat:fat --label 3=lungs:lung --label 4,5=heart:heart --label 5=blood:other --holes keep}
command -v /usr/bin/time > /dev/null || { echo "needs /usr/bin/time (scripts/deps.sh)"; exit 1; }
$PY -c 'import nibabel, scipy' 2> /dev/null || { echo "needs python3-nibabel and python3-scipy"; exit 1; }
W=$(mktemp -d)
if [ "${KEEP:-0}" = 1 ]; then echo "work directory: $W"; else trap 'rm -rf "$W"' EXIT; fi

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), OMP_NUM_THREADS=${OMP_NUM_THREADS:-default}"
read -r NX NY NZ <<< "${SIZE//x/ }"
case $ENDS in
    cut) GEN=() ;;
    closed) GEN=(--closed) ;;
    *) echo "ENDS: cut or closed"; exit 1 ;;
esac
if [ -n "${MAP:-}" ]; then
    [ -f "$MAP" ] || { echo "MAP=$MAP: no such file"; exit 1; }
    echo "input: $MAP (given; made by bench/torso_labels.py), ends $ENDS"
    echo "  ($(du -k "$MAP" | cut -f1) KB)"
else
    MAP=$W/torso.nii.gz
    /usr/bin/time -f "%e %M" -o "$W/gen.time" $PY bench/torso_labels.py "${GEN[@]}" "$MAP" "$NX" "$NY" "$NZ" > "$W/gen.out"
    echo "input: $(sed "s|$W/||" "$W/gen.out"), ends $ENDS"
    echo "  ($(du -k "$MAP" | cut -f1) KB; generated in $(cut -d' ' -f1 "$W/gen.time") s)"
fi
echo

mb() { awk -v k="$1" 'BEGIN { printf "%.0f", k / 1024 }'; }
# median_run NAME RUNS CMD...: runs CMD RUNS times under /usr/bin/time; sets WALL, CPU (user + system)
# and PEAK_MB (medians, each on its own) and leaves the last run's output in $W/NAME.out; returns CMD's
# status
median_run() {
    local name=$1 n=$2
    shift 2
    : > "$W/$name.times"
    for _ in $(seq "$n"); do
        /usr/bin/time -f "%e %M %U %S" -o "$W/$name.time" "$@" > "$W/$name.out" 2>&1 || return 1
        awk '{ printf "%s %s %.2f\n", $1, $2, $3 + $4 }' "$W/$name.time" >> "$W/$name.times"
    done
    WALL=$(cut -d' ' -f1 "$W/$name.times" | sort -n | sed -n "$(( (n + 1) / 2 ))p")
    PEAK_MB=$(mb "$(cut -d' ' -f2 "$W/$name.times" | sort -n | sed -n "$(( (n + 1) / 2 ))p")")
    CPU=$(cut -d' ' -f3 "$W/$name.times" | sort -n | sed -n "$(( (n + 1) / 2 ))p")
}
row() { printf '  %-34s %8s %8s %8s   %s\n' "$@"; }

# ---- thorax ----------------------------------------------------------------------------------------
echo "thorax (median of $RUNS runs):"
row "step" "wall s" "cpu s" "peak MB" "output"
if [ ! -x "$THORAX" ]; then
    echo "  $THORAX: not built (make)"
elif ! "$THORAX" digitize --help > /dev/null 2>&1; then
    echo "  thorax digitize: not available in this build"
else
    # shellcheck disable=SC2086  # THORAX_LABELS is a list of options
    if median_run direct "$RUNS" "$THORAX" surfaces "$MAP" $THORAX_LABELS -o "$W/m" -q; then
        row "image -> surfaces (one command)" "$WALL" "$CPU" "$PEAK_MB" \
            "$($PY -c 'import json,sys; m=json.load(open(sys.argv[1])); s=m["surfaces"]; print("%d surfaces, %d nodes, %d triangles" % (len(s), sum(x["n_nodes"] for x in s), sum(x["n_tris"] for x in s)))' "$W/m/model.json")"
        echo "      target: < 10 s on 2 cores, < 2 GB (issue 25, item 6)"
    else
        echo "  thorax surfaces $(basename "$MAP"): FAILED: $(tail -2 "$W/direct.out")"
    fi
    # shellcheck disable=SC2086
    if median_run digitize "$RUNS" "$THORAX" digitize "$MAP" $THORAX_LABELS -o "$W/c.txt" -q; then
        row "digitize (image -> contours)" "$WALL" "$CPU" "$PEAK_MB" \
            "$(grep -c '^layer' "$W/c.txt") layers, $(grep -c '^loop' "$W/c.txt") loops, $(grep -cE '^-?[0-9]' "$W/c.txt") points"
        if median_run surf "$RUNS" "$THORAX" surfaces "$W/c.txt" -o "$W/mc" -q; then
            row "surfaces (contours -> surfaces)" "$WALL" "$CPU" "$PEAK_MB" ""
        else
            echo "  thorax surfaces contours: FAILED: $(tail -2 "$W/surf.out")"
        fi
    else
        echo "  thorax digitize: FAILED: $(tail -2 "$W/digitize.out")"
    fi
    if [ -f "$W/m/model.json" ]; then
        if "$THORAX" check "$W/m" -q > "$W/check.out" 2>&1; then echo "  thorax check: all surfaces pass"
        else echo "  thorax check: FAILED: $(tail -2 "$W/check.out")"; fi
        # the surfaces' label sets, from THORAX_LABELS: NAME:MODEL/NAME.pts:VALUES:rest (a part's
        # distance is to its label's boundary, all parts of the label included)
        dist_args() {
            local model=$1
            args=()
            # shellcheck disable=SC2086
            set -- $THORAX_LABELS
            while [ $# -gt 0 ]; do
                if [ "$1" = --label ]; then
                    local spec=$2 vals name
                    vals=${spec%%=*}
                    name=${spec#*=}
                    name=${name%%:*}
                    # an organ label of parts well apart gives NAME_right/NAME_left or NAME_1.. (one per part)
                    local f
                    for f in "$model/$name.pts" "$model/${name}"_right.pts "$model/${name}"_left.pts "$model/${name}"_[0-9]*.pts; do
                        [ -f "$f" ] && args+=("$(basename "$f" .pts):$f:$vals:rest")
                    done
                    shift
                fi
                shift
            done
        }
        dist_args "$W/m"
        $PY bench/label_distance.py "$MAP" "${args[@]}" > "$W/thx.dist"
        echo "  distance of the surface nodes to their label boundary (mm: points mean p95 max):"
        sed 's/^/    /' "$W/thx.dist"
        # the mesh: of a model traced MESH_SPACING mm apart (planes and nodes), CGAL's facet size
        if [ "$MESH" = 1 ]; then
            rc=0
            # shellcheck disable=SC2086
            "$THORAX" digitize "$MAP" $THORAX_LABELS --spacing "$MESH_SPACING" --node-spacing "$MESH_SPACING" \
                -o "$W/c4.txt" -q > "$W/mesh.out" 2>&1 && "$THORAX" surfaces "$W/c4.txt" -o "$W/m4" -q >> "$W/mesh.out" 2>&1 ||
                rc=$?
            [ "$rc" = 0 ] && { /usr/bin/time -f "%e %M" -o "$W/mesh.time" timeout "$MESH_TIMEOUT" \
                "$THORAX" mesh "$W/m4" -o "$W/mm" -q > "$W/mesh.out" 2>&1 || rc=$?; }
            echo "  the mesh, of a model traced $MESH_SPACING mm apart (planes and nodes):"
            if [ "$rc" = 0 ]; then
                read -r wall rss < "$W/mesh.time"
                read -r nt dmin b5 b10 remax remean < <($PY bench/tet_quality.py thorax "$W/mm")
                row "mesh (surfaces -> tetrahedra, 1 run)" "$wall" "-" "$(mb "$rss")" \
                    "$($PY -c 'import json,sys; s=json.load(open(sys.argv[1]))["surfaces"]; print("%d surface nodes;" % sum(x["n_nodes"] for x in s))' "$W/m4/model.json") $nt tetrahedra, smallest dihedral $dmin deg ($b5 < 5, $b10 < 10), radius-edge max $remax mean $remean"
                dist_args "$W/m4"
                echo "    distance of its surface nodes to their label boundary (mm: points mean p95 max):"
                $PY bench/label_distance.py "$MAP" "${args[@]}" | sed 's/^/      /'
            elif [ "$rc" = 124 ]; then
                echo "  thorax mesh: stopped after MESH_TIMEOUT=$MESH_TIMEOUT s"
            else
                echo "  thorax mesh: FAILED: $(tail -2 "$W/mesh.out")"
            fi
        fi
    fi
fi
echo

# ---- CGAL ------------------------------------------------------------------------------------------
CGAL=""
if [ -f /usr/include/CGAL/Labeled_mesh_domain_3.h ] && command -v g++ > /dev/null &&
   g++ -O3 -DNDEBUG -std=c++17 -I/usr/include/nifti bench/mesh3_labels.cpp -o "$W/m3" \
       -lnifti2 -lznz -lz -lgmp -lmpfr 2> "$W/cgal.err"; then
    CGAL="$W/m3"
fi
echo "CGAL $(dpkg-query -W -f='${Version}' libcgal-dev 2> /dev/null || echo '?') Mesh_3, labeled image (median of $CGAL_RUNS runs; sequential):"
if [ -z "$CGAL" ]; then
    echo "  not built (needs libcgal-dev, g++, libnifti-dev): $(head -3 "$W/cgal.err" 2> /dev/null)"
else
    mkdir -p "$W/cg"
    # shellcheck disable=SC2086  # CGAL_CRITERIA is three numbers
    if median_run cgal "$CGAL_RUNS" "$CGAL" "$MAP" "$W/cg" $CGAL_CRITERIA; then
        echo "  $(grep '^criteria' "$W/cgal.out" | sed 's/^criteria //; s/_/ /g') (mm, degrees)"
        row "step" "wall s" "cpu s" "peak MB" "output"
        read -r nt dmin b5 b10 remax remean < <($PY bench/tet_quality.py tetgen "$W/cg/cgal")
        row "image -> tetrahedra (whole process)" "$WALL" "$CPU" "$PEAK_MB" \
            "$nt tetrahedra, $(awk '/^vertices/ {print $2}' "$W/cgal.out") vertices, smallest dihedral $dmin deg ($b5 < 5, $b10 < 10), radius-edge max $remax mean $remean"
        echo "    in-process: read $(awk '/^read/ {print $2}' "$W/cgal.out") s, domain + make_mesh_3 $(awk '/^mesh/ {print $2}' "$W/cgal.out") s (last run); tetrahedra per label: $(grep '^tets_per_label' "$W/cgal.out" | cut -d' ' -f2-)"
        args=()
        while read -r _ a b _; do
            args+=("$a|$b:$W/cg/iface_${a}_${b}.pts:$a:$b")
        done < <(grep '^interface' "$W/cgal.out")
        echo "  distance of the interface facets' vertices to the boundary between their two labels (mm: points mean p95 max):"
        $PY bench/label_distance.py "$MAP" "${args[@]}" | sed 's/^/    /'
    else
        echo "  FAILED: $(tail -2 "$W/cgal.out")"
    fi
fi
echo
echo "distance: exact, point to the nearest voxel face between a voxel of the interface's one side and"
echo "one of its other side (thorax: the surface's labels | every other value; CGAL: label A | label B);"
echo "a smooth surface through the staircase is up to ~half a voxel off it where the boundary is oblique."
