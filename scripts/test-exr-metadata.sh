#!/usr/bin/env bash
# EXR provenance read back by a second reader: OpenImageIO's `oiiotool --info -v` (Debian's
# openimageio-tools; scripts/install-test-tools.sh installs it) must show every dibench:*
# attribute of a compare image, its variance image and the reference, with the values the run
# used. The exr crate's reading is tested in src/output/exr.rs and tests/harness_cli.rs.
#
#   scripts/test-exr-metadata.sh     # after cargo build --release
#   (DIBENCH_TARGET=target/test-release to test another profile's build)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${DIBENCH_TARGET:-target/release}/dibench
[ -x "$bin" ] || { echo "test-exr-metadata: $bin not found; run cargo build --release first" >&2; exit 1; }
command -v oiiotool >/dev/null || {
  echo "test-exr-metadata: oiiotool not found; scripts/install-test-tools.sh installs it (openimageio-tools)" >&2
  exit 1
}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
timeout 300 "$bin" compare cornell --spp 8 --reference-spp 32 --strategies light,mis-power \
  --sampler independent,sobol --seed 5 --threads 1 --out "$tmp" >/dev/null 2>"$tmp/stderr" ||
  { cat "$tmp/stderr" >&2; echo "FAIL: test-exr-metadata: compare failed" >&2; exit 1; }
run=$(find "$tmp/cornell" -mindepth 1 -maxdepth 1 -type d -name '*-seed5')
ref=$(find "$tmp/cornell/reference" -maxdepth 1 -name 'direct.*.exr' -not -name '*.variance.exr')
failures=0
# expect FILE ATTRIBUTE VALUE: oiiotool prints `dibench:ATTRIBUTE: "VALUE"` (text) or a number.
expect() {
  local info line
  info=$(oiiotool --info -v "$1")
  line=$(grep -F "    dibench:$2: " <<<"$info" || true)
  if [ "$line" = "    dibench:$2: \"$3\"" ] || [ "$line" = "    dibench:$2: $3" ]; then
    echo "PASS: $(basename "$1") dibench:$2 = $3"
  else
    echo "FAIL: $(basename "$1") dibench:$2: expected $3, oiiotool shows: ${line:-nothing}"
    failures=$((failures + 1))
  fi
}
hash=$(grep -o '"scene_hash": *"[0-9a-f]*"' "$run/run.json" | grep -o '[0-9a-f]\{16,\}')
for f in "$run/light.exr" "$run/mis-power.sobol.exr" "$run/light.variance.exr"; do
  expect "$f" scene cornell
  expect "$f" scene_hash "$hash"
  expect "$f" integrand direct
  expect "$f" spp 8
  expect "$f" seed 5
  expect "$f" threads 1
  expect "$f" backend packet
done
expect "$run/light.exr" strategy light
expect "$run/light.exr" sampler independent
expect "$run/light.exr" content radiance
expect "$run/mis-power.sobol.exr" strategy mis-power
expect "$run/mis-power.sobol.exr" sampler sobol
expect "$run/light.variance.exr" content "variance of the mean"
expect "$ref" spp 32
expect "$ref" sampler independent
expect "$ref" scene_hash "$hash"
# Render time and commit: present and what the program recorded.
for f in "$run/light.exr" "$ref"; do
  t=$(oiiotool --info -v "$f" | sed -n 's/^    dibench:render_time_s: //p')
  if python3 -c "import sys; t=float(sys.argv[1]); sys.exit(0 if 0 < t < 300 else 1)" "$t" 2>/dev/null; then
    echo "PASS: $(basename "$f") dibench:render_time_s = $t"
  else
    echo "FAIL: $(basename "$f") dibench:render_time_s: ${t:-missing}"
    failures=$((failures + 1))
  fi
  commit=$(oiiotool --info -v "$f" | sed -n 's/^    dibench:commit: "\(.*\)"$/\1/p')
  if [ -n "$commit" ] && grep -q "\"commit\": *\"$commit\"" "$run/run.json"; then
    echo "PASS: $(basename "$f") dibench:commit = $commit (as run.json)"
  else
    echo "FAIL: $(basename "$f") dibench:commit: ${commit:-missing}, run.json: $(grep '"commit"' "$run/run.json")"
    failures=$((failures + 1))
  fi
done
# The machine: the same description as run.json's cpu_model, in the images and the reference.
cpu=$(python3 -c "import json, sys; print(json.load(open(sys.argv[1]))['cpu_model'])" "$run/run.json")
for f in "$run/light.exr" "$run/light.variance.exr" "$ref"; do
  expect "$f" cpu "$cpu"
done
if [ "$failures" -eq 0 ]; then
  echo "PASS: test-exr-metadata"
else
  echo "FAIL: test-exr-metadata: $failures check(s) failed"
  exit 1
fi
