#!/usr/bin/env bash
# moma against Pinocchio on the same robots, with the same method, in one run.
#
#   bench/compare_pinocchio.sh [--no-write]
#
# 1. Runs bench/pinocchio/run.sh (Pinocchio 4.1.0 from PyPI, cached in
#    ~/.cache/moma-pinocchio-bench; the first run compiles for ~10 minutes), both variants:
#    header-only -O3 -march=native, and the prebuilt library.
# 2. Builds `moma` twice (portable, and RUSTFLAGS="-C target-cpu=native") and runs
#    `moma bench --json` on the same example-robot-data URDFs.
# 3. Prints the ratio table moma / Pinocchio (the faster of its two variants, per robot and
#    algorithm; < 1 means moma is faster) and, unless --no-write, writes it into the
#    "## Rigid-body dynamics" section of BENCHMARKS.md (between the rigid-body markers).
# Env: NBATCH, WARMUP (passed to both), CARGO_TARGET_DIR (portable build),
#      MOMA_NATIVE_TARGET_DIR (native build; default $CARGO_TARGET_DIR/native).
set -euo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/.." && pwd)"
WRITE=1
[ "${1:-}" = "--no-write" ] && WRITE=0
CACHE="${MOMA_PEERS_CACHE:-${XDG_CACHE_HOME:-$HOME/.cache}/moma-pinocchio-bench}"
OUT="$(mktemp -d)"
trap 'rm -rf "$OUT"' EXIT

echo "# Pinocchio..." >&2
"$HERE/pinocchio/run.sh" > "$OUT/pinocchio.txt"
SP="$("$CACHE/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
ERD="$SP/cmeel.prefix/share/example-robot-data/robots"

TD="${CARGO_TARGET_DIR:-$ROOT/target}"
TDN="${MOMA_NATIVE_TARGET_DIR:-$TD/native}"
echo "# building moma (portable, then target-cpu=native)..." >&2
(cd "$ROOT" && CARGO_TARGET_DIR="$TD" cargo build --release --locked -q -p moma-cli)
(cd "$ROOT" && CARGO_TARGET_DIR="$TDN" RUSTFLAGS="-C target-cpu=native" cargo build --release --locked -q -p moma-cli)

# label  urdf (relative to the robots folder)  root  frame  extra
ROBOTS=(
  "panda panda_description/urdf/panda.urdf fixed panda_hand_tcp"
  "panda_planar panda_description/urdf/panda.urdf planar panda_hand_tcp"
  "panda_freeflyer panda_description/urdf/panda.urdf free-flyer panda_hand_tcp --zero-gravity"
  "ur5 ur_description/urdf/ur5_robot.urdf fixed tool0"
  "tiago tiago_description/robots/tiago.urdf fixed arm_tool_link"
  "tiago_no_hand_planar tiago_description/robots/tiago_no_hand.urdf planar arm_tool_link"
)
for variant in portable native; do
  BIN="$TD/release/moma"
  [ "$variant" = native ] && BIN="$TDN/release/moma"
  for r in "${ROBOTS[@]}"; do
    read -r label urdf root frame extra <<< "$r"
    echo "# moma ($variant) $label..." >&2
    # shellcheck disable=SC2086
    "$BIN" bench "$ERD/$urdf" --root "$root" --frame "$frame" --label "$label" $extra --json \
      > "$OUT/moma_${variant}_${label}.json"
  done
done

python3 - "$OUT" "$ROOT/BENCHMARKS.md" "$WRITE" "$(uname -m)" "$(nproc)" <<'PY'
import glob, json, os, re, sys, datetime
out, md_path, write, arch, ncpu = sys.argv[1], sys.argv[2], sys.argv[3] == "1", sys.argv[4], sys.argv[5]
pin = {}
notes = []
for line in open(os.path.join(out, "pinocchio.txt")):
    if line.startswith("#"):
        if "loadavg" in line or "pinocchio 4" in line or "mode:" in line:
            notes.append(line.strip("# \n"))
        continue
    robot, algo, nq, nv, ns = line.split()
    key = (robot, algo)
    pin[key] = min(pin.get(key, float("inf")), float(ns))
moma = {}
for f in glob.glob(os.path.join(out, "moma_*.json")):
    variant = os.path.basename(f).split("_")[1]
    d = json.load(open(f))
    for algo, ns in d["median_ns"].items():
        moma[(variant, d["robot"], algo)] = ns
robots = ["panda", "panda_planar", "panda_freeflyer", "ur5", "tiago", "tiago_no_hand_planar"]
# rows appear once `moma bench --json` reports the algorithm under the same key
algos = ["rnea", "crba", "aba", "fk", "frame_jacobian", "osc", "rnea_derivatives", "aba_derivatives"]
rows = ["| robot | algorithm | Pinocchio (ns, faster variant) | moma portable (ns) | ratio | moma native (ns) | ratio |",
        "| --- | --- | ---: | ---: | ---: | ---: | ---: |"]
worst = 0.0
for r in robots:
    for a in algos:
        p = pin.get((r, a))
        mp = moma.get(("portable", r, a))
        mn = moma.get(("native", r, a))
        if p is None or mp is None or mn is None:
            continue
        worst = max(worst, min(mp, mn) / p)
        rows.append(f"| {r} | {a} | {p:.0f} | {mp:.0f} | {mp / p:.2f} | {mn:.0f} | {mn / p:.2f} |")
table = "\n".join(rows)
stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
block = f"""<!-- rigid-body:begin -->
Measured {stamp} on {arch} ({ncpu} cores) by `bench/compare_pinocchio.sh`: median ns per call
over 100 seeded random states (batches after warm-up, the method of
`bench/pinocchio/pinocchio_bench.cpp`); ratio = moma / Pinocchio (< 1: moma faster).
Pinocchio: {'; '.join(notes[:3])}.
Worst ratio (best moma build per row): {worst:.2f}.

{table}
<!-- rigid-body:end -->"""
print(table)
print(f"worst ratio: {worst:.2f}")
if write:
    md = open(md_path).read() if os.path.exists(md_path) else "# Benchmarks\n"
    if "<!-- rigid-body:begin -->" in md:
        md = re.sub(r"<!-- rigid-body:begin -->.*<!-- rigid-body:end -->", lambda m: block, md, flags=re.S)
    elif "## Rigid-body dynamics" in md:
        md = md.replace("## Rigid-body dynamics\n", "## Rigid-body dynamics\n\n" + block + "\n", 1)
    else:
        md = md.rstrip() + "\n\n## Rigid-body dynamics\n\n" + block + "\n"
    open(md_path, "w").write(md)
PY
