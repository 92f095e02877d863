#!/usr/bin/env bash
# Checks moma's arm motions with Pinocchio + coal (see the header of motion_check_coal.py), in the
# peers' benchmark venv that bench/ompl_fetch_mbm.sh sets up (Pinocchio 4.1.0 with coal, OMPL,
# PyYAML from PyPI).
#
#   bench/motion_check_coal.sh [motion_check_coal.py options]
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
CACHE="${MOMA_PEERS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/moma-pinocchio-bench}"
mkdir -p "$CACHE"
[ -x "$CACHE/venv/bin/python" ] || python3 -m venv "$CACHE/venv"
"$CACHE/venv/bin/python" -c 'import pinocchio, ompl, yaml' 2>/dev/null ||
  "$CACHE/venv/bin/pip" install -q pin==4.1.0 ompl==2.0.1 pyyaml==6.0.3
exec "$CACHE/venv/bin/python" "$HERE/motion_check_coal.py" "$@"
