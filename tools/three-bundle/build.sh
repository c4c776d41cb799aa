#!/bin/sh
# Rebuild src/visviva/viz/viewer/three.min.js from the exact three.js version pinned in
# package-lock.json: one classic (non-module) script that defines the global `THREE`, with
# three.js's MIT licence at its top. Run from anywhere: sh tools/three-bundle/build.sh
set -eu
here="$(cd "$(dirname "$0")" && pwd)"
out="$here/../../src/visviva/viz/viewer"
cd "$here"
mkdir -p "$out"
npm ci --no-audit --no-fund
version="$(node -p 'require("./node_modules/three/package.json").version')"
license="$(cat node_modules/three/LICENSE)"
banner="/*! three.js r$(echo "$version" | cut -d. -f2) (npm three@$version): the parts the visviva viewer uses.
Rebuild with tools/three-bundle/build.sh. Licence of three.js:

$license
*/"
npx --no-install esbuild entry.js --bundle --format=iife --global-name=THREE --minify \
    --target=es2020 --legal-comments=none --charset=utf8 "--banner:js=$banner" \
    --outfile="$out/three.min.js"
cp node_modules/three/LICENSE "$out/LICENSE-three.txt"
