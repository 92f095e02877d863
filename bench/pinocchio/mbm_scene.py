#!/usr/bin/env python3
"""Flatten a MotionBenchMaker (MoveIt planning-scene) YAML into the text file that
coal_fetch_bench.cpp reads: one primitive per line,

    box      ID px py pz qx qy qz qw  sx sy sz          (full side lengths, m)
    cylinder ID px py pz qx qy qz qw  height radius     (axis = local z, centred)
    sphere   ID px py pz qx qy qz qw  radius

Poses are those of the YAML (quaternions [x, y, z, w]); every object must be in the robot's
`base_link` frame (all Fetch scenes of MotionBenchMaker are), mesh objects are refused.

    python mbm_scene.py SCENE.yaml OUT.txt
"""
import sys

import yaml


def main(src, dst):
    with open(src) as f:
        doc = yaml.safe_load(f)
    lines = []
    for obj in doc["world"]["collision_objects"]:
        frame = obj.get("header", {}).get("frame_id", "world")
        if frame != "base_link":
            sys.exit(f"{src}: object {obj.get('id')}: frame {frame!r}, only base_link is supported")
        if obj.get("meshes"):
            sys.exit(f"{src}: object {obj.get('id')}: meshes are not supported")
        for prim, pose in zip(obj["primitives"], obj["primitive_poses"]):
            kind = prim["type"]
            if kind not in ("box", "cylinder", "sphere"):
                sys.exit(f"{src}: object {obj['id']}: primitive {kind!r} not supported")
            nums = list(pose["position"]) + list(pose["orientation"]) + list(prim["dimensions"])
            lines.append(" ".join([kind, obj["id"]] + [repr(float(x)) for x in nums]))
    with open(dst, "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
