#!/bin/bash
# The command line itself: `thorax help`, every command's --help (exit 0), unknown
# commands and options (exit 2), `thorax help COMMAND`.
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
"$THORAX" > /dev/null 2>&1; [ $? -eq 2 ] && ok "no command exits 2" || bad "no command"
"$THORAX" frobnicate > /dev/null 2>&1; [ $? -eq 2 ] && ok "unknown command exits 2" || bad "unknown command"
"$THORAX" --version | grep -q '^thorax ' && ok "--version" || bad "--version"
if [ $fails -ne 0 ]; then echo "$fails failed"; exit 1; fi
echo "all passed"
