#!/usr/bin/env bash
# OMPL baseline for Fetch arm planning on the MotionBenchMaker problems (see the header of
# ompl_fetch_mbm.py for what is planned and how).
#
#   bench/ompl_fetch_mbm.sh [ompl_fetch_mbm.py options: --fetch DIR --mbm DIR --runs N --time S --json OUT --moma BIN ...]
#
# First run: installs Pinocchio 4.1.0 (with coal 3.0.3), OMPL 2.0.1 and PyYAML from PyPI into the
# venv of the peers' benchmarks (MOMA_PEERS_CACHE, default ~/.cache/moma-pinocchio-bench), the
# one bench/pinocchio/run.sh uses. Later runs reuse it.
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
CACHE="${MOMA_PEERS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/moma-pinocchio-bench}"
mkdir -p "$CACHE"
[ -x "$CACHE/venv/bin/python" ] || python3 -m venv "$CACHE/venv"
"$CACHE/venv/bin/python" -c 'import pinocchio, ompl, yaml' 2>/dev/null ||
  "$CACHE/venv/bin/pip" install -q pin==4.1.0 ompl==2.0.1 pyyaml==6.0.3
exec "$CACHE/venv/bin/python" "$HERE/ompl_fetch_mbm.py" "$@"
