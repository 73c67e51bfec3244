#!/bin/bash
# End-to-end test of `thorax surfaces CONTOURS --edits LOG` (paper 3.2, "Manual editing"; issue 13):
# a log of every edit kind on the medium phantom replays, prints each edit's check (a deleted
# triangle opens the heart, the same triangle added back closes it, a re-lace says which edits it
# discarded), writes the model with the log as MODEL/edits.txt (named with its SHA-256 in
# model.json) and passes `thorax check`; the node moved is exactly where the log says and nothing
# else of its surface moved; the layer moved is the only layer of lung_l that changed, in its
# plane; the run is deterministic; a model records its contours (SHA-256, path from the model).
# Edits that no longer apply, another contour file, other options, a bad log: exit 1 with
# LOG:LINE and nothing written (an existing model kept).
# Environment: THORAX = the CLI, WORK = a scratch directory (created here).
set -u
: "${THORAX:?set THORAX to the thorax executable}"
: "${WORK:?set WORK to a scratch directory}"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

"$THORAX" phantom --resolution medium -o c.txt -q || bad "phantom"
"$THORAX" surfaces c.txt -o m0 -q 2> /dev/null || bad "surfaces m0"
SHA=$(sha256sum c.txt | cut -d' ' -f1)

# ---- the model records its contours ------------------------------------------------------------
$PY - "$SHA" <<'EOF' && ok "model.json records the contours' SHA-256 and their path from the model" || bad "contours record"
import json, sys
p = json.load(open("m0/model.json"))["provenance"]
assert p["input"] == "c.txt" and p["input_sha256"] == sys.argv[1], p
assert p["input_from_model"] == "../c.txt", p["input_from_model"]
assert "edit_log" not in p
EOF

# ---- a log of every kind, its header from the model's record (names as docs/formats.md gives them)
$PY - "$SHA" > e.txt <<'EOF' || bad "writing the log"
import json, sys
p = json.load(open("m0/model.json"))["provenance"]["options"]
def num(v):
    return ("%d" % v) if float(v) == int(v) else repr(float(v))
names = [("spacing", "spacing_mm"), ("smoothing", "smoothing_mm"), ("start", "start_point_mm"), ("cap", "cap"),
         ("cap_grid", "cap_grid_mm"), ("concave_tol", "concave_tol"), ("max_edge", "max_edge"),
         ("phase_weight", "phase_weight"), ("fan_limit", "fan_limit"), ("projected_aspect", "projected_aspect"),
         ("merge_tol", "merge_tol_mm"), ("untangle_tol", "untangle_tol_mm"), ("strict", "strict")]
words = []
for n, k in names:
    v = p[k]
    if k == "start_point_mm": v = "%s,%s" % (num(v[0]), num(v[1]))
    elif k == "cap": pass
    elif k == "strict": v = "1" if v else "0"
    else: v = num(v)
    words.append("%s=%s" % (n, v))
muscle5 = [float(x) for x in open("m0/muscle.pts").read().split("\n")[4].split()]
heart10 = [int(x) for x in open("m0/heart.fac").read().split("\n")[9].split()]
print("thorax-edits 1\n# e2e_edit.sh")
print("contours sha256:%s c.txt" % sys.argv[1])
print("build " + " ".join(words))
print("node_move muscle 5 %r %r %r   # 0.5 mm along x" % (muscle5[0] + 0.5, muscle5[1], muscle5[2]))
print("tri_delete heart 10")
print("tri_add heart %d %d %d   # the same nodes, the other way round" % (heart10[0], heart10[2], heart10[1]))
print("tri_flip fat 3\ntri_flip fat 3")
print("layer_move lung_l z=120 1.5 -1")
print("layer_rotate heart z=110 5")
print("layer_smooth torso z=150 4")
print("end")
EOF
if OMP_NUM_THREADS=1 "$THORAX" surfaces c.txt --edits e.txt -o m1 > out1.txt 2> err1.txt; then ok "surfaces --edits"; else bad "surfaces --edits: $(cat err1.txt)"; fi
grep -q "^e.txt:6: tri_delete heart 10: heart: FAILS: 3 open edges" out1.txt && ok "the deleted triangle opens the heart, and the check says so" || bad "tri_delete line: $(cat out1.txt)"
grep -q "^e.txt:7: tri_add heart .*: heart: passes: closed, orientation ok, solid angle 4pi within" out1.txt && ok "the same triangle added back closes it" || bad "tri_add line"
grep -q "^e.txt:8: tri_flip fat 3: fat: FAILS: closed, orientation: 3 edges traversed twice the same way" out1.txt && ok "a flipped triangle is an orientation fault" || bad "tri_flip line"
grep -q "^e.txt:11:   .*2 earlier node/triangle edits on it discarded by the re-lace" out1.txt && ok "the re-lace says which edits it discarded" || bad "discard note"
cmp -s e.txt m1/edits.txt && ok "the log is the model's edits.txt, byte for byte" || bad "edits.txt differs from the log"
$PY - <<'EOF' && ok "edits.txt named in model.json with its SHA-256" || bad "model.json's edit log record"
import hashlib, json
p = json.load(open("m1/model.json"))["provenance"]
assert p["edit_log"] == "edits.txt"
assert p["edit_log_sha256"] == hashlib.sha256(open("m1/edits.txt", "rb").read()).hexdigest()
EOF
"$THORAX" check m1 > check1.txt 2>&1 && ok "the edited model passes thorax check" || bad "check m1: $(cat check1.txt)"
$PY - <<'EOF' && ok "the node moved 0.5 mm along x, nothing else of muscle moved; only lung_l's layer z=120 moved, in its plane" || bad "what moved"
def pts(p): return [tuple(map(float, l.split())) for l in open(p).read().splitlines()]
a, b = pts("m0/muscle.pts"), pts("m1/muscle.pts")
assert len(a) == len(b)
diff = [i for i in range(len(a)) if a[i] != b[i]]
assert diff == [4], diff
assert abs(b[4][0] - a[4][0] - 0.5) < 2e-6 and b[4][1:] == a[4][1:], (a[4], b[4])
a, b = pts("m0/lung_l.pts"), pts("m1/lung_l.pts")
assert len(a) == len(b)
moved = {a[i][2] for i in range(len(a)) if a[i] != b[i]}
assert moved == {120.0}, moved
assert [p[2] for p in a] == [p[2] for p in b]
# the z=120 nodes' centroid moved by (1.5, -1)
ca = [p for p in a if p[2] == 120]; cb = [p for p in b if p[2] == 120]
dx = sum(p[0] for p in cb) / len(cb) - sum(p[0] for p in ca) / len(ca)
dy = sum(p[1] for p in cb) / len(cb) - sum(p[1] for p in ca) / len(ca)
assert abs(dx - 1.5) < 0.2 and abs(dy + 1) < 0.2, (dx, dy)
for s in ("fat",):
    assert open("m0/%s.fac" % s).read() == open("m1/%s.fac" % s).read()
EOF

# ---- deterministic, whatever the thread count; an edited model replaced by thorax itself --------
OMP_NUM_THREADS=2 "$THORAX" surfaces c.txt --edits e.txt -o m2 -q > /dev/null 2>&1 || bad "surfaces --edits (2 threads)"
diff -r -q -x model.json m1 m2 > /dev/null && ok "the replay is deterministic (1 and 2 threads)" || bad "replays differ"
"$THORAX" surfaces c.txt --edits e.txt -o m1 -q > /dev/null 2>&1 && ok "an edited model is thorax's own output (replaced)" || bad "m1 not replaced"

# ---- what stops a replay: exit 1, LOG:LINE, nothing written -------------------------------------
expect_fail() { # NAME LOG MESSAGE [extra options]
    local name=$1 log=$2 msg=$3
    shift 3
    rm -rf out
    "$THORAX" surfaces c.txt --edits "$log" -o out "$@" > /dev/null 2> err.txt
    local rc=$?
    if [ $rc -eq 1 ] && grep -qF -- "$msg" err.txt && [ ! -e out ]; then ok "$name"; else bad "$name: exit $rc, $(cat err.txt)"; fi
}
printf 'thorax-edits 1\ntri_flip heart 1\nnode_move torso 99999 1 2 3\nend\n' > b1.txt
expect_fail "a node out of range" b1.txt "b1.txt:3: node_move torso 99999 1 2 3: node 99999 out of range 1..3023"
printf 'thorax-edits 1\nlayer_move lung_r z=125 1 1\nend\n' > b2.txt
expect_fail "a layer not in the contours" b2.txt "b2.txt:2: layer_move lung_r z=125 1 1: surface \"lung_r\" has no layer at z=125"
sed "s/sha256:$SHA/sha256:$(echo x | sha256sum | cut -d' ' -f1)/" e.txt > b3.txt
expect_fail "another contour file" b3.txt "b3.txt:3: the log was made on contours of SHA-256"
expect_fail "other options" e.txt "e.txt:4: the log was made on surfaces built with other options (spacing: 10 here, 11 in the log)" --spacing 10
printf 'thorax-edits 1\ntri_flip heart 1\n' > b4.txt
expect_fail "a truncated log" b4.txt "b4.txt:2: truncated edit log (no 'end' line)"
printf 'thorax-edits 1\ntri_add heart 1 2\nend\n' > b5.txt
expect_fail "a bad edit line" b5.txt "b5.txt:2: tri_add: 3 values after the word, 4 needed (tri_add SURFACE NODE NODE NODE)"
expect_fail "a missing log" nothere.txt "nothere.txt"
cp -r m0 keep
"$THORAX" surfaces c.txt --edits b1.txt -o m0 > /dev/null 2>&1
diff -r -q m0 keep > /dev/null && ok "a failed replay keeps the old model" || bad "a failed replay damaged the old model"
printf 'thorax-edits 1\ntri_flip heart 1\ntri_flip heart 1\nend\n' > b6.txt
"$THORAX" surfaces c.txt --edits b6.txt -o m3 > /dev/null 2> err6.txt || bad "a log without a header"
grep -q "b6.txt: no 'contours' line" err6.txt && grep -q "b6.txt: no 'build' line" err6.txt && ok "a log without a header: warned, replayed" || bad "header warnings: $(cat err6.txt)"
"$THORAX" surfaces --help | grep -q -- "--edits LOG" && ok "--help names --edits" || bad "--help"

if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
