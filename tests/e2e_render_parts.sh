#!/usr/bin/env bash
# Sort-last rendering (issue 28 item 2; docs/design/parallel.md, "Sort-last"): a solution written by
# `forward --volume` on N ranks holds its volume in N parts (THXPART2, with ghosts); `render` on N
# ranks has each rank read the model's surfaces, its region table and its own part alone, cut the
# part, draw its own tetrahedra's triangles as a layer with depth, and IceT composite the layers on
# rank 0. Asserted: the picture is the one process's, byte for byte, on 2 and 3 ranks, for slices by
# potential (bands), slices by |J| (a scale of their own, its largest value over the ranks) with a
# colour bar and label, opaque equipotentials (their normals on a part's edge the whole's: the
# ghosts) with a slice; a solution in 2 parts drawn on 3 ranks (sort-first then: the same bytes);
# volume rendering (potential, |J|) within 1/255 (blended in float, front to back); animate on 3
# ranks: every frame drawn by all ranks, frames and movie one process's, kept when run again;
# streamlines (sphere, line and point seeds; J at the ghosts' far nodes from their owners, the lines
# handed from part to part, joined and made tubes on rank 0) one process's, byte for byte.
# Refused, with one message, exit 1 and no picture: a translucent surface (depth compositing needs
# opaque ones), region: and density: streamline seeds (random over the whole volume), IceT's library out of reach (THORAX_ICET_LIBRARY, as on a machine
# without Debian's paraview). Skipped (77) without mpirun. Writes only in a mktemp -d directory.
# Env: THORAX (built CLI); THORAX_PHANTOM_MODELS (optional: the fixture's models).
set -euo pipefail
: "${THORAX:?}"
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/ranks_test.sh"
ranks_test e2e_render_parts

. "$HERE/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 240 -q
"$PY" - <<'PYEOF'
import numpy as np
b = open('beat.raw', 'rb').read()
r, f = (int(x) for x in np.frombuffer(b[8:24], dtype='<u8'))
t = np.frombuffer(b[200:200 + 8 * f], dtype='<f8')
v = np.frombuffer(b[200 + 8 * f:], dtype='<f8').reshape(f, r)
k = [40, 170, 190]   # the P wave, the QRS, its end
h = bytearray(b[:200]); h[16:24] = np.array([len(k)], dtype='<u8').tobytes()
open('e3.raw', 'wb').write(bytes(h) + t[k].tobytes() + v[k].tobytes())
PYEOF
for n in 2 3; do
    "${MPIRUN[@]}" -np $n "$THORAX" forward model --epicardial e3.raw --volume -o sol$n -q > f$n.log 2>&1 ||
        { cat f$n.log; fail "forward --volume on $n ranks"; }
    [ -f sol$n/parts/part_0000.bin ] || fail "forward on $n ranks wrote no parts"
done

# draw K NAME ARGS...: the picture on 1 process and on K ranks, the same bytes
draw() {
    local k=$1 name=$2
    shift 2
    "$THORAX" render "$@" -o ${name}_1.png -q > ${name}_1.log 2>&1 || { cat ${name}_1.log; fail "$name on 1 process"; }
    "${MPIRUN[@]}" -np $k "$THORAX" render "$@" -o ${name}_$k.png -q > ${name}_$k.log 2>&1 ||
        { cat ${name}_$k.log; fail "$name on $k ranks"; }
    cmp -s ${name}_1.png ${name}_$k.png || fail "$name: the picture on $k ranks is not the one process's"
    echo "$name: 1 process = $k ranks, byte for byte ($(stat -c %s ${name}_1.png) bytes)"
}
for n in 2 3; do
    draw $n slices$n --solution sol$n --frame 2 --slice y=0 --slice x=-20 --only slices --view left
    draw $n current$n --solution sol$n --frame 2 --slice y=0 --slice x=0 --slice-current --only slices --view left --colorbar --label
    draw $n iso$n --solution sol$n --frame 3 --isosurface count:5 --surface equipotentials=phong:1 --slice z=0 \
        --only equipotentials --only slices --view superior --colorbar
done
# streamlines: seeds in the torso and round the heart, lines crossing the parts (on 3 ranks the seeds along x
# lie in every part: lines are handed over, which the log's count shows)
for n in 2 3; do
    draw $n stream$n --solution sol$n --frame 2 --streamlines sphere:0,0,0:60:40 --streamlines line:-100,0,0:100,0,0:12 \
        --streamlines point:10,-20,5 --only streamlines --view left
done
grep -q "handed from part to part [1-9][0-9]* times" <("${MPIRUN[@]}" -np 3 "$THORAX" render --solution sol3 --frame 2 \
    --streamlines line:-100,0,0:100,0,0:12 --only streamlines -o hand3.png 2>&1) || fail "streamlines on 3 ranks: no line handed over"
draw 3 oblique3 --solution sol3 --frame 2 --slice 10,-5,3:1,2,0.5 --slice 0,0,0:0.3,-1,2 --only slices --view left
draw 3 other_count --solution sol2 --frame 2 --slice y=0 --only slices --view anterior

# volume rendering: each rank traces the rays' pieces in its box (its mesh: its own tetrahedra and the
# ghosts reaching into the box), every sample a layer of premultiplied floats, IceT blends them front to
# back in the boxes' order from the eye, rank 0 averages the samples over the background: within 1/255
# of one process (float32 compositing; the rays cut at the boxes' sides)
blended() {
    local k=$1 name=$2
    shift 2
    "$THORAX" trace "$@" -o ${name}_1.png -q > ${name}_1.log 2>&1 || { cat ${name}_1.log; fail "$name on 1 process"; }
    "${MPIRUN[@]}" -np $k "$THORAX" trace "$@" -o ${name}_$k.png -q > ${name}_$k.log 2>&1 ||
        { cat ${name}_$k.log; fail "$name on $k ranks"; }
    "$PY" - ${name}_1.png ${name}_$k.png <<'PYEOF' || fail "$name: the picture on $k ranks is not within 1/255 of one process's"
import sys, zlib, struct
def pixels(p):
    b = open(p, 'rb').read(); o = 8; data = b''
    while o < len(b):
        n, = struct.unpack('>I', b[o:o + 4]); t = b[o + 4:o + 8]; c = b[o + 8:o + 8 + n]
        if t == b'IHDR': w, h, depth, ctype = struct.unpack('>IIBB', c[:10]); assert depth == 8 and ctype in (2, 6); ch = 3 if ctype == 2 else 4
        if t == b'IDAT': data += c
        o += 12 + n
    raw, rows, prev, st = zlib.decompress(data), [], bytearray(ch * w), ch * w + 1
    for y in range(h):   # PNG's filters undone (Sub, Up, Average, Paeth)
        f, line, cur = raw[y * st], raw[y * st + 1:(y + 1) * st], bytearray(ch * w)
        for i in range(ch * w):
            a = cur[i - ch] if i >= ch else 0; b = prev[i]; c = prev[i - ch] if i >= ch else 0
            if f == 0: p = 0
            elif f == 1: p = a
            elif f == 2: p = b
            elif f == 3: p = (a + b) // 2
            else:
                pa, pb, pc = abs(b - c), abs(a - c), abs(a + b - 2 * c)
                p = a if pa <= pb and pa <= pc else b if pb <= pc else c
            cur[i] = (line[i] + p) & 255
        rows.append(bytes(cur)); prev = cur
    return b''.join(rows)
a, b = pixels(sys.argv[1]), pixels(sys.argv[2])
worst = max(abs(x - y) for x, y in zip(a, b)); diff = sum(1 for x, y in zip(a, b) if x != y)
print('%s: %d bytes differ, by at most %d' % (sys.argv[2], diff, worst))
assert len(a) == len(b) and worst <= 1, worst
assert len(set(a[i:i + 3] for i in range(0, len(a) - 3, 3 * 97))) > 50, 'an empty picture'
PYEOF
}
blended 2 volume2 --solution sol2 --frame 2 --volume potential --mode hidden --colorbar --size 300x300
blended 3 volume3 --solution sol3 --frame 2 --volume potential --mode hidden --view superior --size 300x300
blended 3 vcurrent3 --solution sol3 --frame 2 --volume current --mode hidden --view left --colorbar --size 300x300

# the pictures are not empty: a picture of the background alone would pass the comparison too
"$PY" - <<'PYEOF'
import zlib, struct
def pixels(p):
    b = open(p, 'rb').read(); o = 8; data = b''; w = h = 0
    while o < len(b):
        n, = struct.unpack('>I', b[o:o + 4]); t = b[o + 4:o + 8]; c = b[o + 8:o + 8 + n]
        if t == b'IHDR': w, h = struct.unpack('>II', c[:8])
        if t == b'IDAT': data += c
        o += 12 + n
    raw = zlib.decompress(data)
    return w, h, raw
for name in ('slices2_2.png', 'current3_3.png', 'iso3_3.png', 'stream3_3.png'):
    w, h, raw = pixels(name)
    bg = raw[1:5]  # the first pixel of the first row: the background
    distinct = len(set(raw[1 + y * (4 * w + 1) + 4 * x: 5 + y * (4 * w + 1) + 4 * x] for y in range(0, h, 4) for x in range(0, w, 4)))
    assert distinct > 50, (name, distinct)
    print('%s: %d distinct colours among a sixteenth of its pixels' % (name, distinct))
PYEOF

# refused: nothing written, one message, exit 1
refused() {
    local what=$1 want=$2
    shift 2
    if "${MPIRUN[@]}" -np 2 "$@" > r.log 2>&1; then cat r.log; fail "$what was drawn"; fi
    grep -q "$want" r.log || { cat r.log; fail "$what: no message naming '$want'"; }
    [ "$(grep -c "thorax \(render\|trace\)" r.log)" -eq 1 ] || { cat r.log; fail "$what: not one message"; }
    [ ! -e no.png ] || fail "$what: a picture was written"
    echo "refused, $what: $(grep "thorax \(render\|trace\)" r.log | head -1)"
}
refused "a translucent torso" "must be opaque" "$THORAX" render --solution sol2 --slice y=0 -o no.png
refused "a surface beside the volume" "volume alone" "$THORAX" trace --solution sol2 --volume potential -o no.png
refused "region seeds" "region seeds are drawn at random" "$THORAX" render --solution sol2 --streamlines region:heart:20 -o no.png
refused "density seeds" "density seeds are drawn at random" "$THORAX" render --solution sol2 --streamlines density:20 -o no.png
refused "a point seed outside" "is outside the domain" "$THORAX" render --solution sol2 --streamlines point:900,0,0 -o no.png
cp -r sol2 bad2
"$PY" -c "
b = bytearray(open('bad2/parts/part_0001.bin', 'rb').read()); b[-40] ^= 1
open('bad2/parts/part_0001.bin', 'wb').write(b)"
refused "rank 1's part damaged (its own message, not rank 0's echo)" "rank 1 of 2.*checksum" \
    "$THORAX" render --solution bad2 --slice y=0 --only slices -o no.png
refused "IceT out of reach" "paraview" env THORAX_ICET_LIBRARY=/nonexistent/libvtkIceTMPI.so \
    "$THORAX" render --solution sol2 --slice y=0 --only slices -o no.png
# animate on the parts: every frame drawn by all ranks together; the frames and the movie one process's;
# run again, every frame kept (rank 0's files decide for all)
ANIM=(--solution sol3 --slice y=0 --isosurface 0 --surface equipotentials=phong:1 --only slices --only equipotentials
      --colorbar --label --size 320x240)
"$THORAX" animate "${ANIM[@]}" -o anim1 -q > a1.log 2>&1 || { cat a1.log; fail "animate on 1 process"; }
"${MPIRUN[@]}" -np 3 "$THORAX" animate "${ANIM[@]}" -o anim3 > a3.log 2>&1 || { cat a3.log; fail "animate on 3 ranks"; }
for f in anim1/frame_*.png anim1/animation.mp4; do
    cmp -s "$f" "anim3/$(basename "$f")" || fail "animate on 3 ranks: $(basename "$f") is not one process's"
done
"${MPIRUN[@]}" -np 3 "$THORAX" animate "${ANIM[@]}" -o anim3 > a3b.log 2>&1 || { cat a3b.log; fail "animate again"; }
grep -q "(0 drawn, 3 kept" a3b.log || { cat a3b.log; fail "animate again on 3 ranks: the frames not kept"; }
echo "animate on 3 ranks (sort-last): $(ls anim1/frame_*.png | wc -l) frames and the movie one process's, byte for byte; run again: $(grep -o '([^)]*)' a3b.log | head -1)"
echo "e2e_render_parts: all checks passed"
