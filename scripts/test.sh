#!/usr/bin/env bash
# The test command: the whole suite on the default build (crates.io only), then, with the
# Embree backend compiled in (fetches Embree 4.4 into third_party/embree first; a no-op once
# done), the library and the tests that exercise backends: the feature changes nothing else,
# and running the whole suite twice would double CI time for no extra coverage.
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release
scripts/setup-embree.sh
cargo test --release --features embree --lib \
    --test embree --test backend_cli --test rays_cli --test harness_cli --test adversarial \
    --test packet --test watertight --test determinism
