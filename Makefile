# thorax — top-level entry points. `make demo` and `make check` set up what is
# missing (scripts/deps.sh), configure, build, and run.
BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
THORAX = $(BUILD)/bin/thorax
OUT ?= out/demo

.PHONY: all deps build demo check check-full sanitize fuzz bench clean install

all: build

deps:
	@bash scripts/deps.sh

$(BUILD)/CMakeCache.txt:
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null

# Quiet: one line with the time; the compiler's whole output goes to $(BUILD)/build.log, its
# warnings are shown, and a failed build shows its errors (the log without make's progress lines)
# and stops here.
build: deps $(BUILD)/CMakeCache.txt
	@t0=$$(date +%s); \
	if cmake --build $(BUILD) -j $(JOBS) > $(BUILD)/build.log 2>&1; then \
	    grep -E 'warning:' $(BUILD)/build.log >&2 || true; \
	    printf '  %-46s %5d s\n' "build ($(BUILD))" $$(( $$(date +%s) - t0 )); \
	else \
	    grep -Ev '^\[ *[0-9]+%\]|^(Consolidate|Scanning)|Entering directory|Leaving directory|^make.*: \*\*\*' $(BUILD)/build.log | tail -n 80 >&2; \
	    echo "build failed: the whole log is $(BUILD)/build.log" >&2; exit 1; \
	fi
	@test -x $(THORAX)

# The main job on the built-in phantom: contours -> surfaces -> volume mesh -> checks ->
# electrodes and heartbeat -> forward solution -> 12-lead ECG -> pictures and a movie ->
# out/demo/index.html (scripts/demo.sh).
demo: build
	@THORAX=$(THORAX) OUT=$(OUT) bash scripts/demo.sh

# The suite with the heaviest tests in their quick forms (label quick; docs/design/testing.md, "Tiers").
check: build
	@cd $(BUILD) && ctest -j $(JOBS) -LE full --output-on-failure

# Every test whole: the quick forms' NAME_full instead of NAME (run it before changing the mesher, the
# surfaces or the solvers).
check-full: build
	@cd $(BUILD) && ctest -j $(JOBS) -LE quick --output-on-failure

# Under AddressSanitizer and UndefinedBehaviorSanitizer: every unit test and fuzz replay, and the
# end-to-end tests that run each command once (CMakeLists.txt, THORAX_SANITIZED_E2E).
sanitize: deps
	@cmake -S . -B $(BUILD)-asan -DCMAKE_BUILD_TYPE=Debug -DTHORAX_SANITIZE=ON >/dev/null
	@cmake --build $(BUILD)-asan -j $(JOBS) 2>&1 | grep -Ev '^\[ *[0-9]+%\]|^(Consolidate|Scanning)|^g?make\[' || true
	@cd $(BUILD)-asan && ASAN_OPTIONS=detect_leaks=1 ctest -j $(JOBS) -LE 'full|plain' --output-on-failure

# Every libFuzzer harness (tests/fuzz/) for FUZZ_TIME seconds each (default 60); fails on a finding.
FUZZ_TIME ?= 60
fuzz: deps
	@FUZZ_TIME=$(FUZZ_TIME) JOBS=$(JOBS) bash scripts/fuzz.sh

# Installs the shared and static library, headers, thorax.pc, the CMake package, the programs, the
# man pages and the Python binding under PREFIX, staged under DESTDIR when given (packaging):
#   make install PREFIX=$$HOME/.local      make install PREFIX=/usr DESTDIR=/tmp/stage
PREFIX ?= /usr/local
install: build
	@DESTDIR="$(DESTDIR)" cmake --install $(BUILD) --prefix "$(PREFIX)" >$(BUILD)/install.log || { cat $(BUILD)/install.log; exit 1; }
	@echo "installed under $(DESTDIR)$(PREFIX) ($$(grep -c '^-- ' $(BUILD)/install.log) files; list in $(BUILD)/install_manifest.txt)"

bench: build
	@bash bench/surfaces.sh
	@bash bench/delaunay.sh
	@bash bench/mesh.sh
	@bash bench/forward.sh
	@bash bench/render.sh

clean:
	rm -rf $(BUILD) $(BUILD)-asan build-fuzz out
