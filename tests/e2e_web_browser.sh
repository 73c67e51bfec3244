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
#     click on the ECG move together; a click on the torso picks a node and plots its series, equal to
#     the solution's within the quantization bound.
#  2. real data: the Utah tank's sock (map3d's 25feb97_sock.pts) with its recording
#     (cool1-atdr-run1.mat through sock128.channels): the page opens without errors, draws as render
#     does, and a picked node's plot is its series.
#  3. the phantom's page in Firefox: the same checks.
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
cp "$SRC/tests/web_browser.mjs" .
for f in 60 193 300; do
    "$THORAX" render --solution sol --only torso --only heart --size 480x540 --frame $f -o ref_$f.png -q
done
cat > phantom.json << EOF
{"page": "$WORK/page.html", "out": "$WORK/phantom", "size": [480, 540],
 "compare": [{"frame": 60, "ref": "$WORK/ref_60.png"}, {"frame": 193, "ref": "$WORK/ref_193.png"},
             {"frame": 300, "ref": "$WORK/ref_300.png"}],
 "series": {"torso": "$WORK/sol/torso.raw"}, "pick": "torso"}
EOF
CHROMIUM=$CHROMIUM node web_browser.mjs phantom.json || fail "the phantom's page in the browser"

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
# ---- 3. Firefox
FIREFOX=${FIREFOX:-/usr/bin/firefox-esr}
[ -x "$FIREFOX" ] || fail "no Firefox at $FIREFOX (scripts/deps.sh installs Debian's firefox-esr)"
sed -e 's|"out": "[^"]*"|"out": "'"$WORK"'/firefox", "browser": "firefox"|' phantom.json > firefox.json
FIREFOX=$FIREFOX node web_browser.mjs firefox.json || fail "the phantom's page in Firefox"
echo "e2e_web_browser: OK"
