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

# cpu_line: "cpu: NAME (family F, model M, stepping S; ISA)" from /proc/cpuinfo's first
# processor, as dibench's run metadata and `rays` name the machine. The timing scripts print it
# first: a VM's bare "AMD EPYC" covers Zen 2 to Zen 5, whose timings differ 2x and more.
cpu_line() {
  awk -F: '/^[ \t]*$/ { exit }
    { k = $1; sub(/[ \t]+$/, "", k); v = substr($0, index($0, ":") + 1); sub(/^[ \t]+/, "", v); f[k] = v }
    END {
      isa = (f["flags"] ~ /(^| )avx512f( |$)/) ? "avx512" : (f["flags"] ~ /(^| )avx2( |$)/) ? "avx2" : "no avx2"
      printf "cpu: %s (family %s, model %s, stepping %s; %s)\n", f["model name"], f["cpu family"], f["model"], f["stepping"], isa
    }' /proc/cpuinfo 2> /dev/null || echo "cpu: unknown"
}
