"""Writes the Pinocchio 4.1 reference cases of moma's frame derivatives
(`crates/moma/tests/data/derivatives/frame_*.json`).

Usage (from the repository root, Pinocchio 4.1.0 in the Python environment:
`pip install pin==4.1.0`):

    python bench/frame_derivatives_pinocchio.py crates/moma/tests/data/derivatives

For each robot (URDFs of `crates/moma/tests/data/pinocchio/urdf/`), root (fixed, planar,
free-flyer) and one end-effector frame, two seeded random states q = neutral ⊕
U(−π, π)^nv, v, a ~ U(−1, 1), and, in each reference frame (LOCAL, WORLD,
LOCAL_WORLD_ALIGNED), the outputs of `computeForwardKinematicsDerivatives(model, data, q,
v, a)` followed by `getFrameVelocityDerivatives` and `getFrameAccelerationDerivatives`,
the frame Jacobian of `computeJointJacobians` + `getFrameJacobian`, and the frame's
velocity and acceleration of `forwardKinematics` + `getFrameVelocity` /
`getFrameAcceleration`, all in Pinocchio's layout (planar root [x, y, cos θ, sin θ] with a
base-frame velocity, continuous joints [cos θ, sin θ]).

Each file records the largest deviation of Pinocchio's derivatives from central finite
differences (q through pinocchio.integrate) relative to max(1, max |entry|), for LOCAL and
WORLD (LOCAL_WORLD_ALIGNED's ∂/∂q are not derivatives of the LOCAL_WORLD_ALIGNED
quantities in Pinocchio; see moma's `dynamics::frame_derivatives`).
"""
import json
import os
import sys

import numpy as np
import pinocchio as pin

SEED = 20261205
URDF_DIR = "../pinocchio/urdf"  # relative to the output folder
CASES = [
    ("ur5_fixed", "ur5_robot.urdf", "fixed", "tool0"),
    ("ur5_planar", "ur5_robot.urdf", "planar", "tool0"),
    ("ur5_freeflyer", "ur5_robot.urdf", "free-flyer", "tool0"),
    ("panda_fixed", "panda.urdf", "fixed", "panda_hand_tcp"),
    ("panda_planar", "panda.urdf", "planar", "panda_hand_tcp"),
    ("panda_freeflyer", "panda.urdf", "free-flyer", "panda_hand_tcp"),
    ("tiago_fixed", "tiago.urdf", "fixed", "arm_tool_link"),
    ("tiago_planar", "tiago.urdf", "planar", "arm_tool_link"),
    ("tiago_freeflyer", "tiago.urdf", "free-flyer", "arm_tool_link"),
]
ROOTS = {"fixed": None, "planar": pin.JointModelPlanar, "free-flyer": pin.JointModelFreeFlyer}
FRAMES = {"local": pin.LOCAL, "world": pin.WORLD, "local_world_aligned": pin.LOCAL_WORLD_ALIGNED}


def rows(m):
    return np.asarray(m).tolist()


def motion(model, data, fid, q, v, a, rf):
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    return (pin.getFrameVelocity(model, data, fid, rf).vector,
            pin.getFrameAcceleration(model, data, fid, rf).vector)


def fd_check(model, data, fid, q, v, a, out, h=1e-6):
    worst = 0.0
    nv = model.nv
    for name in ["local", "world"]:
        rf = FRAMES[name]
        vq, aq, av = np.zeros((6, nv)), np.zeros((6, nv)), np.zeros((6, nv))
        for j in range(nv):
            e = np.zeros(nv)
            e[j] = h
            (v1, a1), (v0, a0) = (motion(model, data, fid, pin.integrate(model, q, s * e), v, a, rf)
                                  for s in (1, -1))
            vq[:, j] = (v1 - v0) / (2 * h)
            aq[:, j] = (a1 - a0) / (2 * h)
            (_, a1), (_, a0) = (motion(model, data, fid, q, v + s * e, a, rf) for s in (1, -1))
            av[:, j] = (a1 - a0) / (2 * h)
        for key, m in [("dv_dq", vq), ("da_dq", aq), ("da_dv", av)]:
            ref = np.asarray(out[name][key])
            worst = max(worst, np.abs(m - ref).max() / max(1.0, np.abs(ref).max()))
    return worst


def main(out_dir):
    for name, urdf, root, frame in CASES:
        path = os.path.join(out_dir, URDF_DIR, urdf)
        model = (pin.buildModelFromUrdf(path) if ROOTS[root] is None
                 else pin.buildModelFromUrdf(path, ROOTS[root]()))
        data = model.createData()
        fid = model.getFrameId(frame)
        rng = np.random.default_rng(SEED)
        nv = model.nv
        states = []
        fd_worst = 0.0
        for _ in range(2):
            q = pin.integrate(model, pin.neutral(model), rng.uniform(-np.pi, np.pi, nv))
            v = rng.uniform(-1, 1, nv)
            a = rng.uniform(-1, 1, nv)
            s = {"q": q.tolist(), "v": v.tolist(), "a": a.tolist()}
            pin.framesForwardKinematics(model, data, q)
            s["placement"] = {"translation": data.oMf[fid].translation.tolist(),
                              "rotation": rows(data.oMf[fid].rotation)}
            for key, rf in FRAMES.items():
                pin.computeJointJacobians(model, data, q)
                pin.updateFramePlacements(model, data)
                jac = pin.getFrameJacobian(model, data, fid, rf)
                vel, acc = motion(model, data, fid, q, v, a, rf)
                pin.computeForwardKinematicsDerivatives(model, data, q, v, a)
                dv_dq, dv_dv = pin.getFrameVelocityDerivatives(model, data, fid, rf)
                pin.computeForwardKinematicsDerivatives(model, data, q, v, a)
                v_dq, da_dq, da_dv, da_da = pin.getFrameAccelerationDerivatives(model, data, fid, rf)
                assert np.abs(v_dq - dv_dq).max() == 0.0
                s[key] = {"jacobian": rows(jac), "velocity": vel.tolist(),
                          "acceleration": acc.tolist(), "dv_dq": rows(dv_dq),
                          "dv_dv": rows(dv_dv), "da_dq": rows(da_dq), "da_dv": rows(da_dv),
                          "da_da": rows(da_da)}
            fd_worst = max(fd_worst, fd_check(model, data, fid, q, v, a, s))
            states.append(s)
        doc = {
            "source": {
                "pinocchio_version": pin.__version__,
                "script": "bench/frame_derivatives_pinocchio.py",
                "seed": SEED, "numpy_rng": "default_rng (PCG64)",
                "functions": "computeForwardKinematicsDerivatives(model, data, q, v, a); "
                             "getFrameVelocityDerivatives / getFrameAccelerationDerivatives"
                             "(model, data, frame_id, rf); computeJointJacobians + "
                             "getFrameJacobian; forwardKinematics + getFrameVelocity / "
                             "getFrameAcceleration",
                "finite_difference_check_local_world": fd_worst,
            },
            "robot": name, "urdf": URDF_DIR + "/" + urdf, "root": root, "frame": frame,
            "layout": "pinocchio", "nq": model.nq, "nv": nv, "states": states,
        }
        with open(os.path.join(out_dir, "frame_" + name + ".json"), "w") as f:
            json.dump(doc, f)
        print(name, "nv", nv, "fd check", fd_worst)


if __name__ == "__main__":
    main(sys.argv[1])
