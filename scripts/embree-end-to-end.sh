#!/usr/bin/env bash
# End to end against Embree (#19): samples/s of the packet backend ÷ the embree backend, the
# same build, `compare SCENE --strategies A,B --time T --reference-spp 16 --threads 1
# --backend packet|embree`, the backends alternated round by round (so load changes hit
# both). A binary built with `--features embree`:
#   scripts/embree-end-to-end.sh BINARY [ROUNDS] [TIME] [SCENE ...]
# (run with LD_LIBRARY_PATH=third_party/embree/lib; the default scenes are every scene in
# scenes/). The rate of a run is spp ÷ time_s at its last checkpoint (render time only).
# `light` and `mis-power` run where the scene has lights; on the environment-only scenes
# they do not apply and `env-latlong-cdf` and `mis-env-latlong-cdf` run instead; a scene
# whose lights are all points or directions (no MIS) runs `light` alone. Prints one line
# per run, then per scene and strategy the ratio of each round and their median.
set -euo pipefail
[[ $# -ge 1 ]] || { echo "usage: $0 BINARY [ROUNDS] [TIME] [SCENE ...]" >&2; exit 2; }
BIN=$(realpath "$1"); ROUNDS=${2:-2}; TIME=${3:-2}
shift $(( $# < 3 ? $# : 3 ))
cd "$(dirname "$0")/.."
source scripts/compare-rows.sh
cpu_line "$BIN"
SCENES=("$@")
if [[ ${#SCENES[@]} -eq 0 ]]; then
  for s in scenes/*.toml; do SCENES+=("$(basename "$s" .toml)"); done
fi
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
for r in $(seq 1 "$ROUNDS"); do
  for scene in "${SCENES[@]}"; do
    listed=$("$BIN" strategies "$scene")
    applies() { grep -Eq "^$1 .*\[applies\]" <<< "$listed"; }
    if applies light && applies mis-power; then strats=light,mis-power
    elif applies light; then strats=light
    else strats=env-latlong-cdf,mis-env-latlong-cdf
    fi
    if (( r % 2 )); then order=(packet embree); else order=(embree packet); fi
    for backend in "${order[@]}"; do
      rows=$(compare_rows "$BIN" "$scene" --strategies "$strats" --threads 1 --time "$TIME" \
        --reference-spp 16 --backend "$backend")
      awk -v sc="$scene" -v b="$backend" -v r="$r" \
        '{ printf "%s %s round %s %s %.1f\n", sc, $1, r, b, $2 / $3 }' <<< "$rows" | tee -a "$LOG"
    done
  done
done
python3 - "$LOG" <<'PY'
import collections, statistics, sys
rate = collections.defaultdict(dict)
for line in open(sys.argv[1]):
    scene, strat, _, r, backend, v = line.split()
    rate[(scene, strat)][(int(r), backend)] = float(v)
print("\nscene strategy: packet/embree per round; median")
for (scene, strat), d in rate.items():
    rounds = sorted({r for r, _ in d})
    ratios = [d[(r, "packet")] / d[(r, "embree")] for r in rounds
              if (r, "packet") in d and (r, "embree") in d]
    print(f"{scene} {strat}: {', '.join(f'{x:.2f}' for x in ratios)}; "
          f"median {statistics.median(ratios):.2f}")
PY
