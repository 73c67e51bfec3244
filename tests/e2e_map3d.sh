#!/bin/bash
# End-to-end: map3d's files through the CLI, checked by programs not written here.
#  - .geom: `thorax import` of the Dalhousie torso and epicardium (daltorsoepi.geom@1, @2) and the
#    closed sock: the model's .pts/.fac equal map3d's own text files of the same surfaces (numpy);
#  - .tsdf: dipole2.tsdf -> .mat read by scipy.io.loadmat equals an independent decoding of the
#    file in Python (VAX floats) and the six .pot files; cool1-atdr-run1.tsdf equals the .mat
#    recording; its q/s/t times come out as map3d fids that scipy reads;
#  - numbered .pot files (pattern and directory) equal the .tsdf;
#  - map3d's ts struct (rsm10jan01-cs-0004.mat) through `series convert` .mat -> .mat: scipy reads
#    the same struct (every field, in order, the fids);
#  - CSV out read by numpy; a plain matrix in; .fids onto a series;
#  - bad input: truncated files, a size larger than the file, a VAX reserved operand (the format's
#    NaN), .tsdfc: exit 1, file and byte named, nothing written;
#  - render draws a .geom@N surface with .tsdf data.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -eu
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
D="$SRC/../shared/data/map3d"
PY=/usr/bin/python3
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail() { echo "e2e_map3d: FAIL: $*" >&2; exit 1; }
[ -f "$D/data/torso/dipole2.tsdf" ] || fail "map3d data missing under $D"

# --- .geom as surfaces ---------------------------------------------------------
"$THORAX" import -q -o dal --up -y --front -z "$D/geom/torso/daltorsoepi.geom@1" --name torso --role outer \
    "$D/geom/torso/daltorsoepi.geom@2" --name epi --role heart || fail "import daltorsoepi.geom"
"$THORAX" import -q -o sock "$D/geom/tank/25feb97_sock_closed.geom" --name sock --role heart || fail "import sock .geom"
set +e
"$THORAX" import -q -o two "$D/geom/torso/daltorsoepi.geom" --name t --role outer 2>err.txt; rc=$?
set -e
[ $rc -eq 1 ] && grep -q "holds 2 surfaces: pick one as .*daltorsoepi.geom@1" err.txt || fail "two surfaces, no pick: $(cat err.txt)"
[ ! -e two ] || fail "a refused import wrote its model"
$PY - "$D/geom" <<'EOF' || fail ".geom surfaces differ from map3d's .pts/.fac"
import sys, numpy as np
g = sys.argv[1]
for model, name, ref in (("dal", "torso", "torso/daltorso"), ("dal", "epi", "torso/dalepi"),
                         ("sock", "sock", "tank/25feb97_sock_closed")):
    p, q = np.loadtxt(f"{model}/{name}.pts"), np.loadtxt(f"{g}/{ref}.pts")
    f, r = np.loadtxt(f"{model}/{name}.fac", dtype=int), np.loadtxt(f"{g}/{ref}.fac", dtype=int)
    assert p.shape == q.shape and f.shape == r.shape, (name, p.shape, q.shape, f.shape, r.shape)
    assert np.abs(p - q).max() <= 1e-5 * max(1, np.abs(q).max()), (name, np.abs(p - q).max())
    assert (f == r).all(), name
    print(f"e2e_map3d: {model}/{name}: {len(p)} nodes, {len(f)} triangles equal {ref}.pts/.fac")
EOF

# --- .tsdf -> .mat, read by scipy; .pot sets ------------------------------------------
"$THORAX" series info "$D/data/torso/dipole2.tsdf" > info.txt
grep -q "^rows *352$" info.txt && grep -q "^frames *6$" info.txt && grep -q "^unit *uV$" info.txt || fail "info dipole2: $(cat info.txt)"
"$THORAX" series convert -q "$D/data/torso/dipole2.tsdf" -o dipole2.mat
"$THORAX" series convert -q "$D/data/torso/dipole2_%03d.pot" -o set.mat
"$THORAX" series convert -q "$D/data/torso" -o dir.mat
"$THORAX" series convert -q "$D/data/tank/cool1-atdr-run1.tsdf" -o cool1.mat
"$THORAX" series info "$D/data/tank/cool1-atdr-run1.tsdf" > cinfo.txt
grep -q "^  qon *type 2 *155 (one value)$" cinfo.txt && grep -q "^  toff *type 7 *384" cinfo.txt || fail "cool1 fiducials: $(cat cinfo.txt)"
$PY - "$D" <<'EOF' || fail ".tsdf values differ"
import sys, struct, numpy as np, scipy.io as sio
D = sys.argv[1]
def tsdf(path):
    # an independent decoding: little-endian longs, VAX F floats, frame-major data
    b = open(path, "rb").read()
    L = lambda o: struct.unpack_from("<i", b, o)[0]
    t = L(32); nch, nfr, off = L(t + 92), L(t + 96), L(t + 100)
    u = np.frombuffer(b, np.uint8, 4 * nch * nfr, off).reshape(-1, 4).astype(np.uint64)
    w = u[:, 1] << 24 | u[:, 0] << 16 | u[:, 3] << 8 | u[:, 2]
    e = ((w >> 23) & 255).astype(int); m = 0.5 + (w & 0x7fffff).astype(float) / 2**24
    v = np.where(e == 0, 0.0, np.where(w >> 31, -1.0, 1.0) * np.ldexp(m, e - 128))
    return v.reshape(nfr, nch).T
d = sio.loadmat("dipole2.mat")
P = d["potvals"]
assert P.shape == (352, 6) and np.array_equal(P, tsdf(f"{D}/data/torso/dipole2.tsdf"))
assert str(d["unit"][0]) == "uV"
pots = np.stack([np.loadtxt(f"{D}/data/torso/dipole2_{k:03d}.pot") for k in range(1, 7)], axis=1)
assert np.abs(P - pots).max() < 1e-6, np.abs(P - pots).max()
for f in ("set.mat", "dir.mat"):
    assert np.array_equal(sio.loadmat(f)["potvals"], pots), f
c = sio.loadmat("cool1.mat")
ref = sio.loadmat(f"{D}/data/tank/cool1-atdr-run1.mat")["onerun"][0, 0]["potvals"]
assert np.array_equal(c["potvals"], ref.astype(float)) and np.array_equal(c["potvals"], tsdf(f"{D}/data/tank/cool1-atdr-run1.tsdf"))
fids = c["fids"]
got = sorted((int(fids[0, k]["type"][0, 0]), float(fids[0, k]["value"][0, 0])) for k in range(fids.shape[1]))
assert got == [(2, 155.0), (4, 196.0), (7, 384.0)], got
print("e2e_map3d: dipole2.tsdf = .pot set = scipy's potvals; cool1 .tsdf = .mat; fids", got)
EOF

# --- map3d's ts struct through .mat -> .mat ----------------------------------------
REC="$D/data/socks/10jan01/rsm10jan01-cs-0004.mat"
"$THORAX" series info "$REC" > rinfo.txt
grep -q "^struct *ts (23 fields kept)$" rinfo.txt && grep -q "^  act *type 10 *490 values" rinfo.txt || fail "rsm info: $(cat rinfo.txt)"
"$THORAX" series convert -q "$REC" -o ts.mat
"$THORAX" series convert -q ts.mat -o ts2.mat
cmp -s ts.mat ts2.mat || fail ".mat -> .mat -> .mat is not byte-identical"
$PY - "$REC" <<'EOF' || fail "the ts struct changed"
import sys, numpy as np, scipy.io as sio
a = sio.loadmat(sys.argv[1], mat_dtype=True)["ts"][0, 0]
b = sio.loadmat("ts.mat", mat_dtype=True)["ts"][0, 0]
assert a.dtype.names == b.dtype.names, (a.dtype.names, b.dtype.names)
for n in a.dtype.names:
    x, y = a[n], b[n]
    if n == "fids":
        assert x.shape == y.shape
        for k in range(x.shape[1]):
            for f in ("value", "type", "fidset"):
                assert np.array_equal(np.asarray(x[0, k][f], float), np.asarray(y[0, k][f], float)), (k, f)
    elif n == "geom":  # MATLAB's [] (1 x 0): libmatio keeps no size for an empty array
        assert x.size == 0 and y.size == 0
    else:
        assert x.dtype.kind == y.dtype.kind and x.shape == y.shape and np.array_equal(x, y), n
print(f"e2e_map3d: ts struct kept: {len(a.dtype.names)} fields, {a['fids'].shape[1]} fiducials")
EOF

# --- CSV out, matrices in, .fids --------------------------------------------------
"$THORAX" series convert -q "$D/data/torso/dipole2.tsdf" -o d.csv
"$THORAX" series convert -q d.csv -o d2.mat
$PY <<'EOF' || fail "CSV"
import numpy as np, scipy.io as sio
t = np.genfromtxt("d.csv", delimiter=",")
P = sio.loadmat("dipole2.mat")["potvals"]
assert np.array_equal(t[1:, 1:], P) and np.array_equal(t[0, 1:], np.arange(6)) and np.array_equal(t[1:, 0], np.arange(1, 353))
assert np.array_equal(sio.loadmat("d2.mat")["potvals"], P)
np.savetxt("m.txt", P.T)  # frames x channels
print("e2e_map3d: CSV read by numpy equals the series; CSV reads back exactly")
EOF
"$THORAX" series convert -q m.txt --transpose -o m.mat
$PY -c "import scipy.io as s, numpy as n; assert n.array_equal(s.loadmat('m.mat')['potvals'], s.loadmat('dipole2.mat')['potvals'])" ||
    fail "a transposed matrix"
{ echo "1"; echo "1 -1"; echo "352 act rec"; for i in $(seq 1 352); do echo "$i $((i % 6 + 1)) 6"; done; } > d.fids
"$THORAX" series info "$D/data/torso/dipole2.tsdf" --fids d.fids | grep -q "^  act *type 10 *352 values (one per row), 0 .. 5$" ||
    fail "--fids"

# --- bad input --------------------------------------------------------------------
head -c 9000 "$D/data/torso/dipole2.tsdf" > cut.tsdf
head -c 3000 "$D/geom/tank/25feb97_sock_closed.geom" > cut.geom
$PY - "$D" <<'EOF'
import sys, struct
D = sys.argv[1]
b = bytearray(open(f"{D}/data/torso/dipole2.tsdf", "rb").read())
big = bytearray(b); struct.pack_into("<i", big, 468 + 96, 100000)  # 100000 frames
open("big.tsdf", "wb").write(big)
nan = bytearray(b); nan[816 + 4 * 10: 816 + 4 * 10 + 2] = b"\x00\x80"  # VAX reserved operand
open("nan.tsdf", "wb").write(nan)
g = bytearray(open(f"{D}/geom/torso/daltorso.geom", "rb").read())
struct.pack_into("<i", g, 576 + 4, 10**6)  # a million nodes
open("big.geom", "wb").write(g)
EOF
set +e
for c in "cut.tsdf:byte 568: the data at byte 816 (8448 bytes) is not inside the file (9000 bytes)" "big.tsdf:byte 560: time series 1: 352 channels x 100000 frames" \
         "nan.tsdf:byte 856: time series 1: channel 11, frame 1 is a VAX reserved operand" "x.tsdfc:.tsdfc (map3d.s container of fiducial sets, a GDBM database"; do
    f=${c%%:*}; want=${c#*:}
    "$THORAX" series convert "$f" -o out.mat 2>err.txt; rc=$?
    [ $rc -eq 1 ] || fail "$f: exit $rc, expected 1"
    grep -q "$f: $want" err.txt || fail "$f: message lacks '$f: $want': $(cat err.txt)"
done
for c in "cut.geom:byte 2152: surface 1: triangle count 252 is impossible in a file of 3000 bytes" "big.geom:byte 580: surface 1: node count 1000000"; do
    f=${c%%:*}; want=${c#*:}
    "$THORAX" import -q -o bad "$f" --name s --role outer 2>err.txt; rc=$?
    [ $rc -eq 1 ] || fail "$f: exit $rc, expected 1"
    grep -q "$f: $want" err.txt || fail "$f: message lacks '$want': $(cat err.txt)"
done
set -e
[ ! -e out.mat ] && [ ! -e bad ] || fail "a refused input left output"
! ls | grep -q '\.tmp' || fail "temporary files left"

# --- render: a .geom surface with .tsdf data --------------------------------------------
"$THORAX" render "$D/geom/torso/daltorso.geom" --data "$D/data/torso/dipole2.tsdf" --up -y --front -z --frame 2 \
    --size 200x200 -o torso.png 2>/dev/null || fail "render .geom with .tsdf"
[ -s torso.png ] || fail "no picture"
echo "e2e_map3d: ok"
