#!/usr/bin/env bash
# End-to-end: the web page of thorax export --format html opened in real browsers (Debian's
# Chromium, headless, WebGL through SwiftShader; Firefox ESR, WebGL through Mesa's llvmpipe), driven
# by puppeteer-core (pinned in
# web/package-lock.json, installed by scripts/web.sh beside the bundle) through the page's test hooks
# (tests/web_browser.mjs, docs/design/web.md):
#  1. the medium phantom's 500-frame beat (torso and heart): the page's pictures at three frames
#     against thorax render's of the same frames and camera, pixel by pixel away from the edges;
#     the load, first-picture and frame-step times printed (bench/web.sh measures them); the slider,
#     the ECG's marker and a
#     click on the ECG move together; a click where a torso node projects (the camera and the points
#     taken from the page's file here) picks that node and plots its series, equal to the solution's
#     within the quantization bound; the same for the heart with the torso hidden.
#     Damaged copies of that page (tests/web_damaged_check.mjs): cut short (the page's waiting text
#     stays, the viewer never runs), a blob that is not base64 or not deflate, data-bytes that
#     disagree, a blob missing, the description not JSON or of a later version: each refused with
#     the message the page shows, nothing drawn.
#  2. real data: the Utah tank's sock (map3d's 25feb97_sock.pts) with its recording
#     (cool1-atdr-run1.mat through sock128.channels): the page opens without errors, draws as render
#     does, and a picked node's plot is its series.
#  3. the phantom's page in Firefox: the same checks.
#  4. the layers (equipotentials, slices by potential and by |J|, the scan's plane) in both browsers
#     against render's pictures; layers stay at their frame; clicks never pick a layer.
# Skipped (77) when Chromium or node is missing, or thorax was built without the page's viewer.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
fail() { echo "e2e_web_browser: FAIL: $*" >&2; exit 1; }
skip() { echo "e2e_web_browser: SKIP: $*"; exit 77; }
CHROMIUM=${CHROMIUM:-/usr/bin/chromium}
[ -x "$CHROMIUM" ] || skip "no Chromium at $CHROMIUM (scripts/deps.sh installs Debian's)"
command -v node > /dev/null || skip "no node (scripts/deps.sh installs it)"
NM=$(cd "$(dirname "$THORAX")/.." && pwd)/web/npm/node_modules
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"

. "$SRC/tests/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw -q
"$THORAX" forward model --epicardial beat.raw -o sol -q
"$THORAX" leads sol --format raw -q
set +e
"$THORAX" export --solution sol --format html -o page.html --only torso --only heart --size 480x540 > out.log 2> err.log
rc=$?
set -e
[ $rc -ne 0 ] && grep -q "without the page's viewer" err.log && skip "$(cat err.log)"
[ $rc -eq 0 ] || fail "export: $(cat err.log)"
cat out.log
[ -d "$NM/puppeteer-core" ] || fail "puppeteer-core is not in $NM (scripts/web.sh installs web/package-lock.json's packages there)"
# the test script beside the packages it imports (an ES module resolves from its own folder)
ln -s "$NM" node_modules
cp "$SRC/tests/web_browser.mjs" "$SRC/tests/web_common.mjs" .
for f in 60 193 300; do
    "$THORAX" render --solution sol --only torso --only heart --size 480x540 --frame $f -o ref_$f.png -q
done
cat > phantom.json << EOF
{"page": "$WORK/page.html", "out": "$WORK/phantom", "size": [480, 540],
 "compare": [{"frame": 60, "ref": "$WORK/ref_60.png"}, {"frame": 193, "ref": "$WORK/ref_193.png"},
             {"frame": 300, "ref": "$WORK/ref_300.png"}],
 "series": {"torso": "$WORK/sol/torso.raw", "heart": "$WORK/beat.raw"},
 "picks": [{"surface": "torso"}, {"surface": "heart", "hide": ["torso"]}]}
EOF
CHROMIUM=$CHROMIUM node web_browser.mjs phantom.json || fail "the phantom's page in the browser"
# damaged copies of it: cut short, a blob spoiled, the description spoiled; never shown half-read
cp "$SRC/tests/web_damaged_check.mjs" .
CHROMIUM=$CHROMIUM node web_damaged_check.mjs "$WORK/page.html" "$WORK/damaged" || fail "a damaged page"

# ---- 2. the Utah tank's sock and its recording
MD="$SRC/../shared/data/map3d"
if [ -f "$MD/geom/tank/25feb97_sock.pts" ] && [ -f "$MD/data/tank/cool1-atdr-run1.mat" ]; then
    SOCK=("$MD/geom/tank/25feb97_sock.pts" --data "$MD/data/tank/cool1-atdr-run1.mat" --channels "$MD/geom/tank/sock128.channels")
    "$THORAX" export "${SOCK[@]}" --format html -o sock.html --size 480x480 --frame 185 --title "Utah tank: sock potentials" \
        > out.log || fail "export of the sock"
    cat out.log
    "$THORAX" render "${SOCK[@]}" --size 480x480 --frame 185 -o sock_185.png -q
    cat > sock.json << EOF
{"page": "$WORK/sock.html", "out": "$WORK/sock", "size": [480, 480],
 "compare": [{"frame": 185, "ref": "$WORK/sock_185.png"}], "pick": "25feb97_sock"}
EOF
    CHROMIUM=$CHROMIUM node web_browser.mjs sock.json || fail "the sock's page in the browser"
else
    echo "e2e_web_browser: the map3d data is not beside the checkout: the sock's page left out"
fi
# ---- 4. the layers render adds, made for the frame shown first (tests/web_layers_check.mjs): volume
# potentials of a short beat, equipotentials, a slice by potential with contour lines and by |J|, the
# scan's plane with the contour lines on it; each page against render's picture of the same options
"$THORAX" beat model -o short.raw --frames 40 --dt 10 -q
"$THORAX" forward model --epicardial short.raw -o vsol --volume -q
"$THORAX" phantom --image ct.nii.gz --voxel 3 --modality ct -q
HIDE=(--surface torso=hidden --surface fat=hidden --surface muscle=hidden --surface lung_r=hidden --surface lung_l=hidden
      --surface heart=hidden)
layer_case() { # NAME OPTIONS...: the page and render's picture of the same options
    local name=$1; shift
    "$THORAX" export "$@" --format html -o "$name.html" -q || fail "export $name"
    "$THORAX" render "$@" -o "$name.png" -q || fail "render $name"
}
layer_case iso --solution vsol --isosurface 12%,30%,70%,88% --only torso --only heart --only equipotentials --frame 20 --size 480x540
layer_case slice --solution vsol --slice z=110 --style continuous+contours --levels 16 --only torso --only heart --only slices \
    --surface torso=phong:0.35 --view superior --frame 20 --size 480x540
layer_case slice_j --solution vsol --slice z=110 --slice-current --only torso --only heart --only slices --view superior --frame 20 \
    --size 480x540
layer_case scan model --image ct.nii.gz --image-plane z=100 "${HIDE[@]}" --view superior --size 480x400
cp "$SRC/tests/web_layers_check.mjs" .
for b in chromium firefox; do
    cat > layers_$b.json << EOF
{"out": "$WORK/layers_$b", "browser": "$b",
 "cases": [{"name": "iso", "page": "$WORK/iso.html", "ref": "$WORK/iso.png"},
           {"name": "slice", "page": "$WORK/slice.html", "ref": "$WORK/slice.png"},
           {"name": "slice_j", "page": "$WORK/slice_j.html", "ref": "$WORK/slice_j.png"},
           {"name": "scan", "page": "$WORK/scan.html", "ref": "$WORK/scan.png"}]}
EOF
    CHROMIUM=$CHROMIUM FIREFOX=${FIREFOX:-/usr/bin/firefox-esr} node web_layers_check.mjs layers_$b.json || fail "the layers in $b"
done

# ---- 3. Firefox
FIREFOX=${FIREFOX:-/usr/bin/firefox-esr}
[ -x "$FIREFOX" ] || fail "no Firefox at $FIREFOX (scripts/deps.sh installs Debian's firefox-esr)"
sed -e 's|"out": "[^"]*"|"out": "'"$WORK"'/firefox", "browser": "firefox"|' phantom.json > firefox.json
FIREFOX=$FIREFOX node web_browser.mjs firefox.json || fail "the phantom's page in Firefox"
echo "e2e_web_browser: OK"
