#!/bin/bash
# End-to-end test of `thorax import` on real closed surfaces: the Utah torso
# tank (tank_full_771, role outer) and the closed epicardial sock
# (25feb97_sock_closed, role heart) from ../shared/data/map3d/geom/tank/.
#
# Environment: THORAX = the built CLI, SRC = the source tree, WORK = a scratch
# directory (created, emptied). Exits non-zero on the first failed expectation.
#
# What is checked:
#  - both surfaces import into one model; the detected .fac base (1 for these
#    files) is reported and recorded in the provenance; `thorax check` passes
#    with |Omega/4pi - 1| < 1e-6 for both, using the stored interior points;
#  - the model's surfaces exported by `thorax export` (stl, obj, ply, vtk, vtp)
#    import again with the same node and triangle counts;
#  - files written by VTK itself (python3-vtk9: legacy 5.1 ASCII and binary,
#    ASCII and binary STL, binary PLY, OBJ) import with the same counts and
#    coordinates within float precision;
#  - a 0-based copy of the .fac is detected as such;
#  - an ECGSim .tri in metres with clockwise triangles (ECGSim's convention),
#    imported with --scale 1000, is reversed (reported) and reproduces the sock;
#  - the open tank_leads_192 surface is refused: exit 1, no model directory;
#    with --force it is written and `thorax check` then fails;
#  - usage errors exit 2.
set -euo pipefail

: "${THORAX:?THORAX must point to the thorax executable}"
: "${SRC:?SRC must point to the source tree}"
: "${WORK:?WORK must name a scratch directory}"
PY=/usr/bin/python3
DATA="$SRC/../shared/data/map3d/geom/tank"
for f in tank_full_771 25feb97_sock_closed tank_leads_192; do
    [ -r "$DATA/$f.pts" ] && [ -r "$DATA/$f.fac" ] || { echo "e2e_import: missing $DATA/$f.pts/.fac"; exit 1; }
done

rm -rf "$WORK"
mkdir -p "$WORK"
fail() { echo "e2e_import: FAIL: $*"; exit 1; }
ok() { echo "ok: $*"; }

# run EXPECTED_RC OUT ERR CMD...: runs CMD, requires its exit status
run() {
    local want=$1 out=$2 err=$3
    shift 3
    set +e
    "$@" >"$out" 2>"$err"
    local rc=$?
    set -e
    if [ $rc -ne "$want" ]; then
        cat "$out" "$err"
        fail "'$*' exited $rc, expected $want"
    fi
}

# counts NAME: "nodes triangles" of a surface in model directory $1
counts() {
    "$PY" -c '
import json, sys
for s in json.load(open(sys.argv[1] + "/model.json"))["surfaces"]:
    if s["name"] == sys.argv[2]: print(s["n_nodes"], s["n_tris"])
' "$1" "$2"
}

# --- the tank and the closed sock into one model -----------------------------
M="$WORK/model"
run 0 "$WORK/import.out" "$WORK/import.err" "$THORAX" import -o "$M" \
    "$DATA/tank_full_771.pts" --name tank --role outer \
    "$DATA/25feb97_sock_closed.pts" --name sock --role heart
cat "$WORK/import.out"
[ "$(grep -c 'node numbers 1-based (detected)' "$WORK/import.out")" -eq 2 ] || fail "detected base 1 not reported twice"
grep -q '^wrote .*model (2 surfaces)$' "$WORK/import.out" || fail "no 'wrote' line"
grep -q 'reversed' "$WORK/import.out" && fail "the tank or sock was reversed, but both are stored outward"
[ "$(counts "$M" tank)" = "771 1538" ] || fail "tank counts: $(counts "$M" tank)"
[ "$(counts "$M" sock)" = "128 252" ] || fail "sock counts: $(counts "$M" sock)"
"$PY" - "$M/model.json" <<'EOF' || fail "model.json provenance / interior points"
import json, sys
m = json.load(open(sys.argv[1]))
assert [s["role"] for s in m["surfaces"]] == ["outer", "heart"]
assert all(len(s["interior"]) == 3 for s in m["surfaces"]), "interior points stored"
p = m["provenance"]
assert "thorax import" in p["command"], p["command"]
ins = {i["surface"]: i for i in p["inputs"]}
for name, f in (("tank", "tank_full_771"), ("sock", "25feb97_sock_closed")):
    i = ins[name]
    assert i["file"].endswith(f + ".pts") and i["fac"].endswith(f + ".fac"), i
    assert i["format"] == "pts/fac" and i["index_base"] == 1 and i["index_base_detected"] is True, i
    assert i["reversed"] is False and i["unused_nodes_removed"] == 0 and i["check"]["ok"] is True, i
    assert i["check"]["solid_angle_rel_error"] < 1e-6, i
EOF
ok "tank + sock imported; base 1 detected and recorded"

run 0 "$WORK/check.json" "$WORK/check.err" "$THORAX" check "$M" --json
"$PY" - "$WORK/check.json" <<'EOF' || fail "thorax check figures"
import json, sys
r = json.load(open(sys.argv[1]))
assert r["ok"] is True
for s in r["surfaces"]:
    sa = s["solid_angle"]
    assert s["ok"] and s["closed"] and sa["interior_source"] == "given", s["name"]
    assert sa["rel_error"] < 1e-6, (s["name"], sa)
    print("check %s: |Omega/4pi - 1| = %.3g" % (s["name"], sa["rel_error"]))
EOF
ok "thorax check passes, solid-angle error < 1e-6 for both"

# coordinates are the files' own (within the %.6f of the model files)
"$PY" - "$DATA/tank_full_771.pts" "$M/tank.pts" <<'EOF' || fail "tank coordinates changed"
import sys
a = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
b = [list(map(float, l.split())) for l in open(sys.argv[2]) if l.strip()]
assert len(a) == len(b) and max(abs(x - y) for p, q in zip(a, b) for x, y in zip(p, q)) < 1e-6
EOF

# --- export and re-import: same counts ---------------------------------------
for fmt in stl obj ply vtk vtp; do
    run 0 /dev/null "$WORK/export.err" "$THORAX" export "$M" --format "$fmt" -o "$WORK/exp_$fmt"
    run 0 "$WORK/re_$fmt.out" "$WORK/re_$fmt.err" "$THORAX" import -o "$WORK/re_$fmt" \
        "$WORK/exp_$fmt/tank.$fmt" --name tank --role outer "$WORK/exp_$fmt/sock.$fmt" --name sock --role heart
    [ "$(counts "$WORK/re_$fmt" tank)" = "771 1538" ] || fail "$fmt: tank counts $(counts "$WORK/re_$fmt" tank)"
    [ "$(counts "$WORK/re_$fmt" sock)" = "128 252" ] || fail "$fmt: sock counts $(counts "$WORK/re_$fmt" sock)"
    grep -q 'reversed' "$WORK/re_$fmt.out" && fail "$fmt: export + import reversed a surface"
    run 0 /dev/null "$WORK/recheck.err" "$THORAX" check "$WORK/re_$fmt" -q
    ok "export $fmt + import: same counts"
done
grep -q 'merged 3843 STL facet corners into 771 shared nodes' "$WORK/re_stl.out" || fail "STL merge not reported"

# --- files written by VTK itself ---------------------------------------------
"$PY" - "$DATA/25feb97_sock_closed.pts" "$DATA/25feb97_sock_closed.fac" "$WORK" <<'EOF' || fail "writing VTK files"
import sys, vtk
pts = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
fac = [list(map(int, l.split())) for l in open(sys.argv[2]) if l.strip()]
P = vtk.vtkPoints()
P.SetDataTypeToDouble()
for p in pts: P.InsertNextPoint(*p)
C = vtk.vtkCellArray()
for t in fac:
    C.InsertNextCell(3)
    for i in t: C.InsertCellPoint(i - 1)
pd = vtk.vtkPolyData(); pd.SetPoints(P); pd.SetPolys(C)
w = sys.argv[3]
def write(writer, name, setup):
    writer.SetFileName(w + "/" + name); writer.SetInputData(pd); setup(writer); writer.Write()
write(vtk.vtkPolyDataWriter(), "vtk_ascii.vtk", lambda x: x.SetFileTypeToASCII())
write(vtk.vtkPolyDataWriter(), "vtk_binary.vtk", lambda x: x.SetFileTypeToBinary())
write(vtk.vtkSTLWriter(), "vtk_ascii.stl", lambda x: x.SetFileTypeToASCII())
write(vtk.vtkSTLWriter(), "vtk_binary.stl", lambda x: x.SetFileTypeToBinary())
write(vtk.vtkPLYWriter(), "vtk_binary.ply", lambda x: x.SetFileTypeToBinary())
write(vtk.vtkOBJWriter(), "vtk.obj", lambda x: None)
write(vtk.vtkXMLPolyDataWriter(), "vtk_ascii.vtp", lambda x: x.SetDataModeToAscii())
write(vtk.vtkXMLPolyDataWriter(), "vtk_appended.vtp", lambda x: None)
EOF
for f in vtk_ascii.vtk vtk_binary.vtk vtk_ascii.stl vtk_binary.stl vtk_binary.ply vtk.obj vtk_ascii.vtp; do
    run 0 "$WORK/$f.out" "$WORK/$f.err" "$THORAX" import -o "$WORK/m_$f" "$WORK/$f" --name sock --role heart
    [ "$(counts "$WORK/m_$f" sock)" = "128 252" ] || fail "$f: counts $(counts "$WORK/m_$f" sock)"
    # same nodes (STL: as a set, in float precision), same triangles as point triples
    "$PY" - "$DATA/25feb97_sock_closed.pts" "$DATA/25feb97_sock_closed.fac" "$WORK/m_$f" <<'EOF' || fail "$f: geometry differs"
import sys
ref = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
rf = [list(map(int, l.split())) for l in open(sys.argv[2]) if l.strip()]
got = [list(map(float, l.split())) for l in open(sys.argv[3] + "/sock.pts") if l.strip()]
gf = [list(map(int, l.split())) for l in open(sys.argv[3] + "/sock.fac") if l.strip()]
tol = 1e-4  # float32 of coordinates up to ~300 mm
def tri(p, f): return [tuple(tuple(p[i - 1]) for i in t) for t in f]
for a, b in zip(tri(ref, rf), tri(got, gf)):
    assert all(abs(x - y) <= tol for pa, pb in zip(a, b) for x, y in zip(pa, pb)), (a, b)
EOF
done
ok "VTK's own vtk (5.1 ascii and binary), stl (ascii, binary), ply (binary), obj, vtp (ascii) import"
run 1 /dev/null "$WORK/appended.err" "$THORAX" import -o "$WORK/m_app" "$WORK/vtk_appended.vtp" --name s --role heart
grep -q 'only format="ascii"' "$WORK/appended.err" || { cat "$WORK/appended.err"; fail "appended VTP: reason"; }
[ ! -e "$WORK/m_app" ] || fail "appended VTP: a model directory was written"

# --- a 0-based copy of the .fac ----------------------------------------------
cp "$DATA/25feb97_sock_closed.pts" "$WORK/zero.pts"
awk 'NF == 3 { print $1 - 1, $2 - 1, $3 - 1 }' "$DATA/25feb97_sock_closed.fac" >"$WORK/zero.fac"
run 0 "$WORK/zero.out" "$WORK/zero.err" "$THORAX" import -o "$WORK/m_zero" "$WORK/zero.pts" --name sock --role heart
grep -q 'node numbers 0-based (detected)' "$WORK/zero.out" || { cat "$WORK/zero.out"; fail "0-based .fac not reported"; }
cmp -s "$WORK/m_zero/sock.fac" "$M/sock.fac" || fail "0-based .fac gave other triangles"
# --fac names the pair explicitly
run 0 /dev/null "$WORK/fac.err" "$THORAX" import -o "$WORK/m_fac" "$WORK/zero.pts" --fac "$WORK/zero.fac" --name s --role heart
ok "0-based .fac detected"

# --- ECGSim .tri: metres, clockwise seen from outside -------------------------
"$PY" - "$DATA/25feb97_sock_closed.pts" "$DATA/25feb97_sock_closed.fac" "$WORK/sock.tri" <<'EOF'
import sys
pts = [list(map(float, l.split())) for l in open(sys.argv[1]) if l.strip()]
fac = [list(map(int, l.split())) for l in open(sys.argv[2]) if l.strip()]
with open(sys.argv[3], "w") as f:
    f.write("%d\n" % len(pts))
    for i, p in enumerate(pts): f.write("%d %.9f %.9f %.9f\n" % (i + 1, p[0] / 1000, p[1] / 1000, p[2] / 1000))
    f.write("%d\n" % len(fac))
    for i, t in enumerate(fac): f.write("%d %d %d %d\n" % (i + 1, t[0], t[2], t[1]))  # clockwise
    f.write("\nsock of 25 Feb 1997, metres (a trailer, as in the PhysioNet files)\n")
EOF
run 0 "$WORK/tri.out" "$WORK/tri.err" "$THORAX" import -o "$WORK/m_tri" "$WORK/sock.tri" --name sock --role heart --scale 1000
cat "$WORK/tri.out"
grep -q 'reversed: triangles were clockwise seen from outside' "$WORK/tri.out" || fail ".tri: reversal not reported"
grep -q 'ignored the text after the last triangle' "$WORK/tri.out" || fail ".tri: trailer not reported"
grep -q 'node numbers 1-based (detected)' "$WORK/tri.out" || fail ".tri: base not reported"
cmp -s "$WORK/m_tri/sock.fac" "$M/sock.fac" || fail ".tri: reversed triangles differ from the sock's"
cmp -s "$WORK/m_tri/sock.pts" "$M/sock.pts" || fail ".tri: scaled coordinates differ from the sock's"
"$PY" -c '
import json, sys
i = json.load(open(sys.argv[1]))["provenance"]["inputs"][0]
assert i["reversed"] is True and i["scale"] == 1000 and i["format"] == "tri", i
' "$WORK/m_tri/model.json" || fail ".tri: provenance"
run 0 /dev/null "$WORK/tri_check.err" "$THORAX" check "$WORK/m_tri"
# the same file without --scale: a warning about units
run 0 /dev/null "$WORK/tri_m.err" "$THORAX" import -o "$WORK/m_tri_m" "$WORK/sock.tri" --name sock --role heart
grep -q 'use --scale 1000' "$WORK/tri_m.err" || { cat "$WORK/tri_m.err"; fail ".tri in metres: no units warning"; }
ok "ECGSim .tri: clockwise reversed, metres scaled, trailer ignored"

# --- an open surface is refused ----------------------------------------------
run 1 "$WORK/refused.out" "$WORK/refused.err" "$THORAX" import -o "$WORK/open" \
    "$DATA/tank_full_771.pts" --name tank --role outer "$DATA/tank_leads_192.pts" --name leads --role other
cat "$WORK/refused.err"
[ ! -e "$WORK/open" ] || fail "open surface: a model directory was written"
ls "$WORK" | grep -q '^open\.' && fail "open surface: temporary output left behind"
grep -q 'surface "leads": not closed' "$WORK/refused.err" || fail "open surface: reason"
grep -q 'surface "leads": refused' "$WORK/refused.err" || fail "open surface: 'refused'"
grep -q '1 of 2 surfaces failed; nothing written' "$WORK/refused.err" || fail "open surface: summary"
# with --force: written with a warning, and `thorax check` fails on it
run 0 "$WORK/force.out" "$WORK/force.err" "$THORAX" import -o "$WORK/forced" "$DATA/tank_leads_192.pts" \
    --name leads --role other --force
grep -q 'warning: .*written anyway (--force)' "$WORK/force.err" || { cat "$WORK/force.err"; fail "--force: no warning"; }
run 1 /dev/null /dev/null "$THORAX" check "$WORK/forced"
ok "open tank_leads_192 refused (exit 1, nothing written); --force writes it with a warning"

# --- a read error names the file and line ------------------------------------
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n' >"$WORK/bad.obj"
run 1 /dev/null "$WORK/bad.err" "$THORAX" import -o "$WORK/bad" "$WORK/bad.obj" --name b --role other
grep -q 'bad.obj:4: surface "b": face refers to vertex 9' "$WORK/bad.err" || { cat "$WORK/bad.err"; fail "bad.obj message"; }
[ ! -e "$WORK/bad" ] || fail "bad.obj: output written"

# --- usage --------------------------------------------------------------------
T="$DATA/tank_full_771.pts"
for args in "" "$T --name t --role outer" "-o $WORK/u $T --role outer" "-o $WORK/u $T --name t" \
            "-o $WORK/u --name t $T --role outer" "-o $WORK/u $T --name t --role liver" \
            "-o $WORK/u $T --name t --role outer $T --name t --role outer" "-o $WORK/u $T --name t --role outer --scale 0" \
            "-o $WORK/u $T --name t --role outer --format gltf" "-o $WORK/u $T --name t --role outer --bogus" \
            "-o $WORK/u $T --name t --name u --role outer" "-o $WORK/u"; do
    set +e
    # shellcheck disable=SC2086
    "$THORAX" import $args >/dev/null 2>&1
    rc=$?
    set -e
    [ $rc -eq 2 ] || fail "usage error '$args': exit $rc, expected 2"
done
[ ! -e "$WORK/u" ] || fail "a usage error wrote output"
"$THORAX" import --help | grep -q '^usage: thorax import' || fail "--help"
q_out=$("$THORAX" import -q -o "$WORK/quiet" "$T" --name t --role outer) || fail "-q run"
[ -z "$q_out" ] || fail "-q printed: $q_out"
ok "usage errors exit 2; --help; -q"

echo "e2e_import: all passed"
