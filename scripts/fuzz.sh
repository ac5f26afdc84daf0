#!/usr/bin/env bash
# Long fuzzing runs of every parser of input from elsewhere, under ASan+UBSan (libFuzzer, clang):
# the glTF/GLB loader, the camera-path CSV reader, the scene and LOD cache readers, the input
# messages of render_client --web's page (common/fuzz/) and the wire decoder (protocol/fuzz/). Builds them into build-fuzz/ (clang,
# -DOCC_LIBFUZZER=ON) and runs each from its checked-in seeds (tests/fuzz/NAME, with
# common/fuzz/NAME.dict where there is one) into a scratch corpus, then prints one table: inputs
# run, seconds, inputs/s, coverage (edges, features), corpus size, crashes. A crash stops with exit
# 1 and names the input libFuzzer saved (OUT/crash-*); reproduce it with build-fuzz/bin/NAME_fuzz FILE.
# The test suite runs a short fixed-seed pass of the same harnesses (fuzz_parsers_test).
#
#   scripts/fuzz.sh [--runs N] [--targets gltf,camera_path,scene_cache,lod_cache,web_input,wire] [--out DIR]
#
# --runs N: inputs per target (default 1000000); --out DIR (default out/fuzz): logs, corpora and
# table.txt.
set -euo pipefail
source "$(dirname "$0")/lib.sh"
runs=1000000 targets=gltf,camera_path,scene_cache,lod_cache,web_input,wire out=out/fuzz
while [ $# -gt 0 ]; do
  case "$1" in
    --runs|--targets|--out) occ_set "$@"; shift 2 ;;
    -h|--help) occ_usage; exit 0 ;;
    *) occ_unexpected "$1" ;;
  esac
done
[[ "$runs" =~ ^[1-9][0-9]*$ ]] || occ_die "--runs '$runs': expected a whole number >= 1"
command -v clang++ >/dev/null || occ_die "clang++ not found (Debian: apt-get install clang)"
cd "$here"
IFS=, read -ra names <<<"$targets"
for n in "${names[@]}"; do
  case "$n" in gltf|camera_path|scene_cache|lod_cache|web_input|wire) ;; *) occ_die "--targets: unknown target '$n'" ;; esac
done

if [ ! -f build-fuzz/CMakeCache.txt ]; then
  CC=clang CXX=clang++ cmake -S . -B build-fuzz -DCMAKE_BUILD_TYPE=RelWithDebInfo -DOCC_LIBFUZZER=ON >/dev/null
fi
cmake --build build-fuzz -j"$(nproc)" --target "${names[@]/%/_fuzz}" >/dev/null
mkdir -p "$out"
out=$(cd "$out" && pwd)
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1

table=$out/table.txt
printf '%-12s %9s %8s %9s %7s %9s %7s %7s\n' target inputs seconds inputs/s edges features corpus crashes >"$table"
for n in "${names[@]}"; do
  corpus=$out/$n.corpus
  rm -rf "$corpus" && mkdir -p "$corpus"
  seeds=()
  [ ! -d tests/fuzz/$n ] || seeds=(tests/fuzz/$n)
  dict=()
  [ ! -f common/fuzz/$n.dict ] || dict=(-dict="$here/common/fuzz/$n.dict")
  echo "fuzz: $n, $runs inputs ..." >&2
  t0=$(date +%s.%N)
  rc=0
  (cd "$out" && "$here/build-fuzz/bin/${n}_fuzz" -runs="$runs" -seed=1 -timeout=10 -rss_limit_mb=4096 \
     -print_final_stats=1 "${dict[@]}" "$corpus" "${seeds[@]/#/$here/}") >"$out/$n.log" 2>&1 || rc=$?
  t1=$(date +%s.%N)
  if [ $rc != 0 ]; then
    echo "error: ${n}_fuzz stopped with status $rc: $(grep -m 1 -E 'ERROR|runtime error|Test unit written' "$out/$n.log" || tail -n 1 "$out/$n.log") (log: $out/$n.log)" >&2
    exit 1
  fi
  done_line=$(grep -E '^#[0-9]+[[:space:]]+DONE' "$out/$n.log" | tail -n 1)
  inputs=$(grep -m 1 -o 'stat::number_of_executed_units: [0-9]*' "$out/$n.log" | awk '{ print $2 }')
  edges=$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$done_line")
  features=$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$done_line")
  corp=$(sed -n 's/.* corp: \([0-9]*\).*/\1/p' <<<"$done_line")
  awk -v n="$n" -v i="$inputs" -v t="$t0" -v u="$t1" -v e="${edges:-?}" -v f="${features:-?}" -v c="${corp:-?}" \
    'BEGIN { printf "%-12s %9s %8.0f %9.0f %7s %9s %7s %7s\n", n, i, u - t, i / (u - t), e, f, c, 0 }' >>"$table"
done
cat "$table"
