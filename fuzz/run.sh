#!/usr/bin/env bash
# Runs fuzz targets one after another (never two at once from one call).
#   fuzz/run.sh SECONDS [TARGET...]        long runs (default: every target)
#   fuzz/run.sh --ci SECONDS [TARGET...]   CI's reproducible short run
#   fuzz/run.sh --checked [--ci] SECONDS [TARGET...]
#                                          the same with debug assertions and overflow
#                                          checks (cargo fuzz build -a), built into its own
#                                          target/checked so it never replaces the plain build
# Both build every target once (FUZZ_NO_BUILD=1 skips it, for a second call running
# next to a first), then run each target's binary directly, so a later edit of the
# library cannot rebuild a target in the middle of a series.
# Long runs: new inputs go to a scratch corpus under target/fuzz-corpus/TARGET (kept
# between runs), the committed seeds in corpus/TARGET are only read, crashes land in
# artifacts/TARGET/.
# --ci: each target first replays its committed seeds and regression inputs
# (regressions/TARGET/, every input a past crash), then fuzzes for SECONDS with the
# fixed seed -seed=1 from an empty scratch corpus (deleted afterwards), so a rerun on
# the same commit generates the same inputs in the same order; only how far it gets in
# SECONDS depends on the machine.
set -euo pipefail
cd "$(dirname "$0")"
ci=0
checked=0
if [ "${1:-}" = "--checked" ]; then
  checked=1
  shift
fi
if [ "${1:-}" = "--ci" ]; then
  ci=1
  shift
fi
secs=${1:?usage: fuzz/run.sh [--checked] [--ci] SECONDS [TARGET...]}
shift
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(urdf ros_yaml map_image movingai_2d movingai_3d sim_scenario states_json states_struct
    eval_json eval_cases sim_scenario_struct mission_toml mission_struct sweep_toml sweep_struct
    collision_mesh collision_text)
fi
build=(cargo fuzz build -s none -O)
tdir=target
if [ $checked = 1 ]; then
  tdir=target/checked
  build+=(-a --target-dir "$tdir")
fi
if [ "${FUZZ_NO_BUILD:-0}" != "1" ]; then
  "${build[@]}"
fi
host=$(rustc -vV | sed -n 's/^host: //p')
bins=$tdir/$host/release
limits=(-rss_limit_mb=2048 -timeout=10)
failed=()
for t in "${targets[@]}"; do
  mkdir -p "artifacts/$t"
  if [ $ci = 1 ]; then
    echo "== fuzz $t: replay the committed seeds and regression inputs"
    replay=("corpus/$t")
    if [ -d "regressions/$t" ]; then
      replay+=("regressions/$t")
    fi
    if ! "$bins/$t" "${limits[@]}" -artifact_prefix="artifacts/$t/" -runs=0 "${replay[@]}"; then
      failed+=("$t(replay)")
      continue
    fi
    scratch=$(mktemp -d "${TMPDIR:-/tmp}/moma-fuzz-$t.XXXXXX")
    echo "== fuzz $t (${secs}s, -seed=1)"
    "$bins/$t" "${limits[@]}" -artifact_prefix="artifacts/$t/" -seed=1 \
      -max_total_time="$secs" -print_final_stats=1 "$scratch" "corpus/$t" || failed+=("$t")
    rm -rf "$scratch"
  else
    scratch=target/fuzz-corpus/$t
    mkdir -p "$scratch"
    echo "== fuzz $t (${secs}s)"
    "$bins/$t" "${limits[@]}" -artifact_prefix="artifacts/$t/" -max_total_time="$secs" \
      -print_final_stats=1 "$scratch" "corpus/$t" || failed+=("$t")
  fi
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz targets that found a crash, panic, timeout or memory blow-up: ${failed[*]}"
  exit 1
fi
