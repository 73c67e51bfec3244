#!/usr/bin/env bash
# The P_1 study on OpenMEEG's three spheres meshed by thorax (docs/validation.md, "On meshes thorax
# makes"): the variants behind the figures there that thorax verify does not run. bench/spheres_study.c
# is built here against the library; each line is one mesh and solve (figures only, no pass/fail):
#   - the brain not meshed, its Steiner nodes interpolated (thorax forward's way), given the analytic
#     value at their position, or left free (levels 3-5; LEVELS overrides);
#   - the brain meshed with free Steiner nodes (levels 2-4);
#   - all three conductivities 1 S/m (levels 2-4).
# Level 6 (40,962 nodes per sphere) takes about 100 s and 2.4 GB without the brain: LEVELS="4 5 6".
set -euo pipefail
cd "$(dirname "$0")/.."
LIB=${LIB:-build/libthorax.a}
[ -f "$LIB" ] || { echo "build first: cmake --build build"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cc -O2 -std=c11 -D_GNU_SOURCE -fopenmp -Iinclude bench/spheres_study.c "$LIB" \
   $(pkg-config --cflags --libs PETSc epoxy egl libpng freetype2 fontconfig libcjson matio) $(mpicc --showme:link) -lz -lm \
   -o "$W/study"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for mode in interp analytic free; do
    for k in ${LEVELS:-3 4 5}; do "$W/study" "$k" "$mode" nobrain; done
done
for k in 2 3 4; do "$W/study" "$k" free brain; done
for k in 2 3 4; do "$W/study" "$k" interp brain 1; done
