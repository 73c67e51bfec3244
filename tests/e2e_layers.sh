#!/bin/bash
# The library's layers (docs/decisions.md, "One direction"): tests/layers.py on the source tree and
# the built objects — includes, public headers and calls all go down the table core < model <
# (geom, io, leads) < (mesh, check) < (fem, render, phantom, import) < cli — after its self-test on
# made-up trees with planted violations.
# Environment: THORAX = the CLI (its build directory holds the objects), SRC = the source tree.
set -u
: "${THORAX:?}" "${SRC:?}"
BUILD=$(dirname "$(dirname "$THORAX")")
python3 -B "$SRC/tests/layers.py" --self-test || { echo "FAIL: the layer checker misses planted violations"; exit 1; }
python3 -B "$SRC/tests/layers.py" "$SRC" --build "$BUILD" || { echo "FAIL: against the direction (above)"; exit 1; }
echo "all passed"
