"""MuJoCo step rate on Panda as a free-floating space manipulator (zero gravity).

The same URDF as moma's `space` bench (crates/moma/tests/data/pinocchio/urdf/panda.urdf,
visual and collision elements removed), given a free joint at its root link with
mujoco.MjSpec, gravity zero, contacts disabled, RK4 with dt = 1 ms, constant joint
torques (motors on every hinge/slide joint). Reported: median wall time per mj_step over
several repeats, timed in C with mujoco.rollout.

Usage: python bench/mujoco_space.py [--steps N] [--repeats R]
"""

import argparse
import json
import os
import re
import statistics
import time

import mujoco
import numpy as np
from mujoco import rollout

HERE = os.path.dirname(os.path.abspath(__file__))
URDF = os.path.join(HERE, "../crates/moma/tests/data/pinocchio/urdf/panda.urdf")


def model():
    text = open(URDF).read()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.S)
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    spec = mujoco.MjSpec.from_string(text)
    root = spec.worldbody.first_body()
    root.add_freejoint()
    for j in spec.joints:
        if j.type in (mujoco.mjtJoint.mjJNT_HINGE, mujoco.mjtJoint.mjJNT_SLIDE):
            a = spec.add_actuator()
            a.target = j.name
            a.trntype = mujoco.mjtTrn.mjTRN_JOINT
    spec.option.gravity = [0.0, 0.0, 0.0]
    spec.option.timestep = 1e-3
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_RK4
    spec.option.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
    return spec.compile()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()
    m = model()
    d = mujoco.MjData(m)
    ctrl = np.full(m.nu, 0.05)
    times = []
    for _ in range(args.repeats):
        mujoco.mj_resetData(m, d)
        d.qvel[:] = 0.1
        state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
        mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        controls = np.tile(ctrl, (args.steps, 1))
        t0 = time.perf_counter()
        rollout.rollout(m, d, state, controls)
        times.append((time.perf_counter() - t0) / args.steps)
    med = statistics.median(times)
    print(json.dumps({"mujoco": mujoco.__version__, "nq": m.nq, "nv": m.nv, "nu": m.nu,
                      "median_step_us": med * 1e6, "steps_per_s": 1.0 / med}, indent=1))


if __name__ == "__main__":
    main()
