#!/bin/bash
# End-to-end volume meshing (paper 3.3) of the medium phantom: phantom -> surfaces ->
# mesh -> check (surfaces and volume: conforming, closed boundary, positive,
# volume within 1% of the torso's), with and without the heart; the counts against
# the paper's medium model (22,000 nodes, 130,000 tetrahedra); vtu and msh exports.
# Environment: THORAX = the CLI, WORK = a scratch directory.
set -u
: "${THORAX:?}" "${WORK:?}"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
"$THORAX" phantom --resolution medium --seed 3 -o "$WORK/c.txt" -q && "$THORAX" surfaces "$WORK/c.txt" -o "$WORK/m" -q || { bad "phantom/surfaces"; exit 1; }
for variant in heart no-heart; do
    opt=""; [ $variant = no-heart ] && opt="--no-heart"
    if "$THORAX" mesh "$WORK/m" -o "$WORK/v_$variant" $opt > "$WORK/mesh_$variant.log" 2>&1; then ok "mesh ($variant)"; else bad "mesh ($variant): $(cat "$WORK/mesh_$variant.log")"; continue; fi
    "$THORAX" check "$WORK/v_$variant" --json > "$WORK/check_$variant.json" 2> "$WORK/check_$variant.err"
    rc=$?
    [ $rc -eq 0 ] && ok "check ($variant) exit 0" || bad "check ($variant) exit $rc: $(cat "$WORK/check_$variant.err")"
    if $PY - "$WORK/check_$variant.json" $variant <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1])); v = d["volume"]; variant = sys.argv[2]
errs = []
if not (v["ok"] and v["conforming"] and v["boundary_closed"] and v["positive"]): errs.append("volume checks: %s" % v.get("reasons"))
diff = v["volume"]["rel_diff"] if isinstance(v["volume"], dict) and "rel_diff" in v["volume"] else None
nodes, tets = v["nodes"], v["tetrahedra"]
print("%s: %d nodes, %d tetrahedra, volume difference %s" % (variant, nodes, tets, diff))
if diff is None or abs(diff) > 0.01: errs.append("volume difference %s" % diff)
# the paper's medium mesh had about 22,000 nodes and 130,000 tetrahedra; the quality refinement adds
# points near the surfaces (docs/decisions.md, "Quality by Delaunay refinement")
# plausibility against the paper's medium model, which did not conform and had no quality bounds:
# conformity and the quality refinement (radius-edge 1.6, 10 deg) take more (TetGen -pq1.414/10
# makes 402,753 of the same surfaces; bench/mesh.sh)
if variant == "heart" and not (15000 <= nodes <= 70000 and 100000 <= tets <= 400000): errs.append("counts %d %d" % (nodes, tets))
# pinned (issue 24): the mesher is deterministic (the same counts in the optimized and the sanitized
# Debug build), so a change in what it makes shows here, not only when a threshold breaks (the
# repair's radius-edge bound left unsquared changed 301,747 tetrahedra into 301,890 and passed every
# threshold). A deliberate change of the mesher updates these figures in the same commit.
pinned = {"heart": (56845, 334139), "no-heart": (54643, 317622)}[variant]
if (nodes, tets) != pinned:
    errs.append("counts %d nodes, %d tetrahedra: pinned %d, %d (a change of the mesher? update the pin with it)"
                % (nodes, tets, pinned[0], pinned[1]))
if errs: print("\n".join(errs)); sys.exit(1)
PYEOF
    then ok "figures ($variant)"; else bad "figures ($variant)"; fi
    # conformity judged independently of thorax (tests/conformity.py)
    if $PY "$SRC/tests/conformity.py" "$WORK/v_$variant" > "$WORK/conf_$variant.txt" 2>&1; then ok "conforming ($variant): $(head -1 "$WORK/conf_$variant.txt")"; else bad "conformity ($variant): $(cat "$WORK/conf_$variant.txt")"; fi
done
grep -q '"regions"' "$WORK/v_heart/model.json" && grep -q '"muscle"' "$WORK/v_heart/model.json" && ok "region table in model.json" || bad "region table"
"$THORAX" export "$WORK/v_heart" --format vtu -o "$WORK/exp" -q && "$THORAX" export "$WORK/v_heart" --format msh -o "$WORK/exp" -q &&
    [ -s "$WORK/exp/volume.vtu" ] && [ -s "$WORK/exp/volume.msh" ] && ok "vtu and msh exports" || bad "exports"
# a model without an outer surface cannot be meshed
mkdir -p "$WORK/noouter" && cp "$WORK/m/heart.pts" "$WORK/m/heart.fac" "$WORK/noouter/" &&
printf '{"format": "thorax-model", "version": 1, "units": "mm", "surfaces": [{"name": "heart", "role": "heart", "pts": "heart.pts", "fac": "heart.fac", "n_nodes": %d, "n_tris": %d}]}\n' \
    "$(grep -c . "$WORK/m/heart.pts")" "$(grep -c . "$WORK/m/heart.fac")" > "$WORK/noouter/model.json"
"$THORAX" mesh "$WORK/noouter" 2> "$WORK/err"; rc=$?
[ $rc -eq 1 ] && grep -q 'no surface of role "outer"' "$WORK/err" && ok "no outer surface: refused" || bad "no outer surface (exit $rc)"
if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
