#!/bin/bash
# End-to-end test of `thorax check` on a real closed surface: the Utah torso
# tank (map3d, ../shared/data/map3d/geom/tank/tank_full_771.pts/.fac); then on
# volume meshes of the medium phantom, good and crafted bad (end of the file).
#
# Environment: THORAX = the built CLI, SRC = the source tree, WORK = a scratch
# directory (created, emptied). Exits non-zero on the first failed expectation.
#
# The tank's .fac is 1-based (min 1, max 771 = node count; checked below) and
# its triangles are stored counterclockwise seen from outside (positive
# signed volume, checked below with an independent computation in Python), so
# the model is written with them as they are; the reversed copy must fail.
set -euo pipefail

: "${THORAX:?THORAX must point to the thorax executable}"
: "${SRC:?SRC must point to the source tree}"
: "${WORK:?WORK must name a scratch directory}"
PY=/usr/bin/python3
DATA="$SRC/../shared/data/map3d/geom/tank"
PTS="$DATA/tank_full_771.pts"
FAC="$DATA/tank_full_771.fac"
[ -r "$PTS" ] && [ -r "$FAC" ] || { echo "e2e_check: missing $PTS or $FAC"; exit 1; }

rm -rf "$WORK"
mkdir -p "$WORK"
fail() { echo "e2e_check: FAIL: $*"; exit 1; }

# --- build model directories by hand -------------------------------------
# make_model DIR MODE: MODE is "as-is", "reversed" (every triangle flipped),
# "hole" (last triangle removed) or "interior" (as-is, with an interior point
# in model.json chosen here from the data: the centroid of the nodes).
make_model() {
    "$PY" - "$PTS" "$FAC" "$1" "$2" <<'EOF'
import json, os, sys
pts_path, fac_path, out, mode = sys.argv[1:5]
pts = [tuple(map(float, l.split())) for l in open(pts_path) if l.strip()]
fac = [tuple(map(int, l.split())) for l in open(fac_path) if l.strip()]
n = len(pts)
lo = min(min(t) for t in fac); hi = max(max(t) for t in fac)
# index base: 1-based iff the indices run 1..n (0-based would be 0..n-1)
if lo == 1 and hi == n: base = 1
elif lo == 0 and hi == n - 1: base = 0
else: sys.exit("cannot tell the .fac index base: min %d max %d nodes %d" % (lo, hi, n))
assert base == 1, "the tank .fac is expected to be 1-based"
tri = [tuple(i - base for i in t) for t in fac]
# orientation, independently of thorax: signed volume by the divergence theorem
def vol(ts):
    v = 0.0
    for a, b, c in ts:
        A, B, C = pts[a], pts[b], pts[c]
        v += (A[0]*(B[1]*C[2]-B[2]*C[1]) - A[1]*(B[0]*C[2]-B[2]*C[0]) + A[2]*(B[0]*C[1]-B[1]*C[0])) / 6
    return v
v = vol(tri)
if v < 0:  # stored clockwise: make counterclockwise seen from outside
    tri = [(a, c, b) for a, b, c in tri]
if mode == "reversed":
    tri = [(a, c, b) for a, b, c in tri]
elif mode == "hole":
    tri = tri[:-1]
os.makedirs(out, exist_ok=True)
with open(os.path.join(out, "tank.pts"), "w") as f:
    for p in pts: f.write("%.6f %.6f %.6f\n" % p)
with open(os.path.join(out, "tank.fac"), "w") as f:
    for t in tri: f.write("%d %d %d\n" % tuple(i + 1 for i in t))
surf = {"name": "tank", "role": "outer", "pts": "tank.pts", "fac": "tank.fac",
        "n_nodes": n, "n_tris": len(tri)}
if mode == "interior":
    surf["interior"] = [sum(p[k] for p in pts) / n for k in range(3)]
man = {"format": "thorax-model", "version": 1, "units": "mm", "surfaces": [surf],
       "provenance": {"source": "map3d geom/tank/tank_full_771 (e2e_check.sh)"}}
json.dump(man, open(os.path.join(out, "model.json"), "w"), indent=1)
print("base %d, stored signed volume %.6g mm^3 (%s)" % (base, v, "ccw" if v > 0 else "cw, reversed"))
EOF
}

make_model "$WORK/tank" as-is
make_model "$WORK/reversed" reversed >/dev/null
make_model "$WORK/hole" hole >/dev/null
make_model "$WORK/interior" interior >/dev/null

# --- the closed tank passes ----------------------------------------------
set +e
"$THORAX" check "$WORK/tank" --json >"$WORK/tank.json" 2>"$WORK/tank.err"
rc=$?
set -e
[ $rc -eq 0 ] || { cat "$WORK/tank.err"; fail "check of the closed tank exited $rc"; }
"$PY" - "$WORK/tank.json" <<'EOF' || fail "tank JSON figures"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["ok"] is True and r["index_base"] == 1, r
(s,) = r["surfaces"]
t = s["topology"]
assert s["name"] == "tank" and s["role"] == "outer" and s["ok"] is True, s
assert s["nodes"] == 771 and s["triangles"] == 1538 and s["edges"] == 2307, s
assert s["closed"] is True and s["manifold"] is True and s["consistently_oriented"] is True
for k in ("boundary_edges", "nonmanifold_edges", "nonmanifold_vertices", "inconsistent_edges",
          "duplicate_triangles", "degenerate_triangles", "unused_nodes", "bad_index_triangles"):
    assert t[k] == 0, (k, t[k])
assert t["euler_characteristic"] == 2 and t["components"] == 1, t
assert s["volume"] > 0
sa = s["solid_angle"]
assert sa["interior_source"] == "found" and sa["ok"] is True, sa
assert sa["rel_error"] < 1e-6, sa
assert abs(sa["omega_over_4pi"] - 1) < 1e-6, sa
assert s["intersections"]["checked"] is True and s["intersections"]["pairs"] == 0, s["intersections"]
q = s["quality"]
h = q["aspect_ratio"]["histogram"]
assert sum(h["counts"]) == 1538 and len(h["edges"]) == len(h["counts"]) + 1, h
assert 0 < q["min_angle_deg"] <= 60 <= q["max_angle_deg"] < 180, q
assert q["aspect_ratio"]["max"] >= q["aspect_ratio"]["mean"] >= 1, q
assert s["failures"] == [] and s["reasons"] == []
print("tank: |Omega/4pi - 1| = %.3g, min angle %.2f deg, worst aspect %.3g" %
      (sa["rel_error"], q["min_angle_deg"], q["aspect_ratio"]["max"]))
EOF

# the readable table names the surface and says it passed
"$THORAX" check "$WORK/tank" >"$WORK/tank.txt" || fail "table mode exited non-zero"
grep -q '^tank .* ok$' "$WORK/tank.txt" || { cat "$WORK/tank.txt"; fail "table line for tank"; }
grep -q 'all checks passed' "$WORK/tank.txt" || fail "table verdict"
grep -q '^\[1, 1.25)' "$WORK/tank.txt" || fail "aspect histogram"
# -q prints nothing for a passing model
[ -z "$("$THORAX" check "$WORK/tank" -q)" ] || fail "-q printed something for a passing model"

# the interior point stored in model.json is the one used
"$THORAX" check "$WORK/interior" --json >"$WORK/interior.json" || fail "tank with stored interior point"
"$PY" -c '
import json, sys
s = json.load(open(sys.argv[1]))["surfaces"][0]["solid_angle"]
assert s["interior_source"] == "given" and s["rel_error"] < 1e-6, s
' "$WORK/interior.json" || fail "stored interior point not used"

# --- the reversed tank fails: -4 pi, negative volume, exit 1 ---------------
set +e
"$THORAX" check "$WORK/reversed" --json >"$WORK/reversed.json" 2>"$WORK/reversed.err"
rc=$?
set -e
[ $rc -eq 1 ] || fail "reversed tank: exit $rc, expected 1"
"$PY" - "$WORK/reversed.json" <<'EOF' || fail "reversed tank JSON"
import json, sys
r = json.load(open(sys.argv[1]))
s = r["surfaces"][0]
assert r["ok"] is False and s["ok"] is False
assert s["closed"] is True and s["consistently_oriented"] is True
assert s["volume"] < 0
assert abs(s["solid_angle"]["omega_over_4pi"] + 1) < 1e-6, s["solid_angle"]
assert set(s["failures"]) == {"volume", "solid_angle"}, s["failures"]
EOF
grep -q 'surface "tank": inward' "$WORK/reversed.err" || { cat "$WORK/reversed.err"; fail "reversed: no reason on stderr"; }

# --- a hole: exit 1, boundary edges reported ------------------------------
set +e
"$THORAX" check "$WORK/hole" >"$WORK/hole.txt" 2>"$WORK/hole.err"
rc=$?
set -e
[ $rc -eq 1 ] || fail "tank with a hole: exit $rc, expected 1"
grep -q 'not closed: 3 boundary edges' "$WORK/hole.err" || { cat "$WORK/hole.err"; fail "hole: reason"; }
grep -q 'CHECK FAILED' "$WORK/hole.txt" || fail "hole: table verdict"
set +e
"$THORAX" check "$WORK/hole" --json >"$WORK/hole.json" 2>/dev/null
rc=$?
set -e
[ $rc -eq 1 ] || fail "hole --json: exit $rc"
"$PY" -c '
import json, sys
s = json.load(open(sys.argv[1]))["surfaces"][0]
assert s["closed"] is False and s["topology"]["boundary_edges"] == 3, s["topology"]
assert "boundary" in s["failures"], s["failures"]
' "$WORK/hole.json" || fail "hole JSON"

# --- --tol reaches the report ---------------------------------------------
"$THORAX" check "$WORK/tank" --tol 1e-3 --json >"$WORK/tol.json" || fail "--tol 1e-3"
"$PY" -c '
import json, sys
r = json.load(open(sys.argv[1]))
assert r["solid_angle_tol"] == 1e-3 and r["surfaces"][0]["solid_angle"]["tolerance"] == 1e-3, r["solid_angle_tol"]
' "$WORK/tol.json" || fail "--tol not in the report"

# --- unreadable model: exit 1 and the message names the file --------------
set +e
"$THORAX" check "$WORK/does-not-exist" 2>"$WORK/missing.err"
rc=$?
set -e
[ $rc -eq 1 ] || fail "missing model: exit $rc, expected 1"
grep -q 'does-not-exist' "$WORK/missing.err" || { cat "$WORK/missing.err"; fail "missing model: message"; }
mkdir -p "$WORK/broken"
cp "$WORK/tank/tank.pts" "$WORK/tank/tank.fac" "$WORK/broken/"
echo '{"format": "thorax-model", "version": 1, "units": "mm", "surfaces": [' >"$WORK/broken/model.json"
set +e
"$THORAX" check "$WORK/broken" 2>"$WORK/broken.err"
rc=$?
set -e
[ $rc -eq 1 ] || fail "broken model.json: exit $rc, expected 1"
grep -q 'model.json' "$WORK/broken.err" || { cat "$WORK/broken.err"; fail "broken model: message"; }

# --- usage errors: exit 2 -------------------------------------------------
for args in "" "--bogus $WORK/tank" "$WORK/tank $WORK/tank" "$WORK/tank --tol" "$WORK/tank --tol abc" \
            "$WORK/tank --tol -1"; do
    set +e
    # shellcheck disable=SC2086
    "$THORAX" check $args >/dev/null 2>&1
    rc=$?
    set -e
    [ $rc -eq 2 ] || fail "usage error '$args': exit $rc, expected 2"
done
# (to a file: grep -q in a pipe may exit before a long text is written, a SIGPIPE under pipefail)
"$THORAX" check --help >"$WORK/help.txt" || fail "--help exit status"
grep -q 'usage: thorax check MODEL' "$WORK/help.txt" || fail "--help"
grep -q -- '--min-dihedral DEG  volume: fail if a dihedral angle is smaller (default 1;' "$WORK/help.txt" || fail "--help: --min-dihedral"

# --- volume meshes of the medium phantom (paper 3.3) --------------------------
# The mesh passes every volume check: each surface triangle covered by faces on
# the boundary or between regions, one region per cell, region volumes within
# 0.5%, smallest dihedral >= 1 degree; with the heart and without. Then bad
# volumes crafted from it fail with the named category.
"$THORAX" phantom --resolution medium -o "$WORK/c.txt" -q
"$THORAX" surfaces "$WORK/c.txt" -o "$WORK/m" -q
for variant in heart no-heart; do
    opt=""; [ $variant = no-heart ] && opt="--no-heart"
    if [ -d "${THORAX_PHANTOM_MODELS:-}" ]; then
        # the same meshes, made once (tests/phantom_models.sh)
        cp -r "$THORAX_PHANTOM_MODELS/$([ $variant = heart ] && echo modelh || echo model)" "$WORK/v_$variant"
    else
        "$THORAX" mesh "$WORK/m" -o "$WORK/v_$variant" $opt -q || fail "mesh ($variant)"
    fi
    set +e
    "$THORAX" check "$WORK/v_$variant" --json >"$WORK/v_$variant.json" 2>"$WORK/v_$variant.err"
    rc=$?
    set -e
    [ $rc -eq 0 ] || { cat "$WORK/v_$variant.err"; fail "check of the meshed phantom ($variant) exited $rc"; }
    "$PY" - "$WORK/v_$variant.json" $variant <<'EOF2' || fail "meshed phantom ($variant): JSON figures"
import json, sys
v = json.load(open(sys.argv[1]))["volume"]; variant = sys.argv[2]
assert v["ok"] is True and v["failures"] == [], v["reasons"]
c = v["coverage"]
assert c["checked"] is True and c["uncovered_triangles"] == 0 and c["faces_off_surfaces"] == 0, c
names = [s["name"] for s in c["surfaces"]]
assert names == ["torso", "fat", "muscle", "lung_r", "lung_l", "heart"], names
for s in c["surfaces"]:
    assert s["covered"] == s["triangles"] > 0 and s["share"] == 1, s
    assert abs(s["covered_area"] - s["area"]) <= 1e-6 * s["area"], s
inside = {s["name"]: s["inside"] for s in c["surfaces"]}
assert inside == {"torso": None, "fat": "torso", "muscle": "fat", "lung_r": "muscle", "lung_l": "muscle",
                  "heart": "muscle"}, inside
assert v["region_cells"]["checked"] is True and v["region_cells"]["outside_region"] == 0
cells = {r["name"]: r["cell"] for r in v["regions"]}
want = {"mean_thorax": "inside muscle", "fat": "inside torso", "muscle": "inside fat", "lung_r": "inside lung_r",
        "lung_l": "inside lung_l"}
if variant == "heart": want["heart"] = "inside heart"
assert cells == want, cells
for r in v["regions"]:
    assert r["ok"] is True and abs(r["rel_diff"]) < 1e-6, r
assert v["region_tolerance"] == 0.005
q = v["quality"]
assert q["min_dihedral_limit"] == 1 and q["min_dihedral_deg"] >= 1, q["min_dihedral_deg"]
if variant == "no-heart":
    assert v["containment"]["excluded_surfaces"] == ["heart"] and v["conformity"]["cavities"] == 1
    assert v["conformity"]["boundary_nodes_off_surfaces"] == 0   # Steiner nodes count as on their surface
nt = v["node_tables"]
assert nt["steiner_nodes"] > 0 and nt["steiner_bad"] == 0 and nt["steiner_mismatches"] == 0, nt
print("%s: %d tetrahedra, %d interface faces cover %d surface triangles; %d Steiner nodes; min dihedral %.2f deg" %
      (variant, v["tetrahedra"], c["interface_faces"], sum(s["triangles"] for s in c["surfaces"]),
       nt["steiner_nodes"], q["min_dihedral_deg"]))
EOF2
done
"$THORAX" check "$WORK/v_heart" >"$WORK/v_heart.txt" || fail "table mode on the meshed phantom"
grep -q '^lung_l .* 100.00% .* muscle$' "$WORK/v_heart.txt" || { cat "$WORK/v_heart.txt"; fail "coverage table"; }
grep -q '^mean_thorax .* in muscle  *0  muscle - lung_r - lung_l - heart$' "$WORK/v_heart.txt" ||
    { cat "$WORK/v_heart.txt"; fail "region table with cells"; }

# craft VARIANT DIR: a copy of v_heart with one defect
craft() {
    rm -rf "$WORK/$2"
    cp -r "$WORK/v_heart" "$WORK/$2"
    "$PY" - "$WORK/$2" "$1" <<'EOF2'
import json, os, sys
d, what = sys.argv[1:3]
man = json.load(open(os.path.join(d, "model.json")))
rid = {r["name"]: r["id"] for r in man["regions"]}
tet = [l.split() for l in open(os.path.join(d, "volume.tet"))]
pts = [l.split() for l in open(os.path.join(d, "volume.pts"))]
st = [l.split() for l in open(os.path.join(d, "volume.steiner"))]
surf = [s["name"] for s in man["surfaces"]]
if what == "relabel":        # one lung tetrahedron labelled mean_thorax: on the wrong side of lung_l
    k = next(i for i, t in enumerate(tet) if int(t[4]) == rid["lung_l"])
    tet[k][4] = str(rid["mean_thorax"])
    print("tetrahedron %d: lung_l -> mean_thorax" % (k + 1))
elif what == "steiner":      # a Steiner record pointing beside its node
    k = next(i for i, r in enumerate(st) if float(r[3]) > 0.2 and float(r[4]) > 0.2)
    b0, b1 = float(st[k][3]), float(st[k][4])
    st[k][3], st[k][4] = "%.17g" % (b0 - 0.1), "%.17g" % (b1 + 0.1)
    print("Steiner record %d moved" % (k + 1))
elif what == "cut":          # a torso Steiner node pushed 0.05 mm out, its record dropped: the mesh
    k = next(i for i, r in enumerate(st) if surf[int(r[1]) - 1] == "torso")
    n = int(st[k][0]) - 1    # faces around it leave the triangle's plane (found without the table)
    tri = int(st[k][2]) - 1
    fac = [list(map(int, l.split())) for l in open(os.path.join(d, "torso.fac"))]
    sp = [list(map(float, l.split())) for l in open(os.path.join(d, "torso.pts"))]
    a, b, c = (sp[i - 1] for i in fac[tri])
    u = [b[i] - a[i] for i in range(3)]; w = [c[i] - a[i] for i in range(3)]
    nrm = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]]
    ln = sum(x * x for x in nrm) ** 0.5
    pts[n] = ["%.17g" % (float(pts[n][i]) + 0.05 * nrm[i] / ln) for i in range(3)]
    del st[k]
    man["volume"]["n_steiner"] = len(st)
    print("volume node %d moved off the torso" % (n + 1))
open(os.path.join(d, "volume.tet"), "w").write("".join(" ".join(t) + "\n" for t in tet))
open(os.path.join(d, "volume.pts"), "w").write("".join(" ".join(p) + "\n" for p in pts))
open(os.path.join(d, "volume.steiner"), "w").write("".join(" ".join(r) + "\n" for r in st))
json.dump(man, open(os.path.join(d, "model.json"), "w"), indent=1)
EOF2
}
# bad_check DIR WANT...: exit 1, the JSON failures are exactly WANT
bad_check() {
    local dir=$1; shift
    set +e
    "$THORAX" check "$WORK/$dir" --json >"$WORK/$dir.json" 2>"$WORK/$dir.err"
    rc=$?
    set -e
    [ $rc -eq 1 ] || { cat "$WORK/$dir.err"; fail "$dir: exit $rc, expected 1"; }
    "$PY" -c '
import json, sys
v = json.load(open(sys.argv[1]))["volume"]
assert v["ok"] is False and sorted(v["failures"]) == sorted(sys.argv[2:]), (v["failures"], v["reasons"])
' "$WORK/$dir.json" "$@" || fail "$dir: failures"
    echo "$dir: $(grep -c 'volume:' "$WORK/$dir.err") reasons, first: $(grep -m1 'volume:' "$WORK/$dir.err")"
}
relabelled=$(craft relabel v_relabel | sed -n 's/^tetrahedron \([0-9]*\): .*/\1/p')
bad_check v_relabel region_cells coverage
grep -q "tetrahedra outside their region: region \"mean_thorax\": 1 of [0-9]* tetrahedra lie inside lung_l, which holds region \"lung_l\" (first: tetrahedron $relabelled)" \
    "$WORK/v_relabel.err" || { cat "$WORK/v_relabel.err"; fail "relabel: cell reason"; }
grep -q 'faces between regions or on the boundary lie on no surface triangle' "$WORK/v_relabel.err" || fail "relabel: coverage reason"
craft steiner v_steiner
bad_check v_steiner node_table
grep -q 'Steiner nodes: 0 records out of range or on a surface node, 1 nodes farther than 1e-05 mm' "$WORK/v_steiner.err" ||
    { cat "$WORK/v_steiner.err"; fail "steiner: reason"; }
craft cut v_cut
bad_check v_cut coverage
grep -q 'coverage: surface "torso": [0-9]* of 6042 triangles not covered' "$WORK/v_cut.err" || fail "cut: uncovered reason"
grep -q 'lie on no surface triangle (region boundary off the surfaces' "$WORK/v_cut.err" || fail "cut: off-surface reason"
# the smallest dihedral: a limit above the mesh's fails, 0 turns it off, a bad value is a usage error
set +e
"$THORAX" check "$WORK/v_heart" --min-dihedral 60 -q 2>"$WORK/dih.err"; rc=$?
set -e
[ $rc -eq 1 ] && grep -q 'quality: smallest dihedral angle .* < 60 deg' "$WORK/dih.err" || fail "--min-dihedral 60 (exit $rc)"
"$THORAX" check "$WORK/v_heart" --min-dihedral 0 -q || fail "--min-dihedral 0"
for args in "--min-dihedral -1" "--min-dihedral 80" "--region-tol -0.1"; do
    set +e
    # shellcheck disable=SC2086
    "$THORAX" check "$WORK/v_heart" $args >/dev/null 2>&1; rc=$?
    set -e
    [ $rc -eq 2 ] || fail "usage error '$args': exit $rc, expected 2"
done
# one tetrahedron is 0.001% of lung_l: within the default 0.5%, not within --region-tol 1e-7
# (the good mesh's regions are within 1e-9 of their surfaces' volumes)
"$THORAX" check "$WORK/v_heart" --region-tol 1e-7 -q || fail "--region-tol 1e-7 on the good mesh"
set +e
"$THORAX" check "$WORK/v_relabel" --region-tol 1e-7 --json >"$WORK/rt.json" 2>"$WORK/rt.err"
set -e
"$PY" -c '
import json, sys
v = json.load(open(sys.argv[1]))["volume"]
assert sorted(v["failures"]) == ["coverage", "region_cells", "region_volume"], v["failures"]
bad = sorted(r["name"] for r in v["regions"] if not r["ok"])
assert bad == ["lung_l", "mean_thorax"], bad
' "$WORK/rt.json" || fail "--region-tol 1e-7"
grep -q 'region "lung_l": tetrahedra .* surfaces (lung_l)' "$WORK/rt.err" || fail "region volume reason"

echo "e2e_check: all passed"
