#!/usr/bin/env bash
# Instructions of whole samples as a timed `compare` renders them, counted by valgrind's
# callgrind: a figure the other tenants of a shared machine cannot move, for changes too
# small for wall-clock A/B runs to resolve. It is work, not time (a division counts as one
# instruction, a cache miss as none): quote it beside `ab-compare.sh`, never instead of it.
#   scripts/instructions.sh PASSES SCENE STRATEGY [GROUPS]
# PASSES is a build of `examples/passes.rs` (`cargo build --release --example passes`, then
# target/release/examples/passes; copy it to keep a build for an A/B). It renders GROUPS
# (default 2) groups of 16 passes with the packet backend on one thread (the calling one),
# each packet one pixel's 16 samples, as `compare` renders every group after its first pass;
# callgrind counts inside `Renderer::add_passes_with_streams` only (camera rays, the
# estimator, its shadow and emission rays, the film; not the scene's preparation). Prints
# "SCENE STRATEGY INSTRUCTIONS PER-SAMPLE" and the eight source files and functions with the
# most instructions of their own (inlined code counts where it was inlined). The count is the same from run to run.
# (Up to stop 58 this script ran `compare --spp 1` under callgrind: one pass, packed in 4×4
# pixel tiles, and the shading phase alone; its figures are not comparable with these. That
# version, which reproduces docs/tracer.md's figures of stops 56–58, is
# `git show 3dc761b:scripts/instructions.sh`.)
set -euo pipefail
[[ $# -eq 3 || $# -eq 4 ]] || { echo "usage: $0 PASSES SCENE STRATEGY [GROUPS]" >&2; exit 2; }
command -v valgrind > /dev/null || { echo "$0: needs valgrind (apt-get install valgrind)" >&2; exit 2; }
BIN=$(realpath "$1"); SCENE=$2; STRATEGY=$3; NGROUPS=${4:-2}
cd "$(dirname "$0")/.."
DIR=$(mktemp -d)
trap 'rm -rf "$DIR"' EXIT
valgrind --tool=callgrind --callgrind-out-file="$DIR/cg.out" \
  --collect-atstart=no --toggle-collect='*Renderer::add_passes_with_streams*' \
  "$BIN" "$SCENE" "$STRATEGY" "$NGROUPS" > "$DIR/log" 2>&1 || { tail -n 20 "$DIR/log" >&2; exit 1; }
total=$(awk '/^summary:/ { print $2 }' "$DIR/cg.out")
samples=$(awk '/ samples / { print $1 }' "$DIR/log")
[[ ${samples:-0} -gt 0 ]] || { echo "$0: no samples rendered" >&2; cat "$DIR/log" >&2; exit 1; }
echo "$SCENE $STRATEGY $total $(( total / samples ))"
callgrind_annotate "$DIR/cg.out" 2> /dev/null | grep -E '^ *[0-9,]+ \([ 0-9.]+%\) ' | sed -n 2,9p
