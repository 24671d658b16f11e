#!/usr/bin/env bash
# Ray throughput of two dibench builds, alternated run by run (the build before a change
# against the build after it, on the same machine under the same load):
#   scripts/rays-ab.sh BEFORE_BINARY AFTER_BINARY [PAIRS] [SCENE] [extra `rays` arguments ...]
# Each pair runs `rays SCENE --backend packet --isa avx512` (or the ISA given in the extra
# arguments) with each binary in turn and prints, per ray class, the best Mrays/s of each
# build and the median, minimum and maximum of the pairs' after ÷ before ratios.
set -euo pipefail
[[ $# -ge 2 ]] || { echo "usage: $0 BEFORE AFTER [PAIRS] [SCENE] [rays args ...]" >&2; exit 2; }
A=$(realpath "$1"); B=$(realpath "$2"); PAIRS=${3:-6}; SCENE=${4:-bunny}
shift $(( $# < 4 ? $# : 4 ))
ISA=avx512
for a in "$@"; do [[ $a == --isa=* ]] && ISA=${a#--isa=}; done
[[ " $* " == *" --isa "* ]] || set -- --isa "$ISA" "$@"
cd "$(dirname "$0")/.."
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
for i in $(seq 1 "$PAIRS"); do
  for which in before after; do
    bin=$A; [[ $which == after ]] && bin=$B
    "$bin" rays "$SCENE" --backend packet --out "$OUT/$which" "$@" |
      awk -v w="$which" -v i="$i" '$1 == "packet" { print w, i, $3, $5 }' >> "$OUT/all"
  done
done
python3 - "$OUT/all" <<'PY'
import collections, statistics, sys
runs = collections.defaultdict(dict)
for line in open(sys.argv[1]):
    which, pair, cls, mrays = line.split()
    runs[(cls, pair)][which] = float(mrays)
print(f"{'class':16s} {'before max':>10s} {'after max':>10s}  after/before median (min, max)")
for cls in sorted({c for c, _ in runs}):
    pairs = [v for (c, _), v in runs.items() if c == cls and len(v) == 2]
    r = [p["after"] / p["before"] for p in pairs]
    print(f"{cls:16s} {max(p['before'] for p in pairs):10.2f} {max(p['after'] for p in pairs):10.2f}"
          f"  {statistics.median(r):.3f} ({min(r):.3f}, {max(r):.3f})")
PY
