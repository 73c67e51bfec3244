# Sourced by bench/same_outputs.sh and bench/same_speed.sh: REV's thorax, built once in a
# worktree under WORKDIR and kept there (WORKDIR/old-build/bin/thorax) for the next run.
# Sets ROOT, REV, W (WORKDIR), NEW (this tree's thorax) and OLD (REV's); NAME names the caller.
# Usage: NAME=same_x; . bench/old_thorax.sh "$@"    (from the checkout's top)
ROOT=$PWD
REV=${1:-HEAD~1}
W=${2:-$(mktemp -d "/tmp/thorax-$NAME.XXXXXX")}
mkdir -p "$W"
NEW=${THORAX:-$ROOT/build/bin/thorax}
[ -x "$NEW" ] || { echo "$NAME: $NEW is not built (make build)" >&2; exit 1; }
if [ ! -x "$W/old-build/bin/thorax" ]; then
    rm -rf "$W/old"
    git worktree add --detach "$W/old" "$REV" > /dev/null
    trap 'git -C "$ROOT" worktree remove --force "$W/old" > /dev/null 2>&1 || true' EXIT
    cmake -S "$W/old" -B "$W/old-build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > /dev/null
    cmake --build "$W/old-build" -j "${JOBS:-2}" --target thorax_cli > /dev/null
fi
OLD=$W/old-build/bin/thorax
