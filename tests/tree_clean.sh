#!/usr/bin/env bash
# The suite leaves nothing in the source tree (issue 11, item 8): tests write only into temporary
# directories or the build directory. Run by ctest as a fixture around every other test:
#   tree_clean.sh stamp STAMP   before the first test: records the time
#   tree_clean.sh check STAMP   after the last: fails naming every file or folder made or changed
#                               in the source tree since, outside .git and the build directories
set -u
mode=$1 stamp=$2
: "${SRC:?}" "${BIN:?}"
case $mode in
stamp) mkdir -p "$(dirname "$stamp")" && : > "$stamp" && sleep 1 && echo "stamped $stamp" ;;
check)
    [ -f "$stamp" ] || { echo "no stamp $stamp (run the whole suite)"; exit 1; }
    bin=$(realpath "$BIN")
    found=$(find "$SRC" \( -path "$SRC/.git" -o -path "$bin" -o -path "$SRC/build" -o -path "$SRC/build-*" \) -prune -o \
        -newer "$stamp" -print | grep -v -x "$SRC" || true)
    if [ -n "$found" ]; then
        echo "FAIL: the suite left these in the source tree:"
        echo "$found" | head -20
        exit 1
    fi
    echo "ok: nothing made or changed in $SRC outside the build directories" ;;
*) echo "usage: tree_clean.sh stamp|check STAMP"; exit 2 ;;
esac
