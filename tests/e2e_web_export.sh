#!/usr/bin/env bash
# End-to-end: thorax export --format html (the web page, docs/design/web.md), read back by Python
# alone (tests/web_page_read.py: the structure, every blob inflated to its declared size, each
# surface's potentials decoded and compared with the solution's series within the page's bound,
# the leads with thorax leads' ECG). The browser's side is tests/e2e_web_browser.sh.
#  1. the medium phantom, the 500 frames of the beat, forward to the torso, the 12-lead ECG: a page of
#     the torso and the heart; the same bytes twice; under 5 MB.
#  2. --scope frame: a scale per frame in the page.
#  3. refusals: options the page cannot show (exit 2), a layer the solution cannot give (exit 1), a
#     solution whose ecg12 is not the 12 leads (exit 1, the page and render --trace), a file thorax
#     did not write (exit 1,
#     untouched), a page without -o (exit 2); nothing left behind.
# Env: THORAX (built CLI), SRC (source dir), WORK (scratch dir, created here).
set -euo pipefail
: "${THORAX:?}" "${SRC:?}" "${WORK:?}"
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
PY=/usr/bin/python3
READ="$SRC/tests/web_page_read.py"
fail() { echo "e2e_web_export: FAIL: $*" >&2; exit 1; }
refused() { # RC WHAT PATTERN CMD... : exit RC, message matching PATTERN
    local want=$1 what=$2 pat=$3; shift 3
    set +e
    "$@" > out.log 2> err.log
    local rc=$?
    set -e
    [ $rc -eq "$want" ] || fail "$what: exit $rc, expected $want ($(cat err.log))"
    grep -q -- "$pat" err.log || fail "$what: message does not say '$pat': $(cat err.log)"
    echo "refused ($what): $(head -1 err.log)"
}
# a build without the viewer refuses every page: say so and stop (the library's test covers that path)
if "$THORAX" export --format html --help > /dev/null 2>&1; then :; else fail "thorax export --format html --help"; fi

. "$SRC/tests/medium_phantom.sh"
medium_phantom || fail "the medium phantom"
"$THORAX" electrodes model -q
"$THORAX" beat model -o beat.raw -q
"$THORAX" forward model --epicardial beat.raw -o sol -q
"$THORAX" leads sol --format raw -q

# ---- 1. the page of the torso and the heart
set +e
"$THORAX" export --solution sol --format html -o page.html --only torso --only heart --size 640x720 > out.log 2> err.log
rc=$?
set -e
if [ $rc -ne 0 ] && grep -q "without the page's viewer" err.log; then
    echo "e2e_web_export: SKIP: this thorax was built without the page's viewer ($(cat err.log))"
    exit 77
fi
[ $rc -eq 0 ] || fail "export: exit $rc: $(cat err.log)"
cat out.log
grep -q "potentials to within" out.log || fail "the error bound is not printed"
$PY "$READ" page.html torso=sol/torso.raw heart=beat.raw --leads sol/ecg12.raw --max-mb 5 || fail "page.html read back"
cp page.html first.html
"$THORAX" export --solution sol --format html -o page.html --only torso --only heart --size 640x720 -q
cmp page.html first.html || fail "the page differs from the same export's first"
$PY - page.html << 'EOF' || fail "the description"
import json, re, sys
t = open(sys.argv[1]).read()
m = json.loads(re.search(r'<script type="application/json" id="thorax-page">(.*?)</script>', t, re.S).group(1))
assert m["size"] == [640, 720], m["size"]
assert [s["name"] for s in m["surfaces"]] == ["torso", "heart"], [s["name"] for s in m["surfaces"]]
assert m["leads"]["names"] == ["I", "II", "III", "aVR", "aVL", "aVF", "V1", "V2", "V3", "V4", "V5", "V6"]
assert {e["name"] for e in m["electrodes"]} >= {"RA", "LA", "LL", "V1", "V6"}
assert set(m["views"]) == {"anterior", "posterior", "left", "right", "superior", "inferior"}
c, a = m["camera"], m["views"]["anterior"]
h = 1.1 * max(a["extent"][1], a["extent"][0] / (640 / 720))
assert abs(c["height"] - h) < 1e-9 * h, (c["height"], h)  # the views' rule gives render's camera back
for s in m["surfaces"]:
    sc = s["data"]["scale"]
    assert sc["model"] == "linear" and sc["mapping"] == "symmetric" and sc["frames"] == 1, sc
    assert s["data"]["knots_n"] == 2
print("description: size, surfaces, leads, electrodes, views and camera as asked")
EOF

# the viewer in the page is the build's bundle, byte for byte, and the bundle is reproducible: the
# same lock and sources bundled again elsewhere give the same bytes
BUNDLE=$(cd "$(dirname "$THORAX")/.." && pwd)/web/thorax-page.js
[ -f "$BUNDLE" ] || fail "no bundle at $BUNDLE"
$PY - page.html "$BUNDLE" << 'EOF' || fail "the page's viewer is not the build's bundle"
import sys
t, b = open(sys.argv[1], encoding="utf-8").read(), open(sys.argv[2], encoding="utf-8").read()
i = t.rindex("<script>\n") + len("<script>\n")
j = t.rindex("\n</script>")
assert t[i:j] == b, "the page's last script differs from the bundle"
print("the page's viewer: the build's bundle (%d bytes)" % len(b))
EOF
bash "$SRC/scripts/web.sh" again.js "$WORK/npm" || fail "scripts/web.sh"
cmp again.js "$BUNDLE" || fail "the bundle made again differs from the build's"
echo "the bundle made again is the same: $(sha256sum again.js | cut -c1-16)"

# ---- 2. a scale per frame
"$THORAX" export --solution sol --format html -o frame.html --only torso --scope frame -q
$PY "$READ" frame.html torso=sol/torso.raw > frame.log || fail "frame.html read back"
$PY -c "
import json, re
t = open('frame.html').read()
m = json.loads(re.search(r'id=\"thorax-page\">(.*?)</script>', t, re.S).group(1))
assert m['surfaces'][0]['data']['scale']['frames'] == 500, m['surfaces'][0]['data']['scale']
print('--scope frame: a scale for each of the 500 frames')" || fail "--scope frame"

# ---- 3. refusals
refused 2 "--clip" "not in the web page" "$THORAX" export --solution sol --format html -o r1.html --clip anterior
refused 2 "--arrows" "not in the web page" "$THORAX" export --solution sol --format html -o r2.html --arrows
refused 1 "--isosurface without volume potentials" "isosurface" "$THORAX" export --solution sol --format html -o r2.html --isosurface 5
refused 2 "no -o" "no page given" "$THORAX" export --solution sol --format html
# the solution's ECG must be the 12 leads: a copy whose ecg12.raw holds the torso's rows is refused,
# by the page and by render's --trace alike (the picture reads it), naming the file
cp -r sol badecg
cp sol/torso.raw badecg/ecg12.raw
refused 1 "an ecg12 that is not the 12 leads" "badecg/ecg12.raw: .* rows, not the 12 leads" \
    "$THORAX" export --solution badecg --format html -o r3.html
refused 1 "render --trace, the same ecg12" "badecg/ecg12.raw: .* rows, not the 12 leads" \
    "$THORAX" render --solution badecg --trace V1 -o r3.png
[ ! -e r3.html ] && [ ! -e r3.png ] || fail "a refused ECG left a file"
echo "my own notes" > notes.html
refused 1 "a file thorax did not write" "notes.html" "$THORAX" export --solution sol --format html -o notes.html
[ "$(cat notes.html)" = "my own notes" ] || fail "notes.html was changed"
[ ! -e r1.html ] && [ ! -e r2.html ] || fail "a refused page left a file"
ls -a | grep -q '\.tmp' && fail "a temporary file was left: $(ls -a | grep '\.tmp')"
echo "e2e_web_export: OK"
