#!/usr/bin/env python3
"""Reference values from Pinocchio for moma's rigid-body tests.

Writes, for a URDF and a root joint, the same schema as the Pinocchio reference sets in
crates/moma/tests/data/pinocchio/: joints, limits and, per seeded random state, rnea,
crba (full symmetric), aba, nle, gravity, com, the centroidal map and two frames'
placements and local-world-aligned Jacobians. q and v are in Pinocchio's layout
(planar [x, y, cos, sin] with a local base velocity; continuous [cos, sin]).

    python pinocchio_refs.py URDF ROOT(fixed|planar|free-flyer) ROBOT_NAME EE_FRAME OUT.json [NSTATES]

Needs `pip install pin==4.1.0` (run inside the venv that bench/pinocchio/run.sh creates).
"""
import json
import sys

import numpy as np
import pinocchio as pin

urdf, root, robot, ee_name, out = sys.argv[1:6]
nstates = int(sys.argv[6]) if len(sys.argv) > 6 else 5
seed = 20261122

if root == "fixed":
    model = pin.buildModelFromUrdf(urdf)
elif root == "planar":
    model = pin.buildModelFromUrdf(urdf, pin.JointModelPlanar())
elif root == "free-flyer":
    model = pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer())
else:
    raise SystemExit(f"unknown root {root}")
data = model.createData()
rng = np.random.default_rng(seed)


def random_q():
    q = np.zeros(model.nq)
    for j in model.joints[1:]:
        iq, nq = j.idx_q, j.nq
        lo = model.lowerPositionLimit[iq:iq + nq]
        hi = model.upperPositionLimit[iq:iq + nq]
        name = j.shortname()
        if name == "JointModelFreeFlyer":
            q[iq:iq + 3] = rng.uniform(-1.0, 1.0, 3)
            quat = rng.normal(size=4)
            q[iq + 3:iq + 7] = quat / np.linalg.norm(quat)
        elif name == "JointModelPlanar":
            th = rng.uniform(-np.pi, np.pi)
            q[iq:iq + 4] = [rng.uniform(-2, 2), rng.uniform(-2, 2), np.cos(th), np.sin(th)]
        elif nq == 2:  # continuous (unbounded revolute)
            th = rng.uniform(-np.pi, np.pi)
            q[iq:iq + 2] = [np.cos(th), np.sin(th)]
        else:
            lo_ = np.where(np.isfinite(lo), lo, -np.pi)
            hi_ = np.where(np.isfinite(hi), hi, np.pi)
            q[iq:iq + nq] = rng.uniform(lo_, hi_)
    return q


def frame_entry(fid, q):
    pin.framesForwardKinematics(model, data, q)
    pin.computeJointJacobians(model, data, q)
    M = data.oMf[fid]
    J = pin.getFrameJacobian(model, data, fid, pin.LOCAL_WORLD_ALIGNED)
    quat = pin.Quaternion(M.rotation).coeffs()  # x, y, z, w
    return {
        "name": model.frames[fid].name,
        "position": M.translation.tolist(),
        "rotation": M.rotation.tolist(),
        "quaternion_xyzw": quat.tolist(),
        "jacobian_local_world_aligned": J.tolist(),
    }


states = []
for _ in range(nstates):
    q = random_q()
    v = rng.normal(size=model.nv)
    a = rng.normal(size=model.nv)
    tau_in = rng.normal(size=model.nv) * 5.0
    rnea_tau = pin.rnea(model, data, q, v, a).copy()
    M = pin.crba(model, data, q).copy()
    M = np.triu(M) + np.triu(M, 1).T
    ddq = pin.aba(model, data, q, v, tau_in).copy()
    nle = pin.nonLinearEffects(model, data, q, v).copy()
    g = pin.computeGeneralizedGravity(model, data, q).copy()
    com = pin.centerOfMass(model, data, q).copy()
    Ag = pin.computeCentroidalMap(model, data, q).copy()
    states.append({
        "q": q.tolist(), "v": v.tolist(), "a": a.tolist(), "tau_in": tau_in.tolist(),
        "rnea_tau": rnea_tau.tolist(), "crba_M": M.tolist(), "aba_ddq": ddq.tolist(),
        "nle": nle.tolist(), "gravity_torque": g.tolist(), "com": com.tolist(),
        "centroidal_map_Ag": Ag.tolist(),
        "last_frame": frame_entry(len(model.frames) - 1, q),
        "ee_frame": frame_entry(model.getFrameId(ee_name), q),
        "residual_M_ddq_plus_nle_minus_tau_in": float(np.abs(M @ ddq + nle - tau_in).max()),
        "residual_M_a_plus_nle_minus_rnea_tau": float(np.abs(M @ a + nle - rnea_tau).max()),
    })

doc = {
    "generator": f"Pinocchio {pin.__version__} (Python bindings), bench/reference/pinocchio_refs.py",
    "pinocchio_version": pin.__version__,
    "robot": robot,
    "urdf": "urdf/" + urdf.split("/")[-1],
    "urdf_source": "example-robot-data " + "/".join(urdf.split("/")[-4:]),
    "root_joint": root,
    "gravity": model.gravity.linear.tolist(),
    "nq": model.nq, "nv": model.nv, "njoints": model.njoints, "nframes": model.nframes,
    "total_mass": float(pin.computeTotalMass(model)),
    "joints": [
        {"name": model.names[i], "type": model.joints[i].shortname(),
         "idx_q": model.joints[i].idx_q, "idx_v": model.joints[i].idx_v,
         "nq": model.joints[i].nq, "nv": model.joints[i].nv,
         "parent": model.names[model.parents[i]]}
        for i in range(1, model.njoints)
    ],
    "neutral_q": pin.neutral(model).tolist(),
    "lower_position_limit": [x if np.isfinite(x) else None for x in model.lowerPositionLimit],
    "upper_position_limit": [x if np.isfinite(x) else None for x in model.upperPositionLimit],
    "seed": seed,
    "numpy_rng": "default_rng (PCG64)",
    "conventions": {
        "spatial_vectors": "[linear; angular]",
        "jacobian": "6 x nv, LOCAL_WORLD_ALIGNED, rows 0-2 linear, 3-5 angular",
        "quaternion_storage": "[x, y, z, w]",
        "freeflyer_q": "[x, y, z, qx, qy, qz, qw]; v = [v_lin, omega] in LOCAL base frame",
        "planar_q": "[x, y, cos(theta), sin(theta)]; v = [vx, vy, omega] in LOCAL base frame",
        "continuous_joint_q": "[cos(theta), sin(theta)]; v = [omega]",
        "crba_M": "full symmetric",
        "aba_ddq": "forward dynamics for tau_in (not for rnea_tau)",
        "mimic_joints": "ignored: every URDF joint is an independent DoF",
    },
    "states": states,
}
with open(out, "w") as f:
    json.dump(doc, f, indent=1)
print(f"{out}: {robot} root={root} nq={model.nq} nv={model.nv} njoints={model.njoints} nframes={model.nframes}")
