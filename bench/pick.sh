#!/usr/bin/env bash
# Benchmark of picking (thorax/geom/pick.h; the viewer's mouse pick, issue 13) on the
# high-resolution phantom built in memory (~42,000 nodes, ~85,000 triangles over six surfaces):
# the index's build time, ray picks per second and the time per pick with the index and by brute
# force over every triangle (the answers compared), node picks (points) per second.
# bench/pick.c is built here against the library. Prints figures; never fails on time.
# Environment: N (rays, default 5000), RES (high or medium, default high).
set -euo pipefail
cd "$(dirname "$0")/.."
LIB=${LIB:-build/libthorax.a}
[ -f "$LIB" ] || { echo "build first: cmake --build build"; exit 1; }
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
cc -O2 -std=c11 -D_GNU_SOURCE -fopenmp -Iinclude bench/pick.c "$LIB" \
   $(pkg-config --cflags --libs PETSc epoxy egl libpng freetype2 fontconfig libcjson matio) $(mpicc --showme:link) -lz -lm \
   -o "$W/pick"
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
"$W/pick" "${N:-5000}" "${RES:-high}"
