"""Generates tiago_planar.json and tiago_freeflyer.json with Pinocchio 4.1.0 (Python
bindings; `pip install pin==4.1.0 example-robot-data==5.0.0`), in the schema of the shared
reference files (panda.json, ...). Usage: python generate_tiago.py ROBOTS_DIR
where ROBOTS_DIR is example-robot-data's `robots` folder."""
import json
import sys

import numpy as np
import pinocchio as pin

from pin_reference import joint_table, random_state

robots = sys.argv[1]
urdf = robots + "/tiago_description/robots/tiago.urdf"
for root, name in [("planar", "tiago_planar"), ("freeflyer", "tiago_freeflyer")]:
    rj = pin.JointModelPlanar() if root == "planar" else pin.JointModelFreeFlyer()
    model = pin.buildModelFromUrdf(urdf, rj)
    data = model.createData()
    rng = np.random.default_rng(20240601)
    joints = joint_table(model)
    states = []
    for _ in range(3):
        s, q, _ = random_state(model, data, rng)
        for key, fname in [("last_frame", "hand_grasping_frame"), ("ee_frame", "arm_tool_link")]:
            fid = model.getFrameId(fname)
            pin.framesForwardKinematics(model, data, q)
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
            M_f = data.oMf[fid]
            s[key] = {"name": fname, "position": M_f.translation.tolist(),
                      "rotation": M_f.rotation.tolist(),
                      "jacobian_local_world_aligned": J.tolist()}
        states.append(s)
    out = {
        "generator": "Pinocchio %s (Python bindings), generate_tiago.py" % pin.__version__,
        "pinocchio_version": pin.__version__, "robot": name, "urdf": "urdf/tiago.urdf",
        "urdf_source": "example-robot-data robots/tiago_description/robots/tiago.urdf",
        "root_joint": root, "gravity": model.gravity.linear.tolist(), "nq": model.nq,
        "nv": model.nv, "njoints": model.njoints, "nframes": model.nframes,
        "total_mass": pin.computeTotalMass(model), "joints": joints,
        "lower_position_limit": model.lowerPositionLimit.tolist(),
        "upper_position_limit": model.upperPositionLimit.tolist(), "states": states,
    }
    with open(name + ".json", "w") as f:
        json.dump(out, f)
