#!/bin/bash
# Runs every fuzz target for a set time, one at a time, niced, seeded with the test fixtures.
# Usage (from anywhere): fuzz/run_all.sh [SECONDS_PER_TARGET]   (default 180)
# Needs cargo-fuzz; on a stable toolchain only `--sanitizer none` works. Crashes land in
# fuzz/artifacts/TARGET/; the new corpus in fuzz/corpus/TARGET/ (both git-ignored).
set -u
secs=${1:-180}
# The loaders' memory checks plan for 1 GiB, below libFuzzer's 2 GB RSS limit (as xtask test).
export SHADOWVOL_MEMORY_LIMIT=$((1 << 30))
cd "$(dirname "$0")"
D=../crates/scenes/tests/data
M=../crates/cli/tests/data/malformed
seeds() {
  case $1 in
    obj_loader) echo "$D $M ../assets" ;;
    gltf_loader) echo "$D $M $D/real" ;;
    stl_loader | ply_loader) echo "$D/real" ;;
    draco_decode) echo "seeds/draco_decode" ;;
    *) echo "" ;;
  esac
}
for t in obj_loader gltf_loader stl_loader ply_loader meshopt_decode draco_decode topology exact_predicate \
  pipeline simd_differential; do
  mkdir -p corpus/$t
  echo "=== $t: ${secs} s from $(date -u +%H:%M:%S)"
  # shellcheck disable=SC2046
  nice -n 10 cargo fuzz run --sanitizer none $t corpus/$t $(seeds $t) -- \
    -max_total_time="$secs" 2>&1 | grep -E "^Done|DONE|Test unit written|panicked" || true
done
