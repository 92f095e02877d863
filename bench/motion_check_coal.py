#!/usr/bin/env python3
"""Checks moma's arm motions with someone else's geometry: Pinocchio + coal on the exact meshes.

For every query of a moma query folder (`moma motion-bench`'s SCENE_DIR, default the shipped
MotionBenchMaker Fetch set), runs `moma motion` (goal state, or `--goal pose`) and checks the
returned JSON with Pinocchio's kinematics and coal's collision checks (exact triangle meshes,
SRDF-enabled self pairs and every link x scene object pair, as bench/ompl_fetch_mbm.py's
validity checker):

* start: the trajectory's and the path's first state equal the query's start;
* goal: the last state equals the goal state (goal state), or gripper_link's pose is within the
  position / orientation tolerance of the goal pose (goal pose);
* joint limits: every group joint within the URDF limits (continuous joints in [-pi, pi]);
* no contact: every path segment and every chord between trajectory samples, at states at most
  `--step` apart per joint (default 1 mrad / 1 mm), collision-free.

    bench/motion_check_coal.sh [--moma BIN] [--dir QUERY_DIR] [--goal state|pose] [--time S] [--seed N] [--mesh convex|exact] [--json OUT]

Prints one line per query and a summary (solved, median / 95th-percentile planning time of the
solved, coal verdicts); `--json` writes the per-query rows. An exit status of `moma motion` other
than 0 (solved) or 3 (not solved, with its reason) is a failure: it is printed and counted (a
panic, or exit 1 on a query whose inputs are valid). Exit 1 if any query failed so.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, HERE)
from ompl_fetch_mbm import GROUP, Checker, Fetch, load_scene, scene_geometry  # noqa: E402


def to_pin(fetch, names, q):
    return fetch.full_q(dict(zip(names, q)))


def dense(points, step):
    out = [np.asarray(points[0], float)]
    for a, b in zip(points[:-1], points[1:]):
        a, b = np.asarray(a, float), np.asarray(b, float)
        n = max(1, int(np.ceil(np.max(np.abs(b - a)) / step)))
        for k in range(1, n + 1):
            out.append(a + (b - a) * k / n)
    return out


def check(fetch, checker, names, out, query, goal_kind, pos_tol, rot_tol, step, ee="gripper_link"):
    """The failed checks of one solved output (empty list: all passed) and the states checked."""
    fails = []
    path, traj = out["path"], out["trajectory"]["q"]
    start = np.array(query["start"])
    if not (np.array_equal(path[0], start) and np.array_equal(traj[0], start)):
        fails.append("start differs")
    if goal_kind == "state":
        if np.max(np.abs(np.array(traj[-1]) - np.array(query["goal_state"]))) > 1e-9:
            fails.append("goal state not reached")
    else:
        q = to_pin(fetch, names, traj[-1])
        pin.framesForwardKinematics(fetch.model, fetch.data, q)
        M = fetch.data.oMf[fetch.model.getFrameId(ee)]
        p, quat = query["goal_pose"][:3], query["goal_pose"][3:]
        x, y, z, w = quat
        T = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(p))
        err = pin.log6(T.actInv(M)).vector
        if np.linalg.norm(M.translation - T.translation) > pos_tol or np.linalg.norm(err[3:]) > rot_tol:
            fails.append("goal pose outside the tolerance")
    idx = [names.index(n) for n in GROUP]
    for q in traj + path:
        x = np.array(q)[idx]
        if np.any(x < fetch.lo - 1e-9) or np.any(x > fetch.hi + 1e-9):
            fails.append("joint limits")
            break
    n = 0
    for pts in (path, traj):
        for q in dense(pts, step):
            n += 1
            if not checker.free(to_pin(fetch, names, q)):
                fails.append("contact")
                break
        if fails and fails[-1] == "contact":
            break
    return fails, n


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--moma", default=os.path.join(ROOT, "target", "release", "moma"))
    ap.add_argument("--dir", default=os.path.join(ROOT, "crates/moma/tests/data/scenes/motion_bench_maker/fetch_queries"))
    ap.add_argument("--fetch", default=os.path.join(ROOT, "crates/moma/tests/data/robots/fetch"))
    ap.add_argument("--goal", choices=["state", "pose"], default="state")
    ap.add_argument("--position-tolerance", type=float, default=0.01)
    ap.add_argument("--orientation-tolerance", type=float, default=0.01)
    ap.add_argument("--time", type=float, default=1.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--step", type=float, default=1e-3)
    ap.add_argument("--problem", default=None)
    ap.add_argument("--json", default=None, help="per-query rows (default: no file)")
    ap.add_argument("--mesh", choices=["convex", "exact"], default="convex",
                    help="moma motion's --mesh: the scenes' meshes as hulls or as triangles")
    args = ap.parse_args()
    with open(os.path.join(args.dir, "queries.json")) as f:
        qf = json.load(f)
    names = qf["joint_order"]
    fetch = Fetch(args.fetch)
    urdf = os.path.join(args.fetch, "fetch_description", "robots", "fetch.urdf")
    srdf = os.path.join(args.fetch, "fetch.srdf")
    tmp = tempfile.mkdtemp(prefix="moma_check_")
    out_path = os.path.join(tmp, "out.json")
    rows = []
    for q in qf["queries"]:
        if args.problem and q["problem"] != args.problem:
            continue
        scene = os.path.join(args.dir, q["scene"])
        for key in ("start", "goal_state"):
            with open(os.path.join(tmp, key + ".json"), "w") as f:
                json.dump({"states": [{"q": q[key]}]}, f)
        cmd = [args.moma, "motion", urdf, "--root", "fixed", "--srdf", srdf, "--package-dir", args.fetch,
               "--scene", scene, "--group", ",".join(qf["group"]), "--start", os.path.join(tmp, "start.json"),
               "--time-limit", str(args.time), "--seed", str(args.seed), "--mesh", args.mesh, "--output", out_path]
        if args.goal == "state":
            cmd += ["--goal-state", os.path.join(tmp, "goal_state.json")]
        else:
            cmd += ["--goal-pose", f"{qf['ee_frame']}:" + ",".join(map(repr, q["goal_pose"])),
                    "--position-tolerance", str(args.position_tolerance),
                    "--orientation-tolerance", str(args.orientation_tolerance)]
        if os.path.exists(out_path):
            os.remove(out_path)  # a run that writes nothing must not be read as the previous query's
        r = subprocess.run(cmd, capture_output=True, text=True)
        row = {"name": q["name"], "problem": q["problem"], "exit": r.returncode, "solved": False,
               "time_s": None, "fails": [], "reason": None}
        rows.append(row)
        if r.returncode not in (0, 3) or not os.path.exists(out_path):
            row["fails"] = [f"exit {r.returncode}"]
            row["reason"] = r.stderr.strip()
            print(f"{q['name']:40s} FAILED: exit {r.returncode}: {r.stderr.strip()}", flush=True)
            continue
        with open(out_path) as f:
            out = json.load(f)
        row["time_s"] = out["planning_time_s"]
        if not out["solved"]:
            row["reason"] = out["reason"]
            print(f"{q['name']:40s} not solved: {out['reason']}", flush=True)
            continue
        row["solved"] = True
        checker = Checker(fetch, scene_geometry(fetch, load_scene(scene))[0])
        row["fails"], n = check(fetch, checker, names, out, q, args.goal, args.position_tolerance,
                                args.orientation_tolerance, args.step)
        print(f"{q['name']:40s} solved in {out['planning_time_s'] * 1e3:7.1f} ms, {n:6d} states checked "
              f"by coal: {'ok' if not row['fails'] else 'FAILED: ' + ', '.join(row['fails'])}", flush=True)
    solved = [r for r in rows if r["solved"]]
    failed = [r for r in rows if r["fails"]]
    ts = np.array([r["time_s"] for r in solved]) * 1e3
    pct = f"median {np.median(ts):.1f} ms, p95 {np.percentile(ts, 95):.1f} ms" if len(ts) else "no times"
    print(f"# {len(solved)}/{len(rows)} solved ({pct}); {len(solved) - sum(1 for r in solved if r['fails'])}"
          f"/{len(solved)} solved motions pass every check; {len(failed)} failures "
          f"(Pinocchio {pin.__version__}, exact meshes by coal, step {args.step}, goal {args.goal}, "
          f"time limit {args.time} s, loadavg {os.getloadavg()[0]:.1f})")
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"settings": vars(args), "rows": rows}, f, indent=1)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
