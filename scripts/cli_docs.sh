#!/bin/bash
# docs/cli.md's generated sections, made by the program from the commands' option tables
# (src/cli/options.h), so that the manual, the help and the parser cannot drift apart:
#   <!-- usage: CMD -->    ... <!-- end usage: CMD -->     the usage lines    (thorax help --usage CMD)
#   <!-- options: CMD -->  ... <!-- end options: CMD -->   the option table   (thorax help --markdown CMD)
# Everything outside the markers is prose and stays as it is.
#
# usage: scripts/cli_docs.sh [--check] [DOC]
#   DOC      the manual (default: docs/cli.md beside this script)
#   --check  change nothing: exit 1, showing the difference, when DOC is not what the tables give
#            (tests/e2e_cli_docs.sh); without it DOC's sections are rewritten in place
#   THORAX   the program (default: build/bin/thorax beside this script)
# Also fails when the tables fail their own check (thorax help --check: every option of a usage
# line declared, every option in some usage line) or a command has no usage or options section.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
check=0
if [ "${1:-}" = "--check" ]; then check=1; shift; fi
DOC=${1:-$here/docs/cli.md}
THORAX=${THORAX:-$here/build/bin/thorax}
[ -x "$THORAX" ] || { echo "cli_docs.sh: $THORAX is not a program (build first, or set THORAX)" >&2; exit 2; }
[ -f "$DOC" ] || { echo "cli_docs.sh: $DOC: no such file" >&2; exit 2; }

"$THORAX" help --check || { echo "cli_docs.sh: the option tables fail their check (above)" >&2; exit 1; }

# DOC with every section replaced by what the program prints for it
generate() {
    local line kind cmd end="" n=0
    while IFS= read -r line || [ -n "$line" ]; do
        n=$((n + 1))
        if [ -n "$end" ]; then
            if [ "$line" = "$end" ]; then printf '%s\n' "$line"; end=""; fi
            continue
        fi
        if [[ $line =~ ^'<!-- '(usage|options)': '([a-z]+)' -->'$ ]]; then
            kind=${BASH_REMATCH[1]} cmd=${BASH_REMATCH[2]}
            printf '%s\n\n' "$line"
            if [ "$kind" = usage ]; then "$THORAX" help --usage "$cmd"; else "$THORAX" help --markdown "$cmd"; fi
            printf '\n'
            end="<!-- end $kind: $cmd -->"
            continue
        fi
        if [[ $line =~ ^'<!-- end '(usage|options)': ' ]]; then
            echo "cli_docs.sh: $DOC:$n: '$line' without its start" >&2
            return 1
        fi
        printf '%s\n' "$line"
    done <"$DOC"
    if [ -n "$end" ]; then echo "cli_docs.sh: $DOC: no '$end'" >&2; return 1; fi
}

# every command (thorax help lists them) has both sections
missing=0
for cmd in $("$THORAX" help | awk '/^commands:/ { on = 1; next } on && /^  [a-z]/ { print $1 }'); do
    [ "$cmd" = help ] && continue
    for kind in usage options; do
        if ! grep -qxF "<!-- $kind: $cmd -->" "$DOC"; then
            echo "cli_docs.sh: $DOC has no '<!-- $kind: $cmd -->' section" >&2
            missing=1
        fi
    done
done
[ $missing -eq 0 ] || exit 1

tmp=$(mktemp "${TMPDIR:-/tmp}/cli_docs.XXXXXX")
trap 'rm -f "$tmp"' EXIT
generate >"$tmp"
if cmp -s "$DOC" "$tmp"; then exit 0; fi
if [ $check -eq 1 ]; then
    diff -u "$DOC" "$tmp" | sed "s|$tmp|(from the option tables)|" || true
    echo "cli_docs.sh: $DOC differs from the option tables; run scripts/cli_docs.sh to rewrite its sections" >&2
    exit 1
fi
cat "$tmp" >"$DOC.tmp.$$" && mv "$DOC.tmp.$$" "$DOC"
echo "cli_docs.sh: rewrote the generated sections of $DOC"
