#!/usr/bin/env bash
# 1 → 2 threads (#19): fixed-work timings of one build at 1 and 2 threads, alternated round by
# round (the order flips each round, so load changes hit both):
#   scripts/threads-scaling.sh BINARY [ROUNDS] [SCENE:STRATEGY:SPP ...]
# Each case runs `compare SCENE --strategies STRATEGY --threads T --spp SPP --reference-spp 16`
# and reads that strategy's own `time_s` (render time) from results.csv. Prints one line per
# run, then per case the range of seconds at each thread count and the speed-up of each round
# (1 thread ÷ 2 threads, adjacent runs under the same load) with their median.
set -euo pipefail
[[ $# -ge 1 ]] || { echo "usage: $0 BINARY [ROUNDS] [SCENE:STRATEGY:SPP ...]" >&2; exit 2; }
BIN=$(realpath "$1"); ROUNDS=${2:-5}
shift $(( $# < 2 ? $# : 2 ))
CASES=("$@")
[[ ${#CASES[@]} -gt 0 ]] || CASES=(cornell:light:2048 cornell:mis-power:1024)
cd "$(dirname "$0")/.."
source scripts/compare-rows.sh
cpu_line "$BIN"
LOG=$(mktemp)
trap 'rm -f "$LOG"' EXIT
for r in $(seq 1 "$ROUNDS"); do
  for c in "${CASES[@]}"; do
    IFS=: read -r scene strat spp <<< "$c"
    if (( r % 2 )); then order=(1 2); else order=(2 1); fi
    for t in "${order[@]}"; do
      s=$(compare_rows "$BIN" "$scene" --strategies "$strat" --threads "$t" --spp "$spp" \
        --reference-spp 16 | awk -v s="$strat" '$1 == s { print $3 }')
      echo "$scene $strat $spp round $r threads $t $s" | tee -a "$LOG"
    done
  done
done
python3 - "$LOG" <<'PY'
import collections, statistics, sys
t = collections.defaultdict(dict)
for line in open(sys.argv[1]):
    scene, strat, spp, _, r, _, threads, s = line.split()
    t[(scene, strat, spp)][(int(r), threads)] = float(s)
print()
for (scene, strat, spp), d in t.items():
    rounds = sorted({r for r, _ in d})
    ratios = [d[(r, "1")] / d[(r, "2")] for r in rounds]
    one = [d[(r, "1")] for r in rounds]
    two = [d[(r, "2")] for r in rounds]
    print(f"{scene} {strat} {spp} spp: 1 thread {min(one):.3f}-{max(one):.3f} s, "
          f"2 threads {min(two):.3f}-{max(two):.3f} s; per round "
          f"{', '.join(f'{x:.2f}' for x in ratios)}: median {statistics.median(ratios):.2f}x")
PY
