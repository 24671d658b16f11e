#!/usr/bin/env bash
# Fetches Embree 4.4 (and its private oneTBB) from the PyPI wheel embreex==4.4.0.post1 into
# third_party/embree/lib (git-ignored). Pinned version and sha256; idempotent.
# Needs python3 with pip. Linux x86-64 only (the wheel is manylinux_2_28_x86_64).
set -euo pipefail
cd "$(dirname "$0")/.."
VERSION=4.4.0.post1
SHA256=2cd0f7d5c6342e6247e31f700761689cae7829454d8c6de0c41e62124a023e1f
ROOT=third_party/embree
LIB=$ROOT/lib
STAMP=$LIB/.installed-$VERSION-$SHA256
if [[ -f $STAMP && -e $LIB/libembree4.so ]]; then
  exit 0 # already installed
fi
[[ $(uname -s)-$(uname -m) == Linux-x86_64 ]] || { echo "setup-embree: only Linux x86-64 is supported (the wheel is manylinux x86_64)" >&2; exit 1; }
command -v python3 >/dev/null || { echo "setup-embree: python3 (with pip) is needed to download the wheel" >&2; exit 1; }
rm -rf "$ROOT/wheel" "$LIB" "$LIB.tmp"
mkdir -p "$ROOT/wheel"
python3 -m pip download --quiet --no-deps --only-binary=:all: --python-version 3.11 \
  --implementation cp --abi cp311 --platform manylinux_2_28_x86_64 \
  -d "$ROOT/wheel" "embreex==$VERSION"
WHEEL=$(ls "$ROOT"/wheel/embreex-"$VERSION"-*.whl)
GOT=$(sha256sum "$WHEEL" | cut -d' ' -f1)
if [[ $GOT != "$SHA256" ]]; then
  echo "setup-embree: sha256 mismatch for $WHEEL: expected $SHA256, got $GOT" >&2
  rm -rf "$ROOT/wheel"
  exit 1
fi
# Extract only the bundled shared libraries (embreex.libs/*.so*), without needing unzip.
python3 - "$WHEEL" "$LIB.tmp" <<'PY'
import os, sys, zipfile
wheel, out = sys.argv[1], sys.argv[2]
os.makedirs(out, exist_ok=True)
n = 0
with zipfile.ZipFile(wheel) as z:
    for name in z.namelist():
        if name.startswith("embreex.libs/") and ".so" in name:
            with open(os.path.join(out, os.path.basename(name)), "wb") as f:
                f.write(z.read(name))
            n += 1
if n == 0:
    sys.exit("setup-embree: no shared libraries found in " + wheel)
PY
EMB=$(cd "$LIB.tmp" && ls libembree4-*.so.4)
ln -sf "$EMB" "$LIB.tmp/libembree4.so"
mv "$LIB.tmp" "$LIB"
rm -rf "$ROOT/wheel"
touch "$STAMP"
echo "setup-embree: installed $(ls "$LIB" | tr '\n' ' ')into $LIB"
