"""Generates osc_tiago_planar.json: Khatib's operational-space quantities of TIAGo's
`arm_tool_link` on a planar base, entirely in Pinocchio's layout (q = [x, y, cos θ,
sin θ, ...], base-frame velocity, continuous joints as cos/sin pairs), from Pinocchio 4.1
(crba, nonLinearEffects, LOCAL_WORLD_ALIGNED frame Jacobian, classical frame acceleration
at a = 0) and numpy. The states (q, v) are those of ../pinocchio/tiago_planar.json; the
task accelerations and null-space torques are seeded. Usage (from this folder):
python generate_osc_tiago_planar.py"""
import json

import numpy as np
import pinocchio as pin

dump = json.load(open("../pinocchio/tiago_planar.json"))
model = pin.buildModelFromUrdf("../pinocchio/urdf/tiago.urdf", pin.JointModelPlanar())
data = model.createData()
fid = model.getFrameId("arm_tool_link")
rng = np.random.default_rng(20261202)
states = []
for s in dump["states"]:
    q, v = np.array(s["q"]), np.array(s["v"])
    xdd = rng.normal(size=6)
    tau0 = rng.normal(size=model.nv)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    h = pin.nonLinearEffects(model, data, q, v)
    pin.forwardKinematics(model, data, q, v, np.zeros(model.nv))
    pin.updateFramePlacements(model, data)
    J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
    acc = pin.getFrameClassicalAcceleration(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    jdv = np.concatenate([acc.linear, acc.angular])
    Minv_Jt = np.linalg.solve(M, J.T)
    Lam = np.linalg.inv(J @ Minv_Jt)
    Jbar = Minv_Jt @ Lam
    N = np.eye(model.nv) - Jbar @ J
    F = Lam @ (xdd - jdv + J @ np.linalg.solve(M, h))
    tau = J.T @ F + N.T @ tau0
    states.append({
        "q": q.tolist(), "v": v.tolist(), "task_acceleration": xdd.tolist(),
        "null_torque": tau0.tolist(), "task_inertia": Lam.tolist(),
        "dynamically_consistent_inverse": Jbar.tolist(), "nullspace_projector": N.tolist(),
        "acceleration_bias": jdv.tolist(), "task_force": F.tolist(), "torque": tau.tolist(),
    })
out = {
    "generator": "Pinocchio %s (Python bindings) and numpy, generate_osc_tiago_planar.py"
    % pin.__version__,
    "robot": "tiago", "urdf": "../pinocchio/urdf/tiago.urdf", "root_joint": "planar",
    "layout": "pinocchio", "frame": "arm_tool_link", "rows": "full",
    "nq": model.nq, "nv": model.nv, "states": states,
}
with open("osc_tiago_planar.json", "w") as f:
    json.dump(out, f)
