#!/usr/bin/env bash
# Benchmark of thx_delaunay3d (paper 3.3, volume mesh) against CGAL, TetGen and
# qhull on the same points, side by side in one run:
#   - 100,000 and 1,000,000 random points in a 100 mm cube (fixed seed);
#   - a thorax-like layered set: 60 planes 5 mm apart, a 5 mm grid inside a
#     330 x 220 mm ellipse, plus the outer loop and three inner loops per plane
#     (~177,000 points, most of them cospherical/coplanar with others).
# For each program: the tetrahedra count, the triangulation time (thorax: the
# thx_delaunay3d call, best of $REPEAT; CGAL: the Delaunay_triangulation_3
# construction from the point range, best of $REPEAT, in bench/delaunay_cgal.cpp
# (a C++ peer built here with g++ when libcgal-dev is installed, never by the
# project's CMake); TetGen: its own "Delaunay seconds" from -V; qdelaunay:
# whole run only), tetrahedra per second from that time, the
# whole-process wall time (reading text input included) and peak memory
# (/usr/bin/time %M). Prints figures; never passes or fails on time.
# Environment: REPEAT (default 3), QHULL_MAX (largest point count given to
# qdelaunay, default 1000000), KEEP=1 keeps the work directory.
set -euo pipefail
cd "$(dirname "$0")/.."
REPEAT=${REPEAT:-3}
QHULL_MAX=${QHULL_MAX:-1000000}
LIB=${LIB:-build/libthorax.a}
[ -f "$LIB" ] || { echo "build first: cmake --build build"; exit 1; }
command -v /usr/bin/time > /dev/null || { echo "needs /usr/bin/time (scripts/deps.sh)"; exit 1; }
W=$(mktemp -d)
[ "${KEEP:-0}" = 1 ] && echo "work directory: $W" || trap 'rm -rf "$W"' EXIT

cc -O2 -std=c11 -D_GNU_SOURCE -Iinclude bench/delaunay_gen.c "$LIB" \
   $(pkg-config --libs libcjson 2> /dev/null || echo -lcjson) -lm -fopenmp -o "$W/dgen"
CGAL=""
if [ -f /usr/include/CGAL/Delaunay_triangulation_3.h ] && command -v g++ > /dev/null &&
   g++ -O3 -DNDEBUG -std=c++17 bench/delaunay_cgal.cpp -o "$W/dcgal" -lgmp -lmpfr 2> "$W/cgal.err"; then
    CGAL="$W/dcgal"
fi

echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //')"
echo "peers: CGAL $(dpkg-query -W -f='${Version}' libcgal-dev 2> /dev/null || echo 'not installed (libcgal-dev)'), TetGen (Debian tetgen $(dpkg-query -W -f='${Version}' tetgen 2> /dev/null || echo '?')), $(qdelaunay -V 2>&1 | head -1)"
echo
printf '%-22s %-10s %10s %11s %9s %8s %9s\n' "points" "program" "tets" "triang. s" "M tets/s" "wall s" "peak MB"

rate() { awk -v t="$1" -v s="$2" 'BEGIN { if (s > 0 && t > 0) printf "%.2f", t / s / 1e6; else printf "-" }'; }
mb() { awk -v k="$1" 'BEGIN { printf "%.0f", k / 1024 }'; }

run_set() { # name kind n
    local name=$1 kind=$2 n=$3 f="$W/$2_$3"
    "$W/dgen" gen "$kind" "$n" 1 "$f.node" "$f.qh"
    local np
    np=$(head -1 "$f.node" | cut -d' ' -f1)
    local label="$name ($np)"

    # thorax: best in-process time of REPEAT runs, then one run under /usr/bin/time
    local rep=$REPEAT
    [ "$np" -ge 500000 ] && rep=1
    local tt ts
    if "$W/dgen" run "$f.node" "$rep" > "$W/thx.out" 2>&1; then
        tt=$(awk '/^tets/ {print $2}' "$W/thx.out")
        ts=$(awk '/^tets/ {print $4}' "$W/thx.out")
        /usr/bin/time -f "%e %M" -o "$W/thx.time" "$W/dgen" run "$f.node" 1 > /dev/null 2>&1 || true
        read -r wall rss < "$W/thx.time"
        printf '%-22s %-10s %10s %11s %9s %8s %9s\n' "$label" thorax "$tt" "$ts" "$(rate "$tt" "$ts")" "$wall" "$(mb "$rss")"
    else
        printf '%-22s %-10s failed: %s\n' "$label" thorax "$(tail -1 "$W/thx.out")"
    fi

    # CGAL: best construction time of REPEAT, then one run under /usr/bin/time
    if [ -n "$CGAL" ]; then
        if "$CGAL" "$f.node" "$rep" > "$W/cg.out" 2>&1; then
            local ct cs
            ct=$(awk '/^tets/ {print $2}' "$W/cg.out")
            cs=$(awk '/^tets/ {print $4}' "$W/cg.out")
            /usr/bin/time -f "%e %M" -o "$W/cg.time" "$CGAL" "$f.node" 1 > /dev/null 2>&1 || true
            read -r wall rss < "$W/cg.time"
            printf '%-22s %-10s %10s %11s %9s %8s %9s\n' "" CGAL "$ct" "$cs" "$(rate "$ct" "$cs")" "$wall" "$(mb "$rss")"
        else
            printf '%-22s %-10s failed: %s\n' "" CGAL "$(tail -1 "$W/cg.out")"
        fi
    fi

    # TetGen: -V reports its own Delaunay time; -NEF writes no mesh files
    if (cd "$W" && /usr/bin/time -f "%e %M" -o "$W/tg.time" tetgen -V -NEF "$f.node" > "$W/tg.out" 2>&1); then
        local gt gs
        gt=$(awk '/Mesh tetrahedra:/ {print $3}' "$W/tg.out")
        gs=$(awk '/^Delaunay seconds:/ {print $3}' "$W/tg.out")
        read -r wall rss < "$W/tg.time"
        printf '%-22s %-10s %10s %11.4f %9s %8s %9s\n' "" "TetGen" "$gt" "$gs" "$(rate "$gt" "$gs")" "$wall" "$(mb "$rss")"
    else
        printf '%-22s %-10s failed\n' "" TetGen
    fi

    # qdelaunay: Qt triangulates the output, i prints one line per tetrahedron after a count line
    if [ "$np" -le "$QHULL_MAX" ]; then
        if /usr/bin/time -f "%e %M" -o "$W/qh.time" qdelaunay Qt i < "$f.qh" > "$W/qh.out" 2> "$W/qh.err"; then
            local qt
            qt=$(head -1 "$W/qh.out")
            read -r wall rss < "$W/qh.time"
            printf '%-22s %-10s %10s %11s %9s %8s %9s\n' "" "qdelaunay" "$qt" "(whole)" "$(rate "$qt" "$wall")" "$wall" "$(mb "$rss")"
        else
            printf '%-22s %-10s failed: %s\n' "" qdelaunay "$(tail -1 "$W/qh.err")"
        fi
    else
        printf '%-22s %-10s skipped (QHULL_MAX=%s)\n' "" qdelaunay "$QHULL_MAX"
    fi
    grep '^stages' "$W/thx.out" | sed 's/^stages: /  thorax stages: /' || true
    rm -f "$f.node" "$f.qh" "$W/qh.out"
}

run_set "random cube" cube 100000
run_set "random cube" cube 1000000
run_set "thorax layers" layers 0
echo
echo "triang. s: thorax = the thx_delaunay3d call (best of $REPEAT; 1 run at 10^6 points),"
echo "CGAL = its Delaunay_triangulation_3 construction (same repeats; spatial sort included),"
echo "TetGen = its own 'Delaunay seconds' (-V); qdelaunay has no inner timer, so its rate uses"
echo "the whole run. wall s and peak MB: whole process, reading the text input included."
echo "Random points are in general position: all counts must agree (unique Delaunay)."
