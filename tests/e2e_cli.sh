#!/bin/bash
# The command line itself: `thorax help`, every command's --help (exit 0), unknown
# commands and options (exit 2), `thorax help COMMAND`; the option tables' parser: "did you mean",
# missing and bad values, the help's defaults and units, PETSc options passed through.
# Environment: THORAX = the CLI.
set -u
: "${THORAX:?}"
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
out=$("$THORAX" help) && ok "thorax help" || bad "thorax help"
for cmd in phantom surfaces check export slice import mesh; do
    echo "$out" | grep -q "^  $cmd " && ok "help lists $cmd" || bad "help does not list $cmd"
    "$THORAX" "$cmd" --help | grep -q "^usage: thorax $cmd" && ok "$cmd --help" || bad "$cmd --help"
    "$THORAX" help "$cmd" | grep -q "^usage: thorax $cmd" && ok "help $cmd" || bad "help $cmd"
    "$THORAX" "$cmd" --no-such-option > /dev/null 2>&1; [ $? -eq 2 ] && ok "$cmd: unknown option exits 2" || bad "$cmd: unknown option"
done
# Every command's options come from one table (src/cli/options.h): its --help, its usage errors.
# For each: --help and `help CMD` exit 0 and start with the usage line; an unknown option exits 2
# naming it; a misspelt one gets "did you mean"; a value missing at the end, and a bad value, exit 2
# naming the option. Columns: command, misspelt option, what it should suggest, an option that
# takes a value, a bad value for it.
err=$(mktemp); trap 'rm -f "$err"' EXIT
while read -r cmd typo near valued badval; do
    "$THORAX" "$cmd" --help > "$err.out" 2>&1; rc=$?
    [ $rc -eq 0 ] && head -n 1 "$err.out" | grep -q "^usage: thorax $cmd" && ok "$cmd --help: exit 0, usage line first" ||
        bad "$cmd --help: exit $rc, $(head -n 1 "$err.out")"
    "$THORAX" help "$cmd" > "$err.out" 2>&1; rc=$?
    [ $rc -eq 0 ] && head -n 1 "$err.out" | grep -q "^usage: thorax $cmd" && ok "help $cmd" || bad "help $cmd: exit $rc"
    "$THORAX" "$cmd" --no-such-option 2> "$err" > /dev/null; rc=$?
    [ $rc -eq 2 ] && grep -q "^thorax $cmd: unknown option '--no-such-option'" "$err" && ok "$cmd: unknown option exits 2, named" ||
        bad "$cmd --no-such-option: exit $rc: $(cat "$err")"
    "$THORAX" "$cmd" "$typo" 1 2> "$err" > /dev/null; rc=$?
    [ $rc -eq 2 ] && grep -q -- "unknown option '$typo' (did you mean $near?)" "$err" && ok "$cmd $typo: did you mean $near" ||
        bad "$cmd $typo: exit $rc: $(cat "$err")"
    "$THORAX" "$cmd" "$valued" 2> "$err" > /dev/null; rc=$?
    [ $rc -eq 2 ] && grep -q -- "^thorax $cmd: $valued needs a value" "$err" && ok "$cmd $valued (no value): exit 2, named" ||
        bad "$cmd $valued without a value: exit $rc: $(cat "$err")"
    "$THORAX" "$cmd" "$valued" "$badval" 2> "$err" > /dev/null; rc=$?
    [ $rc -eq 2 ] && grep -q -- "^thorax $cmd: $valued" "$err" && ok "$cmd $valued $badval: exit 2, named" ||
        bad "$cmd $valued $badval: exit $rc: $(cat "$err")"
done <<'TABLE'
phantom     --sed         --seed          --seed          abc
surfaces    --smothing    --smoothing     --spacing       0
check       --jsn         --json          --tol           x
export      --formt       --format        --format        xyz
slice       --spacng      --spacing       --margin        -1
import      --forse       --force         --scale         0
mesh        --gird        --grid          --grid          five
sigma       --scal        --scale         --scale         -2
series      --fromat      --format        --format        xls
electrodes  --aray        --array         --array         -3
beat        --frmes       --frames        --dt            0
forward     --epicardal   --epicardial    --threshold     nan
verify      --levles      --levels        --levels        9
leads       --twelv       --twelve        --format        pot
render      --colourbar   --colorbar      --levels        1.5
animate     --fsp         --fps           --fps           0
TABLE
rm -f "$err.out"
# the parser's own words: a number, an integer, a choice among words; a prefix; a short option
"$THORAX" mesh m --grid five 2> "$err"; grep -q "^thorax mesh: --grid: 'five' is not a number" "$err" && ok "not a number" || bad "not a number: $(cat "$err")"
"$THORAX" phantom --seed 1.5 2> "$err"; grep -q "^thorax phantom: --seed: '1.5' is not an integer" "$err" && ok "not an integer" || bad "not an integer: $(cat "$err")"
"$THORAX" surfaces c --cap hexagon 2> "$err"; grep -q "^thorax surfaces: --cap: 'hexagon': expected polygon or grid" "$err" && ok "a choice" || bad "a choice: $(cat "$err")"
"$THORAX" check m --no-inter 2> "$err"; grep -q "did you mean --no-intersections?" "$err" && ok "a prefix" || bad "a prefix: $(cat "$err")"
"$THORAX" mesh m -grid 5 2> "$err"; grep -q "did you mean --grid?" "$err" && ok "one dash too few" || bad "one dash: $(cat "$err")"
"$THORAX" mesh --grid 2> "$err"; grep -q "^(see 'thorax mesh --help')" "$err" && ok "usage errors point at --help" || bad "no pointer at --help"
# the help shows the defaults and units of the table, and an option's range rule keeps its message
"$THORAX" phantom --help | grep -A2 -- "^  --jitter MM" | grep -q "(default 0.6)" && ok "help: a default from the code" || bad "help: --jitter's default"
"$THORAX" mesh --help | grep -q "(repeatable; in S/m)" && ok "help: repeatable, a unit" || bad "help: --region"
"$THORAX" mesh m --repair 70 2> "$err"; grep -q "^thorax mesh: --repair must be between 0 and 70 degrees" "$err" && ok "a range rule's message" || bad "range: $(cat "$err")"
# PETSc options (one dash) still pass through forward and verify: not unknown options
"$THORAX" forward -ksp_type cg -ksp_monitor 2> "$err"; rc=$?
[ $rc -eq 2 ] && grep -q "no model given" "$err" && ! grep -q "unknown option" "$err" && ok "forward passes -ksp_type through" ||
    bad "forward -ksp_type: exit $rc: $(cat "$err")"
"$THORAX" verify -ksp_rtol 1e-9 stray 2> "$err"; rc=$?
[ $rc -eq 2 ] && grep -q "unexpected argument 'stray'" "$err" && ok "verify passes -ksp_rtol 1e-9 through" ||
    bad "verify -ksp_rtol: exit $rc: $(cat "$err")"
"$THORAX" forward m --no-such-option 2> "$err"; grep -q "unknown option '--no-such-option'" "$err" && ok "forward: two dashes are its own" || bad "forward --no-such-option"
# the manual's tools (scripts/cli_docs.sh): every table passes its check; the sections print
"$THORAX" help --check && ok "help --check" || bad "help --check"
"$THORAX" help --markdown mesh | grep -q '^| `--grid MM` |' && ok "help --markdown" || bad "help --markdown mesh"
"$THORAX" help --usage mesh | grep -q '^    thorax mesh MODEL \[-o MODEL\]' && ok "help --usage" || bad "help --usage mesh"
"$THORAX" > /dev/null 2>&1; [ $? -eq 2 ] && ok "no command exits 2" || bad "no command"
"$THORAX" frobnicate > /dev/null 2>&1; [ $? -eq 2 ] && ok "unknown command exits 2" || bad "unknown command"
"$THORAX" --version | grep -q '^thorax ' && ok "--version" || bad "--version"
# OpenBLAS's kernels (thorax/core/blas_kernels.h): on a processor with AVX2 and FMA, the commands
# that do dense or sparse-direct algebra (forward, bem, inverse, verify) never run OpenBLAS's SSE3
# fallback ("Prescott"): the last core OpenBLAS names is another; a user's own OPENBLAS_CORETYPE is
# kept; the arguments survive the new execution; the other commands start once.
if grep -q '^flags.* avx2 .*' /proc/cpuinfo && grep -q '^flags.* fma .*' /proc/cpuinfo &&
   OPENBLAS_VERBOSE=2 "$THORAX" --version 2>&1 | grep -q '^Core: '; then
    for cmd in forward bem inverse verify; do
        core=$(env -u OPENBLAS_CORETYPE -u THORAX_BLAS_REEXEC OPENBLAS_VERBOSE=2 "$THORAX" $cmd --help 2>&1 | grep '^Core: ' | tail -n 1)
        [ -n "$core" ] && [ "$core" != "Core: Prescott" ] && ok "OpenBLAS kernels for $cmd: $core" || bad "OpenBLAS kernels for $cmd: ${core:-none named}"
    done
    # the user's OPENBLAS_CORETYPE and OpenMP wait (GOMP_SPINCOUNT or OMP_WAIT_POLICY) kept: one start
    core=$(env -u THORAX_BLAS_REEXEC OPENBLAS_CORETYPE=Prescott GOMP_SPINCOUNT=300000 OPENBLAS_VERBOSE=2 "$THORAX" inverse --help 2>&1 | grep -c '^Core: ')
    [ "$core" = 1 ] && ok "a user's OPENBLAS_CORETYPE and GOMP_SPINCOUNT kept (one start)" || bad "OPENBLAS_CORETYPE=Prescott GOMP_SPINCOUNT=300000: $core starts"
    core=$(env -u GLIBC_TUNABLES -u THORAX_BLAS_REEXEC OPENBLAS_CORETYPE=Haswell OMP_WAIT_POLICY=passive OPENBLAS_VERBOSE=2 "$THORAX" forward --help 2>&1 | grep -c '^Core: ')
    [ "$core" = 1 ] && ok "OPENBLAS_CORETYPE and OMP_WAIT_POLICY given: forward starts once" || bad "forward with OPENBLAS_CORETYPE=Haswell OMP_WAIT_POLICY=passive: $core starts"
    # the core given, the wait not: a second start for GOMP_SPINCOUNT alone, the user's core kept in it
    cores=$(env -u THORAX_BLAS_REEXEC -u GOMP_SPINCOUNT -u OMP_WAIT_POLICY OPENBLAS_CORETYPE=Prescott OPENBLAS_VERBOSE=2 "$THORAX" inverse --help 2>&1 | grep '^Core: ')
    [ "$(echo "$cores" | wc -l)" = 2 ] && [ "$(echo "$cores" | tail -n 1)" = "Core: Prescott" ] &&
        ok "OPENBLAS_CORETYPE given, GOMP_SPINCOUNT not: two starts, the user's core kept" || bad "OPENBLAS_CORETYPE=Prescott alone: $cores"
    out=$(env -u OPENBLAS_CORETYPE -u THORAX_BLAS_REEXEC "$THORAX" bem --help 2>&1 | head -n 1)
    [ "${out#usage: thorax bem}" != "$out" ] && ok "arguments kept across the new execution" || bad "after the new execution: $out"
    core=$(env -u OPENBLAS_CORETYPE -u THORAX_BLAS_REEXEC OPENBLAS_VERBOSE=2 "$THORAX" mesh --help 2>&1 | grep -c '^Core: ')
    [ "$core" = 1 ] && ok "a light command starts once" || bad "thorax mesh --help: $core starts"
fi
if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
