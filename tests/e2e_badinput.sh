#!/usr/bin/env bash
# The bad-input table (docs/validation.md): every malformed input of tests/badinput/fmt_*.py
# exits 1 naming file and position, writes nothing, and leaves an existing output unchanged.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK" && mkdir -p "$WORK"
python3 -B "$SRC/tests/badinput/run.py" "$THORAX" --table "$WORK/table.md"
