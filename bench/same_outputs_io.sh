#!/bin/bash
# Same outputs before and after, io family by io family (issue 25, item 7: src/io split by family,
# docs/design/io.md, "io by family"). bench/same_outputs.sh compares the demo's outputs; this one runs
# a fixed set of commands that goes through every io family (every surface and volume format in,
# every series format in and out, every export, the model directory, map3d's files), with two thorax
# builds, each in a directory of its own, and compares every file written (and every command's
# stdout, stderr and exit status) byte for byte with cmp, printing each comparison.
#
#   bash bench/same_outputs_io.sh [BEFORE_COMMIT]      default 6584983 (the last commit with src/io flat)
#
# BEFORE: `git archive BEFORE_COMMIT` built in a temporary directory (the library and the CLI only,
# RelWithDebInfo; a few minutes), or BEFORE_BUILD=DIR, a build directory of it (DIR/bin/thorax,
# DIR/libthorax.so*). AFTER: AFTER_BUILD=DIR, default build/ of this tree (built already).
# MAP3D=DIR overrides ../shared/data/map3d. KEEP=1 keeps the temporary directory.
# Exit 0 when every file is the same, 1 on any difference (each named), 2 on a setup failure.
# A command that fails is not a setup failure: its exit status and message are compared files.
#
# The families and what exercises them:
#   map3d    .pts/.fac (Utah tank, Dalhousie torso, FwdInvToolkit), .geom (a surface of each file,
#            and a refusal), .tsdf, .pot, .leadlinks and .channels, .lmarks (render --landmarks)
#   surface  import of .pts/.fac, .geom, ECGSim .tri, and of STL/OBJ/PLY/VTK/VTP written by thorax's
#            exports and by VTK itself (legacy ASCII and binary, STL ASCII and binary, PLY binary)
#   volume   import of the phantom's volume as thorax wrote it (.vtu, .msh, volume.pts + .tet) and as
#            VTK rewrote it (legacy .vtk ASCII and binary, .vtu appended raw and zlib)
#   series   convert between text, raw, .mat and CSV; .tsdf, .pot, a numbered .pot set, a folder of
#            them, a map3d .mat recording, a plain matrix; info, with .fids
#   export   stl, obj, ply, vtk, vtp of surfaces; vtu, msh of the volume; solutions and data
#   model    phantom contours, surfaces -> model directory, mesh -> volume files, check, electrodes,
#            beat, forward (solution.json and its series), leads, OpenMEEG dipoles
set -uo pipefail

SRC=$(cd "$(dirname "$0")/.." && pwd)
BEFORE=${1:-6584983}
AFTER_BUILD=${AFTER_BUILD:-$SRC/build}
D=${MAP3D:-$SRC/../shared/data/map3d}
[ -d "$D/geom/tank" ] || { echo "same_outputs_io: no map3d data in $D (MAP3D=DIR)" >&2; exit 2; }
D=$(cd "$D" && pwd)
[ -x "$AFTER_BUILD/bin/thorax" ] || { echo "same_outputs_io: no $AFTER_BUILD/bin/thorax (build first)" >&2; exit 2; }
AFTER_BUILD=$(cd "$AFTER_BUILD" && pwd)
PY=/usr/bin/python3
TMP=$(mktemp -d /tmp/thorax-same-io.XXXXXX)
if [ -n "${KEEP:-}" ]; then echo "same_outputs_io: keeping $TMP"; else trap 'rm -rf "$TMP"' EXIT; fi

if [ -z "${BEFORE_BUILD:-}" ]; then
    echo "same_outputs_io: building $BEFORE in $TMP/before-build"
    mkdir -p "$TMP/before-src"
    git -C "$SRC" archive "$BEFORE" | tar -x -C "$TMP/before-src" ||
        { echo "same_outputs_io: git archive $BEFORE failed" >&2; exit 2; }
    { cmake -S "$TMP/before-src" -B "$TMP/before-build" -DCMAKE_BUILD_TYPE=RelWithDebInfo &&
        nice cmake --build "$TMP/before-build" -j "${JOBS:-2}" --target thorax_cli; } > "$TMP/before-build.log" 2>&1 ||
        { tail -20 "$TMP/before-build.log" >&2; echo "same_outputs_io: building $BEFORE failed" >&2; exit 2; }
    BEFORE_BUILD=$TMP/before-build
fi
BEFORE_BUILD=$(cd "$BEFORE_BUILD" && pwd)
echo "same_outputs_io: before = $BEFORE_BUILD/bin/thorax ($BEFORE), after = $AFTER_BUILD/bin/thorax"

# Inputs written by VTK itself, once, read by both runs: the Utah tank from its .pts/.fac.
mkdir -p "$TMP/in"
"$PY" - "$D/geom/tank/tank_full_771.pts" "$D/geom/tank/tank_full_771.fac" "$TMP/in" <<'EOF' ||
import sys, numpy as np, vtk
from vtk.util.numpy_support import numpy_to_vtk, numpy_to_vtkIdTypeArray
P = np.loadtxt(sys.argv[1]); F = np.loadtxt(sys.argv[2], dtype=np.int64) - 1
pd = vtk.vtkPolyData(); pts = vtk.vtkPoints(); pts.SetData(numpy_to_vtk(P.copy(), deep=True)); pd.SetPoints(pts)
cells = vtk.vtkCellArray()
cells.SetData(numpy_to_vtkIdTypeArray(np.arange(0, 3 * len(F) + 1, 3, dtype=np.int64), deep=True),
              numpy_to_vtkIdTypeArray(F.ravel().copy(), deep=True))
pd.SetPolys(cells)
for name, w, binary in (("vtk_ascii.vtk", vtk.vtkPolyDataWriter(), False), ("vtk_binary.vtk", vtk.vtkPolyDataWriter(), True),
                        ("vtk_ascii.stl", vtk.vtkSTLWriter(), False), ("vtk_binary.stl", vtk.vtkSTLWriter(), True),
                        ("vtk_binary.ply", vtk.vtkPLYWriter(), True)):
    w.SetInputData(pd); w.SetFileName(sys.argv[3] + "/" + name)
    w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII()
    w.Write()
EOF
    { echo "same_outputs_io: writing the VTK inputs failed" >&2; exit 2; }

# Volume files rewritten by VTK from a run's own .vtu (in that run's directory).
vtk_volumes() {
    "$PY" - out_vol/volume.vtu <<'EOF'
import sys, vtk
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(sys.argv[1]); r.Update()
g = r.GetOutput()
for name, binary in (("vtkvol_ascii.vtk", False), ("vtkvol_binary.vtk", True)):
    w = vtk.vtkUnstructuredGridWriter(); w.SetInputData(g); w.SetFileName(name)
    w.SetFileTypeToBinary() if binary else w.SetFileTypeToASCII(); w.Write()
for name, zlib in (("vtkvol_raw.vtu", False), ("vtkvol_zlib.vtu", True)):
    w = vtk.vtkXMLUnstructuredGridWriter(); w.SetInputData(g); w.SetFileName(name)
    w.SetDataModeToAppended(); w.EncodeAppendedDataOff()
    w.SetCompressorTypeToZLib() if zlib else w.SetCompressorTypeToNone(); w.Write()
EOF
}

# One thorax command with $BIN (its own build's library): NAME ARGS...; stdout, stderr and the exit
# status go to log/NNN_NAME.{out,err,rc}.
t() {
    local name=$1; shift
    n=$((n + 1))
    local base; base=log/$(printf %03d $n)_$name
    LD_LIBRARY_PATH="$LIB" "$BIN" "$@" > "$base.out" 2> "$base.err"
    echo $? > "$base.rc"
}
commands() {
    mkdir -p log
    local G=$D/geom I=$TMP/in T=$D/data/torso K=$D/data/tank
    # --- map3d and surface: every surface format in
    t imp_ptsfac import -q -o s_tank "$G/tank/tank_full_771.pts" --name tank --role outer \
        "$G/tank/25feb97_sock_closed.pts" --name sock --role heart
    t imp_dal import -q -o s_dal "$G/torso/daltorso.pts" --name torso --role outer
    t imp_geom import -q -o s_geom --up -y --front -z "$G/torso/daltorsoepi.geom@1" --name torso --role outer \
        "$G/torso/daltorsoepi.geom@2" --name heart --role heart
    t imp_geom1 import -q -o s_geom1 "$G/tank/25feb97_sock_closed.geom" --name sock --role heart
    t imp_geom_bad import -q -o s_geom_bad "$G/torso/daltorsoepi.geom" --name t --role outer
    t imp_tri import -q -o s_tri --scale 1000 "$SRC/tests/data/ecgsim/thorax.tri" --name torso --role outer \
        "$SRC/tests/data/ecgsim/heart.tri" --name heart --role heart
    t imp_fwdinv import -q -o s_fwdinv "$SRC/tests/data/fwdinv/torso_closed.pts" --name torso --role outer \
        "$SRC/tests/data/fwdinv/heart_closed.pts" --name heart --role heart
    t imp_open import -q -o s_open "$G/tank/tank_leads_192.pts" --name leads --role outer
    for f in vtk_ascii.vtk vtk_binary.vtk vtk_ascii.stl vtk_binary.stl vtk_binary.ply; do
        t "imp_${f/./_}" import -q -o "s_${f/./_}" "$I/$f" --name tank --role outer
    done
    # --- export: every surface format out, and in again
    for fmt in stl obj ply vtk vtp; do
        t "exp_$fmt" export s_tank --format "$fmt" -o "e_$fmt" -q
        t "reimp_$fmt" import -q -o "r_$fmt" "e_$fmt/tank.$fmt" --name tank --role outer "e_$fmt/sock.$fmt" --name sock --role heart
    done
    # --- model: the phantom's pipeline (contours, model directory, volume, series, solution)
    t phantom phantom --resolution medium --seed 1 -o c.txt -q
    t surfaces surfaces c.txt -o model -q
    t mesh mesh model --no-heart -q
    t check check model
    t electrodes electrodes model -q
    t electrodes_64 electrodes model -o el --array 64 -q
    t beat beat model -o beat.raw --frames 6 --dt 40 -q
    t forward forward model --epicardial beat.raw -o sol -q --volume
    t forward_t forward model --epicardial beat.raw -o solt -q --format mat
    t leads_sol leads sol -q
    # OpenMEEG dipoles at the centroids of two of the volume's tetrahedra
    for k in 1000 5000; do
        read -r a b c d _ < <(sed -n ${k}p model/volume.tet)
        awk -v a="$a" -v b="$b" -v c="$c" -v d="$d" 'NR == a || NR == b || NR == c || NR == d { x += $1; y += $2; z += $3 }
            END { printf "%.3f %.3f %.3f 0 0.001 0.001\n", x / 4, y / 4, z / 4 }' model/volume.pts
    done > d.dip
    t forward_dip forward model --dipoles d.dip --rows model/electrodes/array.txt -o dsol -q --format text
    # --- export: the volume, the solutions and a series on the volume
    t exp_vtu export model --format vtu -o out_vol -q
    t exp_msh export model --format msh -o out_vol -q
    t exp_sol_vtu export model --solution sol --format vtu --frames 1:6:2 -o out/vtu -q
    t exp_sol_vtp export model --solution sol --format vtp -o out/vtp -q
    t exp_sol_vtk export model --solution sol --format vtk --frames 2,4 -o out/vtk -q
    t exp_sol_msh export model --solution sol --format msh -o out/msh -q
    t exp_solt_vtp export model --solution solt --format vtp -o out/t -q
    t exp_data_vtu export model --data sol/volume.raw --format vtu --frames 1:6:2 -o out/d -q
    # --- volume: every volume format in
    vtk_volumes > log/vtk_volumes.log 2>&1
    t vimp_vtu import -q -o v_vtu out_vol/volume.vtu
    t vimp_msh import -q -o v_msh out_vol/volume.msh --force
    t vimp_pts import -q -o v_pts model/volume.pts
    awk 'NR == FNR { n++; next } FNR == 1 { print n } { print }' model/volume.pts model/volume.pts > carp.pts
    awk 'NR == FNR { n++; next } FNR == 1 { print n } { print "Tt", $1 - 1, $2 - 1, $3 - 1, $4 - 1, $5 }' \
        model/volume.tet model/volume.tet > carp.elem
    t vimp_carp import -q -o v_carp carp.pts
    for f in vtkvol_ascii.vtk vtkvol_binary.vtk vtkvol_raw.vtu vtkvol_zlib.vtu; do
        t "vimp_${f/./_}" import -q -o "v_${f/./_}" "$f"
    done
    t vcheck check v_vtu
    # --- series and recordings: every format in and out
    t s_tsdf_txt series convert -q "$T/dipole2.tsdf" -o dipole2.txt
    t s_tsdf_mat series convert -q "$T/dipole2.tsdf" -o dipole2.mat
    t s_tsdf_csv series convert -q "$T/dipole2.tsdf" -o dipole2.csv
    t s_tsdf_raw series convert -q "$T/dipole2.tsdf" -o dipole2.raw
    t s_epi_raw series convert -q "$T/p2_3200_77_epi.tsdf" -o epi.raw
    t s_pot_raw series convert -q "$T/dipole2_004.pot" -o pot4.raw
    t s_potset series convert -q "$T/dipole2_%03d.pot" -o set.mat
    t s_potdir series convert -q "$T" -o dir.mat
    t s_cool_tsdf series convert -q "$K/cool1-atdr-run1.tsdf" -o cool1.mat
    t s_cool_mat series convert -q "$K/cool1-atdr-run1.mat" -o cool1.txt
    t s_txt_mat series convert -q dipole2.txt -o d2.mat
    t s_mat_raw series convert -q d2.mat -o d2.raw
    t s_raw_txt series convert -q d2.raw -o d2.txt
    t s_csv_mat series convert -q dipole2.csv -o d3.mat
    t s_beat_txt series convert -q beat.raw -o beat.txt
    t s_beat_dat series convert -q beat.raw -o beat.dat --format raw
    t s_info_tsdf series info "$T/dipole2.tsdf"
    t s_info_cool series info "$K/cool1-atdr-run1.tsdf"
    t s_info_mat series info "$K/cool1-atdr-run1.mat"
    t s_info_txt series info beat.txt
    "$PY" -c 'import numpy as np; np.savetxt("m.txt", np.loadtxt("dipole2.csv", delimiter=",", skiprows=1, usecols=range(1, 7)))' \
        > log/matrix.log 2>&1
    t s_matrix series convert -q m.txt --transpose -o m.mat
    { echo "1"; echo "1 -1"; echo "352 act rec"; for i in $(seq 1 352); do echo "$i $((i % 6 + 1)) 6"; done; } > d.fids
    t s_fids series info "$T/dipole2.tsdf" --fids d.fids
    # --- map3d: lead links, channels, landmarks
    t leads_ll leads s_dal --data "$T/dipole2_001.pot" --array "$G/torso/daltorso.leadlinks" -o l_ll
    t leads_ll_mat leads s_dal --data "$T/dipole2_001.pot" --array "$G/torso/daltorso.leadlinks" -o l_llm -q --format mat
    seq 1 7 350 > nodes.txt
    awk 'NR % 9 == 1' "$G/torso/daltorso.pts" > positions.txt
    t leads_nodes leads s_dal --data "$T/dipole2_001.pot" --array nodes.txt -o l_nodes -q
    t leads_pos leads s_dal --data "$T/dipole2_001.pot" --array positions.txt -o l_pos
    t s_channels series info "$K/cool1-atdr-run1.tsdf" --channels "$G/tank/sock128.channels"
    t render_lm render s_geom1 --surface sock=flat:1:#808080 --landmarks "$G/tank/25feb97_sock.lmarks" --up +z --front +y --size 160x120 -o lm.png -q
}

# Both runs in one directory ($TMP/run, renamed after each) and through one path to the program
# ($TMP/bin/thorax, a link to the side's), since model.json and solution.json record the command
# line and absolute paths.
mkdir -p "$TMP/bin"
BIN=$TMP/bin/thorax
for side in before after; do
    if [ $side = before ]; then ln -sfn "$BEFORE_BUILD/bin/thorax" "$BIN"; LIB=$BEFORE_BUILD
    else ln -sfn "$AFTER_BUILD/bin/thorax" "$BIN"; LIB=$AFTER_BUILD; fi
    mkdir -p "$TMP/run"
    t0=$(date +%s)
    cd "$TMP/run" || exit 2
    n=0
    commands
    cd "$TMP" && mv run "$side" || exit 2
    echo "same_outputs_io: $side: $n commands in $(( $(date +%s) - t0 )) s"
done
cd "$TMP" || exit 2

# Compare: the same list of files, each the same bytes.
status=0
(cd before && find . -type f | LC_ALL=C sort) > list.before
(cd after && find . -type f | LC_ALL=C sort) > list.after
if ! cmp -s list.before list.after; then
    echo "DIFFERENT  the lists of files:"; diff list.before list.after | sed 's/^/  /'
    status=1
fi
same=0 differ=0
while read -r f; do
    [ -f "after/$f" ] || continue
    if cmp -s "before/$f" "after/$f"; then
        echo "same       ${f#./}"; same=$((same + 1))
    elif [ "${f##*/}" = solution.json ] &&
        cmp -s <(grep -v '"seconds_[a-z]*":' "before/$f") <(grep -v '"seconds_[a-z]*":' "after/$f"); then
        # the solver's timings (seconds_assembly, _setup, _matrix, _solve, _total) differ from run to run
        echo "same       ${f#./} (but its \"seconds_*\" timings)"; same=$((same + 1))
    else
        echo "DIFFERENT  ${f#./}: $(cmp "before/$f" "after/$f" 2>&1 | head -1)"; differ=$((differ + 1)); status=1
    fi
done < list.before
failed=$(grep -Lx 0 after/log/*.rc | sed 's|.*/||; s|\.rc$||' | tr '\n' ' ')
echo "same_outputs_io: $same files the same, $differ different ($(wc -l < list.before) files before, $(wc -l < list.after) after);" \
     "commands exiting non-zero: ${failed:-none}"
exit $status
