#!/usr/bin/env bash
# The test command: the whole suite on the default build (crates.io only); then the system
# tests, which need tools a fresh machine lacks (scripts/install-test-tools.sh installs them with
# apt-get, a no-op once there): EXR metadata read back by oiiotool, a real one-node Slurm
# cluster rendering and merging a sharded reference, and report.html driven in headless
# Chromium; then, with the Embree backend compiled in (fetches Embree 4.4 into third_party/embree
# first; a no-op once done), the library and the tests that exercise backends: the feature
# changes nothing else, and running the whole suite twice would double CI time for no extra
# coverage.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release
cargo build --release
scripts/install-test-tools.sh
scripts/test-exr-metadata.sh
scripts/test-slurm.sh
scripts/test-browser.sh
scripts/setup-embree.sh
cargo test --release --features embree --lib \
    --test embree --test backend_cli --test rays_cli --test harness_cli --test adversarial \
    --test packet --test watertight --test determinism
