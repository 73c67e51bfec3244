#!/usr/bin/env bash
# Are thorax's outputs unchanged by a change of the code that should change nothing (a refactoring)?
# Builds REV (default: the commit before HEAD) in a temporary worktree, runs the demo pipeline
# (scripts/demo.sh: contours, surfaces, volume mesh, checks, electrodes, beat, forward solution,
# leads, pictures, movies, exports) with REV's thorax and with this tree's, and compares every file
# the two runs wrote, byte for byte. Files that hold times are compared with the times left out:
# timings.txt, index.html and the animations' resume keys (frames.settings: sizes and times of the
# program and the solution) are skipped, mesh.txt loses its seconds, the JSON files their keys that
# name seconds. Prints one line per differing file and the count; exits 1 if any differ.
# Usage: bash bench/same_outputs.sh [REV] [WORKDIR]   (about 2 x the demo's time, ~10 minutes)
set -euo pipefail
cd "$(dirname "$0")/.."
NAME=same_outputs
. bench/old_thorax.sh "$@"
echo "same_outputs: $REV ($(git rev-parse --short "$REV")) against this tree ($(git rev-parse --short HEAD)$(git diff --quiet || echo ', with changes'))"
# the demo reads the shared data beside the checkout: run both from this checkout's directory
for side in old new; do
    bin=$NEW
    [ $side = old ] && bin=$OLD
    if [ $side = new ] || [ ! -f "$W/out-old/index.html" ]; then
        # one output path for both (provenance records the command line),
        rm -rf "$W/out-$side" "$W/out"
        # and one program path (provenance records argv[0] too)
        mkdir -p "$W/bin" && cp "$bin" "$W/bin/thorax"
        t0=$(date +%s)
        THORAX=$W/bin/thorax OUT=$W/out bash scripts/demo.sh > "$W/demo-$side.log" 2>&1
        mv "$W/out" "$W/out-$side"
        echo "same_outputs: demo with the $side thorax: $(( $(date +%s) - t0 )) s"
    fi
done
python3 -B - "$W/out-old" "$W/out-new" <<'EOF'
import json, os, re, sys
a, b = sys.argv[1], sys.argv[2]
SKIP = {"timings.txt", "index.html", "frames.settings"}

def strip(obj):
    if isinstance(obj, dict):
        return {k: strip(v) for k, v in obj.items() if not re.search(r"seconds|time_s|wall|elapsed", k)}
    if isinstance(obj, list):
        return [strip(v) for v in obj]
    return obj

def content(path):
    name = os.path.basename(path)
    data = open(path, "rb").read()
    if name.endswith(".json"):
        return json.dumps(strip(json.loads(data)), sort_keys=True).encode()
    if name == "mesh.txt":
        data = re.sub(rb"times \(s\):[^\n]*", lambda m: re.sub(rb"[0-9]+\.[0-9]+", b"_", m.group(0)), data)
        return re.sub(rb"[0-9]+\.[0-9]+ s\b", b"_ s", data)
    return data

files = set()
for root in (a, b):
    for d, _, fs in os.walk(root):
        for f in fs:
            files.add(os.path.relpath(os.path.join(d, f), root))
diff = same = 0
for f in sorted(files):
    if os.path.basename(f) in SKIP:
        continue
    pa, pb = os.path.join(a, f), os.path.join(b, f)
    if not os.path.exists(pa) or not os.path.exists(pb):
        print("only in %s: %s" % ("new" if os.path.exists(pb) else "old", f))
        diff += 1
    elif content(pa) != content(pb):
        print("differs: %s" % f)
        diff += 1
    else:
        same += 1
print("same_outputs: %d files identical, %d differ" % (same, diff))
sys.exit(1 if diff else 0)
EOF
