#!/usr/bin/env bash
# Runs every libFuzzer harness (tests/fuzz/fuzz_*.c) for FUZZ_TIME seconds each (default 60)
# and fails on any finding. `make fuzz` and CI call it; bench/fuzz.sh calls it for long
# campaigns. Usage: scripts/fuzz.sh [TARGET...]  (default: every harness)
#
# Each harness starts from its seeds, tests/fuzz/corpus/NAME/, copied into a scratch corpus
# (the source tree is never written). A finding (crash, leak, timeout, out-of-memory) is kept
# under $FUZZ_OUT/NAME/ (default: a temporary directory, printed) so that it can be added to the
# seeds as a regression input. Limits per input: FUZZ_RSS_MB (default 1024) of memory, a single
# allocation above FUZZ_MALLOC_MB (default 256) and FUZZ_TIMEOUT seconds (default 10): a reader
# given a file of at most FUZZ_MAX_LEN bytes (default 65536) must stay far below those.
# The DICOM reader runs GDCM in its helper program (exec'd: none of libFuzzer's handlers follow it),
# held to FUZZ_RSS_MB of address space and FUZZ_TIMEOUT/2 seconds per file (THORAX_DICOM_MEMORY_MB,
# THORAX_DICOM_SECONDS), so that the reader refuses a file GDCM chokes on before libFuzzer's own
# timeout would call it a finding (docs/design/image.md, "The DICOM helper program").
# Prints one line per target: executions, coverage (edges), corpus size and findings. JOBS
# harnesses (default: the number of cores) run side by side.
set -euo pipefail
cd "$(dirname "$0")/.."
FUZZ_TIME=${FUZZ_TIME:-60}
FUZZ_BUILD=${FUZZ_BUILD:-build-fuzz}
FUZZ_RSS_MB=${FUZZ_RSS_MB:-1024}
FUZZ_MALLOC_MB=${FUZZ_MALLOC_MB:-256}
FUZZ_TIMEOUT=${FUZZ_TIMEOUT:-10}
FUZZ_MAX_LEN=${FUZZ_MAX_LEN:-65536}
JOBS=${JOBS:-$(nproc 2>/dev/null || echo 2)}

bash scripts/deps.sh
if ! command -v clang >/dev/null; then
  echo "fuzz: clang is missing (scripts/deps.sh installs it)" >&2
  exit 1
fi
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  for f in tests/fuzz/fuzz_*.c; do
    n=$(basename "$f" .c)
    targets+=("${n#fuzz_}")
  done
fi
# Only the harnesses asked for (and the library they link): not the programs, the unit tests, the
# replay tests, the benchmark helpers or the man pages, which a fuzzing build never runs. A name
# with no tests/fuzz/fuzz_NAME.c is left to run_one, which reports it missing.
build=()
for t in "${targets[@]}"; do
  [ -f "tests/fuzz/fuzz_$t.c" ] && build+=("fuzz_$t")
done
cmake -S . -B "$FUZZ_BUILD" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo -DTHORAX_FUZZ=ON >/dev/null
if [ ${#build[@]} -gt 0 ]; then
  cmake --build "$FUZZ_BUILD" -j "$JOBS" --target "${build[@]}" 2>&1 | grep -Ev '^\[ *[0-9]+%\]|^(Consolidate|Scanning)|^g?make\[' || true
fi
scratch=$(mktemp -d "${TMPDIR:-/tmp}/thorax-fuzz-run.XXXXXX")
trap 'rm -rf "$scratch"' EXIT
out=${FUZZ_OUT:-}
if [ -z "$out" ]; then out=$(mktemp -d "${TMPDIR:-/tmp}/thorax-fuzz-findings.XXXXXX"); fi
mkdir -p "$out"

# One harness: runs it, writes its table line to $out/NAME/line and its findings' summary to
# $out/NAME/findings (empty: none). JOBS harnesses run at once, each a single process.
run_one() {
  local t=$1 bin corpus log rc execs secs edges ncorp nfind
  bin="$FUZZ_BUILD/bin/fuzz_$t"
  mkdir -p "$out/$t"
  : > "$out/$t/findings"
  if [ ! -x "$bin" ]; then
    echo "fuzz: no harness $bin" > "$out/$t/findings"
    printf '%-14s %8s %12s %10s %8s %7s %9s\n' "$t" - - - - - missing > "$out/$t/line"
    return
  fi
  bin=$(realpath "$bin")
  corpus="$scratch/$t"
  mkdir -p "$corpus"
  [ -d "tests/fuzz/corpus/$t" ] && cp -r "tests/fuzz/corpus/$t/." "$corpus/"
  log="$out/$t/fuzz.log"
  set +e
  # -fork would add parallel jobs within a harness; one process each keeps the figures
  # comparable run to run.
  (cd "$out/$t" && ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=1 \
     THORAX_DICOM_MEMORY_MB="$FUZZ_RSS_MB" THORAX_DICOM_SECONDS=$(( FUZZ_TIMEOUT > 3 ? FUZZ_TIMEOUT / 2 : 1 )) \
     "$bin" "$corpus" -max_total_time="$FUZZ_TIME" -rss_limit_mb="$FUZZ_RSS_MB" \
     -malloc_limit_mb="$FUZZ_MALLOC_MB" -timeout="$FUZZ_TIMEOUT" -max_len="$FUZZ_MAX_LEN" \
     -print_final_stats=1 -artifact_prefix="$out/$t/" >"$log" 2>&1)
  rc=$?
  set -e
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  secs=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | tail -1)
  edges=$(grep -Eo 'cov: [0-9]+' "$log" | tail -1 | awk '{print $2}')
  ncorp=$(find "$corpus" -type f | wc -l)
  nfind=$(find "$out/$t" -maxdepth 1 -type f \( -name 'crash-*' -o -name 'leak-*' -o -name 'timeout-*' -o -name 'oom-*' -o -name 'slow-unit-*' \) | wc -l)
  if [ "$rc" -ne 0 ] && [ "$nfind" -eq 0 ]; then nfind=1; fi
  printf '%-14s %8s %12s %10s %8s %7s %9s\n' "$t" "$FUZZ_TIME" "${execs:-?}" "${secs:-?}" "${edges:-?}" "$ncorp" "$nfind" > "$out/$t/line"
  if [ "$nfind" -ne 0 ]; then
    { echo "fuzz: $t: finding(s) in $out/$t/ (log: $log):"
      grep -E 'ERROR|SUMMARY|fuzz property|Test unit written' "$log" | head -8 || true; } > "$out/$t/findings"
  fi
}

running=0
for t in "${targets[@]}"; do
  if [ "$running" -ge "$JOBS" ]; then wait -n || true; running=$((running - 1)); fi
  run_one "$t" &
  running=$((running + 1))
done
wait

printf '%-14s %8s %12s %10s %8s %7s %9s\n' target seconds executions exec/s edges corpus findings
failed=0
for t in "${targets[@]}"; do
  cat "$out/$t/line" 2>/dev/null || { printf '%-14s (did not run)\n' "$t"; failed=1; }
  if [ -s "$out/$t/findings" ]; then failed=1; cat "$out/$t/findings" >&2; fi
done
if [ "$failed" -ne 0 ]; then exit 1; fi
[ -z "${FUZZ_OUT:-}" ] && rm -rf "$out"
echo "fuzz: no finding"
