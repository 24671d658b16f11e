# Sourced by the timing scripts (ab-compare.sh, threads-scaling.sh, embree-end-to-end.sh).
# compare_rows BINARY SCENE [compare arguments ...]: runs `BINARY compare SCENE ARGS` into a
# scratch directory and prints one line per strategy, "STRATEGY SPP TIME_S", from its last
# checkpoint in results.csv (time_s is render time only). If compare fails, its error goes to
# stderr and the script exits non-zero.
compare_rows() {
  local bin=$1 scene=$2 out csv
  shift 2
  out=$(mktemp -d)
  if ! "$bin" compare "$scene" "$@" --out "$out" > /dev/null 2> "$out.err"; then
    cat "$out.err" >&2
    rm -rf "$out" "$out.err"
    exit 1
  fi
  csv=$(find "$out/$scene" -path '*/reference' -prune -o -name results.csv -print | head -1)
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) { if ($i == "time_s") t = i; if ($i == "spp") s = i } }
    NR > 1 { spp[$2] = $s; time[$2] = $t }
    END { for (k in spp) print k, spp[k], time[k] }' "$csv"
  rm -rf "$out" "$out.err"
}

# cpu_line BINARY: "cpu: ..." as BINARY's run metadata names the machine (`cpu_model`: name,
# family, model, stepping, ISA), from a one-sample compare of cornell. The timing scripts print
# it first: a VM's bare "AMD EPYC" covers Zen 2 to Zen 5, whose timings differ 2x and more.
cpu_line() {
  local out
  out=$(mktemp -d)
  if "$1" compare cornell --strategies light --spp 1 --reference-spp 1 --out "$out" \
      > /dev/null 2>&1; then
    sed -n 's/.*"cpu_model": *"\([^"]*\)".*/cpu: \1/p' "$out"/cornell/*/run.json | head -1
  else
    echo "cpu: unknown (compare failed)"
  fi
  rm -rf "$out"
}
