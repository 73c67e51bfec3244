#!/bin/bash
# End-to-end test of `thorax surfaces`: both phantom resolutions build, pass
# `thorax check` (closed, outward, 4 pi to 1e-6, no self-intersections) with the
# paper's counts; every kind of bad contour input fails with a message naming
# file and line, a non-zero exit, and no output directory.
# Environment: THORAX = the CLI, WORK = a scratch directory (created here).
set -u
shopt -s lastpipe # `printf ... | bad_input ...` runs bad_input in this shell, so its failures count
: "${THORAX:?set THORAX to the thorax executable}"
: "${WORK:?set WORK to a scratch directory}"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

# ---- the phantom at both resolutions --------------------------------------
# expected totals (paper 3.3): high 42,000 nodes / 85,000 triangles, medium 11,000 / 19,000 (+-15%, +-20% for medium nodes)
for res in high medium; do
    "$THORAX" phantom --resolution $res --seed 7 -o "$WORK/c_$res.txt" -q || bad "phantom $res"
    if "$THORAX" surfaces "$WORK/c_$res.txt" -o "$WORK/m_$res" > "$WORK/s_$res.log" 2>&1; then ok "surfaces $res"; else bad "surfaces $res: $(cat "$WORK/s_$res.log")"; fi
    "$THORAX" check "$WORK/m_$res" --json > "$WORK/check_$res.json" 2> "$WORK/check_$res.err"
    rc=$?
    [ $rc -eq 0 ] && ok "check $res exit 0" || bad "check $res exit $rc: $(cat "$WORK/check_$res.err")"
    if $PY - "$WORK/check_$res.json" $res <<'PYEOF'
import json, sys
d = json.load(open(sys.argv[1]))
res = sys.argv[2]
nodes = sum(s["nodes"] for s in d["surfaces"])
tris = sum(s["triangles"] for s in d["surfaces"])
want = {"high": (42000, 85000, 0.15), "medium": (11000, 19000, 0.20)}[res]
errs = []
names = sorted(s["name"] for s in d["surfaces"])
if names != sorted(["torso", "fat", "muscle", "lung_r", "lung_l", "heart"]): errs.append("surfaces %s" % names)
for s in d["surfaces"]:
    if not s["closed"] or not s["consistently_oriented"]: errs.append("%s not closed/oriented" % s["name"])
    if s["solid_angle"]["rel_error"] is None or s["solid_angle"]["rel_error"] > 1e-6: errs.append("%s solid angle %s" % (s["name"], s["solid_angle"]["rel_error"]))
    if s["intersections"]["pairs"] != 0: errs.append("%s intersects itself" % s["name"])
    if s["volume"] <= 0: errs.append("%s volume" % s["name"])
if abs(nodes - want[0]) > want[2] * want[0]: errs.append("nodes %d vs %d" % (nodes, want[0]))
if abs(tris - want[1]) > 0.15 * want[1]: errs.append("triangles %d vs %d" % (tris, want[1]))
print("%s: %d nodes, %d triangles, worst solid-angle error %.2e" % (res, nodes, tris, max(s["solid_angle"]["rel_error"] for s in d["surfaces"])))
if errs: print("\n".join(errs)); sys.exit(1)
PYEOF
    then ok "check $res figures"; else bad "check $res figures"; fi
done
# the model directory holds what map3d/SCIRun read: 1-based .fac, 3 columns; the manifest records provenance
head -n 1 "$WORK/m_medium/torso.fac" | grep -Eq '^[0-9]+ [0-9]+ [0-9]+$' && ok "fac format" || bad "fac format"
$PY -c "import json,sys; d=json.load(open('$WORK/m_medium/model.json')); assert d['provenance']['options']['spacing_mm']==11; assert 'thorax surfaces' in d['provenance']['command']" && ok "provenance" || bad "provenance"
# determinism: the same input gives byte-identical models
"$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/m_again" -q && diff -r -q -x model.json "$WORK/m_medium" "$WORK/m_again" > /dev/null && ok "deterministic" || bad "not deterministic"
OMP_NUM_THREADS=1 "$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/m_one" -q && diff -r -q -x model.json "$WORK/m_medium" "$WORK/m_one" > /dev/null && ok "same with 1 thread" || bad "thread count changes the model"
# both cap methods on the command line
"$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/m_poly" --cap polygon -q && "$THORAX" check "$WORK/m_poly" -q && ok "--cap polygon" || bad "--cap polygon"
"$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/m_grid" --cap grid --cap-grid 6 -q && "$THORAX" check "$WORK/m_grid" -q && ok "--cap grid 6" || bad "--cap grid"

# ---- bad input --------------------------------------------------------------
# bad_input NAME EXPECTED_MESSAGE_REGEX [OPTIONS...]: the contour text comes on stdin
bad_input() {
    local name=$1 want=$2 f="$WORK/bad_$1.txt" out="$WORK/bad_$1_model"
    shift 2
    cat > "$f"
    "$THORAX" surfaces "$f" -o "$out" "$@" > "$WORK/bad.out" 2> "$WORK/bad.err"
    local rc=$?
    if [ $rc -eq 0 ]; then bad "$name: accepted"; return; fi
    if [ -e "$out" ] || ls "$WORK" | grep -q "bad_${name}_model.tmp"; then bad "$name: left output behind"; fi
    if grep -Eq "$want" "$WORK/bad.err"; then ok "$name: $(cat "$WORK/bad.err")"; else bad "$name: message '$(cat "$WORK/bad.err")' does not match '$want'"; fi
}
HEAD='thorax-contours 1
surface s other'
SQ='0 0
10 0
10 10
0 10'
printf '%s\nlayer 0\nloop s\n0 0\n10 0\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input few_points 'bad_few_points.txt:4: surface "s" layer 1 \(z=0\) loop 1: loop has 2 points'
printf '%s\nlayer 0\nloop s\n0 0\n10 0\n10 0\n0 10\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input duplicate 'bad_duplicate.txt:7: surface "s" layer 1 \(z=0\) loop 1: the point repeats the point before .*refused: --strict' --strict
printf '%s\nlayer 0\nloop s\n0 0\n10 10\n10 0\n0 10\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input self_intersecting 'bad_self_intersecting.txt:[0-9]+: surface "s" layer 1 \(z=0\) loop 1: loop intersects itself'
printf '%s\nlayer 0\nloop s\n0 0\nnan 0\n10 10\n0 10\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input nan "bad_nan.txt:6: surface \"s\" layer 1 \\(z=0\\) loop 1: 'nan' is neither a keyword nor a finite decimal number"
printf '%s\nlayer 0\nloop s\n0 0\ninf 0\n10 10\n0 10\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input inf "bad_inf.txt:6: .*'inf' is neither a keyword nor a finite decimal number"
printf '%s\nlayer 5\nloop s\n%s\nlayer 0\nloop s\n%s\nlayer 10\nloop s\n%s\nend\n' "$HEAD" "$SQ" "$SQ" "$SQ" | bad_input out_of_order 'bad_out_of_order.txt:15: layer z=10 is out of order'
printf '%s\nlayer 0\nloop s\n%s\nlayer 0\nloop s\n%s\nend\n' "$HEAD" "$SQ" "$SQ" | bad_input duplicated_layer 'bad_duplicated_layer.txt:9: layer z=0 duplicates the layer at line 3'
printf 'thorax-contours 1\nsurface s other\nsurface t other\nlayer 0\nloop s\n%s\nloop t\n%s\nlayer 5\nloop t\n%s\nlayer 10\nloop s\n%s\nloop t\n%s\nend\n' "$SQ" "$SQ" "$SQ" "$SQ" "$SQ" | bad_input vanishes 'bad_vanishes.txt:[0-9]+: surface "s" vanishes at z=5 and reappears at z=10'
printf '%s\nlayer 0\nloop s\n%s\nlayre 5\nend\n' "$HEAD" "$SQ" | bad_input unknown_keyword "bad_unknown_keyword.txt:9: unknown keyword 'layre'"
printf '%s\nlayer 0\nloop s\n%s\nlayer 5\nloop s\n0 0\n10 0\n10 1' "$HEAD" "$SQ" | bad_input truncated "bad_truncated.txt:[0-9]+: truncated file: surface \"s\" layer 2 loop 1 is cut short \\(no 'end' line\\)"
printf '' | bad_input empty 'bad_empty.txt: empty file'
printf '# only a comment\n\n' | bad_input comments_only 'bad_comments_only.txt: empty file'
printf 'thorax-contours 2\nend\n' | bad_input version 'bad_version.txt:1: not a thorax contour file'
printf '%s\nlayer 0\nloop s\n0 0 0\nend\n' "$HEAD" | bad_input three_numbers "bad_three_numbers.txt:5: surface \"s\" layer 1 \\(z=0\\) loop 1 point 1: a point is two finite decimal numbers 'x y'"
printf '%s\nlayer 0\nloop lung\n%s\nend\n' "$HEAD" "$SQ" | bad_input undeclared 'bad_undeclared.txt:4: loop of undeclared surface "lung"'
printf 'thorax-contours 1\nsurface s liver\nend\n' | bad_input role "bad_role.txt:2: surface \"s\": unknown role 'liver'"
printf '%s\nlayer 0\nloop s\n%s\nend\n' "$HEAD" "$SQ" | bad_input one_layer 'bad_one_layer.txt:2: surface "s" is digitized on only one layer'
printf '%s\nlayer 0\nloop s\n%s\nlayer 5\nloop s\n%s\nloop s\n100 100\n101 100\n101 101\nlayer 10\nloop s\n%s\nend\n' "$HEAD" "$SQ" "$SQ" "$SQ" | bad_input island 'bad_island.txt:15: surface "s" layer 2 \(z=5\): the loop overlaps no loop of the layers above and below'
# repaired, not refused (issue 11 item 6): a repeated point and a closing point are dropped and reported
printf '%s\nlayer 0\nloop s\n0 0\n10 0\n10 0\n0 10\n0 0\nlayer 5\nloop s\n%s\nend\n' "$HEAD" "$SQ" > "$WORK/repair.txt"
if "$THORAX" surfaces "$WORK/repair.txt" -o "$WORK/m_repair" > /dev/null 2> "$WORK/repair.err" && "$THORAX" check "$WORK/m_repair" -q &&
    grep -q 'repair.txt:7: surface "s" layer 1 (z=0) loop 1: the point repeats the point before (10, 0): merged into one' "$WORK/repair.err" &&
    grep -q 'repair.txt:9: surface "s" layer 1 (z=0) loop 1: the last point (5) repeats the first point (0, 0): dropped' "$WORK/repair.err" &&
    ! grep -q 'intersects' "$WORK/repair.err"; then ok "repeated and closing points repaired and reported"
else bad "repair: $(cat "$WORK/repair.err")"; fi
"$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/x" --merge-tol -1 2> /dev/null; [ $? -eq 2 ] && ok "bad --merge-tol: usage error" || bad "bad --merge-tol"
# a missing file and usage errors
"$THORAX" surfaces "$WORK/does_not_exist.txt" -o "$WORK/x" 2> "$WORK/err" ; rc=$?
[ $rc -eq 1 ] && grep -q "does_not_exist.txt: cannot open" "$WORK/err" && ok "missing file" || bad "missing file (exit $rc)"
"$THORAX" surfaces "$WORK/c_medium.txt" 2> /dev/null; [ $? -eq 2 ] && ok "no -o: usage error" || bad "no -o"
"$THORAX" surfaces "$WORK/c_medium.txt" -o "$WORK/x" --cap hexagon 2> /dev/null; [ $? -eq 2 ] && ok "bad --cap: usage error" || bad "bad --cap"
# a failed run leaves an existing model untouched
cp -r "$WORK/m_medium" "$WORK/m_keep"
printf '' > "$WORK/empty.txt"
"$THORAX" surfaces "$WORK/empty.txt" -o "$WORK/m_keep" 2> /dev/null
diff -r -q "$WORK/m_medium" "$WORK/m_keep" > /dev/null && ok "failed run keeps the old model" || bad "failed run damaged the old model"

if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
