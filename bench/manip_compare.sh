#!/usr/bin/env sh
# Runs the whole-body kinematics / manipulability benches of moma and the Pinocchio peer
# measurements in the same session (see BENCHMARKS.md, "Whole-body kinematics and
# manipulability"). Needs Python 3 with the PyPI packages `pin` and `numpy`.
set -eu
cd "$(dirname "$0")/.."
cargo bench -p moma --locked --bench manipulability -- --warm-up-time 1 --measurement-time 5
cargo build -p moma-cli --release --locked
/usr/bin/time -f "moma reach-map 100x100x8: %e s wall, %U s user CPU" \
  "${CARGO_TARGET_DIR:-target}/release/moma" reach-map crates/moma/tests/data/manipulability/panda.urdf \
  --frame panda_hand_tcp --target 1.0,0.5,0.5 --area 0,-0.5,1.98,1.48 --step 0.02 --headings 8
uptime
python3 bench/manip_pinocchio.py crates/moma/tests/data/manipulability/panda.urdf
