#!/usr/bin/env bash
# Builds the web viewer (web/src, ES modules) into one minified IIFE, the script that
# `thorax export --format html` embeds in its page (docs/design/web.md).
#
#   scripts/web.sh OUT.js [WORKDIR]
#
# WORKDIR (default: a temporary directory, removed afterwards) receives web/package.json and
# web/package-lock.json and `npm ci` installs the pinned three.js and esbuild there, from the lock
# (integrity-checked; from npm's cache when it holds them); node_modules is never written into the
# source tree. The same sources and lock give the same bytes: esbuild's output is deterministic
# and carries no paths or dates.
set -euo pipefail

usage() { echo "usage: scripts/web.sh OUT.js [WORKDIR]" >&2; exit 2; }
[ $# -ge 1 ] && [ $# -le 2 ] || usage
out=$1
here=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd -P)
web="$here/web"

for tool in node npm; do
  if ! command -v "$tool" >/dev/null 2>&1; then
    echo "web.sh: '$tool' not found: the viewer's bundle needs Node.js and npm (Debian: apt-get install nodejs npm; scripts/deps.sh)" >&2
    exit 1
  fi
done
for f in package.json package-lock.json src/main.js; do
  [ -f "$web/$f" ] || { echo "web.sh: $web/$f is missing" >&2; exit 1; }
done

if [ $# -ge 2 ]; then
  work=$(realpath -m "$2")
  case "$work/" in
    "$web/"*) echo "web.sh: WORKDIR $work is inside web/: node_modules stays out of the source tree" >&2; exit 1 ;;
  esac
  mkdir -p "$work"
else
  work=$(mktemp -d "${TMPDIR:-/tmp}/thorax-web.XXXXXX")
  trap 'rm -rf "$work"' EXIT
fi

cp "$web/package.json" "$web/package-lock.json" "$work/"
# --ignore-scripts: nothing runs at install (esbuild's binary comes in its platform package).
if ! (cd "$work" && npm ci --no-audit --no-fund --ignore-scripts --prefer-offline --loglevel=error >/dev/null); then
  echo "web.sh: npm ci failed in $work (the npm registry or npm's cache must hold the locked packages)" >&2
  exit 1
fi
esbuild="$work/node_modules/esbuild/bin/esbuild"
[ -x "$esbuild" ] || { echo "web.sh: esbuild is not installed in $work/node_modules" >&2; exit 1; }

mkdir -p "$(dirname "$out")"
tmp="$out.tmp.$$"
# NODE_PATH: `import ... from 'three'` in web/src resolves in WORKDIR/node_modules.
if ! NODE_PATH="$work/node_modules" "$esbuild" "$web/src/main.js" \
    --bundle --minify --format=iife --target=es2020 --legal-comments=none \
    --platform=browser --log-level=warning --outfile="$tmp"; then
  rm -f "$tmp"
  echo "web.sh: esbuild failed" >&2
  exit 1
fi
mv -f "$tmp" "$out"
echo "web.sh: $out ($(wc -c <"$out") bytes, sha256 $(sha256sum "$out" | cut -c1-16)...)"
