#!/usr/bin/env bash
# End-to-end: thorax export --solution / --data (exports with data), read back by VTK and Gmsh
# themselves (tests/export_data_read.py: every potential compared with the series, the currents
# with -sigma grad(phi) computed by numpy from the points and model.json's tensors, the .pvd's
# times with the series', the msh's tagged surfaces against each surface's area and volume).
#  1. the medium phantom: a forward solution with volume potentials as vtu (frames 1:6:2), vtp,
#     vtk (frames 2,4), msh; a torso-only solution as vtp (torso and heart); --data of a volume
#     series; output byte-identical twice; every refusal leaves nothing written.
#  2. real files: the Dalhousie torso and epicardium (map3d geom/torso) imported with thorax
#     import and meshed; the six dipole2_00N.pot torso maps assembled into one series (times
#     0..5), exported as vtp, vtk and msh; one .pot read directly; a forward solution on the real
#     geometry (an epicardial series made here) as vtu with currents, and a defibrillation one.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
CHK="$SRC/tests/export_data_read.py"
DATA="$SRC/../shared/data/map3d"
fail() { echo "e2e_export_data: FAIL: $*" >&2; exit 1; }
# each export is read back at the end, all in one Python process (VTK imported and each model read
# once; the outputs are not touched after their read_back line)
read_back() { echo "$*" >> "$WORK/jobs.txt"; }
refused() { # RC WHAT PATTERN CMD... : exit RC, message matching PATTERN
    local want=$1 what=$2 pat=$3; shift 3
    set +e
    "$@" > out.log 2> err.log
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || fail "$what: exit $rc, expected $want ($(cat err.log))"
    grep -q -- "$pat" err.log || fail "$what: message does not say '$pat': $(cat err.log)"
    echo "refused ($what): $(head -1 err.log)"
}

# ---- 1. the phantom
# the medium phantom meshed without the heart (tests/medium_phantom.sh)
. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 6 --dt 40 -q
"$THORAX" forward model --epicardial beat.raw -o sol -q --volume
"$THORAX" forward model --epicardial beat.raw -o solt -q

"$THORAX" export model --solution sol --format vtu --frames 1:6:2 -o out/vtu -q
ls out/vtu | tr '\n' ' ' | grep -qx "volume.pvd volume_0001.vtu volume_0003.vtu volume_0005.vtu " || fail "vtu files: $(ls out/vtu)"
read_back model sol/volume.raw volume out/vtu vtu 1,3,5 noheart
"$THORAX" export model --solution sol --format vtp -o out/vtp -q
[ "$(ls out/vtp | wc -l)" -eq $((6 * 7)) ] || fail "vtp: 6 surfaces x (6 frames + .pvd) expected: $(ls out/vtp)"
read_back model sol/volume.raw volume out/vtp vtp
"$THORAX" export model --solution sol --format vtk --frames 2,4 -o out/vtk -q
read_back model sol/volume.raw volume out/vtk vtk 2,4
"$THORAX" export model --solution sol --format msh -o out/msh -q
read_back model sol/volume.raw volume out/msh msh
# the torso-only solution: the torso's series and the heart's (the epicardial input)
"$THORAX" export model --solution solt --format vtp -o out/t -q
ls out/t | tr '\n' ' ' | grep -qx "heart.pvd heart_0001.vtp.*torso_0006.vtp " || fail "torso-only: $(ls out/t)"
read_back model solt/torso.raw surface:torso out/t vtp
read_back model beat.raw surface:heart out/t vtp
"$THORAX" export model --solution solt --format msh -o out/tm -q
read_back model solt/torso.raw surface:torso out/tm msh
read_back model beat.raw surface:heart out/tm msh
# --data: the volume series itself; the same files as --solution's, and written again alike
"$THORAX" export model --data sol/volume.raw --format vtu --frames 1:6:2 -o out/d -q
for f in volume.pvd volume_0001.vtu volume_0005.vtu; do cmp -s out/vtu/$f out/d/$f || fail "--data and --solution differ: $f"; done
"$THORAX" export model --data sol/volume.raw --format vtu --frames 1:6:2 -o out/d -q
cmp -s out/vtu/volume_0003.vtu out/d/volume_0003.vtu || fail "a second export differs"
# nested -o directories are created
"$THORAX" export model --data beat.raw --surface heart --format vtp -o out/a/b/c -q
[ -s out/a/b/c/heart.pvd ] || fail "nested -o"

# refusals: exit status, a message naming the file, nothing written
printf 'thorax-series 1\nrows 7\nframes 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\n1 2\nend\n' > seven.txt
refused 1 "rows match nothing" "seven.txt: 7 rows match no node set" "$THORAX" export model --data seven.txt --format vtp -o out/no
refused 1 "surface data as vtu" "not on the volume's nodes" "$THORAX" export model --data beat.raw --format vtu -o out/no
refused 2 "no -o" "need -o DIR" "$THORAX" export model --data beat.raw --format vtp
refused 2 "bad --frames" "--frames '0:3'" "$THORAX" export model --data beat.raw --format vtp --frames 0:3 -o out/no
refused 2 "--frames alone" "--frames goes with" "$THORAX" export model --format vtp --frames 1 -o out/no
refused 2 "obj with data" "not 'obj'" "$THORAX" export model --data beat.raw --format obj -o out/no
refused 1 "not a solution" "not a thorax solution\|solution.json" "$THORAX" export model --solution model --format vtp -o out/no
[ ! -e out/no ] || fail "a refused export wrote out/no"
# a file thorax did not write is never replaced, and then nothing else is written either
mkdir -p out/mine && echo "my notes" > out/mine/volume_0002.vtu
refused 1 "foreign file" "volume_0002.vtu" "$THORAX" export model --solution sol --format vtu -o out/mine
[ "$(cat out/mine/volume_0002.vtu)" = "my notes" ] && [ "$(ls out/mine)" = "volume_0002.vtu" ] || fail "out/mine touched: $(ls out/mine)"
ls out/* | grep -q tmp && fail "temporary files left"

# ---- 2. real files: the Dalhousie torso (map3d)
G="$DATA/geom/torso"
"$THORAX" import -o dal "$G/daltorso.pts" --name torso --role outer "$G/dalepi.pts" --name heart --role heart -q
"$THORAX" mesh dal --grid 25 --no-heart -q
# the six dipole maps as one series (one frame per file, times 0..5) in thorax's text format
"$PY" - "$DATA/data/torso" <<'EOF'
import sys, numpy as np
v = np.column_stack([np.loadtxt("%s/dipole2_%03d.pot" % (sys.argv[1], k)).ravel() for k in range(1, 7)])
assert v.shape == (352, 6), v.shape
with open("dipole2.txt", "w") as f:
    f.write("thorax-series 1\nrows 352\nframes 6\nlabel map3d dipole2_001..006.pot\ntime 0 1 2 3 4 5\n")
    for row in v:
        f.write(" ".join(repr(float(x)) for x in row) + "\n")
    f.write("end\n")
EOF
"$THORAX" series convert dipole2.txt -o dipole2.raw -q
for fmt in vtp vtk msh; do
    "$THORAX" export dal --data dipole2.txt --format $fmt -o dout/$fmt -q
    read_back dal dipole2.raw surface:torso dout/$fmt $fmt
done
# one .pot, as thorax series reads it (one frame at time 0)
"$THORAX" export dal --data "$DATA/data/torso/dipole2_004.pot" --format vtp -o dout/pot -q
"$THORAX" series convert "$DATA/data/torso/dipole2_004.pot" -o pot4.raw -q
read_back dal pot4.raw surface:torso dout/pot vtp
# a forward solution on the real geometry: an epicardial series made here (linear in x, y, z)
"$PY" - "$G/dalepi.pts" <<'EOF'
import sys, numpy as np
x = np.loadtxt(sys.argv[1]); d = x - x.mean(axis=0)
with open("epi3.txt", "w") as f:
    f.write("thorax-series 1\nrows %d\nframes 3\nunit mV\ntime 0 2.5 5\n" % len(x))
    for p in d:
        f.write("%r %r %r\n" % (p[0] / 10, p[1] / 10, (p[0] + p[2]) / 10))
    f.write("end\n")
EOF
"$THORAX" forward dal --epicardial epi3.txt --volume -o dsol -q
"$THORAX" export dal --solution dsol --format vtu -o dout/vtu -q
read_back dal dsol/volume.raw volume dout/vtu vtu all noheart
"$THORAX" export dal --solution dsol --format msh -o dout/msh3 -q
read_back dal dsol/volume.raw volume dout/msh3 msh
# a defibrillation solution (volts, every region conducts): two pads on the real torso
"$THORAX" forward dal -o dfb -q --electrode "a,at=-200:300:0,radius=60,voltage=1" \
    --electrode "b,at=200:300:0,radius=60,voltage=0"
"$THORAX" export dal --solution dfb --format vtu -o dout/dfb -q
read_back dal dfb/volume.raw volume dout/dfb vtu all all
# a solution of another model, and a series whose rows are not the named surface's
refused 1 "another model's solution" "sol/volume.raw: [0-9]* rows, but the model.s volume mesh has" \
    "$THORAX" export dal --solution sol --format vtu -o dout/no
refused 1 "rows of another surface" "among the --surface names" \
    "$THORAX" export model --data beat.raw --surface torso --format vtp -o dout/no
[ ! -e dout/no ] || fail "a refused export wrote dout/no"
"$PY" "$CHK" --jobs "$WORK/jobs.txt" > chk.log 2>&1 || { grep -v '^ok' chk.log >&2; fail "read back"; }
grep '^== \|checks passed\|jobs passed' chk.log
[ "$(grep -c '^== ' chk.log)" -eq 15 ] || fail "read back: $(grep -c '^== ' chk.log) jobs, 15 expected"
echo "e2e_export_data: ok"
