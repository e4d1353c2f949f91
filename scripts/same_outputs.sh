#!/usr/bin/env bash
# Behaviour check for refactors: runs every example program (host_sim/examples/*.ngc) on every shipped XYZ
# machine through `lissom-sim run --json --no-drive` and `run --json` (with the drives), and keeps the summary
# (host timings *_ns_* removed: they are measurements, not behaviour) and setpoints.csv of each run, plus the
# host twins' reports of the Cortex-M self-test and contour programs.
#   scripts/same_outputs.sh snapshot DIR [BUILD]   writes the outputs of BUILD (default build/) into DIR
#   scripts/same_outputs.sh compare  A B           exits 1 unless the two snapshots are byte-identical
set -euo pipefail
cd "$(dirname "$0")/.."
cmd=${1:-}; dir=${2:-}
case "$cmd" in
  snapshot)
    build=${3:-build}
    sim=$build/bin/lissom-sim
    [ -x "$sim" ] || { echo "same_outputs: no $sim (build first)" >&2; exit 2; }
    rm -rf "$dir"; mkdir -p "$dir"
    for prog in host_sim/examples/*.ngc; do
      for m in router beudaert_table1 kombarov_table1; do
        for drive in drive no-drive no-csv; do
          name=$(basename "$prog" .ngc)-$m-$drive
          out=$(mktemp -d)
          args=(run "$prog" --machine "host_sim/machines/$m.json" --out "$out" --json --no-progress)
          [ "$drive" = no-drive ] && args+=(--no-drive)
          [ "$drive" = no-csv ] && args+=(--no-csv) # the windowed program and the streaming measurement
          if "$sim" "${args[@]}" > "$out/stdout.json" 2> "$out/stderr.txt"; then rc=0; else rc=$?; fi
          echo "$rc" > "$dir/$name.rc"
          sed -E 's/"[a-z_]*_ns_[a-z_]*": [-0-9.eE+null]+/"ns": 0/g' "$out/stdout.json" > "$dir/$name.json"
          grep -v "ns" "$out/stderr.txt" > "$dir/$name.stderr" || true
          [ -f "$out/setpoints.csv" ] && cp "$out/setpoints.csv" "$dir/$name.setpoints.csv"
          [ -f "$out/run.csv" ] && cp "$out/run.csv" "$dir/$name.run.csv"
          rm -rf "$out"
        done
      done
    done
    for twin in lissom-selftest-host lissom-contour-host; do
      [ -x "$build/bin/$twin" ] && "$build/bin/$twin" > "$dir/$twin.txt" 2>&1 || true
    done
    echo "same_outputs: $(ls "$dir" | wc -l) files in $dir"
    ;;
  compare)
    b=${3:-}
    [ -d "$dir" ] && [ -d "$b" ] || { echo "usage: same_outputs.sh compare A B" >&2; exit 2; }
    if diff -rq "$dir" "$b"; then echo "same_outputs: identical ($(ls "$dir" | wc -l) files)"; else exit 1; fi
    ;;
  *) echo "usage: scripts/same_outputs.sh snapshot DIR [BUILD] | compare A B" >&2; exit 2 ;;
esac
