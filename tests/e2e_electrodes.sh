#!/bin/bash
# End-to-end: the phantom's electrodes and heartbeat through the CLI.
# phantom -> surfaces -> `thorax electrodes` (12lead.txt and array.txt in
# MODEL/electrodes or -o DIR; read back independently here: every node's
# position equals its line of torso.pts; byte-identical reruns) -> `thorax
# beat` (a series whose rows are the heart's nodes, checked with `thorax
# series info`; the same values in .txt, .raw and .mat; scipy reads the .mat);
# usage errors exit 2, bad input exits 1 and writes nothing.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

fail() { echo "e2e_electrodes: FAIL: $*" >&2; exit 1; }
no_tmp() { ! find "$WORK" -name '*.tmp*' | grep -q . || fail "temporary files left: $(find "$WORK" -name '*.tmp*')"; }
expect_rc() { # CODE ARGS...: run the CLI, check its exit status
    local want=$1; shift
    set +e
    "$THORAX" "$@" >out.log 2>err.log
    local rc=$?
    set -e
    [ "$rc" -eq "$want" ] || fail "thorax $* -> exit $rc, expected $want: $(cat err.log)"
}

"$THORAX" phantom --resolution medium -o c.txt 2>/dev/null
"$THORAX" surfaces c.txt -o model >/dev/null 2>&1

# --- help and usage ---------------------------------------------------------------
"$THORAX" electrodes --help | grep -q "usage: thorax electrodes MODEL" || fail "electrodes --help"
"$THORAX" help beat | grep -q "usage: thorax beat MODEL -o FILE" || fail "help beat"
"$THORAX" help | grep -q "^  electrodes " || fail "electrodes not in the command list"
"$THORAX" help | grep -q "^  beat " || fail "beat not in the command list"
expect_rc 2 electrodes
expect_rc 2 electrodes model --array -1
expect_rc 2 electrodes model --colour red
expect_rc 2 beat model
expect_rc 2 beat model -o b.xls
grep -q "give --format" err.log || fail "no hint at --format: $(cat err.log)"
expect_rc 2 beat model -o b.txt --frames 0
expect_rc 2 beat model -o b.txt --dt -1
expect_rc 2 beat model -o b.txt --format xml
[ ! -e model/electrodes ] && [ ! -e b.txt ] && [ ! -e b.xls ] || fail "a usage error wrote something"

# --- electrodes ---------------------------------------------------------------------
"$THORAX" electrodes model > el.log
[ -f model/electrodes/12lead.txt ] && [ -f model/electrodes/array.txt ] || fail "electrode files missing"
grep -q "^V4 " el.log || fail "the 12 leads were not printed: $(cat el.log)"
head -n 3 model/electrodes/12lead.txt | tr '\n' '|' | grep -q "^thorax-electrodes 1|surface torso|count 9|$" ||
    fail "12lead.txt header: $(head -n 3 model/electrodes/12lead.txt)"
head -n 3 model/electrodes/array.txt | tr '\n' '|' | grep -q "^thorax-electrodes 1|surface torso|count 192|$" ||
    fail "array.txt header"
tail -n 1 model/electrodes/array.txt | grep -qx end || fail "array.txt does not end with 'end'"
"$THORAX" electrodes model -o el2 --array 64 -q
cmp -s model/electrodes/12lead.txt el2/12lead.txt || fail "the 12-lead set changed between runs"
grep -q "^count 64$" el2/array.txt || fail "--array 64"
"$THORAX" electrodes model -o el3 --array 0 -q
[ -f el3/12lead.txt ] && [ ! -e el3/array.txt ] || fail "--array 0 wrote an array"
"$THORAX" electrodes model -o el4 -q
cmp -s model/electrodes/array.txt el4/array.txt || fail "the array changed between runs"
no_tmp

# the files read back independently: each node's X Y Z is its line of torso.pts, names and order as documented
"$PY" - model <<'EOF' || fail "electrode files do not match the model"
import sys
model = sys.argv[1]
pts = [l.split() for l in open(f"{model}/torso.pts")]
def read(path):
    lines = [l.split('#')[0].split() for l in open(path)]
    lines = [l for l in lines if l]
    assert lines[0] == ['thorax-electrodes', '1'] and lines[1] == ['surface', 'torso'], lines[:2]
    n = int(lines[2][1])
    body = lines[3:3 + n]
    assert lines[3 + n] == ['end'] and len(lines) == 4 + n
    out = []
    for name, node, x, y, z in body:
        assert pts[int(node) - 1] == [x, y, z], (name, node, x, y, z, pts[int(node) - 1])
        out.append((name, int(node), float(x), float(y), float(z)))
    return out
e12 = read(f"{model}/electrodes/12lead.txt")
assert [e[0] for e in e12] == ['RA', 'LA', 'LL', 'V1', 'V2', 'V3', 'V4', 'V5', 'V6']
xs = [e[2] for e in e12[3:]]
assert all(a > b for a, b in zip(xs, xs[1:])), xs          # V1..V6 from the right (+x) to the left
assert all(e[3] > 0 for e in e12[3:8]), e12                 # V1..V5 anterior (+y)
arr = read(f"{model}/electrodes/array.txt")
assert [e[0] for e in arr] == ['A%03d' % (i + 1) for i in range(192)]
assert len({e[1] for e in arr}) == 192                      # distinct nodes
print("e2e_electrodes: 12lead.txt and array.txt match torso.pts")
EOF

# --- beat -----------------------------------------------------------------------------
nheart=$("$PY" -c "import json; print([s['n_nodes'] for s in json.load(open('model/model.json'))['surfaces'] if s['role'] == 'heart'][0])")
"$THORAX" beat model -o beat.txt > beat.log
grep -q "^wrote beat.txt: $nheart nodes of surface heart x 500 frames" beat.log || fail "beat output: $(cat beat.log)"
"$THORAX" series info beat.txt > info.txt
for want in "^rows *$nheart$" "^frames *500$" "^unit *mV$" "^time *0 \.\. 499 ms (step 1)$" "^label *phantom beat" \
            "^non-finite *0$"; do
    grep -q "$want" info.txt || fail "series info lacks /$want/: $(cat info.txt)"
done
# the default scale is the dipole moment (16 uA m at the QRS peak, named in the label); --peak 40
# scales the same beat linearly so that the largest |phi| on the heart is 40 mV
grep -q "^label *phantom beat: dipole 0.016 mA m at QRS peak" info.txt || fail "default dipole: $(grep label info.txt)"
"$THORAX" beat model -o beat40.txt --peak 40 -q
"$THORAX" series info beat40.txt > info40.txt
"$PY" - <<'EOF' || fail "--peak 40 is not a linear rescaling of the default beat with max |phi| 40 mV"
def rng(f):
    r = {}
    for l in open(f):
        k, _, v = l.partition(' ')
        if k in ('min', 'max'): r[k] = float(v)
    return r['min'], r['max']
def rows(f):
    return [[float(x) for x in l.split()] for l in open(f) if l[:1] in '-0123456789' and len(l.split()) > 100]
lo, hi = rng('info40.txt')
assert abs(max(-lo, hi) - 40) < 1e-9, (lo, hi)
lo1, hi1 = rng('info.txt')
k = 40 / max(-lo1, hi1)
a, b = rows('beat.txt'), rows('beat40.txt')
assert len(a) == len(b) > 0
assert max(abs(k * x - y) for ra, rb in zip(a, b) for x, y in zip(ra, rb)) < 1e-9 * 40
print("e2e_electrodes: default beat peaks at %.3f mV on the heart (16 uA m); --peak 40 is it times %.2f" % (max(-lo1, hi1), k))
EOF
"$THORAX" beat model -o beat.mat -q
"$THORAX" beat model -o beat.dat --format raw -q
"$THORAX" series convert beat.dat -o beat2.txt -q
cmp -s beat.txt beat2.txt || fail "raw and text beats differ"
"$THORAX" series convert beat.mat -o beat3.txt -q
cmp -s beat.txt beat3.txt || fail ".mat and text beats differ"
"$THORAX" beat model -o short.txt --frames 300 --dt 2 --peak 5 -q
"$THORAX" series info short.txt | grep -q "^time *0 \.\. 598 ms (step 2)$" || fail "--frames/--dt"
"$PY" - "$nheart" <<'EOF' || fail "scipy check of beat.mat"
import sys
import numpy as np
import scipy.io
n = int(sys.argv[1])
m = scipy.io.loadmat('beat.mat')
pv = m['potvals']
assert pv.shape == (n, 500) and pv.dtype == np.float64, pv.shape
top = np.abs(pv).max()
assert 1 < top < 4, top   # the 16 uA m dipole on the phantom's heart: about 2 mV (docs/decisions.md)
assert np.array_equal(m['time'][0], np.arange(500.0))
assert str(m['unit'][0]) == 'mV'
# QRS (150-240 ms) is the largest wave; baselines are zero; frame-to-frame changes are small
a = np.abs(pv)
assert a[:, 150:240].max() == a.max() and a[:, :150].max() < 0.25 * a.max() and a[:, 240:].max() < 0.5 * a.max()
assert not a[:, :11].any() and not a[:, 470:].any()
assert np.abs(np.diff(pv, axis=1)).max() < 0.1 * top
print("e2e_electrodes: scipy reads beat.mat (%d x 500, max |phi| %.3f mV)" % (n, top))
EOF

# --- failures: exit 1, nothing written ----------------------------------------------
expect_rc 1 electrodes nomodel -o el5
grep -q "nomodel" err.log || fail "missing model not named: $(cat err.log)"
[ ! -e el5 ] || fail "a failed run created el5"
"$THORAX" import -o torsoonly --up +z --front +y model/torso.pts --name torso --role outer -q >/dev/null 2>&1 || fail "import"
expect_rc 1 beat torsoonly -o nb.txt
grep -q "no heart surface" err.log || fail "beat without a heart: $(cat err.log)"
expect_rc 1 electrodes torsoonly -o nb
grep -q "no heart surface" err.log || fail "electrodes without a heart: $(cat err.log)"
[ ! -e nb.txt ] && [ ! -e nb ] && [ ! -e torsoonly/electrodes ] || fail "a failed run wrote output"
cp beat.txt keep.txt
expect_rc 1 beat torsoonly -o keep.txt
cmp -s beat.txt keep.txt || fail "a failed run changed an existing file"
# a model without an anatomical frame: both commands stop, naming the options that give one
"$THORAX" import -o noframe model/torso.pts --name torso --role outer model/heart.pts --name heart --role heart >imp.log 2>&1 ||
    fail "import without a frame"
grep -q "frame: unknown" imp.log || fail "import's summary does not say the frame is unknown: $(cat imp.log)"
grep -q '"frame"' noframe/model.json && fail "a model imported without --up/--front has a frame"
expect_rc 1 electrodes noframe -o nf
grep -q "noframe has no anatomical frame.*--up and --front to thorax import" err.log || fail "electrodes without a frame: $(cat err.log)"
expect_rc 1 beat noframe -o keep.txt
grep -q "noframe has no anatomical frame.*--up and --front" err.log || fail "beat without a frame: $(cat err.log)"
cmp -s beat.txt keep.txt && [ ! -e nf ] && [ ! -e noframe/electrodes ] || fail "a run refused for its frame wrote output"
# the phantom's model carries RAS from its contours, and the same model imported with that frame
# gives the same electrodes
grep -q '"superior":[[:space:]]*"+z"' model/model.json || fail "the phantom's model has no RAS frame"
"$THORAX" import -o ras --up +z --front +y model/torso.pts --name torso --role outer model/heart.pts --name heart --role heart -q ||
    fail "import with a frame"
"$THORAX" electrodes ras -o el_ras -q || fail "electrodes on the imported RAS model"
cmp -s el_ras/12lead.txt el4/12lead.txt || fail "the imported RAS model gives other 12-lead electrodes"
# the same torso turned (superior -> +x, anterior -> -z): the same nodes, the same beat values
"$PY" - <<'EOF2' || fail "rotated model"
import json, os
os.makedirs('rot', exist_ok=True)
man = json.load(open('ras/model.json'))
for s in man['surfaces']:
    pts = [list(map(float, l.split())) for l in open('ras/' + s['pts'])]
    # RAS (x right, y anterior, z superior) -> model axes: superior = +x, anterior = -z, so left =
    # superior x anterior = +y (a rotation: the triangles keep their orientation)
    with open('rot/' + s['pts'], 'w') as f:
        for x, y, z in pts: f.write('%.6f %.6f %.6f\n' % (z, -x, -y))
    open('rot/' + s['fac'], 'w').write(open('ras/' + s['fac']).read())
    s.pop('interior', None)
man['frame'] = {'superior': '+x', 'anterior': '-z', 'left': '+y'}
json.dump(man, open('rot/model.json', 'w'))
EOF2
"$THORAX" electrodes rot -o el_rot -q || fail "electrodes on the rotated model"
"$PY" - <<'EOF2' || fail "rotated electrodes differ"
a = [l.split()[:2] for l in open('el_ras/12lead.txt')][3:-1]
b = [l.split()[:2] for l in open('el_rot/12lead.txt')][3:-1]
assert a == b, (a, b)
EOF2
"$THORAX" beat ras -o b_ras.txt -q && "$THORAX" beat rot -o b_rot.txt -q || fail "beat on the RAS/rotated models"
"$PY" - <<'EOF2' || fail "rotated beat differs"
def rows(p):
    out = []
    for l in open(p):
        try: out.append([float(x) for x in l.split()])
        except ValueError: pass
    return [r for r in out if len(r) > 2]
a, b = rows('b_ras.txt'), rows('b_rot.txt')
assert len(a) == len(b) and all(abs(x - y) <= 1e-6 * 40 for r, q in zip(a, b) for x, y in zip(r, q)), 'values'
print('e2e_electrodes: rotated model: same 12-lead nodes, beat within 4e-5 mV')
EOF2
no_tmp
echo "e2e_electrodes: ok"
