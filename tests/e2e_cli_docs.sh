#!/bin/bash
# docs/cli.md's usage lines and option lists are what the commands' option tables generate
# (scripts/cli_docs.sh --check: `thorax help --usage/--markdown CMD` between its markers, every
# command with both sections), and the tables pass their own check (`thorax help --check`: every
# option a usage line names is declared, every declared option is in some usage line).
# Environment: THORAX = the CLI, SRC = the source tree, WORK = a scratch directory.
set -u
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK" && mkdir -p "$WORK"
if THORAX="$THORAX" TMPDIR="$WORK" bash "$SRC/scripts/cli_docs.sh" --check "$SRC/docs/cli.md"; then
    echo "e2e_cli_docs: docs/cli.md matches the option tables"
else
    echo "e2e_cli_docs: FAIL: docs/cli.md differs from the option tables (above); scripts/cli_docs.sh rewrites it" >&2
    exit 1
fi
