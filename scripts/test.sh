#!/usr/bin/env bash
# The test command: the default build (crates.io only), then the Embree backend
# (fetches Embree 4.4 into third_party/embree first; a no-op once done).
set -euo pipefail
cd "$(dirname "$0")/.."
cargo test --release
scripts/setup-embree.sh
cargo test --release --features embree
