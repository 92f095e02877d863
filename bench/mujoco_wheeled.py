"""MuJoCo step rate on the diff-drive arm (the robot of scenarios/robots/diffdrive_arm.urdf).

Two MJCF models of the same robot (same masses, inertias, joint placements):
  * mujoco_wheeled.xml:        free-floating base on the floor, wheels as hinge joints
                               with frictional cylinder contacts, frictionless caster
                               sphere (MuJoCo's way of modelling wheels);
  * mujoco_wheeled_planar.xml: base on slide x / slide y / hinge z, no contacts and no
                               no-side-slip constraint (MuJoCo has no non-holonomic
                               equality constraint).
Both use the RK4 integrator with dt = 1 ms (as moma's fixed-step runs) and constant
torques. Reported: median wall time per mj_step over several repeats, timed in C via
mujoco.rollout when available (else a Python loop, which adds call overhead).

Usage: python bench/mujoco_wheeled.py [--steps N] [--repeats R]
"""

import argparse
import json
import os
import statistics
import time

import mujoco

HERE = os.path.dirname(os.path.abspath(__file__))


def rate(xml, steps, repeats):
    m = mujoco.MjModel.from_xml_path(os.path.join(HERE, xml))
    d = mujoco.MjData(m)
    ctrl = [0.25, 0.45, 0.0, 0.0, 0.0]
    times = []
    try:
        from mujoco import rollout
        import numpy as np

        for _ in range(repeats):
            mujoco.mj_resetData(m, d)
            d.ctrl[:] = ctrl
            state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
            mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
            controls = np.tile(np.array(ctrl), (steps, 1))
            t0 = time.perf_counter()
            rollout.rollout(m, d, state, controls)
            times.append((time.perf_counter() - t0) / steps)
        how = "mujoco.rollout (C loop)"
    except Exception:  # older mujoco without rollout
        times = []
        for _ in range(repeats):
            mujoco.mj_resetData(m, d)
            d.ctrl[:] = ctrl
            t0 = time.perf_counter()
            for _ in range(steps):
                mujoco.mj_step(m, d)
            times.append((time.perf_counter() - t0) / steps)
        how = "Python loop of mj_step"
    med = statistics.median(times)
    return {
        "model": xml,
        "nq": m.nq,
        "nv": m.nv,
        "integrator": "RK4",
        "timestep": m.opt.timestep,
        "median_us_per_step": med * 1e6,
        "steps_per_second": 1.0 / med,
        "timed_with": how,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=7)
    a = ap.parse_args()
    out = {
        "mujoco_version": mujoco.__version__,
        "results": [
            rate("mujoco_wheeled.xml", a.steps, a.repeats),
            rate("mujoco_wheeled_planar.xml", a.steps, a.repeats),
        ],
    }
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()
