#!/usr/bin/env bash
# thorax field on a solution in parts (docs/design/parallel.md, "thorax field on the parts"): a
# solution written by `forward --volume` on N ranks holds its volume in N parts; `field` on N ranks
# has each rank read the model's region table and its own part alone, cut it, keep its own
# tetrahedra's triangles, and rank 0 put them together and write. Asserted, on 2 and 3 ranks, on
# copies of the solutions without volume.raw and of the model without its volume mesh (so that no
# rank can read the whole): the files are the one process's (field on the whole solution), byte for
# byte, for equipotential surfaces by count and slices (one oblique) with contours over every frame
# (a directory of .vtp and the .pvd; a frame of constant potential among them, with its warning), for
# one frame as .obj and as .vtp (values, regions chosen); the messages are the one process's;
# --streamlines (point, line and sphere seeds, RK2 and RK45: the lines handed from part to part,
# written by rank 0) the one process's file. Refused
# with one message, exit status non-zero on every rank and nothing written: the parts' rank count
# other than the run's (both counts named), a solution without parts, --streamlines seeded at random
# (density:, the default; region:), a bad --frame,
# an empty cut (found by rank 0 as it writes), one rank's part damaged (that rank's message).
# Skipped (77) without mpirun. Writes only in a mktemp -d directory.
# Env: THORAX (built CLI); THORAX_PHANTOM_MODELS (optional: the fixture's models).
set -euo pipefail
: "${THORAX:?}"
HERE=$(cd "$(dirname "$0")" && pwd)
. "$HERE/ranks_test.sh"
ranks_test e2e_field_parts

. "$HERE/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 240 -q
# four frames: before the beat (constant potentials), the P wave, the QRS, its end
"$PY" - <<'PYEOF'
import struct
b = open('beat.raw', 'rb').read()
r, f = struct.unpack('<QQ', b[8:24])
k = [0, 40, 170, 190]
h = bytearray(b[:200]); h[16:24] = struct.pack('<Q', len(k))
t = b''.join(b[200 + 8 * i:208 + 8 * i] for i in k)
v = b''.join(b[200 + 8 * f + 8 * r * i:200 + 8 * f + 8 * r * (i + 1)] for i in k)
open('e4.raw', 'wb').write(bytes(h) + t + v)
PYEOF
# the model without its volume mesh, for the solutions' copies without volume.raw
cp -r model blind_model
rm blind_model/volume.* blind_model/*.vmap
for n in 2 3; do
    "${MPIRUN[@]}" -np $n "$THORAX" forward model --epicardial e4.raw --volume -o sol$n -q > f$n.log 2>&1 ||
        { cat f$n.log; fail "forward --volume on $n ranks"; }
    [ -f sol$n/parts/part_0000.bin ] || fail "forward on $n ranks wrote no parts"
    mkdir parts$n
    cp -r sol$n/parts sol$n/torso.raw parts$n/
    "$PY" - sol$n parts$n "$TMP/blind_model" <<'PYEOF'
import json, sys
j = json.load(open(sys.argv[1] + '/solution.json'))
j['model'] = sys.argv[3]
json.dump(j, open(sys.argv[2] + '/solution.json', 'w'), indent=1)
PYEOF
done

# same K NAME OUT ARGS...: field on the whole solution (one process) and on its parts (K ranks): the
# same files, byte for byte, and the same messages (the time taken aside)
same() {
    local k=$1 name=$2 out=$3
    shift 3
    "$THORAX" field sol$k "$@" -o 1_$out 2> ${name}_1.log || { cat ${name}_1.log; fail "$name on 1 process"; }
    "${MPIRUN[@]}" -np $k "$THORAX" field parts$k "$@" -o ${k}_$out > ${name}_$k.out 2> ${name}_$k.log ||
        { cat ${name}_$k.log ${name}_$k.out; fail "$name on $k ranks"; }
    local files=1_$out
    [ -d 1_$out ] && files=$(cd 1_$out && ls)
    for f in $files; do
        local a=1_$out b=${k}_$out
        [ -d 1_$out ] && a=1_$out/$f b=${k}_$out/$f
        cmp -s $a $b || fail "$name: $b ($(stat -c %s $b) bytes) is not the one process's $a ($(stat -c %s $a) bytes)"
        echo "$name: $(basename $b) on $k ranks = 1 process, byte for byte ($(stat -c %s $a) bytes)"
    done
    [ -d 1_$out ] && [ "$(ls ${k}_$out)" != "$(ls 1_$out)" ] && fail "$name: other files on $k ranks: $(ls ${k}_$out)"
    sed -e "s/1_$out/OUT/g" -e 's/[0-9.]* s$/S s/' ${name}_1.log > m1.txt
    sed -e "s/${k}_$out/OUT/g" -e 's/[0-9.]* s$/S s/' ${name}_$k.log > m$k.txt
    cmp -s m1.txt m$k.txt || { diff m1.txt m$k.txt; fail "$name: the messages on $k ranks are not the one process's"; }
    return 0
}
for n in 2 3; do
    same $n frames$n frames --isosurface count:4 --slice y=0 --slice 10,20,150:1,1,0.5 --contours count:5 --frame all
    same $n obj$n one.obj --isosurface 25%,50%,75% --slice z=0 --frame 3
done
same 3 regions3 one.vtp --isosurface -0.05,0,0.05 --slice x=0 --contours 0,0.02 --region lung_l --region muscle --frame 4

# streamlines: traced across the parts (J at the ghosts' far nodes from their owners, each line handed to the
# part it enters), joined and written by rank 0: the one process's file
for n in 2 3; do
    for integ in rk2 rk45; do
        S=(--streamlines --seed sphere:0,0,0:60:40 --seed line:-100,0,0:100,0,0:12 --seed point:10,-20,5 --integrator $integ
           --frame 3)
        "$THORAX" field sol$n "${S[@]}" -o 1_lines.vtp -q || fail "streamlines ($integ) on 1 process"
        "${MPIRUN[@]}" -np $n "$THORAX" field parts$n "${S[@]}" -o ${n}_lines.vtp > l.log 2>&1 ||
            { cat l.log; fail "streamlines ($integ) on $n ranks"; }
        cmp -s 1_lines.vtp ${n}_lines.vtp || fail "streamlines ($integ): the file on $n ranks is not the one process's"
        grep -q "handed from part to part [1-9]" l.log || { cat l.log; fail "streamlines ($integ) on $n ranks: no line handed over"; }
        echo "streamlines ($integ): on $n ranks = 1 process, byte for byte ($(stat -c %s 1_lines.vtp) bytes; $(grep -o 'handed.*rounds' l.log))"
    done
done

# what was compared is not empty: triangles and contour lines in every frame but the constant one,
# whose warning was given (and compared above)
grep -q "the potentials are all 0 in this frame" frames3_1.log || fail "no warning for the constant frame"
"$PY" - <<'PYEOF' || fail "empty cuts compared"
import re
for f in ('2_frames/field_0002.vtp', '3_frames/field_0003.vtp', '3_frames/field_0004.vtp', '3_one.vtp'):
    head = open(f, 'rb').read(4096).decode('latin-1')
    polys, lines = int(re.search(r'NumberOfPolys="(\d+)"', head).group(1)), int(re.search(r'NumberOfLines="(\d+)"', head).group(1))
    assert polys > 1000 and lines > 10, (f, polys, lines)
    print('%s: %d triangles, %d contour segments' % (f, polys, lines))
PYEOF

# refused: one message, exit status non-zero on every rank, nothing written (each rank's status kept in a
# file by a shell that itself exits 0: mpirun ends the job at the first non-zero exit, before the others
# could be seen)
refused() {
    local what=$1 want=$2 k=$3
    shift 3
    rm -f rc.*
    "${MPIRUN[@]}" -np $k sh -c '"$@"; echo $? > rc.${OMPI_COMM_WORLD_RANK:-${PMIX_RANK:-x}}' sh "$THORAX" field "$@" \
        -o no.vtp > r.log 2>&1 || { cat r.log; fail "$what: mpirun failed"; }
    grep -q -- "$want" r.log || { cat r.log; fail "$what: no message naming '$want'"; }
    [ "$(grep -c "^thorax field" r.log)" -eq 1 ] || { cat r.log; fail "$what: not one message"; }
    local codes
    codes=$(cat rc.* 2> /dev/null | sort | uniq -c | sed 's/^ *\([0-9]*\) \(.*\)/\1 x \2/' | tr '\n' ' ')
    [ "$(cat rc.* | grep -c '^[12]$')" -eq $k ] || fail "$what: the ranks' exit statuses: $codes"
    [ ! -e no.vtp ] || fail "$what: a file was written"
    echo "refused, $what: $(grep "^thorax field" r.log) (exit status: $codes)"
}
refused "parts for 2 ranks, run on 3" "in parts for 2 ranks, and this run has 3" 3 parts2 --isosurface count:3
refused "parts for 3 ranks, run on 2" "in parts for 3 ranks, and this run has 2" 2 parts3 --slice y=0
"$THORAX" forward model --epicardial e4.raw --volume -o whole -q
refused "a solution without parts" "no parts" 2 whole --isosurface count:3
refused "--streamlines seeded by density (the default)" "density seeds are drawn at random" 2 parts2 --streamlines
refused "--streamlines from region seeds" "region seeds are drawn at random" 2 parts2 --streamlines --seed region:lung_l:5
refused "a bad --frame" "frames 1..4" 2 parts2 --isosurface count:3 --frame 9
# found by rank 0 alone, as it writes: the constant frame's cut is empty (no value for a count)
refused "an empty cut" "the cuts asked for are empty" 2 parts2 --isosurface count:3 --frame 1
# one rank's part damaged: that rank's message alone, every rank out
cp -r parts2 bad2
"$PY" -c "f = open('bad2/parts/part_0001.bin', 'r+b'); f.seek(5000); b = f.read(1); f.seek(5000); f.write(bytes([b[0] ^ 1]))"
refused "rank 1's part damaged" "rank 1 of 2.*part_0001.bin: the part's checksum" 2 bad2 --isosurface count:3
echo "e2e_field_parts: all checks passed"
