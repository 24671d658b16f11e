#!/usr/bin/env bash
# Instructions executed by the render's shading phase (the estimator, its shadow and emission
# rays, the film's update), counted by valgrind's callgrind: a figure the other tenants of a
# shared machine cannot move, for changes too small for wall-clock A/B runs to resolve. It is
# work, not time (a division counts as one instruction, a cache miss as none): quote it beside
# `ab-compare.sh`, never instead of it.
#   scripts/instructions.sh BINARY SCENE STRATEGY
# runs `BINARY compare SCENE --strategies STRATEGY --threads 1 --spp 1 --reference-spp 1`
# under callgrind, collecting only inside `Renderer::shading_phase`, and
# prints "SCENE STRATEGY INSTRUCTIONS" and the eight functions with the most instructions
# of their own (inlined code counts where it was inlined). The
# scene's preparation runs under valgrind too: about 3 minutes for many_mesh. One pass: past
# the first, compare groups passes by their measured time (`render::group_size`), and how
# they are grouped changes the packets and so the count (by 15 % between two runs of one
# binary at 8 spp), never the image.
set -euo pipefail
[[ $# -eq 3 ]] || { echo "usage: $0 BINARY SCENE STRATEGY" >&2; exit 2; }
command -v valgrind > /dev/null || { echo "$0: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
BIN=$(realpath "$1"); SCENE=$2; STRATEGY=$3
cd "$(dirname "$0")/.."
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$DIR/cg.out" --collect-atstart=no \
  --toggle-collect='*Renderer::shading_phase*' "$BIN" compare "$SCENE" \
  --strategies "$STRATEGY" --threads 1 --spp 1 --reference-spp 1 --out "$DIR/out" \
  > "$DIR/log" 2>&1 || { tail -n 20 "$DIR/log" >&2; exit 1; }
total=$(awk '/^summary:/ { print $2 }' "$DIR/cg.out")
echo "$SCENE $STRATEGY $total"
callgrind_annotate "$DIR/cg.out" 2> /dev/null | grep -E '^ *[0-9,]+ \([ 0-9.]+%\) ' | sed -n 2,9p
