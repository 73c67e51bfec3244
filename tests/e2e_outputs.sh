#!/usr/bin/env bash
# Outputs never destroy what thorax did not write (issue 11, item 1): a directory output (a model,
# a solution) is replaced only when it is thorax's own output of the same kind and holds nothing
# else and no input of the command; never through a symbolic link. Refusals exit 1, name what is
# there and leave every file as it was. Two commands writing the same output at once: one wins
# whole, the other exits 1, and nothing is left behind.
# Environment: THORAX = the CLI, WORK = a scratch directory.
set -u
: "${THORAX:?}" "${WORK:?}" "${SRC:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK" || exit 1
. "$SRC/tests/outputs_lib.sh"  # ok, bad, refused, snap
leftovers() { ls -a "$1" | grep -E '\.(tmp|old)' || true; }

"$THORAX" phantom --resolution medium --seed 2 -o c.txt -q || { bad "phantom"; exit 1; }
# Under the sanitizers (THORAX_QUICK, set by CMakeLists.txt) the phantom's torso and heart alone:
# the model is meshed seven times below (two races), and what is tested is how outputs are replaced
# or refused, which does not depend on the model's size. Every command and every meshing step still
# runs, on a model with a third of the surface nodes and half the tetrahedra; the plain build
# uses the whole phantom.
if [ -n "${THORAX_QUICK:-}" ]; then
    /usr/bin/python3 "$SRC/tests/contours_keep.py" c.txt c_quick.txt torso heart && mv c_quick.txt c.txt || { bad "contours_keep.py"; exit 1; }
fi

# 1. the issue's case: -o a folder that holds the command's input and an unrelated file in a subfolder
mkdir -p proj/sub && cp c.txt proj/c.txt && echo "my notes" > proj/sub/notes.txt
before=$(snap proj)
refused "input inside the output" "an input of this command" "$THORAX" surfaces proj/c.txt -o proj -q
[ "$before" = "$(snap proj)" ] && ok "the folder is unchanged" || bad "the folder changed"

# 2. a folder thorax did not write (no manifest), the input elsewhere
mkdir -p user && echo data > user/results.csv
before=$(snap user)
refused "a folder thorax did not write" "is not a thorax output of this kind" "$THORAX" surfaces c.txt -o user -q
[ "$before" = "$(snap user)" ] && ok "it is unchanged" || bad "it changed"

mkdir -p other && printf '{"format": "someone-else", "files": {"a": "a.txt"}}\n' > other/model.json && echo a > other/a.txt
refused "a model.json of another program" '"format": "someone-else"' "$THORAX" surfaces c.txt -o other -q
[ -s other/a.txt ] && ok "it is unchanged" || bad "changed"
mkdir -p empty && "$THORAX" surfaces c.txt -o empty -q && [ -s empty/model.json ] && ok "an empty folder is used" || bad "an empty folder was refused"

# 3. thorax's own model is replaced, and a mesh written in place
"$THORAX" surfaces c.txt -o m -q && "$THORAX" surfaces c.txt -o m -q && ok "own model replaced" || bad "own model not replaced"
"$THORAX" mesh m -q && [ -s m/volume.tet ] && ok "mesh in place" || bad "mesh in place"
[ -z "$(leftovers .)" ] && ok "no temporary directories left" || bad "left: $(leftovers .)"

# electrodes written into the model (thorax electrodes' default) are thorax's own, by their manifest
"$THORAX" electrodes m -q && [ -s m/electrodes/electrodes.json ] && "$THORAX" surfaces c.txt -o m -q && [ ! -e m/electrodes ] &&
    ok "a model holding its electrodes is rewritten" || bad "a model holding its electrodes"
"$THORAX" mesh m -q && "$THORAX" electrodes m -q && cp -r m m_el && rm m_el/electrodes/electrodes.json
refused "electrodes without their manifest" '"electrodes", a folder' "$THORAX" mesh m_el -q
[ -s m_el/electrodes/12lead.txt ] && ok "they are kept" || bad "they went"
"$THORAX" mesh m -q || bad "mesh in place again"

# 4. thorax's own model with something added by the user
cp -r m m_extra && echo "keep me" > m_extra/README.txt
before=$(snap m_extra)
refused "own model with a user file" '"README.txt", a file its manifest does not name' "$THORAX" surfaces c.txt -o m_extra -q
[ "$before" = "$(snap m_extra)" ] && ok "the user's file and the model are unchanged" || bad "changed"
cp -r m m_sub && mkdir m_sub/plots && echo p > m_sub/plots/a.txt
refused "own model with a user folder" '"plots", a folder' "$THORAX" mesh m -o m_sub -q
[ -s m_sub/plots/a.txt ] && ok "the folder is kept" || bad "the folder went"

# 5. a symbolic link is never followed
ln -s m mlink
before=$(snap m)
refused "a link to a model" "symbolic link" "$THORAX" surfaces c.txt -o mlink -q
[ "$before" = "$(snap m)" ] && [ -L mlink ] && ok "the link and its target are unchanged" || bad "changed"
cp -r m m_ln && ln -s ../c.txt m_ln/link.txt
refused "a model holding a link" '"link.txt", a symbolic link' "$THORAX" surfaces c.txt -o m_ln -q

# 6. an input inside thorax's own output: import of the model's own surface file
cp -r m m_in
before=$(snap m_in)
refused "import from inside the output" "an input of this command" "$THORAX" import -o m_in m_in/torso.pts --name torso --role outer -q
[ "$before" = "$(snap m_in)" ] && ok "unchanged" || bad "changed"

# 7. another kind: a solution over a model, a model over a solution
before=$(snap m)
refused "a solution over its own model" "an input of this command" "$THORAX" forward m --epicardial none.txt -o m
[ "$before" = "$(snap m)" ] && ok "the model is unchanged" || bad "changed"
cp -r m m_other
before=$(snap m_other)
refused "a solution over another model" "it has no solution.json" "$THORAX" forward m --epicardial none.txt -o m_other
[ "$before" = "$(snap m_other)" ] && ok "that model is unchanged" || bad "changed"
mkdir sol && printf '{"format": "thorax-solution", "version": 1, "files": {"torso": "torso.txt"}}\n' > sol/solution.json && echo 1 > sol/torso.txt
refused "a model over a solution" "it has no model.json" "$THORAX" surfaces c.txt -o sol -q
[ -s sol/torso.txt ] && ok "the solution is unchanged" || bad "changed"
refused "not a directory" "not a directory" "$THORAX" surfaces c.txt -o c.txt -q
cmp -s c.txt proj/c.txt && ok "the file is unchanged" || bad "the contours file changed"

# 8. two commands writing the same new output at once: one wins whole, the other exits 1
for round in new existing; do
    [ $round = new ] && rm -rf race
    [ $round = existing ] && { rm -rf race; cp -r m race; }
    "$THORAX" mesh m -o race -q > r1.log 2>&1 & p1=$!
    "$THORAX" mesh m -o race -q > r2.log 2>&1 & p2=$!
    wait $p1; r1=$?; wait $p2; r2=$?
    if [ $((r1 + r2)) -eq 1 ] && { [ $r1 -eq 0 ] || [ $r2 -eq 0 ]; }; then
        loser=$([ $r1 -eq 1 ] && echo r1.log || echo r2.log)
        grep -q "changed by another command" "$loser" && ok "race ($round output): one won, the other exited 1 ($(head -1 "$loser"))" ||
            bad "race ($round): loser's message: $(cat "$loser")"
    else bad "race ($round output): exits $r1 and $r2"; fi
    "$THORAX" check race -q > /dev/null 2>&1 && ok "race ($round): the output is whole and passes thorax check" || bad "race ($round): the output fails its check"
    cmp -s race/volume.tet m/volume.tet && ok "race ($round): it is one command's mesh" || bad "race ($round): differs from the mesh"
    [ -z "$(leftovers .)" ] && ok "race ($round): nothing left behind" || bad "race ($round): left $(leftovers .)"
done

if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
