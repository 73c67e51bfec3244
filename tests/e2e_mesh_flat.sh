#!/usr/bin/env bash
# Surfaces with large flat faces at every grid from 4 to 12 mm (issue 24): a box (100 x 80 x 60 mm,
# each face a 5 x 5 grid of squares cut in two) holding a smaller box as the heart, generated here,
# and the Utah tank, whose lid is flat, with its closed sock. `thorax mesh --grid G` must give a
# volume that passes `thorax check` for G = 4, 5, ..., 12, with no lowered-bar warning.
# Under THORAX_QUICK (the sanitized build) the tank runs at 8 and 12 mm only.
set -uo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }

$PY - <<'PYEOF'
# two boxes, outward triangles; the inner one shifted to (30, 25, 20)
def box(out, L, n, off):
    P, idx, F = [], {}, []
    def node(p):
        k = tuple(round(c, 9) for c in p)
        if k not in idx: idx[k] = len(P); P.append(k)
        return idx[k] + 1
    for ax in range(3):
        for side in (0, 1):
            u, v = (ax + 1) % 3, (ax + 2) % 3
            for i in range(n):
                for j in range(n):
                    def pt(a, b):
                        p = [0.0] * 3; p[ax] = side * L[ax]; p[u] = a * L[u] / n; p[v] = b * L[v] / n
                        return node([p[k] + off[k] for k in range(3)])
                    a, b, c, d = pt(i, j), pt(i + 1, j), pt(i + 1, j + 1), pt(i, j + 1)
                    tris = [(a, b, c), (a, c, d)] if (i + j) % 2 == 0 else [(a, b, d), (b, c, d)]
                    for t in tris: F.append(t if side == 1 else (t[0], t[2], t[1]))
    open(out + ".pts", "w").write("".join("%.6f %.6f %.6f\n" % p for p in P))
    open(out + ".fac", "w").write("".join("%d %d %d\n" % t for t in F))
box("box", (100, 80, 60), 5, (0, 0, 0))
box("core", (40, 30, 20), 3, (30, 25, 20))
PYEOF
"$THORAX" import -o box -q box.pts --name box --role outer core.pts --name core --role heart && "$THORAX" check box -q ||
    { bad "box: import/check"; exit 1; }
models="box"
G=$DATA/map3d/geom/tank
if [ -r "$G/tank_full_771.pts" ]; then
    "$THORAX" import -o tank -q "$G/tank_full_771.pts" --name tank --role outer "$G/25feb97_sock_closed.pts" --name sock --role heart &&
        models="box tank" || bad "tank: import"
else echo "skip: $G not found (Utah tank)"; fi
for m in $models; do
    grids="4 5 6 7 8 9 10 11 12"
    [ -n "${THORAX_QUICK:-}" ] && [ $m = tank ] && grids="8 12"
    for g in $grids; do
        if "$THORAX" mesh $m -o v_${m}_$g --grid $g -q 2> m_${m}_$g.err && "$THORAX" check v_${m}_$g > c_${m}_$g.txt 2>&1 &&
            ! grep -q 'provenance.*"mesh"' v_${m}_$g/model.json; then
            ok "$m grid $g: $(awk '$1 == "volume" && $2 ~ /^[0-9]+$/ {print $2 " tetrahedra, smallest dihedral " $8 " deg"}' c_${m}_$g.txt)"
        else bad "$m grid $g: $(head -2 m_${m}_$g.err) $(grep -v '^ ' c_${m}_$g.txt 2>/dev/null | tail -1)"; fi
        rm -rf v_${m}_$g
    done
done
[ $fails -eq 0 ] || { echo "$fails failed"; exit 1; }
echo "all passed"
