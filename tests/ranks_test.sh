# Sourced by the end-to-end tests that run thorax under mpirun (e2e_forward_ranks, e2e_render_parts,
# e2e_field_parts): `ranks_test NAME` skips the test (exit 77) without mpirun (Debian package
# openmpi-bin), defines fail, makes a mktemp -d directory TMP (removed at exit) the working
# directory, and sets MPIRUN (--oversubscribe; --allow-run-as-root for root) and one OpenMP thread a
# process (ctest's setting: three ranks share two cores here). PY is Debian's python3 (numpy).
ranks_test() {
    TEST_NAME=$1
    PY=/usr/bin/python3
    if ! command -v mpirun > /dev/null; then
        echo "$TEST_NAME: mpirun missing (Debian package openmpi-bin); skipped"
        exit 77
    fi
    TMP=$(mktemp -d "${TMPDIR:-/tmp}/$TEST_NAME.XXXXXX")
    trap 'rm -rf "$TMP"' EXIT
    cd "$TMP"
    MPIRUN=(mpirun --oversubscribe)
    if [ "$(id -u)" -eq 0 ]; then MPIRUN+=(--allow-run-as-root); fi
    export OMP_NUM_THREADS=1
}
fail() { echo "$TEST_NAME: FAIL: $*" >&2; exit 1; }
