#!/usr/bin/env bash
# The installable library (issue 14, item 8): `make install PREFIX=/opt/thorax DESTDIR=STAGE` into a
# temporary stage, then, using only what was installed (the stage moved nowhere else: thorax.pc and
# the programs' RPATH are relative, so the staged tree works where it lies):
#  - the layout: libthorax.so.0.1.0 with SONAME libthorax.so.0.1 and its links, libthorax.a, the
#    public headers (not the viewer's), thorax.pc, the CMake package, thorax and thorax-view, the man
#    pages, the licence, the Python package;
#  - the installed thorax runs on the installed libthorax.so (ldd), not the build tree's;
#  - the DICOM helper libexec/thorax/thorax-dicom is installed and found by the installed thorax (in a
#    copy of the prefix moved elsewhere too), and its absence is a message naming where it was sought;
#  - a C program built with `cc prog.c $(pkg-config --cflags --libs thorax)` alone reads the
#    Dalhousie torso (map3d daltorso.pts/.fac) and prints its node and triangle counts, the enclosed
#    volume and the Euler characteristic: compared with the same computed by NumPy from the files;
#  - the same program linked statically against libthorax.a with `pkg-config --static --libs`
#    (no libthorax.so in its NEEDED), and built through CMake's find_package(thorax) (thorax::thorax);
#  - `man -l` renders thorax(1) and thorax-forward(1) with their options;
#  - the installed Python package finds the installed library by itself.
# Without ../shared/data beside the checkout, the phantom's torso (made by the CLI) is read instead.
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
PY=/usr/bin/python3
DATA=${THORAX_DATA:-$SRC/../shared/data}
G=$DATA/map3d/geom/torso
BUILD=$(cd "$(dirname "$THORAX")/.." && pwd)
# the version the build was configured with (CMake's project version): VER 0.1.0, SO 0.1 (the SONAME's)
VER=$(sed -n 's/^CMAKE_PROJECT_VERSION:STATIC=//p' "$BUILD/CMakeCache.txt")
SO=${VER%.*}
[ -n "$VER" ] || { echo "e2e_install: no project version in $BUILD/CMakeCache.txt" >&2; exit 1; }
rm -rf "$WORK" && mkdir -p "$WORK" && cd "$WORK"
fail() { echo "e2e_install: FAIL: $*" >&2; exit 1; }
# the surface the programs read: map3d's Dalhousie torso, or (no data folder) the phantom's torso
if [ -f "$G/daltorso.pts" ]; then
    PTS=$G/daltorso.pts FAC=$G/daltorso.fac
else
    echo "note: $G not found: the phantom's torso stands in for the Dalhousie torso"
    "$THORAX" phantom -o contours.txt -q && "$THORAX" surfaces contours.txt -o phantom -q || fail "the phantom"
    PTS=$WORK/phantom/torso.pts FAC=$WORK/phantom/torso.fac
fi

# installed twice, staged: cmake --install, and the Makefile's target as a packager runs it (the build
# is up to date, so make's build step does nothing)
DESTDIR="$WORK/stage" cmake --install "$BUILD" --prefix /opt/thorax >install.log 2>&1 || fail "cmake --install: $(cat install.log)"
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL make -s -C "$SRC" install BUILD="$BUILD" PREFIX=/opt/thorax DESTDIR="$WORK/stage2" >make.log 2>&1 || fail "make install: $(cat make.log)"
P=$WORK/stage/opt/thorax
[ -d "$WORK/stage2/opt/thorax/lib" ] || fail "make install DESTDIR=stage2 PREFIX=/opt/thorax put nothing in stage2/opt/thorax"
L=$P/lib
for f in lib/libthorax.so.$VER lib/libthorax.a include/thorax/core/core.h include/thorax/capi/capi.h \
    include/thorax/fem/fem.h lib/pkgconfig/thorax.pc lib/cmake/thorax/thoraxConfig.cmake \
    lib/cmake/thorax/thoraxConfigVersion.cmake lib/cmake/thorax/thoraxTargets.cmake bin/thorax bin/thorax-view \
    share/man/man1/thorax.1 share/man/man1/thorax-forward.1 share/man/man1/thorax-view.1 share/doc/thorax/LICENSE \
    share/doc/thorax/examples/surface_facts.c share/doc/thorax/examples/dipole_forward.py lib/thorax/libthorax-petsc.so \
    lib/python3/dist-packages/thorax/__init__.py lib/python3/dist-packages/thorax/_installed.py; do
    [ -e "$P/$f" ] || fail "not installed: $f"
done
[ ! -e "$P/include/thorax/view" ] || fail "the viewer's header was installed (libthorax_view is not)"
[ "$(readlink "$L/libthorax.so")" = libthorax.so.$SO ] || fail "libthorax.so -> $(readlink "$L/libthorax.so"), not libthorax.so.$SO"
[ "$(readlink "$L/libthorax.so.$SO")" = libthorax.so.$VER ] || fail "libthorax.so.$SO -> $(readlink "$L/libthorax.so.$SO")"
soname=$(readelf -d "$L/libthorax.so.$VER" | sed -n 's/.*(SONAME).*\[\(.*\)\]/\1/p')
[ "$soname" = libthorax.so.$SO ] || fail "SONAME '$soname', not libthorax.so.$SO"
n_pages=$(ls "$P/share/man/man1" | wc -l)
n_cmds=$("$THORAX" help | awk '/^commands:/ { on = 1; next } on && /^  [a-z]/ && $1 != "help" { n++ } END { print n }')
[ "$n_pages" -eq $((n_cmds + 1)) ] || fail "$n_pages man pages for $n_cmds commands (+ thorax.1)"

# the installed program runs on the installed library
loaded() { realpath "$(ldd "$1" | awk -v n="libthorax.so.$SO" '$1 == n { print $3 }')"; }
for prog in thorax thorax-view; do
    [ "$(loaded "$P/bin/$prog")" = "$L/libthorax.so.$VER" ] || fail "bin/$prog loads $(loaded "$P/bin/$prog"), not $L/libthorax.so.$VER"
done
[ "$("$P/bin/thorax" --version)" = "thorax $VER" ] || fail "installed thorax --version: $("$P/bin/thorax" --version)"

# the DICOM helper (docs/design/image.md, "The DICOM helper program"): installed in libexec/thorax/,
# where the installed thorax looks for it (relative to bin/, so also in a moved prefix); without it
# a read of DICOM says what is missing and where it looked
[ -x "$P/libexec/thorax/thorax-dicom" ] || fail "not installed: libexec/thorax/thorax-dicom"
mkdir -p dcm && head -c 24 /dev/zero >px.raw
gdcmimg --size 4,3 --depth 16 --sign 1 -C 1.2.840.10008.5.1.4.1.1.2 -i px.raw -o px.dcm \
    && gdcmanon --dumb --replace '0020,0032=0\0\0' --replace '0020,0037=1\0\0\0\1\0' --replace '0028,0030=0.5\0.5' \
        -i px.dcm -o dcm/s.dcm || fail "gdcmimg/gdcmanon could not write a slice"
cp -a "$P" "$WORK/moved"
for prefix in "$P" "$WORK/moved"; do
    env -u THORAX_DICOM_HELPER "$prefix/bin/thorax" image info dcm >dcm.txt 2>&1 || fail "$prefix/bin/thorax image info (DICOM): $(cat dcm.txt)"
    grep -q '^format *dicom' dcm.txt && grep -q '^dimensions *4 x 3 x 1' dcm.txt || fail "$prefix/bin/thorax image info: $(cat dcm.txt)"
done
rm "$WORK/moved/libexec/thorax/thorax-dicom"
! env -u THORAX_DICOM_HELPER "$WORK/moved/bin/thorax" image info dcm >dcm.txt 2>&1 || fail "read DICOM without its helper"
grep -q "thorax-dicom is missing (looked for .*$WORK/moved/bin/../libexec/thorax/thorax-dicom" dcm.txt \
    || fail "without the helper: $(cat dcm.txt)"
# the solver module (docs/design/fem.md, "The solver module"): PETSc and MPI are loaded from
# lib/thorax/libthorax-petsc.so beside the installed library (in the moved copy too) on the first
# solve, never at start; without it a solve says where it looked
[ -z "$(ldd "$P/bin/thorax" | grep -E 'libpetsc|libmpi')" ] || fail "the installed thorax loads PETSc or MPI at start"
for prefix in "$P" "$WORK/moved"; do
    env -u THORAX_PETSC_MODULE LD_DEBUG=files "$prefix/bin/thorax" verify --levels 2 --spheres off >verify.txt 2>verify.err \
        || fail "$prefix/bin/thorax verify: $(tail -3 verify.txt verify.err)"
    mod=$(sed -n 's/.*file=\([^ ]*libthorax-petsc\.so\) .*generating link map.*/\1/p' verify.err | head -1)
    [ -n "$mod" ] && [ "$(realpath "$mod")" = "$(realpath "$prefix/lib/thorax/libthorax-petsc.so")" ] \
        || fail "$prefix/bin/thorax verify did not load $prefix/lib/thorax/libthorax-petsc.so: $(grep -m3 'thorax-petsc' verify.err)"
done
rm "$WORK/moved/lib/thorax/libthorax-petsc.so"
! env -u THORAX_PETSC_MODULE "$WORK/moved/bin/thorax" verify --levels 2 --spheres off >verify.txt 2>&1 || fail "a solve without the solver module"
grep -q "the solver module libthorax-petsc.so (PETSc and MPI) could not be loaded ($WORK/moved/[a-z./]*/thorax/libthorax-petsc.so: not found" verify.txt \
    || fail "without the solver module: $(cat verify.txt)"
rm -rf "$WORK/moved"

# the reference: the same facts computed by NumPy from the files (0- or 1-based .fac detected alike)
"$PY" - "$PTS" "$FAC" >expected.txt <<'EOF'
import sys
import numpy as np
x = np.loadtxt(sys.argv[1])
f = np.loadtxt(sys.argv[2], dtype=np.int64)
base = 0 if f.min() == 0 else 1
f = f - base
a, b, c = x[f[:, 0]], x[f[:, 1]], x[f[:, 2]]
vol = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0
edges = {tuple(sorted(e)) for t in f for e in ((t[0], t[1]), (t[1], t[2]), (t[2], t[0]))}
print(f"nodes {len(x)}\ntriangles {len(f)}\nbase {base}\nvolume {vol:.3f}\neuler {len(x) - len(edges) + len(f)}")
EOF

compare() {  # compare WHAT OUTPUT: counts, base and Euler exact, volume to 1e-6 relative
    "$PY" - "$2" expected.txt "$1" <<'EOF' || exit 1
import sys
got = dict(l.split(None, 1) for l in open(sys.argv[1]) if l.strip())
want = dict(l.split(None, 1) for l in open(sys.argv[2]) if l.strip())
for k in ("nodes", "triangles", "base", "euler"):
    if got.get(k, "").strip() != want[k].strip():
        sys.exit(f"e2e_install: FAIL: {sys.argv[3]}: {k} {got.get(k, '(missing)').strip()}, NumPy says {want[k].strip()}")
g, w = float(got["volume"]), float(want["volume"])
if abs(g - w) > 1e-6 * abs(w):
    sys.exit(f"e2e_install: FAIL: {sys.argv[3]}: volume {g}, NumPy says {w}")
print(f"{sys.argv[3]}: nodes {got['nodes'].strip()}, triangles {got['triangles'].strip()}, "
      f"volume {g:.0f} mm^3 (NumPy {w:.0f}), Euler {got['euler'].strip()}: agree")
EOF
}
grep -q '^euler 2$' expected.txt || fail "$PTS is not a closed sphere-like surface? $(cat expected.txt)"

# A sanitized build (THORAX_SANITIZE) installs a sanitized library: the programs built against it are
# sanitized alike (the runtime must come first), and Python cannot load it (step 5 is skipped).
SAN=""
if readelf -d "$L/libthorax.so.$VER" | grep -q 'NEEDED.*lib[at]san'; then SAN="-fsanitize=address,undefined"; fi

# 1. pkg-config alone
export PKG_CONFIG_PATH=$L/pkgconfig
[ "$(pkg-config --modversion thorax)" = "$VER" ] || fail "pkg-config --modversion thorax: $(pkg-config --modversion thorax 2>&1)"
cc $SAN -o facts_pc "$SRC/tests/install/surface_facts.c" $(pkg-config --cflags --libs thorax) -Wl,-rpath,"$L" 2>cc.log \
    || fail "cc with pkg-config --cflags --libs thorax: $(cat cc.log)"
readelf -d facts_pc | grep -q "NEEDED.*libthorax.so.$SO" || fail "facts_pc does not need libthorax.so.$SO"
./facts_pc "$PTS" "$FAC" >facts_pc.txt || fail "facts_pc: $(cat facts_pc.txt)"
[ "$(loaded ./facts_pc)" = "$L/libthorax.so.$VER" ] || fail "facts_pc runs on $(loaded ./facts_pc), not the installed library"
compare "pkg-config (shared)" facts_pc.txt

# 2. pkg-config --static: libthorax.a and every library it needs
libs=$(pkg-config --static --libs thorax)
cc $SAN -o facts_static "$SRC/tests/install/surface_facts.c" $(pkg-config --cflags thorax) ${libs/-lthorax/-l:libthorax.a} 2>cc.log \
    || fail "cc with pkg-config --static --libs thorax and libthorax.a: $(cat cc.log)"
! readelf -d facts_static | grep -q 'NEEDED.*libthorax' || fail "facts_static still needs libthorax.so"
./facts_static "$PTS" "$FAC" >facts_static.txt || fail "facts_static: $(cat facts_static.txt)"
compare "pkg-config --static" facts_static.txt

# 3. CMake's find_package(thorax): thorax::thorax
cmake -S "$SRC/tests/install" -B consumer -DCMAKE_PREFIX_PATH="$P" -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_C_FLAGS="$SAN" -DCMAKE_EXE_LINKER_FLAGS="$SAN" >cmake.log 2>&1 \
    || fail "find_package(thorax): $(cat cmake.log)"
cmake --build consumer >>cmake.log 2>&1 || fail "building against thorax::thorax: $(cat cmake.log)"
grep -q "thorax_DIR:PATH=$P/lib/cmake/thorax" consumer/CMakeCache.txt || fail "find_package found another thorax: $(grep thorax_DIR consumer/CMakeCache.txt)"
consumer/surface_facts "$PTS" "$FAC" >facts_cmake.txt || fail "CMake-built program: $(cat facts_cmake.txt)"
compare "find_package(thorax)" facts_cmake.txt

# 4. the man pages render, with the options from the help
for page in thorax thorax-forward thorax-mesh thorax-view; do
    MANWIDTH=100 man -l "$P/share/man/man1/$page.1" >"$page.man" 2>man.err || fail "man -l $page.1: $(cat man.err)"
    [ ! -s man.err ] || fail "man -l $page.1 warns: $(cat man.err)"
done
grep -q 'thorax-forward - finite-element forward solutions' thorax-forward.man || fail "thorax-forward(1) NAME: $(head -5 thorax-forward.man)"
for opt in --epicardial --transfer-out --currents; do
    grep -q -- "$opt" thorax-forward.man || fail "thorax-forward(1) lacks $opt"
done
for cmd in phantom surfaces mesh forward leads render view; do
    grep -q "thorax $cmd" thorax.man || fail "thorax(1) does not list '$cmd'"
done
grep -q -- '--grid MM' thorax-mesh.man || fail "thorax-mesh(1) lacks --grid MM"
groff -man -ww -z "$P/share/man/man1/"*.1 2>groff.err; [ ! -s groff.err ] || fail "groff warns: $(head -5 groff.err)"

# 5. the installed Python package finds the installed library by itself
if [ -n "$SAN" ]; then echo "e2e_install: passed (a sanitized library: the Python step skipped)"; exit 0; fi
env -u THORAX_LIBRARY PYTHONPATH="$P/lib/python3/dist-packages" "$PY" -B - "$G" "$L" "$SO" "$VER" <<'EOF' >py.txt || fail "installed Python package: $(cat py.txt)"
import os, sys
import thorax
g, lib = sys.argv[1], sys.argv[2]
assert os.path.realpath(thorax.library_path()) == os.path.realpath(os.path.join(lib, "libthorax.so." + sys.argv[3])), thorax.library_path()
assert thorax.version() == sys.argv[4], thorax.version()
print("python: library", thorax.library_path())
EOF
cat py.txt
echo "e2e_install: passed"
