#!/usr/bin/env bash
# End-to-end test of `thorax phantom --image` (the phantom as a label map and as simulated CT/MR
# scans) and `--from MODEL` (any model's closed surfaces voxelized), judged by nibabel and numpy:
#  - the label map: nibabel reads it, RAS axes, 3 mm voxels, the affine places the labelled voxels
#    on the phantom's extent (z faces 0 and 270 mm, two voxels of air around), labels 0..6, the
#    counts printed equal the file's;
#  - CT: noise-free, every voxel a mix of the table's values (between the smallest and largest),
#    the voxels whole inside one tissue exactly the table's value, and they are most of each region;
#    with --noise 20 their mean equals the table within 4 standard errors and their standard
#    deviation is 20 within 3%;
#  - MR, Rician noise 30: in air the Rayleigh mean and deviation (sigma sqrt(pi/2), sigma
#    sqrt(2 - pi/2)), in fat sqrt(900^2 + sigma^2) and about sigma;
#  - the bias field: MR with --bias 0.3 over MR without equals 1 + 0.3 q(u, v, w) computed here from
#    the voxel indices (q = 0.5 u + 0.3 v + 0.2 (2 w^2 - 1), u, v, w in -1..1), to float precision;
#  - the same seed gives the same bytes, another seed another image;
#  - the Utah tank + sock and the Dalhousie torso + epicardium (../shared/data/map3d) voxelized at
#    2 mm: each region's label volume within 0.2% of the volumes their surfaces enclose (divergence
#    theorem computed here from the model's .pts/.fac); the tank imported with a frame (superior
#    +x, anterior +z) is written in RAS: the sock's centroid where the frame puts it;
#  - usage errors (exit 2) and a missing model (exit 1), nothing written.
set -uo pipefail
: "${THORAX:?}" "${WORK:?}"
SRC=${SRC:-$(cd "$(dirname "$0")/.." && pwd)}
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
run() { # NAME ARGS...: thorax ARGS > NAME.txt (thorax phantom with the --sub of the run)
    local name=$1; shift
    if [ "$1" = phantom ]; then shift; set -- phantom --sub "$SUB" "$@"; fi
    if "$THORAX" "$@" > "$name.txt" 2> "$name.err"; then return 0; fi
    bad "thorax $*: $(cat "$name.err")"; return 1
}

# THORAX_QUICK (the sanitized build): 2 x 2 x 2 sub-samples per boundary voxel instead of 4 x 4 x 4;
# the checks are the same (they use the whole voxels, the extent and ratios, not the boundaries)
SUB=4
[ -n "${THORAX_QUICK:-}" ] && SUB=2
run lab phantom --image lab.nii.gz --voxel 3 -q
run ct0 phantom --image ct0.nii.gz --voxel 3 --modality ct -q
run ct phantom --image ct.nii.gz --voxel 3 --modality ct --noise 20 --seed 7 -q
run ct_again phantom --image ct_again.nii.gz --voxel 3 --modality ct --noise 20 --seed 7 -q
run ct_other phantom --image ct_other.nii.gz --voxel 3 --modality ct --noise 20 --seed 8 -q
run mr0 phantom --image mr0.nii.gz --voxel 3 --modality mr -q
run mr_rice phantom --image mr_rice.nii.gz --voxel 3 --modality mr --noise 30 --noise-kind rician --seed 3 -q
run mr_bias phantom --image mr_bias.nii.gz --voxel 3 --modality mr --bias 0.3 -q

if cmp -s ct.nii.gz ct_again.nii.gz; then ok "the same seed, the same bytes"; else bad "two runs with seed 7 differ"; fi
if cmp -s ct.nii.gz ct_other.nii.gz; then bad "seeds 7 and 8 give the same image"; else ok "another seed, another image"; fi

if $PY - <<'PYEOF'
import math, sys
import nibabel as nib, numpy as np
fails = 0
def check(cond, what):
    global fails
    print(("ok: " if cond else "FAIL: ") + what, file=sys.stdout if cond else sys.stderr)
    fails += not cond
lab_img = nib.load("lab.nii.gz")
lab = np.asarray(lab_img.dataobj).astype(int)
A = lab_img.affine
check(nib.aff2axcodes(A) == ("R", "A", "S"), f"label map in RAS ({nib.aff2axcodes(A)})")
check(np.allclose(A[:3, :3], np.diag([3, 3, 3])), "3 mm voxels, axis-aligned")
check(set(np.unique(lab)) == set(range(7)), f"labels 0..6 ({sorted(set(np.unique(lab)))})")
# the printed table (label region tissue value voxels volume) against the file
table = [l.split() for l in open("lab.txt") if not l.startswith("#")]
counts = np.bincount(lab.ravel(), minlength=7)
check(all(int(t[4]) == counts[int(t[0])] for t in table) and len(table) == 7, "the printed label counts are the file's")
# the labelled voxels' extent in RAS: z faces at 0 and 270 mm (the torso's caps), air all round
idx = np.argwhere(lab > 0)
lo, hi = idx.min(0), idx.max(0)
clo, chi = A[:3, :3] @ lo + A[:3, 3], A[:3, :3] @ hi + A[:3, 3]
check(abs(clo[2] - 1.5) < 1e-6 and abs(chi[2] - 268.5) < 1e-6, f"torso voxel centres from z {clo[2]} to {chi[2]} mm (faces 0, 270)")
check(all(lo >= 2) and all(hi <= np.array(lab.shape) - 3), f"two voxels of air around the torso ({lo}, {hi}, shape {lab.shape})")
# the torso's half-widths to the right (+x), left and front at theta = 0, pi, pi/2 are the
# superellipse's semi-axes, interpolated between the phantom's key heights by a smoothstep: the
# widest right and left at the top cap (z = 270), the deepest front at z = 130 (phantom.c's table)
def smooth(z0, z1, z):
    t = min(max((z - z0) / (z1 - z0), 0), 1)
    return t * t * (3 - 2 * t)
right, left, front = 174 + 2 * smooth(260, 320, 270), -(172 + 2 * smooth(260, 320, 270)), 112.0
check(abs(chi[0] - right) <= 3 and abs(clo[0] - left) <= 3 and abs(chi[1] - front) <= 3,
      f"labelled voxel centres reach x {clo[0]:.1f} .. {chi[0]:.1f} and y {chi[1]:.1f} mm: the torso's "
      f"{left:.2f} .. {right:.2f} and {front:.0f} within a voxel")
# CT: the table (region -> HU), from the CT run's printout
ct_tab = {int(t[0]): float(t[3]) for t in (l.split() for l in open("ct0.txt") if not l.startswith("#"))}
ct0 = np.asarray(nib.load("ct0.nii.gz").dataobj)
ct = np.asarray(nib.load("ct.nii.gz").dataobj)
check(np.allclose(nib.load("ct.nii.gz").affine, A), "the scan's affine is the label map's")
vals = np.array([ct_tab[r] for r in range(7)])
check(ct0.min() >= vals.min() - 1e-3 and ct0.max() <= vals.max() + 1e-3, "noise-free CT: every voxel a mix of the table")
for r in range(7):
    reg = lab == r
    pure = reg & (np.abs(ct0 - vals[r]) < 1e-3)
    frac = pure.sum() / reg.sum()
    x = ct[pure]
    se = 20 / math.sqrt(len(x))
    check(frac > (0.5 if r in (1, 2) else 0.75), f"CT region {r}: {100 * frac:.1f}% of its voxels whole")
    check(abs(x.mean() - vals[r]) < 4 * se, f"CT region {r}: mean {x.mean():.2f} HU, table {vals[r]:g} (+-{4 * se:.2f})")
    check(abs(x.std() - 20) < 0.6, f"CT region {r}: noise sd {x.std():.2f}, asked 20")
# MR with Rician noise: air is Rayleigh, fat nearly Gaussian about sqrt(900^2 + s^2)
mr_tab = {int(t[0]): float(t[3]) for t in (l.split() for l in open("mr0.txt") if not l.startswith("#"))}
mr0 = np.asarray(nib.load("mr0.nii.gz").dataobj)
mr = np.asarray(nib.load("mr_rice.nii.gz").dataobj)
s = 30.0
air = (lab == 0) & (np.abs(ct0 - vals[0]) < 1e-3)
fat = (lab == 1) & (np.abs(ct0 - vals[1]) < 1e-3)
check(mr_tab[0] == 0 and mr_tab[1] == 900, "MR table: air 0, fat 900")
m, d = mr[air].mean(), mr[air].std()
check(abs(m - s * math.sqrt(math.pi / 2)) < 0.3 and abs(d - s * math.sqrt(2 - math.pi / 2)) < 0.3,
      f"Rician in air: mean {m:.2f} (Rayleigh {s * math.sqrt(math.pi / 2):.2f}), sd {d:.2f} ({s * math.sqrt(2 - math.pi / 2):.2f})")
m, d = mr[fat].mean(), mr[fat].std()
check(abs(m - math.hypot(900, s)) < 4 * s / math.sqrt(fat.sum()) + 0.05 and abs(d - s) < 1.0,
      f"Rician in fat: mean {m:.2f} ({math.hypot(900, s):.2f}), sd {d:.2f}")
check((mr >= 0).all(), "Rician values are magnitudes (>= 0)")
# the bias field
mb = np.asarray(nib.load("mr_bias.nii.gz").dataobj)
n = np.array(mb.shape)
i, j, k = np.meshgrid(*[np.arange(c) for c in n], indexing="ij")
u, v, w = 2 * i / (n[0] - 1) - 1, 2 * j / (n[1] - 1) - 1, 2 * k / (n[2] - 1) - 1
q = 0.5 * u + 0.3 * v + 0.2 * (2 * w * w - 1)
body = mr0 > 1
err = np.abs(mb[body] / mr0[body] - (1 + 0.3 * q[body])).max()
check(err < 1e-5, f"bias field = 1 + 0.3 q to {err:.1e}")
sys.exit(1 if fails else 0)
PYEOF
then ok "phantom images judged by nibabel/numpy"; else bad "phantom images (see above)"; fi

# real surfaces: the Utah tank + sock, the Dalhousie torso + epicardium
if [ -d "$DATA/map3d/geom/tank" ]; then
    G=$DATA/map3d/geom
    "$THORAX" import -o tank -q "$G/tank/tank_full_771.pts" --name tank --role outer "$G/tank/25feb97_sock_closed.pts" --name sock --role heart &&
        run tank phantom --image tank.nii.gz --from tank --voxel 2 -q || bad "tank: import"
    "$THORAX" import -o dal -q "$G/torso/daltorso.pts" --name torso --role outer "$G/torso/dalepi.pts" --name epicardium --role heart &&
        run dal phantom --image dal.nii.gz --from dal --voxel 2 -q || bad "dalhousie: import"
    for m in tank dal; do
        if $PY - "$m" <<'PYEOF'
import json, sys
import nibabel as nib, numpy as np
m = sys.argv[1]
meta = json.load(open(f"{m}/model.json"))
def volume(s):
    p = np.loadtxt(f"{m}/{s['pts']}")
    f = np.loadtxt(f"{m}/{s['fac']}", dtype=int) - 1
    p = p - p.mean(0)
    a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
    return abs(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6
vol = [volume(s) for s in meta["surfaces"]]
img = nib.load(f"{m}.nii.gz")
lab = np.asarray(img.dataobj).astype(int)
vv = abs(np.linalg.det(img.affine[:3, :3]))
got = np.bincount(lab.ravel(), minlength=3) * vv
want = [None, vol[0] - vol[1], vol[1]]
bad = 0
for r in (1, 2):
    e = (got[r] - want[r]) / want[r]
    print(f"{m}: region {r} ({meta['surfaces'][r - 1]['name']}): {got[r]:.0f} mm^3 by labels, {want[r]:.0f} enclosed ({100 * e:+.2f}%)")
    bad += abs(e) > 0.002
sys.exit(1 if bad else 0)
PYEOF
        then ok "$m: label volumes within 0.2% of the enclosed volumes"; else bad "$m: label volumes"; fi
    done
    # a model with a frame (superior +x, anterior +z: RAS = (y, z, x) of the model's coordinates):
    # the image's affine turns the grid into RAS; the sock's labelled voxels' centroid lands on
    # its polyhedron's centroid mapped so, within a quarter voxel
    "$THORAX" import -o tankf -q "$G/tank/tank_full_771.pts" --name tank --role outer "$G/tank/25feb97_sock_closed.pts" \
        --name sock --role heart --up +x --front +z && run tankf phantom --image tankf.nii.gz --from tankf --voxel 2 -q &&
    if $PY - <<'PYEOF'
import sys
import nibabel as nib, numpy as np
img = nib.load("tankf.nii.gz")
lab = np.asarray(img.dataobj).astype(int)
p = np.loadtxt("tankf/sock.pts")
f = np.loadtxt("tankf/sock.fac", dtype=int) - 1
a, b, c = p[f[:, 0]], p[f[:, 1]], p[f[:, 2]]
v6 = np.einsum("ij,ij->i", a, np.cross(b, c))
cen = (v6[:, None] * (a + b + c)).sum(0) / (4 * v6.sum())  # centroid of the polyhedron (tetrahedra from 0)
want = np.array([cen[1], cen[2], cen[0]])
idx = np.argwhere(lab == 2)
got = (img.affine[:3, :3] @ idx.T).T.mean(0) + img.affine[:3, 3]
d = np.linalg.norm(got - want)
print(f"sock centroid in RAS {got.round(2)}, expected {want.round(2)}, {d:.3f} mm apart; axes {nib.aff2axcodes(img.affine)}")
sys.exit(0 if d < 0.5 else 1)
PYEOF
    then ok "a model's frame turns the image into RAS"; else bad "a model's frame: the image's affine"; fi
else
    echo "skip: $DATA/map3d not found (Utah tank, Dalhousie torso)"
fi

# usage errors and failures: nothing written
expect() { # RC NAME ARGS...
    local want=$1 name=$2; shift 2
    "$THORAX" "$@" > /dev/null 2> "$name.err"
    local rc=$?
    if [ "$rc" -eq "$want" ] && [ ! -e "$name.nii.gz" ]; then ok "$name: exit $rc, nothing written ($(head -c 120 "$name.err"))"
    else bad "$name: exit $rc (expected $want) or a file left: $(cat "$name.err")"; fi
}
expect 2 noisy_labels phantom --image noisy_labels.nii.gz --noise 5
expect 2 rician_ct phantom --image rician_ct.nii.gz --modality ct --noise 5 --noise-kind rician
expect 2 zero_voxel phantom --image zero_voxel.nii.gz --voxel 0
expect 2 both phantom --image both.nii.gz -o both.txt
expect 1 no_model phantom --image no_model.nii.gz --from does_not_exist

[ "$fails" -eq 0 ] && echo "all passed" || { echo "$fails failed" >&2; exit 1; }
