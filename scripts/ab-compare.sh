#!/usr/bin/env bash
# Fixed-work timings of two dibench builds, alternated round by round (the build before a
# change against the build after it, on the same machine under the same load):
#   scripts/ab-compare.sh BEFORE_BINARY AFTER_BINARY [ROUNDS] [SCENE:STRATEGY:SPP ...]
# Each case runs `compare SCENE --strategies STRATEGY --threads 1 --spp SPP --reference-spp 16`
# with each binary (order alternating by round) and reads that strategy's own `time_s` from
# results.csv. Prints one line per run, then per case the minimum (median) seconds of each
# build and the speed-up (minimum before ÷ minimum after).
set -euo pipefail
[[ $# -ge 2 ]] || { echo "usage: $0 BEFORE AFTER [ROUNDS] [SCENE:STRATEGY:SPP ...]" >&2; exit 2; }
A=$(realpath "$1"); B=$(realpath "$2"); ROUNDS=${3:-3}
shift $(( $# < 3 ? $# : 3 ))
CASES=("$@")
if [[ ${#CASES[@]} -eq 0 ]]; then
  CASES=(cornell:light:512 cornell:mis-power-area:512 bunny:light:256 bunny:mis-power-area:256
    sphere_light:light:512 sphere_light:mis-power:512 mesh_light:light:512
    mesh_light:mis-power-area:512 env_venice_bunny:env-latlong-hier:128
    env_venice_bunny:mis-env-latlong-hier:128 glossy:light:256 many_mesh:light:16)
fi
cd "$(dirname "$0")/.."
source scripts/compare-rows.sh
cpu_line "$B"
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
for r in $(seq 1 "$ROUNDS"); do
  for c in "${CASES[@]}"; do
    IFS=: read -r scene strat spp <<< "$c"
    if (( r % 2 )); then order=(before after); else order=(after before); fi
    for which in "${order[@]}"; do
      bin=$A; [[ $which == after ]] && bin=$B
      t=$(compare_rows "$bin" "$scene" --strategies "$strat" --threads 1 --spp "$spp" \
        --reference-spp 16 | awk -v s="$strat" '$1 == s { print $3 }')
      echo "$scene $strat $spp round $r $which $t" | tee -a "$LOG"
    done
  done
done
python3 - "$LOG" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(lambda: collections.defaultdict(list))
for line in open(sys.argv[1]):
    scene, strat, spp, _, _, which, t = line.split()
    runs[scene, strat, spp][which].append(float(t))
print(f"\n{'scene':18} {'strategy':22} {'spp':>5} {'before min (median)':>20} {'after min (median)':>20} {'speed-up':>8}")
for (scene, strat, spp), v in runs.items():
    b, a = v["before"], v["after"]
    print(f"{scene:18} {strat:22} {spp:>5} {f'{min(b):.3f} ({statistics.median(b):.3f})':>20} "
          f"{f'{min(a):.3f} ({statistics.median(a):.3f})':>20} {min(b) / min(a):8.3f}")
PY
