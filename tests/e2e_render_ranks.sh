#!/usr/bin/env bash
# Sort-first rendering under mpirun (issue 28, item 1; docs/design/parallel.md), on the medium
# phantom's forward solution with volume potentials:
#  - thorax trace (tiles dealt to the ranks; surfaces with a colour bar, and volume rendering) and
#    thorax render (OpenGL, rows in bands; one panel and panels, at sizes the bands do not divide)
#    write the same bytes on 1, 2 and 3 ranks, and say how many ranks drew;
#  - thorax animate (frames dealt to the ranks; OpenGL and traced): the same frames and the same
#    movie on 1, 2 and 3 ranks; a run on 2 ranks over the frames 1 rank drew keeps them all;
#  - a picture refused under 3 ranks is refused once (one message, from one rank), with a non-zero
#    exit and nothing written; a launcher's rank count that is not a number, and MPI out of reach
#    (the solver module missing), are refused by name before anything is drawn;
#  - a command that runs in one process (electrodes) started on 2 ranks is refused once, writing
#    nothing (every rank would write the same files).
# Env: THORAX, WORK, SRC. Skipped (77) without mpirun (Debian package openmpi-bin).
set -euo pipefail
: "${THORAX:?}" "${WORK:?}"
command -v mpirun > /dev/null || { echo "e2e_render_ranks: mpirun missing (Debian package openmpi-bin); skipped"; exit 77; }
MPI=(mpirun --oversubscribe)
[ "$(id -u)" = 0 ] && MPI+=(--allow-run-as-root)
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_render_ranks: FAIL: $*" >&2; exit 1; }

. "$(dirname "$0")/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" beat model -o beat.raw --frames 8 --dt 40 -q
"$THORAX" forward model --epicardial beat.raw -o sol --volume -q || fail "forward"

# picture CMD NAME ARGS...: the picture by 1 rank, then by 2 and 3, compared byte for byte
picture() {
    local cmd=$1 name=$2
    shift 2
    "$THORAX" "$cmd" --solution sol "$@" -o "$name.1.png" -q || fail "$cmd $*: 1 rank"
    for n in 2 3; do
        "${MPI[@]}" -np $n "$THORAX" "$cmd" --solution sol "$@" -o "$name.$n.png" > "$name.$n.out" ||
            fail "$cmd $*: $n ranks"
        grep -q ", $n ranks" "$name.$n.out" || fail "$cmd on $n ranks: no word of the ranks: $(cat "$name.$n.out")"
        cmp -s "$name.1.png" "$name.$n.png" || fail "$cmd $*: $n ranks drew another picture than 1"
    done
    echo "$cmd $*: the same $(stat -c %s "$name.1.png") bytes on 1, 2 and 3 ranks"
}
picture trace surfaces --frame 5 --size 241x190 --colorbar --scope all --samples 1 --ao 4
picture trace volume --frame 3 --size 200x200 --volume potential --colorbar --scope all --samples 1 --ao 0
picture render gl --frame 6 --size 301x233 --colorbar --label
picture render panels --frame 2 --size 333x250 --panels --colorbar --style bands+contours --levels 10

# animate: frames dealt round-robin, the movie made by rank 0
animation() {
    local name=$1
    shift
    "$THORAX" animate --solution sol "$@" -o "$name.1" -q || fail "animate $*: 1 rank"
    for n in 2 3; do
        "${MPI[@]}" -np $n "$THORAX" animate --solution sol "$@" -o "$name.$n" > "$name.$n.out" || fail "animate $*: $n ranks"
        grep -q "drawn, 0 kept.* by $n ranks" "$name.$n.out" || fail "animate on $n ranks: $(cat "$name.$n.out")"
        for f in "$name.1"/frame_*.png; do
            cmp -s "$f" "$name.$n/${f##*/}" || fail "animate $*: $n ranks drew ${f##*/} otherwise"
        done
        if [ -f "$name.1/animation.mp4" ]; then
            cmp -s "$name.1/animation.mp4" "$name.$n/animation.mp4" || fail "animate $*: the movie of $n ranks differs"
        fi
    done
    echo "animate $*: $(ls "$name.1"/frame_*.png | wc -l) frames and the movie the same on 1, 2 and 3 ranks"
}
animation agl --size 200x160 --colorbar --scope all
animation atr --frames 2:6 --size 120x100 --renderer trace --samples 1 --ao 0
# resumed on 2 ranks over what 1 rank drew: every frame kept
"${MPI[@]}" -np 2 "$THORAX" animate --solution sol --size 200x160 --colorbar --scope all -o agl.1 > resume.out ||
    fail "animate resumed on 2 ranks"
grep -q "(0 drawn, 8 kept from an earlier run)" resume.out || fail "resumed on 2 ranks: $(cat resume.out)"

# a picture refused on 3 ranks: one message, a non-zero exit, nothing written
if "${MPI[@]}" -np 3 "$THORAX" render --solution sol --size 160x120 --colorbar -o refused.png > refused.out 2> refused.err; then
    fail "a picture too small for its colour bars was drawn on 3 ranks"
fi
[ "$(grep -c 'thorax render' refused.err)" = 1 ] || fail "the refusal, not once: $(cat refused.err)"
grep -q 'colour bars fit' refused.err || fail "the refusal's reason: $(cat refused.err)"
[ ! -e refused.png ] || fail "a refused picture was written"

# a launcher's count that is not a number; MPI out of reach
if OMPI_COMM_WORLD_SIZE=two "$THORAX" render --solution sol --size 100x100 -o bad1.png 2> bad1.err; then fail "OMPI_COMM_WORLD_SIZE=two accepted"; fi
grep -q 'not a positive number' bad1.err || fail "OMPI_COMM_WORLD_SIZE=two: $(cat bad1.err)"
if OMPI_COMM_WORLD_SIZE=2 THORAX_PETSC_MODULE=/nonexistent/libthorax-petsc.so "$THORAX" trace --solution sol --size 100x100 \
    -o bad2.png 2> bad2.err; then fail "2 ranks without MPI accepted"; fi
grep -q 'started by mpirun with 2 ranks, but MPI cannot be reached' bad2.err || fail "MPI out of reach: $(cat bad2.err)"
[ ! -e bad1.png ] && [ ! -e bad2.png ] || fail "a refused run wrote its picture"
# a command that does not share its work, under mpirun: refused once, before it writes anything
if "${MPI[@]}" -np 2 "$THORAX" electrodes model -q > one.out 2> one.err; then fail "electrodes ran on 2 ranks"; fi
[ "$(grep -c 'runs in one process' one.err)" = 1 ] || fail "electrodes on 2 ranks, the refusal not once: $(cat one.err)"
[ ! -e model/electrodes ] || fail "electrodes on 2 ranks wrote its files"
echo "e2e_render_ranks: ok"
