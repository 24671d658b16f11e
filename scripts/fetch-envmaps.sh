#!/usr/bin/env bash
# Regenerates scenes/envmaps/*.exr from the npm package `@pmndrs/assets@1.7.0` (CC0 Poly Haven
# HDRIs, 512×256, half-float DWAB): decodes the base64 data URL in hdri/<name>.exr.js, then
# re-encodes losslessly (negative DWA-ringing texels clamped to zero, half-float ZIP scan
# lines) with examples/reencode_envmap.rs. The EXRs are committed; this documents their origin.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
maps=(venice forest sky esplanade)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent @pmndrs/assets@1.7.0 >/dev/null && tar xzf pmndrs-assets-1.7.0.tgz)
mkdir -p "$here/scenes/envmaps"
for m in "${maps[@]}"; do
  sed -e "s/^export default 'data:application\/exr;base64,//" -e "s/'[;]*[[:space:]]*$//" \
    "$tmp/package/hdri/$m.exr.js" | base64 -d > "$tmp/$m.exr"
  (cd "$here" && cargo run --release --quiet --example reencode_envmap -- "$tmp/$m.exr" "scenes/envmaps/$m.exr")
done
