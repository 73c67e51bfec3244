#!/bin/bash
# End-to-end: a model directory with a volume mesh (written by the test
# program test_volume_io --write-model: a Delaunay-meshed 10 mm cube, 320
# nodes, about 2000 right-handed tetrahedra in three regions plus an unused
# fourth, two surfaces with node tables) is exported by `thorax export
# --format vtu|msh`, and VTK and Gmsh themselves read the files
# (tests/volume_read.py): counts, connectivity, regions, orientation.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
# Gmsh (python3-gmsh, or at least the gmsh command) is required: the test
# fails without it (scripts/deps.sh installs both).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
MAKER="$(dirname "$THORAX")/../tests/test_volume_io"
rm -rf "$WORK"
mkdir -p "$WORK"

fail() { echo "e2e_volume_export: FAIL: $*" >&2; exit 1; }

[ -x "$MAKER" ] || fail "$MAKER not built"
"$MAKER" --write-model "$WORK/model" 300 || fail "could not write the test model"
[ -s "$WORK/model/volume.tet" ] || fail "no volume.tet in the model"

# Usage errors exit 2; a model without a volume exits 1, naming the reason.
set +e
"$THORAX" export "$WORK/model" --format vtu --surface box 2>"$WORK/err.txt"; rc=$?
[ $rc -eq 2 ] || fail "--surface with vtu gave exit $rc, expected 2"
mkdir -p "$WORK/novol"
cp "$WORK/model/box.pts" "$WORK/model/box.fac" "$WORK/novol/"
cat > "$WORK/novol/model.json" <<'EOF'
{ "format": "thorax-model", "version": 1, "units": "mm",
  "surfaces": [ { "name": "box", "role": "outer", "pts": "box.pts", "fac": "box.fac",
                  "n_nodes": 14, "n_tris": 24 } ] }
EOF
"$THORAX" export "$WORK/novol" --format msh -o "$WORK/novol_out" 2>"$WORK/err.txt"; rc=$?
[ $rc -eq 1 ] || fail "a model without a volume gave exit $rc, expected 1"
grep -q "no volume mesh" "$WORK/err.txt" || fail "error does not say why: $(cat "$WORK/err.txt")"
[ -e "$WORK/novol_out/volume.msh" ] && fail "volume.msh written for a model without a volume"
# A corrupted model is refused, naming the file and line.
cp -r "$WORK/model" "$WORK/broken"
sed -i '7s/.*/1 2 3 4 9/' "$WORK/broken/volume.tet"
"$THORAX" export "$WORK/broken" --format vtu -o "$WORK/broken_out" 2>"$WORK/err.txt"; rc=$?
[ $rc -eq 1 ] || fail "a corrupted volume.tet gave exit $rc, expected 1"
grep -q "volume.tet:7: region 9 out of range 1..4" "$WORK/err.txt" || fail "error does not name file and line: $(cat "$WORK/err.txt")"
set -e

# Default output directory is the model; -o elsewhere; output deterministic.
"$THORAX" export "$WORK/model" --format vtu -q
[ -s "$WORK/model/volume.vtu" ] || fail "no volume.vtu in the model directory"
"$THORAX" export "$WORK/model" --format vtu -o "$WORK/out" -q
"$THORAX" export "$WORK/model" --format msh -o "$WORK/out" -q
[ -s "$WORK/out/volume.vtu" ] && [ -s "$WORK/out/volume.msh" ] || fail "exports missing in $WORK/out"
cmp -s "$WORK/model/volume.vtu" "$WORK/out/volume.vtu" || fail "two exports of the same model differ"
head -2 "$WORK/out/volume.msh" | tail -1 | grep -qx "4.1 0 8" || fail "volume.msh is not MSH 4.1 ASCII"
ls "$WORK/out" | grep -q tmp && fail "temporary files left in $WORK/out"

/usr/bin/python3 "$SRC/tests/volume_read.py" "$WORK/model" "$WORK/out/volume.vtu" "$WORK/out/volume.msh" \
    || fail "VTK or Gmsh disagree with the model (see above)"
echo "e2e_volume_export: ok"
