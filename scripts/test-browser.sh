#!/usr/bin/env bash
# The browser test of report.html: makes two small compare runs of cornell in a temporary
# output root (every strategy; then two with the sobol sampler beside the independent one),
# writes their reports with `dibench report`, and drives each page in headless Chromium (tests/browser/report.test.mjs; playwright-core from tests/browser's lock file).
# Builds nothing: expects $DIBENCH_TARGET/dibench and $DIBENCH_TARGET/examples/exr_pixel
# (DIBENCH_TARGET defaults to target/release: cargo build --release --bins --example exr_pixel). Needs node (18 or later), npm and
# /usr/bin/chromium (scripts/install-browser.sh). Screenshots go to docs/figures/report-*.png
# (SCREENSHOTS=none to skip, or another folder).
set -euo pipefail
cd "$(dirname "$0")/.."
target=${DIBENCH_TARGET:-target/release}
case $target in /*) ;; *) target=$PWD/$target ;; esac
fail() {
    echo "test-browser: $*" >&2
    exit 1
}
[ -x "$target/dibench" ] || fail "$target/dibench is missing: build it (cargo build --release for target/release)"
[ -x "$target/examples/exr_pixel" ] ||
    fail "$target/examples/exr_pixel is missing: build it (cargo build --release --example exr_pixel for target/release)"
command -v node >/dev/null || fail "node is not installed (node 18 or later is needed)"
command -v npm >/dev/null || fail "npm is not installed"
[ -x "${CHROMIUM:-/usr/bin/chromium}" ] ||
    fail "${CHROMIUM:-/usr/bin/chromium} is missing: run scripts/install-browser.sh"
node_major=$(node -p 'process.versions.node.split(".")[0]')
[ "$node_major" -ge 18 ] || fail "node $(node --version) is too old (18 or later)"

out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
start=$(date +%s)
# A small run: 2 runs of 0.2 s per strategy against a 64-spp reference.
"$target/dibench" compare cornell --time 0.2 --runs 2 --reference-spp 64 --out "$out" \
    >"$out/compare.log" 2>&1 || { cat "$out/compare.log" >&2; fail "dibench compare failed"; }
run_dir=$(find "$out/cornell" -mindepth 1 -maxdepth 1 -type d ! -name reference | head -n 1)
[ -n "$run_dir" ] || fail "compare wrote no run directory under $out/cornell"
# compare writes report.html itself (with the FLIP maps it computed).
[ -s "$run_dir/report.html" ] || fail "compare wrote no $run_dir/report.html"
(cd tests/browser && npm ci --no-audit --no-fund --loglevel=error)
EXR_PIXEL="$target/examples/exr_pixel" node tests/browser/report.test.mjs "$run_dir"
# A second run with a non-independent sampler too: images named <strategy>.<sampler>, some
# without a variance map (no screenshots from this one).
"$target/dibench" compare cornell --time 0.1 --runs 2 --reference-spp 64 --out "$out" \
    --strategies light,mis-power --sampler independent,sobol >"$out/compare2.log" 2>&1 ||
    { cat "$out/compare2.log" >&2; fail "dibench compare --sampler independent,sobol failed"; }
run_dir2=$(find "$out/cornell" -mindepth 1 -maxdepth 1 -type d ! -name reference ! -path "$run_dir" | head -n 1)
[ -n "$run_dir2" ] || fail "the second compare wrote no run directory under $out/cornell"
# The subcommand writes the same page anew.
rm "$run_dir2/report.html"
"$target/dibench" report "$run_dir2"
SCREENSHOTS=none EXR_PIXEL="$target/examples/exr_pixel" \
    node tests/browser/report.test.mjs "$run_dir2"
echo "test-browser: passed in $(($(date +%s) - start)) s"
