# Shared by tests/e2e_outputs.sh and tests/e2e_outfiles.sh (sourced; not a test itself):
# ok/bad count results in $fails; refused CASE PATTERN CMD... expects exit 1, a message matching
# PATTERN and "nothing was written"; snap DIR lists a tree with checksums, to see nothing changed.
fails=0
ok() { echo "ok: $1"; }
bad() { echo "FAIL: $1" >&2; fails=$((fails + 1)); }
refused() {
    local name=$1 pat=$2; shift 2
    "$@" > out.log 2> err.log; local rc=$?
    if [ $rc -eq 1 ] && grep -q -- "$pat" err.log && grep -q "nothing was written" err.log; then ok "$name: refused ($(head -1 err.log))"
    else bad "$name: exit $rc, $(cat err.log)"; fi
}
snap() { (cd "$1" && find . -print0 | sort -z | xargs -0 -I{} sh -c 'if [ -f "{}" ]; then echo "{} $(md5sum < "{}")"; else echo "{}"; fi'); }
