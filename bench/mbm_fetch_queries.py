#!/usr/bin/env python3
"""Exports the MotionBenchMaker Fetch queries of bench/ompl_fetch_mbm_goals.json (scenes drawn
from the problems' variation files, start and IK goal states, goal poses) as the query folder
`moma motion-bench` reads: QUERY_DIR/queries.json and one MoveIt planning-scene YAML per query
under QUERY_DIR/scenes/. Queries without a start or goal state are left out. Standard library only.

    python3 bench/mbm_fetch_queries.py [--goals bench/ompl_fetch_mbm_goals.json] [--out DIR]
"""
import argparse
import json
import os
import shutil

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def scene_yaml(objects, mesh_dir=None):
    """Planning-scene YAML of the objects; a mesh object's file is copied into `mesh_dir` (the
    scene's folder) and named relative to it."""
    lines = ["# MotionBenchMaker scene drawn from the problem's variation file (bench/mbm_fetch_queries.py)",
             "world:", "  collision_objects:"]
    for o in objects:
        if o["type"] == "mesh":
            shutil.copy(o["resource"], mesh_dir)
            lines += [f"    - header: {{frame_id: base_link}}",
                      f"      id: {o['id']}",
                      f"      meshes:",
                      f"        - resource: {os.path.basename(o['resource'])}",
                      f"      mesh_poses:",
                      f"        - position: {json.dumps(o['position'])}",
                      f"          orientation: {json.dumps(o['orientation'])}"]
            continue
        lines += [f"    - header: {{frame_id: base_link}}",
                  f"      id: {o['id']}",
                  f"      primitives:",
                  f"        - type: {o['type']}",
                  f"          dimensions: {json.dumps(o['dimensions'])}",
                  f"      primitive_poses:",
                  f"        - position: {json.dumps(o['position'])}",
                  f"          orientation: {json.dumps(o['orientation'])}"]
    return "\n".join(lines) + "\n"


def write_query_folder(goals, out, source, name_suffix=""):
    """Writes the queries of `goals` (bench/ompl_fetch_mbm.py's layout) with a start and a goal
    state as a query folder under `out`; each name ends with `name_suffix`. Returns the count."""
    os.makedirs(os.path.join(out, "scenes"), exist_ok=True)
    queries = []
    for q in goals["queries"]:
        if q.get("start_q") is None or q.get("goal_q") is None:
            continue
        name = f"{q['problem']}-{q['tag']}-{q['object']}-{q['sample']}{name_suffix}".replace(" ", "_")
        scene = f"scenes/{name}.yaml"
        with open(os.path.join(out, scene), "w") as f:
            f.write(scene_yaml(q["scene_objects"], os.path.join(out, "scenes")))
        pose = q["goal_pose"]
        queries.append({"name": name, "problem": q["problem"], "scene": scene, "start": q["start_q"],
                        "goal_state": q["goal_q"], "goal_pose": pose["position"] + pose["orientation_xyzw"]})
    doc = {
        "source": source,
        "joint_order": goals["joint_order"],
        "group": goals["group"],
        "ee_frame": goals["ee_link"],
        "queries": queries,
    }
    with open(os.path.join(out, "queries.json"), "w") as f:
        f.write("{\n")
        for k in ("source", "joint_order", "group", "ee_frame"):
            f.write(f" {json.dumps(k)}: {json.dumps(doc[k])},\n")
        f.write(' "queries": [\n')
        f.write(",\n".join("  " + json.dumps(q, separators=(",", ":")) for q in queries))
        f.write("\n ]\n}\n")
    return len(queries)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--goals", default=os.path.join(HERE, "ompl_fetch_mbm_goals.json"))
    ap.add_argument("--out", default=os.path.join(ROOT, "crates/moma/tests/data/scenes/motion_bench_maker/fetch_queries"))
    args = ap.parse_args()
    with open(args.goals) as f:
        goals = json.load(f)
    source = ("MotionBenchMaker (scenes, variation files, goal queries); start = MotionBenchMaker's "
              "default Fetch state; goal states by damped-least-squares IK with Pinocchio 4.1.0 "
              "(bench/ompl_fetch_mbm.py, its note in bench/ompl_fetch_mbm_goals.json)")
    n = write_query_folder(goals, args.out, source)
    print(f"{n} queries written to {args.out}")


if __name__ == "__main__":
    main()
