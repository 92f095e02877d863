#!/usr/bin/env bash
# Runs fuzz targets one after another (never two at once on a shared machine).
#   fuzz/run.sh SECONDS [TARGET...]    (default: every target)
# New inputs go to a scratch corpus under target/fuzz-corpus/, the committed seeds in
# fuzz/corpus/ are only read; crashes land in fuzz/artifacts/TARGET/.
set -euo pipefail
cd "$(dirname "$0")"
secs=${1:?usage: fuzz/run.sh SECONDS [TARGET...]}
shift
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(urdf ros_yaml map_image movingai_2d movingai_3d sim_scenario states_json states_struct
    eval_json eval_cases sim_scenario_struct)
fi
cargo fuzz build -s none -O
failed=()
for t in "${targets[@]}"; do
  scratch=target/fuzz-corpus/$t
  mkdir -p "$scratch"
  echo "== fuzz $t (${secs}s)"
  cargo fuzz run -s none -O "$t" "$scratch" "corpus/$t" -- \
    -max_total_time="$secs" -rss_limit_mb=2048 -timeout=10 -print_final_stats=1 ||
    failed+=("$t")
done
if [ ${#failed[@]} -gt 0 ]; then
  echo "fuzz targets that found a crash, panic, timeout or memory blow-up: ${failed[*]}"
  exit 1
fi
