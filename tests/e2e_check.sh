#!/bin/bash
# End-to-end test of `thorax check` on a real closed surface: the Utah torso
# tank (map3d, ../shared/data/map3d/geom/tank/tank_full_771.pts/.fac).
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
"$THORAX" check --help | grep -q 'usage: thorax check MODEL' || fail "--help"

echo "e2e_check: all passed"
