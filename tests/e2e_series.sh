#!/bin/bash
# End-to-end: `thorax series` on the real map3d recording
# (../shared/data/map3d/data/tank/cool1-atdr-run1.mat: struct `onerun`,
# potvals 512 x 608, unit 'uV') and on a hand-written series with NaN and
# infinities: info, conversions text <-> raw <-> mat that give identical files
# back, scipy.io.loadmat reading our .mat files (values compared with the text
# files we wrote, and with the recording as scipy reads it), and failures that
# leave no output behind.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
REC="$SRC/../shared/data/map3d/data/tank/cool1-atdr-run1.mat"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

fail() { echo "e2e_series: FAIL: $*" >&2; exit 1; }
[ -f "$REC" ] || fail "recording $REC missing"
no_tmp() { ! ls "$WORK" | grep -q '\.tmp' || fail "temporary files left: $(ls "$WORK" | grep '\.tmp')"; }

# --- usage: --help exits 0; bad usage exits 2; a bad file exits 1 --------------
"$THORAX" series --help | grep -q "usage: thorax series info FILE" || fail "--help"
"$THORAX" help series | grep -q "thorax series convert IN -o OUT" || fail "help series"
"$THORAX" help | grep -q "^  series " || fail "series not in the command list"
set +e
"$THORAX" series 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "no subcommand gave exit $rc, expected 2"
"$THORAX" series shuffle "$REC" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "unknown subcommand gave exit $rc, expected 2"
"$THORAX" series info 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "info without a file gave exit $rc, expected 2"
"$THORAX" series convert "$REC" 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "convert without -o gave exit $rc, expected 2"
"$THORAX" series convert "$REC" -o x.xyz 2>err.txt; rc=$?
[ $rc -eq 2 ] || fail "unknown output extension gave exit $rc, expected 2"
grep -q "give --format" err.txt || fail "no hint at --format: $(cat err.txt)"
"$THORAX" series convert "$REC" -o x.txt --format xml 2>/dev/null; rc=$?
[ $rc -eq 2 ] || fail "unknown --format gave exit $rc, expected 2"
"$THORAX" series info none.mat 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail "missing file gave exit $rc, expected 1"
grep -q "none.mat: cannot open" err.txt || fail "error does not name the file: $(cat err.txt)"
set -e
[ ! -e x.xyz ] && [ ! -e x.txt ] || fail "a refused command wrote a file"

# --- info on the recording ----------------------------------------------------
"$THORAX" series info "$REC" > info.txt
for want in "^rows *512$" "^frames *608$" "^unit *uV$" "^time *0 \.\. 607 ms (step 1)$" \
            "^min *-36860$" "^max *20555$" "^non-finite *0$"; do
    grep -q "$want" info.txt || fail "info lacks /$want/: $(cat info.txt)"
done

# --- round trips: identical files back ------------------------------------------
"$THORAX" series convert "$REC" -o a.txt -q
"$THORAX" series convert a.txt -o a.raw -q
"$THORAX" series convert a.raw -o a.mat -q
"$THORAX" series convert a.mat -o b.txt -q
cmp -s a.txt b.txt || fail "mat -> text -> raw -> mat -> text changed the text"
"$THORAX" series convert a.mat -o b.raw -q
cmp -s a.raw b.raw || fail "raw -> mat -> raw changed the raw file"
"$THORAX" series convert a.raw -o b.mat -q
cmp -s a.mat b.mat || fail "the same series gave two different .mat files"
"$THORAX" series convert a.mat -o c.dat --format raw -q
cmp -s a.raw c.dat || fail "--format raw did not write raw"
"$THORAX" series convert "$REC:onerun" -o d.txt -q
cmp -s a.txt d.txt || fail "FILE.mat:onerun read differently"
[ "$(stat -c %s a.raw)" -eq $((200 + 8 * 608 * 513)) ] || fail "a.raw is $(stat -c %s a.raw) bytes"
head -n 7 a.txt | tr '\n' '|' | grep -q "^thorax-series 1|rows 512|frames 608|unit uV|time_unit ms|t0 0|dt 1|$" ||
    fail "unexpected text header: $(head -n 7 a.txt)"
tail -n 1 a.txt | grep -qx end || fail "a.txt does not end with 'end'"

# --- a hand-written series: NaN, infinities, a non-uniform axis, a label --------
cat > nan.txt <<'EOF'
thorax-series 1
# three leads, four instants
rows 3
frames 4
unit mV
time_unit s
label bench test #2 (lead 3 lost)
time 0 0.001 0.0025 0.004
0.1 -2 nan 4e-3
inf 5 6 7
8 9 10 -inf    # the last value is -inf
end
EOF
"$THORAX" series info nan.txt > info2.txt
grep -q "^non-finite *3 (first: row 2, frame 1)$" info2.txt || fail "NaN/Inf not reported: $(cat info2.txt)"
grep -q "^time *0 \.\. 0.004 s (non-uniform steps)$" info2.txt || fail "time axis: $(cat info2.txt)"
"$THORAX" series convert nan.txt -o nan.mat -q
"$THORAX" series convert nan.mat -o nan.raw -q
"$THORAX" series convert nan.raw -o nan2.txt -q
"$THORAX" series convert nan2.txt -o nan2.mat -q
cmp -s nan.mat nan2.mat || fail "the NaN series changed on its way through raw and text"
grep -q "^label bench test #2 (lead 3 lost)$" nan2.txt || fail "label lost: $(cat nan2.txt)"
no_tmp

# --- scipy reads our .mat files ---------------------------------------------------
"$PY" - "$REC" <<'EOF' || fail "scipy check"
import math, sys
import numpy as np
import scipy.io

def read_text(path):
    """Our text format (docs/formats.md, "Time series"), read independently."""
    head, rows = {}, []
    for raw in open(path):
        line = raw.strip()
        if not line or line.startswith('#'):
            continue
        if line.startswith('label'):
            head['label'] = line[5:].strip()
            continue
        line = line.split('#')[0].split()
        if line[0] == 'thorax-series' or line[0] == 'end':
            continue
        try:
            rows.append([float(t) for t in line])
        except ValueError:
            head[line[0]] = line[1:]
    v = np.array(rows)
    assert v.shape == (int(head['rows'][0]), int(head['frames'][0])), v.shape
    if 'time' in head:
        t = np.array([float(x) for x in head['time']])
    else:
        t = float(head.get('t0', ['0'])[0]) + np.arange(v.shape[1]) * float(head['dt'][0])
    return v, t, head

def text_of(m, key):
    a = m[key]
    return str(a[0]) if a.size else ''

def check(matfile, txtfile):
    m = scipy.io.loadmat(matfile)
    v, t, head = read_text(txtfile)
    pv = m['potvals']
    assert pv.dtype == np.float64 and pv.shape == v.shape, (pv.dtype, pv.shape, v.shape)
    assert np.array_equal(np.isnan(pv), np.isnan(v)), 'NaN positions differ'
    assert np.array_equal(pv[~np.isnan(pv)], v[~np.isnan(v)]), 'values differ'
    assert m['time'].shape == (1, v.shape[1]) and np.array_equal(m['time'][0], t), 'time differs'
    assert text_of(m, 'unit') == head.get('unit', [''])[0], text_of(m, 'unit')
    assert text_of(m, 'time_unit') == (head['time_unit'][0] if head.get('time_unit') else ''), text_of(m, 'time_unit')
    assert text_of(m, 'label') == head.get('label', ''), text_of(m, 'label')
    return pv

pv = check('a.mat', 'a.txt')
orig = scipy.io.loadmat(sys.argv[1])['onerun'][0, 0]
assert np.array_equal(pv, orig['potvals'].astype(np.float64)), 'differs from the recording'
assert str(orig['unit'][0]) == 'uV'
pv = check('nan.mat', 'nan.txt')
assert math.isnan(pv[0, 2]) and pv[1, 0] == math.inf and pv[2, 3] == -math.inf
print('e2e_series: scipy reads a.mat (512 x 608) and nan.mat as written')
EOF

# --- failures: exit 1, the file and line named, nothing written -----------------
head -n -1 a.txt > trunc.txt
set +e
"$THORAX" series convert trunc.txt -o out.mat 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail "truncated text gave exit $rc, expected 1"
grep -q "trunc.txt:519: truncated file (no 'end' line)" err.txt || fail "truncation message: $(cat err.txt)"
sed '300s/^\([^ ]*\) /\1 x4 /' a.txt > word.txt
"$THORAX" series convert word.txt -o out.mat 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail "a non-number gave exit $rc, expected 1"
grep -q "word.txt:300: row 293, frame 2: 'x4' is not a number" err.txt || fail "non-number message: $(cat err.txt)"
head -c 100000 a.raw > trunc.raw
"$THORAX" series convert trunc.raw -o out.mat 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail "truncated raw gave exit $rc, expected 1"
grep -q "trunc.raw: byte offset 100000: truncated (the file ends here): 512 rows x 608 frames take 2495432 bytes" err.txt ||
    fail "raw truncation message: $(cat err.txt)"
# issue 11: the recording cut in half lost its time step, unit and label (exit 0); a 48-byte text
# series claiming 5e8 frames took 3.9 GB and 15 s before it was refused
head -c $(( $(stat -c %s "$REC") / 2 )) "$REC" > half.mat
"$THORAX" series convert half.mat -o out.txt 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail "the recording cut in half gave exit $rc, expected 1"
grep -q "half.mat: variable 1 ('onerun', at byte offset 128; .*truncated" err.txt || fail "half .mat message: $(cat err.txt)"
printf 'thorax-series 1\nrows 1\nframes 500000000\n0 0\nend\n' > claim.txt
t0=$(date +%s%N)
"$THORAX" series info claim.txt 2>err.txt >/dev/null; rc=$?
t1=$(date +%s%N)
[ $rc -eq 1 ] || fail "5e8 claimed frames gave exit $rc, expected 1"
grep -q "claim.txt:3: 'frames 500000000': a file of 48 bytes cannot hold" err.txt || fail "claim message: $(cat err.txt)"
[ $(( (t1 - t0) / 1000000 )) -lt 2000 ] || fail "5e8 claimed frames took $(( (t1 - t0) / 1000000 )) ms"
"$PY" -c "import scipy.io; scipy.io.savemat('chars.mat', {'name': 'abc'})"
"$THORAX" series convert chars.mat -o out.txt 2>err.txt; rc=$?
[ $rc -eq 1 ] || fail ".mat without numbers gave exit $rc, expected 1"
grep -q "chars.mat: no numeric variable" err.txt || fail ".mat message: $(cat err.txt)"
# an existing output is kept when the conversion fails
cp nan.txt keep.txt
"$THORAX" series convert trunc.txt -o keep.txt 2>/dev/null; rc=$?
[ $rc -eq 1 ] || fail "failed conversion over an existing file gave exit $rc"
set -e
[ ! -e out.mat ] && [ ! -e out.txt ] || fail "a failed conversion left an output file"
cmp -s nan.txt keep.txt || fail "a failed conversion changed an existing file"
no_tmp
echo "e2e_series: ok"
