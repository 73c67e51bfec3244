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
# Before those (they need ../shared/data/map3d), without shared data:
#  - volume meshes: a thorax-made volume (two nested spheres from VTK's sphere
#    source, imported and meshed by thorax) exported as .vtu and .msh, its own
#    volume.pts/.tet, a CARP copy, and VTK's own .vtk (ASCII, binary) and .vtu
#    (binary, appended raw, zlib) writings of it all import to the same mesh:
#    node and tetrahedron counts, the same volume.tet, region volumes equal to
#    the original's, `thorax check` passing;
#  - a sphere in a sphere meshed by Gmsh itself (python3-gmsh, MSH 4.1):
#    imported with --scale and --region, region volumes equal to the ones
#    computed from Gmsh's own mesh, surfaces named by its physical surfaces;
#  - bad volume meshes are refused (exit 1, nothing written): truncated,
#    non-tetrahedral cells, counts beyond the file, a failed check (written
#    with --force, and then `thorax check` fails); usage errors exit 2;
# and, when ../shared/data/openmeeg-spheres is there (else skipped, saying
# so; OPENMEEG_DATA overrides the place):
#  - OpenMEEG's three-sphere heads (Head1-3: .tri with normals, 0-based,
#    clockwise, radius 1) import with --scale 100, are reversed, and pass
#    `thorax check` with radius 100 mm.
set -euo pipefail

: "${THORAX:?THORAX must point to the thorax executable}"
: "${SRC:?SRC must point to the source tree}"
: "${WORK:?WORK must name a scratch directory}"
PY=/usr/bin/python3
DATA="$SRC/../shared/data/map3d/geom/tank"
OPENMEEG_DATA="${OPENMEEG_DATA:-$SRC/../shared/data/openmeeg-spheres/data}"

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

# --- OpenMEEG's three-sphere heads (.tri with normals) -------------------------
if [ -r "$OPENMEEG_DATA/Head1/scalp.1.tri" ]; then
    for h in 1 2 3; do
        D="$OPENMEEG_DATA/Head$h"
        run 0 "$WORK/head$h.out" "$WORK/head$h.err" "$THORAX" import -o "$WORK/head$h" --scale 100 \
            "$D/scalp.$h.tri" --name scalp --role outer "$D/skull.$h.tri" --name skull --role other \
            "$D/cortex.$h.tri" --name brain --role other
        [ "$(grep -c 'read: OpenMEEG .tri (vertex normals ignored)' "$WORK/head$h.out")" -eq 3 ] || fail "Head$h: format not reported"
        [ "$(grep -c 'reversed: triangles were clockwise' "$WORK/head$h.out")" -eq 3 ] || fail "Head$h: not reversed"
        run 0 "$WORK/head$h.json" "$WORK/head$h.cerr" "$THORAX" check "$WORK/head$h" --json
        "$PY" - "$WORK/head$h" "$WORK/head$h.json" $h <<'EOF' || fail "Head$h: check figures"
import json, math, sys
d, r, h = sys.argv[1], json.load(open(sys.argv[2])), int(sys.argv[3])
assert r["ok"] is True
nv = {1: 42, 2: 162, 3: 642}[h]
radius = {"scalp": 100.0, "skull": 92.0, "brain": 87.0}
for s in r["surfaces"]:
    assert s["ok"] and s["closed"] and s["nodes"] == nv and s["triangles"] == 2 * nv - 4, s["name"]
    assert s["solid_angle"]["rel_error"] < 1e-9, s["solid_angle"]
    pts = [list(map(float, l.split())) for l in open(d + "/" + s["name"] + ".pts") if l.strip()]
    rr = [math.sqrt(sum(c * c for c in p)) for p in pts]
    assert max(abs(x - radius[s["name"]]) for x in rr) < 1e-3, (s["name"], min(rr), max(rr))
print("Head%d: 3 spheres of %d nodes, radii 100/92/87 mm, thorax check ok" % (h, nv))
EOF
    done
    # a copy cut short is refused, naming the line where it ends
    head -30 "$OPENMEEG_DATA/Head1/scalp.1.tri" >"$WORK/cut.tri"
    run 1 /dev/null "$WORK/cut.err" "$THORAX" import -o "$WORK/cut" "$WORK/cut.tri" --name scalp --role outer
    grep -q 'cut.tri:30: surface "scalp": file ends at vertex 30 of 42' "$WORK/cut.err" || { cat "$WORK/cut.err"; fail "cut .tri"; }
    [ ! -e "$WORK/cut" ] || fail "cut .tri: output written"
    ok "OpenMEEG Head1-3 (.tri, --scale 100) import and pass thorax check"
else
    echo "e2e_import: skipped OpenMEEG heads: $OPENMEEG_DATA not found"
fi

# --- volume meshes ------------------------------------------------------------
# vcounts DIR: "nodes tetrahedra regions surfaces" of a model directory's volume
vcounts() {
    "$PY" -c '
import json, sys
m = json.load(open(sys.argv[1] + "/model.json"))
print(m["volume"]["n_nodes"], m["volume"]["n_tets"], len(m["regions"]), len(m["surfaces"]))
' "$1"
}
# rvolumes DIR: the volume of each region (mm^3, by region id), from volume.pts/.tet
rvolumes() {
    "$PY" -c '
import sys
d = sys.argv[1]
p = [list(map(float, l.split())) for l in open(d + "/volume.pts") if l.strip()]
vol = {}
for l in open(d + "/volume.tet"):
    if not l.strip(): continue
    a, b, c, e, r = map(int, l.split())
    A, B, C, E = p[a - 1], p[b - 1], p[c - 1], p[e - 1]
    u = [B[i] - A[i] for i in range(3)]; v = [C[i] - A[i] for i in range(3)]; w = [E[i] - A[i] for i in range(3)]
    det = (u[1] * v[2] - u[2] * v[1]) * w[0] + (u[2] * v[0] - u[0] * v[2]) * w[1] + (u[0] * v[1] - u[1] * v[0]) * w[2]
    assert det > 0, "left-handed tetrahedron"
    vol[r] = vol.get(r, 0.0) + det / 6.0
print(" ".join("%.6f" % vol[k] for k in sorted(vol)))
' "$1"
}
V="$WORK/vol"
mkdir -p "$V"
"$PY" - "$V" <<'EOF' || fail "writing the spheres"
import sys, vtk
for name, r, res in (("outer", 60, 16), ("inner", 30, 12)):
    s = vtk.vtkSphereSource(); s.SetRadius(r); s.SetThetaResolution(res); s.SetPhiResolution(res); s.Update()
    w = vtk.vtkPolyDataWriter(); w.SetFileName(sys.argv[1] + "/" + name + ".vtk"); w.SetInputData(s.GetOutput()); w.Write()
EOF
run 0 /dev/null "$V/s.err" "$THORAX" import -o "$V/spheres" "$V/outer.vtk" --name outer --role outer "$V/inner.vtk" --name inner --role other
run 0 /dev/null "$V/mesh.err" "$THORAX" mesh "$V/spheres" -o "$V/made" -q
run 0 /dev/null "$V/x.err" "$THORAX" export "$V/made" --format vtu -o "$V/exp" -q
run 0 /dev/null "$V/x.err" "$THORAX" export "$V/made" --format msh -o "$V/exp" -q
REF="$(vcounts "$V/made")"
REFV="$(rvolumes "$V/made")"
echo "thorax-made volume: $REF (nodes tetrahedra regions surfaces); region volumes $REFV"
# its own volume.pts + volume.tet (1-based, region column) and a CARP copy (counted, Tt, 0-based)
cp "$V/made/volume.pts" "$V/plain.pts"
cp "$V/made/volume.tet" "$V/plain.tet"
awk 'NR == FNR { n++; next } FNR == 1 { print n } { print }' "$V/plain.pts" "$V/plain.pts" >"$V/carp.pts"
awk 'NR == FNR { n++; next } FNR == 1 { print n } { print "Tt", $1 - 1, $2 - 1, $3 - 1, $4 - 1, $5 }' \
    "$V/plain.tet" "$V/plain.tet" >"$V/carp.elem"
# VTK's own writings of the .vtu
"$PY" - "$V" <<'EOF' || fail "VTK writing the volume"
import sys, vtk
d = sys.argv[1]
r = vtk.vtkXMLUnstructuredGridReader(); r.SetFileName(d + "/exp/volume.vtu"); r.Update()
ug = r.GetOutput()
def leg(name, binary):
    w = vtk.vtkUnstructuredGridWriter(); w.SetFileName(d + "/" + name); w.SetInputData(ug)
    (w.SetFileTypeToBinary if binary else w.SetFileTypeToASCII)(); w.Write()
def xml(name, setup):
    w = vtk.vtkXMLUnstructuredGridWriter(); w.SetFileName(d + "/" + name); w.SetInputData(ug); setup(w); w.Write()
leg("vtk_ascii.vtk", 0)
leg("vtk_binary.vtk", 1)
xml("vtk_zlib.vtu", lambda w: None)  # VTK's default: appended, base64, zlib
xml("vtk_binary.vtu", lambda w: (w.SetDataModeToBinary(), w.SetCompressorTypeToNone()))
xml("vtk_raw.vtu", lambda w: (w.SetDataModeToAppended(), w.EncodeAppendedDataOff(), w.SetCompressorTypeToNone()))
xml("vtk_lz4.vtu", lambda w: w.SetCompressorTypeToLZ4())
EOF
for f in exp/volume.vtu exp/volume.msh plain.pts carp.pts vtk_ascii.vtk vtk_binary.vtk vtk_zlib.vtu vtk_binary.vtu vtk_raw.vtu; do
    out="$V/m_$(echo "$f" | tr '/.' '__')"
    run 0 "$out.out" "$out.err" "$THORAX" import -o "$out" "$V/$f"
    [ "$(vcounts "$out")" = "$REF" ] || { cat "$out.out"; fail "$f: counts $(vcounts "$out"), expected $REF"; }
    cmp -s "$out/volume.tet" "$V/made/volume.tet" || fail "$f: volume.tet differs from the thorax-made one"
    "$PY" -c 'import sys; a, b = (list(map(float, x.split())) for x in sys.argv[1:3])
assert len(a) == len(b) and all(abs(x - y) <= 1e-9 * y for x, y in zip(a, b)), (a, b)' "$(rvolumes "$out")" "$REFV" ||
        fail "$f: region volumes $(rvolumes "$out"), expected $REFV (within 1e-9)"
    grep -q 'no conductivity given, using mean_thorax' "$out.err" || { cat "$out.err"; fail "$f: no default-conductivity warning"; }
    # the import ran the checks of `thorax check`; run it itself on the exports of thorax
    case $f in exp/*) run 0 /dev/null "$out.check" "$THORAX" check "$out" -q ;; esac
    echo "ok: $f: $(head -2 "$out.out" | tail -1 | sed 's/^ *read: //')"
done
grep -q 'node numbers 1-based (detected)' "$V/m_plain_pts.out" || fail "plain .pts/.tet: base not reported"
grep -q 'CARP .pts/.elem.*0-based (by the format)' "$V/m_carp_pts.out" || fail "CARP: not reported"
grep -q 'surface "inner" (other): interface, inside: inner, outside: mean_thorax' "$V/m_exp_volume_msh.out" ||
    { cat "$V/m_exp_volume_msh.out"; fail "msh: the interface surface"; }
run 1 /dev/null "$V/lz4.err" "$THORAX" import -o "$V/m_lz4" "$V/vtk_lz4.vtu"
grep -q 'compressor "vtkLZ4DataCompressor" is not supported' "$V/lz4.err" || { cat "$V/lz4.err"; fail "lz4: reason"; }
[ ! -e "$V/m_lz4" ] || fail "lz4: output written"
ok "thorax-made volume through vtu, msh, pts/tet, CARP and VTK's own vtk/vtu: the same mesh, thorax check passes"

# a sphere (radius 0.5) in a sphere (1) meshed by Gmsh, physical volumes and surfaces named
"$PY" - "$V/gmsh.msh" "$V/gmsh_volumes.txt" <<'EOF' || fail "gmsh (python3-gmsh) could not make the test mesh"
import sys, gmsh
gmsh.initialize()
gmsh.option.setNumber("General.Terminal", 0)
gmsh.model.add("spheres")
a = gmsh.model.occ.addSphere(0, 0, 0, 1.0)
b = gmsh.model.occ.addSphere(0, 0, 0, 0.5)
gmsh.model.occ.fragment([(3, a)], [(3, b)])
gmsh.model.occ.synchronize()
small, big = [e[1] for e in sorted(gmsh.model.getEntities(3), key=lambda e: gmsh.model.occ.getMass(*e))]
inner = [s[1] for s in gmsh.model.getBoundary([(3, small)], oriented=False)]
outer = [s[1] for s in gmsh.model.getBoundary([(3, big)], oriented=False) if s[1] not in inner]
for dim, tags, tag, name in ((3, [small], 1, "brain"), (3, [big], 2, "scalp"), (2, inner, 11, "cortex"), (2, outer, 12, "skin")):
    gmsh.model.addPhysicalGroup(dim, tags, tag)
    gmsh.model.setPhysicalName(dim, tag, name)
gmsh.option.setNumber("Mesh.MeshSizeMax", 0.15)
gmsh.model.mesh.generate(3)
gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
gmsh.write(sys.argv[1])
# Gmsh's own tetrahedron volumes per physical volume (mm^3 after --scale 100)
tags, coord, _ = gmsh.model.mesh.getNodes()
xyz = {int(t): coord[3 * i:3 * i + 3] * 100 for i, t in enumerate(tags)}
out = []
for ent in (small, big):
    _, _, nodes = gmsh.model.mesh.getElements(3, ent)
    v = 0.0
    n = list(map(int, nodes[0]))
    for k in range(0, len(n), 4):
        A, B, C, D = (xyz[n[k + j]] for j in range(4))
        u, w, z = B - A, C - A, D - A
        v += abs(u[0] * (w[1] * z[2] - w[2] * z[1]) - u[1] * (w[0] * z[2] - w[2] * z[0]) + u[2] * (w[0] * z[1] - w[1] * z[0])) / 6
    out.append(v)
open(sys.argv[2], "w").write("%.6f %.6f\n" % tuple(out))
gmsh.finalize()
EOF
run 0 "$V/gmsh.out" "$V/gmsh.err" "$THORAX" import -o "$V/m_gmsh" "$V/gmsh.msh" --scale 100 --region 1=:0.33 --region 2=scalp:0.43
cat "$V/gmsh.out"
grep -q 'warning' "$V/gmsh.err" && { cat "$V/gmsh.err"; fail "gmsh: warnings although every region has a conductivity"; }
grep -q 'surface "skin" (outer): boundary, inside: scalp, named by the file' "$V/gmsh.out" || fail "gmsh: outer surface"
grep -q 'surface "cortex" (other): interface, inside: brain, outside: scalp, named by the file' "$V/gmsh.out" || fail "gmsh: interface"
run 0 /dev/null "$V/gmsh.check" "$THORAX" check "$V/m_gmsh" -q
"$PY" - "$V/gmsh_volumes.txt" "$(rvolumes "$V/m_gmsh")" "$V/m_gmsh/model.json" <<'EOF' || fail "gmsh: region volumes"
import json, sys
ref = list(map(float, open(sys.argv[1]).read().split()))
got = list(map(float, sys.argv[2].split()))
assert len(got) == 2 and all(abs(a - b) <= 1e-6 * b for a, b in zip(got, ref)), (got, ref)
m = json.load(open(sys.argv[3]))
rg = {r["name"]: r for r in m["regions"]}
assert rg["brain"]["sigma"] == 0.33 and rg["scalp"]["sigma"] == 0.43, rg
i = m["provenance"]["inputs"][0]
assert i["format"] == "msh" and i["scale"] == 100 and [r["file_region"] for r in i["regions"]] == [1, 2], i
assert [r["name_from"] for r in i["regions"]] == ["the file's name", "--region"], i["regions"]
print("gmsh sphere in sphere: region volumes %s mm^3 (Gmsh's own: %s)" % (got, ref))
EOF
ok "Gmsh's own MSH 4.1 (sphere in sphere) imports with its physical names; thorax check passes"

# bad volume meshes: refused, naming file and line; nothing written
head -n "$(grep -n '^\$EndNodes' "$V/gmsh.msh" | cut -d: -f1)" "$V/gmsh.msh" >"$V/cut.msh"
printf '$Elements\n1 100 1\n' >>"$V/cut.msh"
run 1 /dev/null "$V/cut.err" "$THORAX" import -o "$V/m_cut" "$V/cut.msh"
grep -q 'cut.msh:[0-9]*: \$Elements: expected 4 numbers on this line' "$V/cut.err" || { cat "$V/cut.err"; fail "cut .msh"; }
[ ! -e "$V/m_cut" ] || fail "cut .msh: output written"
"$PY" - "$V/hex.vtk" <<'EOF'
import sys, vtk
ug = vtk.vtkUnstructuredGrid(); P = vtk.vtkPoints()
for i in range(8): P.InsertNextPoint(i & 1, (i >> 1) & 1, (i >> 2) & 1)
ug.SetPoints(P); ug.InsertNextCell(12, 8, [0, 1, 3, 2, 4, 5, 7, 6])
w = vtk.vtkUnstructuredGridWriter(); w.SetFileName(sys.argv[1]); w.SetInputData(ug); w.Write()
EOF
run 1 /dev/null "$V/hex.err" "$THORAX" import -o "$V/m_hex" "$V/hex.vtk"
grep -q 'hex.vtk:[0-9]*: cell 0 (0-based) is of VTK type 12 (hexahedron): only tetrahedra' "$V/hex.err" || { cat "$V/hex.err"; fail "hexahedron"; }
printf '0 0 0\n1 0 0\n0 1 0\n0 0 1\n' >"$V/big.pts"
printf '9999999\n1 2 3 4\n' >"$V/big2.tet"
run 1 /dev/null "$V/big.err" "$THORAX" import -o "$V/m_big" "$V/big.pts" --elem "$V/big2.tet"
grep -q 'big2.tet:1: the count line says 9999999 elements, but 1 follow' "$V/big.err" || { cat "$V/big.err"; fail "count beyond the file"; }
# two tetrahedra on duplicated nodes: the check refuses them; --force writes them, then thorax check fails
printf '0 0 0\n10 0 0\n0 10 0\n0 0 10\n10 0 0\n0 10 0\n0 0 10\n10 10 10\n' >"$V/dup.pts"
printf '1 2 3 4\n5 7 6 8\n' >"$V/dup.tet"
run 1 /dev/null "$V/dup.err" "$THORAX" import -o "$V/m_dup" "$V/dup.pts" --region 1=:0.2
grep -q 'dup.pts: volume: duplicate' "$V/dup.err" || { cat "$V/dup.err"; fail "duplicate nodes: reason"; }
grep -q 'refused: the mesh failed its checks (--force writes it anyway); nothing written' "$V/dup.err" || fail "dup: refused"
[ ! -e "$V/m_dup" ] || fail "dup: output written"
run 0 /dev/null "$V/dupf.err" "$THORAX" import -o "$V/m_dup" "$V/dup.pts" --region 1=:0.2 --force
grep -q 'written anyway (--force)' "$V/dupf.err" || { cat "$V/dupf.err"; fail "dup --force: warning"; }
run 1 /dev/null /dev/null "$THORAX" check "$V/m_dup" -q
ok "bad volume meshes refused (truncated, hexahedron, counts beyond the file, failed check); --force writes"
# usage
M1="$V/gmsh.msh"
for args in "-o $V/u $M1 --name x" "-o $V/u $M1 --role outer" "-o $V/u $M1 $V/outer.vtk --name o --role outer" \
            "-o $V/u $V/outer.vtk --name o --role outer --region 1=a" "-o $V/u $M1 --region 1" \
            "-o $V/u $M1 --region x=a:1" "-o $V/u $M1 --region 1=a:-1" "-o $V/u $M1 --region 1=a --region 1=b" \
            "-o $V/u $M1 --region-array"; do
    set +e
    # shellcheck disable=SC2086
    "$THORAX" import $args >/dev/null 2>&1
    rc=$?
    set -e
    [ $rc -eq 2 ] || fail "volume usage error '$args': exit $rc, expected 2"
done
run 1 /dev/null "$V/u.err" "$THORAX" import -o "$V/u" "$M1" --region 5=x
grep -q 'region 5: the mesh has no region 5 (its regions: 1, 2)' "$V/u.err" || { cat "$V/u.err"; fail "--region 5"; }
[ ! -e "$V/u" ] || fail "a volume usage error wrote output"
ok "volume usage errors exit 2; an unknown --region exits 1"

# the map3d tank data are needed from here on
for f in tank_full_771 25feb97_sock_closed tank_leads_192; do
    [ -r "$DATA/$f.pts" ] && [ -r "$DATA/$f.fac" ] || { echo "e2e_import: missing $DATA/$f.pts/.fac"; exit 1; }
done

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
"$THORAX" import --help >"$WORK/help.txt" || fail "--help exit status"
grep -q '^usage: thorax import' "$WORK/help.txt" || fail "--help"
q_out=$("$THORAX" import -q -o "$WORK/quiet" "$T" --name t --role outer) || fail "-q run"
[ -z "$q_out" ] || fail "-q printed: $q_out"
ok "usage errors exit 2; --help; -q"

echo "e2e_import: all passed"
