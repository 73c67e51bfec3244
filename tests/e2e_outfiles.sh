#!/usr/bin/env bash
# Single-file outputs never destroy what thorax did not write (issue 11, item 1): a file a command
# writes (exports; contours, series, images, movies as they are wired to thx_atomic_open_output)
# replaces an existing file only when that file is thorax's own output of the same kind (its
# signature in the first 4096 bytes), a regular file, not a link and not an input. Refusals exit 1,
# say what is there, and leave every file as it was; a command writing several files claims all
# before writing any. Two commands writing the same new file at once: one wins, the other exits 1.
# Environment: THORAX = the CLI, WORK = a scratch directory.
set -u
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1
. "$SRC/tests/outputs_lib.sh"  # ok, bad, refused, snap
leftovers() { ls -a "$1" | grep -E '\.tmp' || true; }

"$THORAX" phantom -o c.txt -q && "$THORAX" surfaces c.txt -o m -q || { bad "phantom model"; exit 1; }

# export: thorax's own files are replaced; a user's file of the same name stops the whole run
for f in obj stl ply vtk vtp; do
    "$THORAX" export m --format $f -o ex_$f -q && "$THORAX" export m --format $f -o ex_$f -q &&
        ok "$f: thorax's own export replaced" || bad "$f: re-export failed"
    echo "my own torso, keep me" > ex_$f/torso.$f
    before=$(snap ex_$f)
    refused "$f: a user's torso.$f" "is not thorax's own output of this kind" "$THORAX" export m --format $f -o ex_$f -q
    [ "$before" = "$(snap ex_$f)" ] && ok "$f: no file changed (the other surfaces neither)" || bad "$f: files changed"
done
# the volume exports likewise (a mesh of the phantom's torso and lungs)
if "$THORAX" mesh m -o mv -q 2> mv.err; then
    for f in vtu msh; do
        "$THORAX" export mv --format $f -o exv_$f -q && "$THORAX" export mv --format $f -o exv_$f -q &&
            ok "$f: thorax's own volume export replaced" || bad "$f: re-export failed"
        echo "my mesh" > exv_$f/volume.$f
        refused "$f: a user's volume.$f" "is not thorax's own output of this kind" "$THORAX" export mv --format $f -o exv_$f -q
        grep -q "my mesh" exv_$f/volume.$f && ok "$f: the user's file is unchanged" || bad "$f: changed"
    done
else bad "mesh: $(cat mv.err)"; fi
# a link is never followed, a directory is never replaced
mkdir -p elsewhere ex_link && echo "precious" > elsewhere/target.obj && ln -s ../elsewhere/target.obj ex_link/torso.obj
refused "symbolic link" "symbolic link" "$THORAX" export m --format obj --surface torso -o ex_link -q
grep -q precious elsewhere/target.obj && ok "the link's target is unchanged" || bad "the link's target changed"
mkdir -p ex_dir/torso.obj
refused "a directory in the way" "is a directory" "$THORAX" export m --format obj --surface torso -o ex_dir -q
# nothing is left half-written, and a refused run into a new folder creates no folder
refused "the user file still stops a re-export" "is not thorax's own" "$THORAX" export m --format obj -o ex_obj -q
[ -z "$(leftovers ex_obj)" ] && ok "no temporary file left" || bad "left $(leftovers ex_obj)"
# two exports of the same new file at once: one wins, the other exits 1 naming the race
for i in 1 2 3; do
    rm -rf race && mkdir race
    "$THORAX" export m --format obj --surface torso -o race -q > r1.log 2>&1 & p1=$!
    "$THORAX" export m --format obj --surface torso -o race -q > r2.log 2>&1 & p2=$!
    wait $p1; r1=$?; wait $p2; r2=$?
    if [ $r1 -eq 0 ] && [ $r2 -eq 0 ]; then echo "race $i: both finished without overlapping (no race this time)"
    elif [ $((r1 + r2)) -eq 1 ]; then
        loser=r1.log; [ $r2 -ne 0 ] && loser=r2.log
        grep -q "another command wrote this file" "$loser" && ok "race $i: one won, the other exited 1" || bad "race $i: loser said $(cat $loser)"
    else bad "race $i: exits $r1 $r2"; fi
    head -1 race/torso.obj | grep -q "# thorax surface torso" && ok "race $i: the file is whole" || bad "race $i: file broken"
    [ -z "$(leftovers race)" ] && ok "race $i: nothing left behind" || bad "race $i: left $(leftovers race)"
done

# contours (phantom, slice): a user's text file of the same name stops the run; thorax's own is replaced
echo "my digitized notes" > notes.txt
before=$(md5sum < notes.txt)
refused "phantom over a user's file" "is not thorax's own output of this kind" "$THORAX" phantom -o notes.txt -q
[ "$before" = "$(md5sum < notes.txt)" ] && ok "the user's file is unchanged" || bad "the user's file changed"
"$THORAX" phantom -o c.txt -q && "$THORAX" slice m --spacing 20 -o s.txt -q && "$THORAX" slice m --spacing 20 -o s.txt -q &&
    ok "contours: thorax's own replaced" || bad "contours: rewrite failed"
refused "slice over its input's neighbour: a user's file" "is not thorax's own" "$THORAX" slice m --spacing 20 -o notes.txt -q
# series: text, raw and .mat; the input itself is never the output
printf 'thorax-series 1\nrows 2\nframes 3\ntime 0 1 2\n1 2 3\n4 5 6\nend\n' > s1.txt
if "$THORAX" series convert s1.txt -o s1.mat -q 2> se.err; then
    for f in txt raw mat; do
        "$THORAX" series convert s1.mat -o out.$f -q && "$THORAX" series convert s1.mat -o out.$f -q &&
            ok "series $f: thorax's own replaced" || bad "series $f: rewrite failed"
        echo "someone else's data" > user.$f
        refused "series $f over a user's file" "is not thorax's own output of this kind" "$THORAX" series convert s1.mat -o user.$f -q
        grep -q "someone else" user.$f && ok "series $f: the user's file is unchanged" || bad "series $f: changed"
    done
    cp s1.txt same.txt
    refused "series convert onto its own input" "an input of this command" "$THORAX" series convert same.txt -o same.txt -q
    cmp -s s1.txt same.txt && ok "the input is unchanged" || bad "the input changed"
else bad "series: $(cat se.err)"; fi

# render: a PNG carries thorax's tEXt signature; a user's picture of the same name stops the run
if "$THORAX" render m -o pic.png --size 64x64 -q 2> r.err && "$THORAX" render m -o pic.png --size 64x64 -q 2>> r.err; then
    ok "render: thorax's own picture replaced"
else bad "render: $(cat r.err)"; fi
printf '\x89PNG\r\n\x1a\n a user picture' > user.png
before=$(md5sum < user.png)
refused "render over a user's PNG" "is not thorax's own output of this kind" "$THORAX" render m -o user.png --size 64x64 -q
[ "$before" = "$(md5sum < user.png)" ] && ok "the user's PNG is unchanged" || bad "the user's PNG changed"

[ $fails -eq 0 ] && echo "e2e_outfiles: all passed" || echo "e2e_outfiles: $fails failed" >&2
exit $((fails > 0))
