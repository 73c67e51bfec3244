#!/usr/bin/env bash
# The shared phantom models (a CTest fixture, registered by CMakeLists.txt in every build;
# not an e2e_*.sh test itself). Ten end-to-end tests (THORAX_PHANTOM_USERS in CMakeLists.txt:
# e2e_forward, e2e_render, e2e_check, e2e_export_data, e2e_view, e2e_field, ...) each begin by meshing
# the same medium phantom (seed 1) without the heart, two of them with it as well: the same input,
# the same commands and byte-identical files twelve times, at 3 CPU-s a mesh in the plain build and
# 15 to 30 s under ASan. Here they are made once, with
# exactly the commands those tests run:
#   $OUT/c.txt       thorax phantom --resolution medium --seed 1 -o c.txt
#   $OUT/model       thorax surfaces c.txt -o model; thorax mesh model --no-heart
#   $OUT/modelh      thorax mesh model -o modelh (the heart included)
# and those tests copy them when THORAX_PHANTOM_MODELS names this folder (run alone, without it,
# they make their own). Written into $OUT.tmp and renamed when whole.
set -euo pipefail
: "${THORAX:?}" "${OUT:?}"
rm -rf "$OUT" "$OUT.tmp"
mkdir -p "$OUT.tmp"
cd "$OUT.tmp"
"$THORAX" phantom --resolution medium --seed 1 -o c.txt -q
"$THORAX" surfaces c.txt -o model -q
"$THORAX" mesh model --no-heart -q
"$THORAX" check model -q
# the model with the heart meshed: e2e_forward's and e2e_check's alone, and neither runs under the
# sanitizers (THORAX_PHANTOM_HEART=0 there: CMakeLists.txt, THORAX_SANITIZED_E2E)
if [ "${THORAX_PHANTOM_HEART:-1}" != 0 ]; then
    "$THORAX" mesh model -o modelh -q
    "$THORAX" check modelh -q
fi
cd ..
mv "$OUT.tmp" "$OUT"
echo "phantom_models: $OUT/model (no heart), $OUT/modelh (the heart included), $OUT/c.txt"
