#!/usr/bin/env bash
# Rebuild fabricate/assets/three-viewer.min.js from the npm registry (run by a
# maintainer when upgrading three.js; the result is committed, so users and CI
# need neither node nor network).  three.js is MIT licensed; esbuild keeps its
# @license header in the bundle.
set -euo pipefail
THREE_VERSION="${THREE_VERSION:-0.185.0}"
here="$(cd "$(dirname "$0")" && pwd)"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
npm init -y >/dev/null
npm install --no-audit --no-fund "three@${THREE_VERSION}" esbuild@0.28 >/dev/null
cp "$here/viewer.src.js" .
npx esbuild viewer.src.js --bundle --minify --format=iife --legal-comments=inline \
    --target=es2020 --outfile="$here/three-viewer.min.js" \
    --banner:js="/*! three.js ${THREE_VERSION} (MIT, Copyright 2010-2026 Three.js Authors, see three.LICENSE) with GLTFLoader and OrbitControls, bundled with viewer.src.js by build_viewer.sh */"
cp node_modules/three/LICENSE "$here/three.LICENSE"
ls -l "$here/three-viewer.min.js"
