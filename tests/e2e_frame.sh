#!/usr/bin/env bash
# The anatomical frame belongs to the model (issue 11, item 7). The Dalhousie torso (map3d; long
# axis y, head at -y, anterior -z, the subject's left +x) imported with --up -y --front -z:
#  - model.json records the frame; a model imported without it has none and is refused by
#    electrodes, beat and render's named views, naming --up/--front; import's usage errors;
#  - thorax electrodes: V1-V6 on six distinct nodes, in order from the right of the sternum around
#    the left anterior chest (V1-V4 on the front, V6 at the side), at the heart's height; RA and LA
#    high on the right and left, LL low on the left;
#  - thorax beat: the dipole fitted to its potentials at the QRS peak points left and inferior in
#    the model's frame, and is the phantom's dipole (RAS) carried through the frame;
#  - thorax render: the default (anterior) view of the framed model is the view given by --up -y
#    --front -z on the frameless one, and the views differ from the frameless default (+z, +y).
# Skipped (with a message) when ../shared/data is not beside the checkout.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
G=$DATA/map3d/geom/torso
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fail() { echo "e2e_frame: FAIL: $*" >&2; exit 1; }
if [ ! -f "$G/daltorso.pts" ]; then echo "skip: $G not found (the Dalhousie torso)"; exit 0; fi

# import: the frame's options
set +e
"$THORAX" import -o x --up -y "$G/daltorso.pts" --name torso --role outer 2>err.txt; rc=$?
[ $rc -eq 2 ] && grep -q -- "--up needs --front" err.txt || fail "--up alone: exit $rc $(cat err.txt)"
"$THORAX" import -o x --up -y --front +w "$G/daltorso.pts" --name torso --role outer 2>err.txt; rc=$?
[ $rc -eq 2 ] && grep -q 'anterior axis "+w"' err.txt || fail "--front +w: exit $rc $(cat err.txt)"
"$THORAX" import -o x --up -y --front +y "$G/daltorso.pts" --name torso --role outer 2>err.txt; rc=$?
[ $rc -eq 2 ] && grep -q "must be different axes" err.txt || fail "--up -y --front +y: exit $rc $(cat err.txt)"
[ ! -e x ] || fail "a refused import wrote x"
set -e
"$THORAX" import -o dal --up -y --front -z "$G/daltorso.pts" --name torso --role outer "$G/dalepi.pts" --name epicardium \
    --role heart >imp.txt
grep -q "^frame: superior -y, anterior -z, left +x" imp.txt || fail "import summary: $(cat imp.txt)"
"$PY" -c "
import json; f = json.load(open('dal/model.json'))['frame']
assert f == {'superior': '-y', 'anterior': '-z', 'left': '+x'}, f" || fail "model.json frame"
"$THORAX" import -o dal_nf -q "$G/daltorso.pts" --name torso --role outer "$G/dalepi.pts" --name epicardium --role heart
for c in "electrodes dal_nf -o el_nf" "beat dal_nf -o nf.txt" "render dal_nf -o nf.png"; do
    set +e
    "$THORAX" $c 2>err.txt; rc=$?
    set -e
    [ $rc -eq 1 ] && grep -q "dal_nf has no anatomical frame.*--up and --front" err.txt || fail "$c: exit $rc: $(cat err.txt)"
done
[ ! -e el_nf ] && [ ! -e nf.txt ] && [ ! -e nf.png ] || fail "a command refused for its frame wrote output"

# electrodes
"$THORAX" electrodes dal -o el -q
"$PY" - <<'EOF2' || fail "Dalhousie electrodes"
lines = open('el/12lead.txt').read().split('\n')
e = {l.split()[0]: (int(l.split()[1]), [float(x) for x in l.split()[2:5]]) for l in lines[3:] if len(l.split()) == 5}
pts = [[float(x) for x in l.split()] for l in open('dal/torso.pts') if l.strip()]
heart = [[float(x) for x in l.split()] for l in open('dal/epicardium.pts') if l.strip()]
# model frame: superior -y, anterior -z, left +x; in body terms: up = -y, front = -z, left = x
up = lambda p: -p[1]; front = lambda p: -p[2]; left = lambda p: p[0]
V = ['V%d' % k for k in range(1, 7)]
assert len({e[v][0] for v in V}) == 6, 'V1-V6 not on six distinct nodes'
assert len({e[n][0] for n in e}) == 9, 'two electrodes on one node'
ls = [left(e[v][1]) for v in V]
assert all(a < b for a, b in zip(ls, ls[1:])), ('V1..V6 not in order toward the left', ls)
assert left(e['V1'][1]) < 0 < left(e['V2'][1]), 'V1/V2 not either side of the sternum'
zmid = 0.5 * (min(front(p) for p in pts) + max(front(p) for p in pts))
assert all(front(e[v][1]) > zmid for v in V[:5]), 'V1-V5 not on the front'
zlo, zhi = min(up(p) for p in heart), max(up(p) for p in heart)
assert all(zlo <= up(e[v][1]) <= zhi for v in V), 'precordial leads not at the heart\'s height'
assert up(e['V4'][1]) <= up(e['V2'][1]), 'V4 above V2'
top, bot = max(up(p) for p in pts), min(up(p) for p in pts)
H = top - bot
ra, la, ll = e['RA'][1], e['LA'][1], e['LL'][1]
assert left(ra[:3]) < -50 and left(la) > 50, ('RA/LA not right/left', ra, la)
assert up(ra) > top - 0.3 * H and up(la) > top - 0.3 * H, ('RA/LA not high', ra, la)
assert left(ll) > 20 and up(ll) < bot + 0.15 * H, ('LL not low left', ll)
for n in ['RA', 'LA', 'LL'] + V:
    node, xyz = e[n]
    assert pts[node - 1] == xyz, (n, node, xyz)
print('e2e_frame: Dalhousie electrodes: ' + ', '.join('%s (%.0f, %.0f, %.0f)' % ((n,) + tuple(e[n][1])) for n in ['RA', 'LA', 'LL'] + V))
EOF2

# beat: the dipole fitted to the potentials at the QRS peak, in the model's frame and in RAS
"$THORAX" beat dal -o beat_dal.txt -q
"$THORAX" phantom --resolution medium -o c.txt -q
"$THORAX" surfaces c.txt -o ph -q
"$THORAX" beat ph -o beat_ph.txt -q
"$PY" - <<'EOF2' || fail "Dalhousie beat"
import re
def load(series, model, heart):
    rows, label = [], ''
    for l in open(series):
        if l.startswith('label '): label = l
        try: rows.append([float(x) for x in l.split()])
        except ValueError: pass
    rows = [r for r in rows if len(r) > 2]
    r0 = [float(x) for x in re.search(r'at \(([-\d.]+), ([-\d.]+), ([-\d.]+)\) mm', label).groups()]
    pts = [[float(x) for x in l.split()] for l in open(model + '/' + heart + '.pts') if l.strip()]
    return rows, r0, pts
def fit(rows, r0, pts, f):
    # phi_i = p . g_i, g_i = (r_i - r0) / |r_i - r0|^3: least squares for p (3 x 3 normal equations)
    A = [[0.0] * 3 for _ in range(3)]; b = [0.0] * 3
    for r, row in zip(pts, rows):
        d = [r[k] - r0[k] for k in range(3)]; n = sum(x * x for x in d) ** 1.5
        g = [x / n for x in d]
        for i in range(3):
            b[i] += g[i] * row[f]
            for j in range(3): A[i][j] += g[i] * g[j]
    def det(M): return (M[0][0] * (M[1][1] * M[2][2] - M[1][2] * M[2][1]) - M[0][1] * (M[1][0] * M[2][2] - M[1][2] * M[2][0])
                        + M[0][2] * (M[1][0] * M[2][1] - M[1][1] * M[2][0]))
    D = det(A); p = []
    for k in range(3):
        M = [row[:] for row in A]
        for i in range(3): M[i][k] = b[i]
        p.append(det(M) / D)
    n = sum(x * x for x in p) ** 0.5
    return [x / n for x in p]
rows, r0, pts = load('beat_dal.txt', 'dal', 'epicardium')
f = max(range(len(rows[0])), key=lambda f: max(abs(r[f]) for r in rows))
p = fit(rows, r0, pts, f)
# Dalhousie frame: left = +x, inferior = +y, anterior = -z
ras = [-p[0], -p[2], -p[1]]   # (right, anterior, superior)
rows2, r02, pts2 = load('beat_ph.txt', 'ph', 'heart')
q = fit(rows2, r02, pts2, f)
cos = sum(a * b for a, b in zip(ras, q))
assert p[0] > 0.3 and p[1] > 0.3, ('QRS peak dipole not left-inferior in the model frame', p)
assert cos > 0.999, ('not the phantom dipole carried through the frame', ras, q, cos)
print('e2e_frame: beat at the QRS peak (%d ms): dipole %s in the Dalhousie axes = (left %.2f, inferior %.2f, anterior %.2f); '
      'the phantom\'s in RAS (%.2f, %.2f, %.2f), cos %.6f' % (f, '(%.2f, %.2f, %.2f)' % tuple(p), p[0], p[1], -p[2], q[0], q[1], q[2], cos))
EOF2

# render: the model's frame is the views' default
"$THORAX" render dal --size 200x200 -o ant.png -q
"$THORAX" render dal_nf --up -y --front -z --size 200x200 -o ant_explicit.png -q
"$THORAX" render dal_nf --up +z --front +y --size 200x200 -o ant_zy.png -q
cmp -s ant.png ant_explicit.png || fail "the framed model's anterior view is not the --up -y --front -z view"
cmp -s ant.png ant_zy.png && fail "the framed model's anterior view is the +z/+y view"
"$THORAX" render dal --view left --clip anterior:0.5 --size 200x200 -o left.png -q
"$THORAX" render dal_nf --up -y --front -z --view left --clip anterior:0.5 --size 200x200 -o left_explicit.png -q
cmp -s left.png left_explicit.png || fail "left view / anterior clip differ from the explicit frame"
"$THORAX" render dal --up +z --front +y --size 200x200 -o override.png -q
cmp -s override.png ant_zy.png || fail "--up/--front on render do not override the model's frame"
# the lacing start point follows the contours' frame: anterior in the contour plane, else superior
start_of() { $PY -c "import json,sys; print(json.load(open(sys.argv[1] + '/model.json'))['provenance']['options']['start_point_mm'])" "$1"; }
"$THORAX" phantom -o ph.txt -q
sed 's/^frame +z +y$/frame +z -x/' ph.txt > ph_x.txt
grep -qx "frame +z -x" ph_x.txt || fail "could not set the phantom's frame line"
"$THORAX" surfaces ph.txt -o ph_m -q && [ "$(start_of ph_m)" = "[0, 1000]" ] || fail "RAS contours: start $(start_of ph_m), not [0, 1000]"
"$THORAX" surfaces ph_x.txt -o ph_xm -q && [ "$(start_of ph_xm)" = "[-1000, 0]" ] || fail "anterior -x: start $(start_of ph_xm), not [-1000, 0]"
"$THORAX" slice dal --spacing 20 -o dal_c.txt -q && grep -qx "frame -y -z" dal_c.txt || fail "the Dalhousie slices do not carry its frame"
"$THORAX" surfaces dal_c.txt -o dal_cm -q && [ "$(start_of dal_cm)" = "[0, -1000]" ] ||
    fail "Dalhousie slices (anterior across the planes): start $(start_of dal_cm), not superior [0, -1000]"
"$THORAX" surfaces ph_x.txt --start 5,6 -o ph_sm -q && [ "$(start_of ph_sm)" = "[5, 6]" ] || fail "--start does not override the frame"
echo "e2e_frame: ok"
