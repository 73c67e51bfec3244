# Sourced by the image e2e tests (e2e_render_image.sh, e2e_render_image_ct.sh, e2e_view_image.sh):
# the same start for each, and the synthetic scan they share (tests/image_fixture.py).
#   . "$(dirname "$0")/image_fixture.sh"
# Then: a fresh, empty $WORK is the working directory; $PY is the system Python, which finds
# image_fixture.py (PYTHONPATH; no bytecode written into the source tree); fail MESSAGE exits 1;
#   square_image FILE [K]   the 40 x 40 x 20 NIfTI of 2 mm with the bright square at every z, or in
#                           the plane k = K only (image_fixture.square_image)
#   box                     box.pts/box.fac around the plane z = 0 (image_fixture.box)
# and in Python: `from image_fixture import png` reads a picture back with VTK's PNG reader.
set -euo pipefail
: "${THORAX:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
IMAGE_FIXTURE_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
export PYTHONPATH="$IMAGE_FIXTURE_DIR${PYTHONPATH:+:$PYTHONPATH}" PYTHONDONTWRITEBYTECODE=1
fail() { echo "FAIL: $*"; exit 1; }
square_image() { $PY -c 'import sys, image_fixture as f; f.square_image(sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else None)' "$@"; }
box() { $PY -c 'import image_fixture as f; f.box()'; }
