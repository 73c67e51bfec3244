#!/usr/bin/env bash
# Conductivities end to end on the medium phantom: thorax mesh --sigma (numbers and tensors into
# model.json's table), thorax sigma (the table listed; changed in place, atomically, the mesh
# untouched; bad values and unknown names refused with the model unchanged), and the forward
# solver seeing the new table: every conductivity scaled by k leaves the body-surface potentials
# of the epicardial (potential) problem unchanged, while a change of the lungs' alone changes
# them. The potentials are compared by scipy reading thorax's .mat output.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
PY=/usr/bin/python3
fail() { echo "FAIL: $*"; exit 1; }
# region NAME's "sigma" in DIR/model.json, as JSON
sigma_of() { $PY -c "import json,sys; print(json.dumps([r['sigma'] for r in json.load(open(sys.argv[1]+'/model.json'))['regions'] if r['name']==sys.argv[2]][0]))" "$1" "$2"; }
# whether region NAME's conductivity in DIR/model.json is the tensor EXPECTED (JSON, 3x3) exactly
sigma_is() { $PY -c "import json,sys; r=[r['sigma'] for r in json.load(open(sys.argv[1]+'/model.json'))['regions'] if r['name']==sys.argv[2]][0]; sys.exit(0 if r==json.loads(sys.argv[3]) else 1)" "$1" "$2" "$3"; }

"$THORAX" phantom --resolution medium --seed 1 -o c.txt -q
"$THORAX" surfaces c.txt -o model -q

# 1. thorax mesh --sigma: refused before anything is written when the value is bad (usage, 2) or
#    the name unknown (1, with the nearest name); else in the table with its source
for bad in "lung_l=-0.1" "lung_l=0.1,0.1" "lung_l=1,1,1,2,0,0" "lung_l" "=0.1"; do
    set +e; "$THORAX" mesh model -o bad --no-heart --sigma "$bad" -q 2> err.log; rc=$?; set -e
    [ $rc = 2 ] || fail "mesh --sigma $bad: exit $rc, not 2"
    [ ! -e bad ] || fail "mesh --sigma $bad: output written"
    echo "refused (mesh --sigma $bad): $(head -1 err.log)"
done
set +e; "$THORAX" mesh model -o bad --no-heart --sigma lungl=0.1 -q 2> err.log; rc=$?; set -e
[ $rc = 1 ] && [ ! -e bad ] || fail "mesh --sigma lungl: exit $rc"
grep -q 'did you mean lung_l' err.log || fail "mesh --sigma lungl: no suggestion: $(cat err.log)"
"$THORAX" mesh model --no-heart --sigma lung_l=0.11 --sigma muscle=0.05,0.06,0.5,0.01,0,0 -q
[ "$(sigma_of model lung_l)" = "0.11" ] || fail "lung_l: $(sigma_of model lung_l)"
sigma_is model muscle "[[0.05, 0.01, 0], [0.01, 0.06, 0], [0, 0, 0.5]]" || fail "muscle: $(sigma_of model muscle)"
grep -q 'thorax mesh --sigma' model/model.json || fail "source of --sigma"
[ "$(sigma_of model lung_r)" = "0.05" ] || fail "lung_r default"

# 2. thorax sigma: the listing; refusals leave the model as it was; a change rewrites model.json only
"$THORAX" sigma model > list.txt
grep -q '^lung_l  *0.11 ' list.txt && grep -q '^muscle  *0.05,0.06,0.5,0.01,0,0 ' list.txt || fail "listing: $(cat list.txt)"
cp -r model keep
for bad in "lungl=0.2" "lung_l=0" "lung_l=nan" "lung_l=1,2" "lung_l=abc" "lung_l"; do
    set +e; "$THORAX" sigma model "$bad" -q > /dev/null 2> err.log; rc=$?; set -e
    [ $rc != 0 ] || fail "sigma $bad accepted"
    diff -r model keep > /dev/null || fail "sigma $bad changed the model"
    echo "refused (sigma $bad): $(head -1 err.log)"
done
grep -q 'did you mean lung_l' <("$THORAX" sigma model lungl=1 2>&1) || fail "no suggestion"
"$THORAX" sigma model lung_l=0.05 muscle=0.04,0.04,0.4 -q
[ "$(sigma_of model lung_l)" = "0.05" ] || fail "sigma lung_l"
sigma_is model muscle "[[0.04, 0, 0], [0, 0.04, 0], [0, 0, 0.4]]" || fail "sigma muscle"
for f in volume.pts volume.tet torso.pts torso.fac lung_l.vmap; do cmp -s model/$f keep/$f || fail "$f changed"; done
"$THORAX" check model -q || fail "the changed model fails thorax check"

# 3. the forward solver reads the table: scaled by 3 -> the same potentials; lungs changed -> not
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw --frames 6 --dt 40 -q
"$THORAX" forward model --epicardial beat.raw -o sol0 --format mat -q
"$THORAX" sigma model --scale 3 -q
grep -q 'scaled by 3' model/model.json || fail "scale not recorded"
"$THORAX" forward model --epicardial beat.raw -o sol1 --format mat -q
"$THORAX" sigma model --scale 0.3333333333333333 lung_l=0.5 lung_r=0.5 -q
"$THORAX" forward model --epicardial beat.raw -o sol2 --format mat -q
$PY - <<'PYEOF'
import scipy.io as sio, numpy as np
a, b, c = (sio.loadmat(f'sol{k}/torso.mat')['potvals'] for k in range(3))
peak = np.abs(a).max()
d_scaled, d_lungs = np.abs(b - a).max() / peak, np.abs(c - a).max() / peak
print(f"body surface, {a.shape[0]} nodes x {a.shape[1]} frames, peak {peak:.3f} mV: "
      f"all sigma x3 -> max change {d_scaled:.2e} of the peak; lungs 0.05 -> 0.5 S/m -> {d_lungs:.3f} of the peak")
assert d_scaled < 1e-8, d_scaled
assert d_lungs > 0.01, d_lungs
PYEOF
echo "e2e_sigma: ok"
