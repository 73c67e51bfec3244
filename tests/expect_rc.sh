# Sourced by tests/e2e_inverse.sh, e2e_inverse_shapes.sh and e2e_bad_leads.sh (not a test itself):
# expect_rc CODE ARGS... runs ARGS with stdout in out.txt and stderr in err.txt (the working
# directory) and calls the script's own fail() unless the exit status is CODE.
expect_rc() { # CODE ARGS...
    local want=$1; shift
    set +e
    "$@" > out.txt 2> err.txt
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || { cat err.txt >&2; fail "exit $rc, expected $want: $*"; }
}
