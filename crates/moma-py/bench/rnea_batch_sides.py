"""Side-by-side rounds of rnea_vs_pin.py in the configurations of BENCHMARKS.md's Python
section: one rayon thread timed in process CPU time, and all threads (two on the
benchmark machine) timed in wall-clock time, for one or more builds of the package;
configurations alternate round by round, and the table gives the medians over rounds
of each round's medians.

    .venv/bin/python crates/moma-py/bench/rnea_batch_sides.py [--rounds 5] \\
        [--build portable=] [--build native=/path/holding/a/moma/package]

A build is NAME=DIR: DIR is put first on PYTHONPATH (empty: the installed package).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

BENCH = Path(__file__).resolve().parent / "rnea_vs_pin.py"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=5)
    ap.add_argument("--inner", type=int, default=3, help="rounds inside each bench run")
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--batch", type=int, default=10000)
    ap.add_argument("--build", action="append", default=[], help="NAME=DIR (repeatable)")
    args = ap.parse_args()
    builds = [b.split("=", 1) for b in args.build] or [["installed", ""]]
    configs = [(name, path, threads) for name, path in builds for threads in ("1", "all")]
    results = {c: [] for c in configs}
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "r.json")
        for r in range(args.rounds):
            for c in configs:
                name, path, threads = c
                env = dict(os.environ)
                if path:
                    env["PYTHONPATH"] = path + os.pathsep + env.get("PYTHONPATH", "")
                cmd = [sys.executable, str(BENCH), "--rounds", str(args.inner), "--calls", str(args.calls),
                       "--batch", str(args.batch), "--no-tiago", "--json", out]
                if threads == "1":
                    env["RAYON_NUM_THREADS"] = "1"
                else:
                    env.pop("RAYON_NUM_THREADS", None)
                    cmd.append("--wall")
                subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL)
                with open(out) as f:
                    results[c].append(json.load(f))
            print(f"round {r + 1}/{args.rounds} done", file=sys.stderr)
    med = statistics.median
    keys = ["moma.rnea", "pinocchio.rnea", "loop", "moma.rnea_batch"]
    head = [f"{n}, {'1 thread CPU' if t == '1' else 'all threads wall'}" for n, _, t in configs]
    print("| Panda, ns per call / per state | " + " | ".join(head) + " |")
    print("| --- |" + " ---: |" * len(configs))
    label = {"moma.rnea": "`moma.rnea`", "pinocchio.rnea": "`pinocchio.rnea`",
             "loop": "Python loop of `moma.rnea`", "moma.rnea_batch": f"`moma.rnea_batch` ({args.batch} states)",
             "moma.rnea_batch out": "the same with `out=` a reused array"}
    for k in keys:
        print(f"| {label[k]} | " + " | ".join(f"{med(x[k] for x in results[c]):.0f}" for c in configs) + " |")
    print("| batch speed-up over the loop | " + " | ".join(
        f"{med(x['loop'] for x in results[c]) / med(x['moma.rnea_batch'] for x in results[c]):.1f}×" for c in configs) + " |")
    if all("moma.rnea_batch out" in x for c in configs for x in results[c]):
        print(f"| {label['moma.rnea_batch out']} | " + " | ".join(f"{med(x['moma.rnea_batch out'] for x in results[c]):.0f}" for c in configs) + " |")
        print("| speed-up with `out=` | " + " | ".join(
            f"{med(x['loop'] for x in results[c]) / med(x['moma.rnea_batch out'] for x in results[c]):.1f}×" for c in configs) + " |")
    print("| `moma.rnea` / `pinocchio.rnea` | " + " | ".join(
        f"{med(x['moma.rnea'] for x in results[c]) / med(x['pinocchio.rnea'] for x in results[c]):.2f}" for c in configs) + " |")


if __name__ == "__main__":
    main()
