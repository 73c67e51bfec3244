#!/usr/bin/env bash
# Sort-first rendering under mpirun (issue 28, item 1): the same work on 1 rank and on 2, timed as
# whole processes by farm-bench (pairs of runs, medians), the pictures compared byte for byte:
#   1. thorax trace of the high-resolution phantom's surfaces with the potentials at 1920 x 1080
#      (tiles dealt to the ranks), 2 ranks of one OpenMP thread each beside one process of
#      BASE_THREADS threads (1, the default: each rank stands for a machine, and the ratio is the
#      ranks' scaling; 2: this machine's two cores in one process, what sharing costs here);
#   2. thorax render (OpenGL, llvmpipe) of the same picture (rows in bands);
#   3. thorax animate of 24 frames at 800 x 600 (frames dealt to the ranks).
# Threads: OpenMP's (the tracer) and llvmpipe's (OpenGL: LP_NUM_THREADS) are both set, one a rank and
# BASE_THREADS for the one process. This machine has 2 cores: the figures say what sharing costs and
# gains here; across machines each rank brings its own cores. Prints figures; never fails on time.
#   DATA=DIR   reuse DIR/m (model, meshed) and DIR/sol (solution); else the high phantom is made
#   RUNS=N     farm-bench pairs (default 3)
#   BASE_THREADS=N  the one process's OpenMP threads (default 1)
set -euo pipefail
cd "$(dirname "$0")/.."
THORAX=${THORAX:-$PWD/build/bin/thorax}
[ -x "$THORAX" ] || { echo "build first (make)"; exit 1; }
command -v mpirun > /dev/null || { echo "mpirun missing (Debian package openmpi-bin)"; exit 1; }
command -v farm-bench > /dev/null || { echo "farm-bench missing (the tool library)"; exit 1; }
RUNS=${RUNS:-3}
BT=${BASE_THREADS:-1}
MPI="mpirun --oversubscribe"
[ "$(id -u)" = 0 ] && MPI="$MPI --allow-run-as-root"
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
echo "machine: $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), load $(cut -d' ' -f1-3 /proc/loadavg)"
if [ -n "${DATA:-}" ]; then
    S=$DATA/sol
else
    S=$W/sol
    "$THORAX" phantom --resolution high --seed 1 -o "$W/c.txt" -q
    "$THORAX" surfaces "$W/c.txt" -o "$W/m" -q 2> /dev/null
    "$THORAX" mesh "$W/m" --no-heart -q
    "$THORAX" beat "$W/m" -o "$W/beat.raw" --frames 300 -q
    "$THORAX" forward "$W/m" --epicardial "$W/beat.raw" -o "$S" -q
fi
# case NAME OUT1 OUT2 ARGS...: 2 ranks (1 thread each) against 1 process (BT threads), then the outputs compared
case_() {
    local name=$1 o1=$2 o2=$3
    shift 3
    echo
    echo "== $name: $*"
    # (the outputs removed before each run: animate would keep the frames of the run before)
    farm-bench -n "$RUNS" --warmup 1 --timeout 1200 \
        --vs "sh -c 'rm -rf $o1; OMP_NUM_THREADS=$BT LP_NUM_THREADS=$BT exec $THORAX $* -o $o1 -q'" \
        -- sh -c "rm -rf $o2; OMP_NUM_THREADS=1 LP_NUM_THREADS=1 exec $MPI -np 2 $THORAX $* -o $o2 -q" 2>&1 | sed 's/^/  /'
    echo "  (A: 2 ranks of 1 thread; B: 1 process of $BT thread(s); A/B below 1: sharing gains)"
}
case_ "trace, one picture of 1920 x 1080" "$W/t1.png" "$W/t2.png" trace --solution "$S" --frame 150 --size 1920x1080 --colorbar
cmp -s "$W/t1.png" "$W/t2.png" && echo "  the same bytes on 1 and 2 ranks" || echo "  THE PICTURES DIFFER"
case_ "render (OpenGL), one picture of 1920 x 1080" "$W/r1.png" "$W/r2.png" render --solution "$S" --frame 150 --size 1920x1080 --colorbar
cmp -s "$W/r1.png" "$W/r2.png" && echo "  the same bytes on 1 and 2 ranks" || echo "  THE PICTURES DIFFER"
case_ "animate, 24 frames of 800 x 600" "$W/a1" "$W/a2" animate --solution "$S" --frames 100:123 --size 800x600 --colorbar --mp4 none
same=1
for f in "$W"/a1/frame_*.png; do cmp -s "$f" "$W/a2/${f##*/}" || same=0; done
[ $same = 1 ] && echo "  the same frames on 1 and 2 ranks" || echo "  THE FRAMES DIFFER"
