#!/bin/bash
# End-to-end: a model directory made by hand from the real Utah tank surface
# (771 nodes, 1538 triangles, 1-based .fac) is exported by `thorax export` in
# all five formats, and VTK's own readers (tests/vtk_read.py) check the files.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
DATA="$SRC/../shared/data/map3d/geom/tank"
rm -rf "$WORK"
mkdir -p "$WORK/model"

fail() { echo "e2e_export: FAIL: $*" >&2; exit 1; }

# The model: the tank surface verbatim (its .fac is already 1-based, which the
# model format requires) and a hand-written manifest.
cp "$DATA/tank_full_771.pts" "$WORK/model/tank.pts"
cp "$DATA/tank_full_771.fac" "$WORK/model/tank.fac"
cat > "$WORK/model/model.json" <<'EOF'
{
  "format": "thorax-model",
  "version": 1,
  "units": "mm",
  "surfaces": [
    { "name": "tank", "role": "outer", "pts": "tank.pts", "fac": "tank.fac",
      "n_nodes": 771, "n_tris": 1538 }
  ],
  "provenance": { "source": "map3d tank_full_771 (e2e_export.sh)" }
}
EOF

# Usage: --help exits 0; bad usage exits 2; a missing model or surface exits 1.
"$THORAX" export --help | grep -q "usage: thorax export" || fail "--help"
set +e
"$THORAX" export "$WORK/model" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "missing --format gave exit $rc, expected 2"
"$THORAX" export "$WORK/model" --format xyz 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "unknown format gave exit $rc, expected 2"
"$THORAX" export "$WORK/nomodel" --format vtk 2>"$WORK/err.txt"; rc=$?
[ $rc -eq 1 ] || fail "missing model gave exit $rc, expected 1"
grep -q "nomodel/model.json" "$WORK/err.txt" || fail "error does not name model.json: $(cat "$WORK/err.txt")"
"$THORAX" export "$WORK/model" --format vtk --surface lung 2>"$WORK/err.txt"; rc=$?
[ $rc -eq 1 ] || fail "unknown surface gave exit $rc, expected 1"
grep -q '"lung"' "$WORK/err.txt" || fail "error does not name the surface: $(cat "$WORK/err.txt")"
set -e

# Default output directory is the model itself; -o elsewhere (created).
"$THORAX" export "$WORK/model" --format vtk -q
[ -f "$WORK/model/tank.vtk" ] || fail "no tank.vtk in the model directory"
for fmt in vtk vtp obj stl ply; do
    "$THORAX" export "$WORK/model" --format "$fmt" -o "$WORK/out" --surface tank -q
    [ -s "$WORK/out/tank.$fmt" ] || fail "no $WORK/out/tank.$fmt"
done
cmp -s "$WORK/model/tank.vtk" "$WORK/out/tank.vtk" || fail "two exports of the same model differ"
# Binary STL: 80-byte header + count + 50 bytes per triangle.
size=$(stat -c %s "$WORK/out/tank.stl")
[ "$size" -eq $((84 + 50 * 1538)) ] || fail "tank.stl is $size bytes"
ls "$WORK/out" | grep -q tmp && fail "temporary files left in $WORK/out"

/usr/bin/python3 "$SRC/tests/vtk_read.py" "$WORK/out" tank 771 1538 "$DATA/tank_full_771.pts"
echo "e2e_export: ok"
