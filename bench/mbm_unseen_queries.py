#!/usr/bin/env python3
"""Draws MotionBenchMaker Fetch queries nobody has planned on: for each seed of `--seeds`, one
scene per goal query of every problem (bench/ompl_fetch_mbm.py's compute_goals: the objects' own
variations from the problem's variation file, start = MotionBenchMaker's default state, goal state
by collision-free damped-least-squares IK of the query's gripper pose), written as one query folder
(`moma motion-bench`'s SCENE_DIR, bench/motion_check_coal.sh's --dir) whose names end in -sSEED.
A URDF scene (kitchen, table_bars) becomes one mesh object per link at the URDF's zero joint
positions (mesh files copied beside the scenes), placed at the problem's base_offset from
base_link (table_bars; see ompl_fetch_mbm.in_base_frame); its variation file moves those
objects by link name. With `--draw mbm` the scenes are drawn as MotionBenchMaker's code
draws them (SceneSampler::sample: the base_offset and the World variation applied in the world
frame, T·M, as MoveIt's World::moveObject does; positions Gaussian; a URDF scene's joints
uniform within their limits, so the kitchen's doors stand open at random and table_bars's bars
slide). Plan on those with `moma motion --mesh exact`.
Runs in the peers' venv (Pinocchio 4.1.0 + coal, PyYAML):

    ~/.cache/moma-pinocchio-bench/venv/bin/python bench/mbm_unseen_queries.py --mbm MBM_DIR --seeds 11,12,13,14,15 [--problems P,...] [--draw uniform|mbm] --out DIR

then check every motion moma returns on them with coal:

    bench/motion_check_coal.sh --dir DIR --goal state|pose --time 1|10 [--mesh exact] [--json OUT]
"""
import argparse
import os
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
from mbm_fetch_queries import write_query_folder  # noqa: E402
from ompl_fetch_mbm import Fetch, compute_goals  # noqa: E402

ROOT = os.path.dirname(HERE)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--mbm", required=True, help="MotionBenchMaker folder (configs/problems, configs/scenes)")
    ap.add_argument("--fetch", default=os.path.join(ROOT, "crates/moma/tests/data/robots/fetch"))
    ap.add_argument("--seeds", default="11,12,13,14,15", help="comma-separated numpy seeds, one scene per goal query each")
    ap.add_argument("--problems", default=None, help="comma-separated problem names (default: every problem)")
    ap.add_argument("--draw", choices=["uniform", "mbm"], default="uniform",
                    help="uniform: the objects' own variations uniform in [-bound, bound], no World variation, a URDF "
                         "scene at zero joint positions; mbm: as MotionBenchMaker's code draws (Gaussian positions, "
                         "the World variation, a URDF scene's joints uniform within their limits)")
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    seeds = [int(s) for s in args.seeds.split(",")]
    fetch = Fetch(args.fetch)
    merged = None
    for seed in seeds:
        goals = compute_goals(fetch, args.mbm, "gripper_link", seed, 1, urdf_scenes=True,
                              problems=args.problems.split(",") if args.problems else None, draw=args.draw)
        for q in goals["queries"]:
            q["sample"] = f"{q['sample']}-s{seed}"
        if merged is None:
            merged = goals
        else:
            merged["queries"] += goals["queries"]
    missing = [f"{q['problem']}-{q['tag']}-{q['object']}-{q['sample']}" for q in merged["queries"] if q.get("goal_q") is None]
    source = (f"MotionBenchMaker (scenes, variation files, goal queries) drawn with seeds {args.seeds} by "
              "bench/mbm_unseen_queries.py; start = MotionBenchMaker's default Fetch state; goal states by "
              "damped-least-squares IK with Pinocchio (bench/ompl_fetch_mbm.py's compute_goals)")
    n = write_query_folder(merged, args.out, source)
    print(f"{n} queries written to {args.out}; no collision-free IK goal in 20 scene draws: {missing or 'none'}")


if __name__ == "__main__":
    main()
