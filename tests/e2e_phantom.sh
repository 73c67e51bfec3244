#!/bin/bash
# End-to-end test of `thorax phantom`: both resolutions, determinism (byte-identical
# output for a seed), standard output, usage errors (exit 2), failures (exit 1, no output).
# Environment: THORAX = the CLI, WORK = a scratch directory (created here).
set -u
: "${THORAX:?set THORAX to the thorax executable}"
: "${WORK:?set WORK to a scratch directory}"
rm -rf "$WORK"
mkdir -p "$WORK"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
check() { local what=$1; shift; if "$@"; then ok "$what"; else bad "$what"; fi; }

# Runs the CLI and checks its exit code: expect_rc CODE ARGS...
expect_rc() {
    local want=$1; shift
    "$THORAX" "$@" >"$WORK/out.log" 2>"$WORK/err.log"
    local rc=$?
    if [ "$rc" -eq "$want" ]; then ok "thorax $* -> exit $rc"; else bad "thorax $* -> exit $rc (expected $want): $(cat "$WORK/err.log")"; fi
}

# A contour file as the reader expects it: header, units, spacing, six surfaces, layers, end.
well_formed() { # FILE SPACING LAYERS
    local f=$1
    [ "$(head -n 1 "$f")" = "thorax-contours 1" ] &&
    [ "$(tail -n 1 "$f")" = "end" ] &&
    grep -qx "units mm" "$f" &&
    grep -qx "spacing $2" "$f" &&
    [ "$(grep -c '^surface ' "$f")" -eq 6 ] &&
    grep -qx "surface torso outer cap grid" "$f" &&
    grep -qx "surface fat fat cap grid" "$f" &&
    grep -qx "surface muscle muscle cap grid" "$f" &&
    grep -qx "surface lung_r lung cap polygon" "$f" &&
    grep -qx "surface lung_l lung cap polygon" "$f" &&
    grep -qx "surface heart heart cap grid" "$f" &&
    [ "$(grep -c '^layer ' "$f")" -eq "$3" ] &&
    # every data line is a loop header or two numbers
    # the anatomical frame: the phantom is drawn in RAS (+z superior, +y anterior)
    grep -qx "frame +z +y" "$f" &&
    ! grep -v -E '^(#|thorax-contours 1$|units mm$|spacing [0-9.]+$|frame [-+][xyz] [-+][xyz]$|surface |layer -?[0-9.]+$|loop [a-z_]+$|end$|-?[0-9]+\.[0-9]+ -?[0-9]+\.[0-9]+$)' "$f" | grep -q .
}

expect_rc 0 phantom --resolution medium --seed 3 -o "$WORK/m3a.txt"
expect_rc 0 phantom --resolution medium --seed 3 -o "$WORK/m3b.txt"
expect_rc 0 phantom --resolution high --seed 3 -o "$WORK/h3.txt"
expect_rc 0 phantom --seed 4 -o "$WORK/m4.txt"
check "medium file is well formed (28 layers, spacing 11)" well_formed "$WORK/m3a.txt" 11 28
check "high file is well formed (55 layers, spacing 5)" well_formed "$WORK/h3.txt" 5 55
check "same seed, same bytes" cmp -s "$WORK/m3a.txt" "$WORK/m3b.txt"
check "different seed, different points" bash -c "! cmp -s '$WORK/m3a.txt' '$WORK/m4.txt'"
check "header records the options" grep -q "^# command: thorax phantom --resolution high --seed 3" "$WORK/h3.txt"
check "high has about twice the loops of medium" \
    bash -c "[ \$(grep -c '^loop ' '$WORK/h3.txt') -gt \$((2 * \$(grep -c '^loop ' '$WORK/m3a.txt') - 12)) ]"

# Standard output gives the same bytes as a file; the default is medium, seed 1.
expect_rc 0 phantom -o "$WORK/d1.txt"
"$THORAX" phantom --seed 1 --resolution medium -q -o - >"$WORK/stdout.txt" 2>"$WORK/err.log"
check "-o - writes to standard output" cmp -s "$WORK/d1.txt" "$WORK/stdout.txt"
check "-q is quiet" test ! -s "$WORK/err.log"

# Help and usage errors.
expect_rc 0 phantom --help
check "--help names the options" grep -q -- "--resolution" "$WORK/out.log"
expect_rc 0 help phantom
expect_rc 2 phantom --resolution ultra -o "$WORK/x.txt"
check "bad resolution is explained" grep -q "ultra" "$WORK/err.log"
expect_rc 2 phantom --resolution
expect_rc 2 phantom --seed abc -o "$WORK/x.txt"
expect_rc 2 phantom --seed -1 -o "$WORK/x.txt"
expect_rc 2 phantom --frobnicate -o "$WORK/x.txt"
expect_rc 2 phantom
check "no output file left by usage errors" test ! -e "$WORK/x.txt"

# Failures: exit 1, message, no partial file.
expect_rc 1 phantom --jitter 9 -o "$WORK/x.txt"
expect_rc 1 phantom -o "$WORK/no/such/dir/x.txt"
check "a failed write leaves nothing" test ! -e "$WORK/no/such/dir/x.txt"
check "no temporary files left" bash -c "! ls -a '$WORK' | grep -q tmp"

if [ "$fails" -ne 0 ]; then
    echo "$fails check(s) failed" >&2
    exit 1
fi
echo "all phantom e2e checks passed"
