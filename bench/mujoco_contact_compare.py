"""moma's contact plant against MuJoCo on the diff-drive arm, under the same torques.

Reads the trajectories written by `cargo run --release --example contact_rollout -- DIR`
(DIR/contact_{roll,brake,spin}.json: each carries its torque schedule, arm PD gains and
friction coefficient), replays every scenario in MuJoCo on bench/mujoco_contact.xml with
the same torque law (wheel torques linear between the knots, arm u = kp (q_ref - q) - kd
qdot from MuJoCo's own state, every step), and prints the differences:

  roll   largest base position (m), yaw (rad) and wheel-speed (rad/s) difference over the
         run, sampled every 10 ms;
  brake  the time the first contact lifts off (its lowest point 1 mm above the ground) after
         the settling time, the time its normal force first reaches zero, and the time a
         loaded wheel's contact point first slides at 0.2 m/s;
  spin   the time a loaded wheel's contact point first slides at 0.2 m/s (the same
         threshold on both; four times the regularisation velocity of moma's friction).

With --reference FILE it also writes the MuJoCo figures the Rust test
crates/moma/tests/contact_mujoco.rs checks against.

With --time it also times mj_step on bench/mujoco_contact.xml (the model of the
comparison: semi-implicit Euler, 0.1 ms) in a C loop (mujoco.rollout), the robot rolling
under wheel torques (0.25, 0.45) N·m: median of 7 repeats of 5000 steps.

Usage: python bench/mujoco_contact_compare.py DIR [--reference FILE] [--time]
"""

import argparse
import json
import math
import os

import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
WHEEL_R = 0.08


def wheel_torques(knots, t):
    for a, b in zip(knots, knots[1:]):
        if a[0] <= t < b[0]:
            s = (t - a[0]) / (b[0] - a[0])
            return [a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])]
    last = knots[-1]
    if t >= last[0]:
        return [last[1], last[2]]
    return [knots[0][1], knots[0][2]]


def yaw_pitch(quat_wxyz):
    w, x, y, z = quat_wxyz
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    return yaw, pitch


def model_xml():
    """The text of bench/mujoco_contact.xml (bench/mujoco_contact_settings.py varies it)."""
    with open(os.path.join(HERE, "mujoco_contact.xml")) as f:
        return f.read()


def replay(sc, xml=None, probe=None):
    """Replays scenario `sc` on the model `xml` (default bench/mujoco_contact.xml). Each
    record carries per contact (left wheel, right wheel, caster) the normal force and the
    magnitude of the tangential force, from mj_contactForce. `probe(m, d)`, if given, is
    called after every step."""
    m = mujoco.MjModel.from_xml_string(xml if xml is not None else model_xml())
    d = mujoco.MjData(m)
    mu = sc["mu"]
    for g in ("floor", "left_wheel", "right_wheel"):
        m.geom_friction[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g)][0] = mu
    dt = sc["params"]["dt"]
    assert abs(m.opt.timestep - dt) < 1e-15, "the MJCF step must be moma's"
    geoms = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in ("left_wheel", "right_wheel", "caster")]
    wheel_bodies = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in ("left_wheel", "right_wheel")]
    arm_ref = np.array(sc["arm_ref"])
    d.qpos[:] = 0
    d.qpos[2] = 0.08
    d.qpos[3] = 1.0
    d.qpos[9:12] = arm_ref
    mujoco.mj_forward(m, d)
    kp, kd = sc["kp"], sc["kd"]
    nsteps = int(round(sc["duration"] / dt))
    every = int(round(0.01 / dt))
    records = []
    first_lift = None
    first_slip = None
    first_unloaded = None
    force = np.zeros(6)
    vel = np.zeros(6)
    for k in range(nsteps + 1):
        t = d.time
        if k > 0:
            normal = [0.0, 0.0, 0.0]
            tangential = [0.0, 0.0, 0.0]
            for i in range(d.ncon):
                c = d.contact[i]
                for j, g in enumerate(geoms):
                    if c.geom1 == g or c.geom2 == g:
                        mujoco.mj_contactForce(m, d, i, force)
                        normal[j] += force[0]
                        tangential[j] += math.hypot(force[1], force[2])
            slip = []
            for b in wheel_bodies:
                mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_BODY, b, vel, 0)
                w, v = vel[:3], vel[3:]
                vp = v + np.cross(w, np.array([0.0, 0.0, -WHEEL_R]))
                slip.append(float(np.hypot(vp[0], vp[1])))
            lowest = [float(d.geom_xpos[g][2] - m.geom_size[g][0]) for g in geoms]
            if t > sc["settle"]:
                for j in range(3):
                    if first_unloaded is None and normal[j] <= 0.0:
                        first_unloaded = {"t": t, "contact": sc["contacts"][j]}
                    if first_lift is None and lowest[j] >= sc["lift_height"]:
                        first_lift = {"t": t, "contact": sc["contacts"][j]}
                for j in range(2):
                    if first_slip is None and normal[j] > 0.0 and slip[j] >= sc["slip_speed"]:
                        first_slip = {"t": t, "contact": sc["contacts"][j]}
            if k % every == 0:
                yaw, pitch = yaw_pitch(d.qpos[3:7])
                records.append({
                    "t": t, "x": float(d.qpos[0]), "y": float(d.qpos[1]), "z": float(d.qpos[2]),
                    "yaw": yaw, "pitch": pitch,
                    "wheel_speeds": [float(d.qvel[6]), float(d.qvel[7])],
                    "arm_q": [float(x) for x in d.qpos[9:12]],
                    "normal": normal, "tangential": tangential, "slip_speed": slip,
                })
        if k < nsteps:
            w = wheel_torques(sc["wheel_knots"], t)
            d.ctrl[0:2] = w
            d.ctrl[2:5] = kp * (arm_ref - d.qpos[9:12]) - kd * d.qvel[8:11]
            mujoco.mj_step(m, d)
            if probe:
                probe(m, d)
    return {"records": records, "first_lift": first_lift, "first_slip": first_slip,
            "first_unloaded": first_unloaded}


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def compare_roll(moma, mj):
    pos = yaw = wheel = 0.0
    for a, b in zip(moma["records"], mj["records"]):
        assert abs(a["t"] - b["t"]) < 1e-6, (a["t"], b["t"])
        pos = max(pos, math.hypot(a["x"] - b["x"], a["y"] - b["y"]))
        yaw = max(yaw, abs(wrap(a["yaw"] - b["yaw"])))
        wheel = max(wheel, *(abs(p - q) for p, q in zip(a["wheel_speeds"], b["wheel_speeds"])))
    end = mj["records"][-1]
    return {
        "max_position_diff_m": pos,
        "max_yaw_diff_rad": yaw,
        "max_wheel_speed_diff_rad_s": wheel,
        "mujoco_end": {k: end[k] for k in ("t", "x", "y", "yaw", "wheel_speeds")},
        "moma_end": {k: moma["records"][-1][k] for k in ("t", "x", "y", "yaw", "wheel_speeds")},
    }


def time_step(steps=5000, repeats=7):
    import statistics
    import time

    from mujoco import rollout

    m = mujoco.MjModel.from_xml_path(os.path.join(HERE, "mujoco_contact.xml"))
    d = mujoco.MjData(m)
    ctrl = np.tile(np.array([0.25, 0.45, 0.0, 0.0, 0.0]), (steps, 1))
    times = []
    for _ in range(repeats):
        mujoco.mj_resetData(m, d)
        d.qpos[2] = 0.08
        d.qpos[3] = 1.0
        state = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
        mujoco.mj_getState(m, d, state, mujoco.mjtState.mjSTATE_FULLPHYSICS)
        t0 = time.perf_counter()
        rollout.rollout(m, d, state, ctrl)
        times.append((time.perf_counter() - t0) / steps)
    return {"model": "mujoco_contact.xml", "integrator": "Euler", "timestep": m.opt.timestep,
            "median_us_per_step": statistics.median(times) * 1e6}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--reference")
    ap.add_argument("--time", action="store_true")
    a = ap.parse_args()
    out = {"mujoco_version": mujoco.__version__}
    ref = {"source": f"MuJoCo {mujoco.__version__} (PyPI), bench/mujoco_contact.xml, bench/mujoco_contact_compare.py"}
    for name in ("roll", "brake", "spin"):
        with open(os.path.join(a.dir, f"contact_{name}.json")) as f:
            sc = json.load(f)
        mj = replay(sc)
        res = {k: {"moma": sc[k], "mujoco": mj[k]} for k in ("first_lift", "first_unloaded", "first_slip")}
        if name == "roll":
            res.update(compare_roll(sc, mj))
            ref["roll"] = [
                {k: r[k] for k in ("t", "x", "y", "yaw", "wheel_speeds")}
                for r in mj["records"] if abs(r["t"] - round(r["t"])) < 1e-6 and r["t"] > 0.5
            ]
        if name == "brake":
            ref["brake_first_lift"] = mj["first_lift"]
            ref["brake_first_slip"] = mj["first_slip"]
        if name == "spin":
            ref["spin_first_slip"] = mj["first_slip"]
        out[name] = res
    if a.time:
        out["mj_step"] = time_step()
    print(json.dumps(out, indent=2))
    if a.reference:
        with open(a.reference, "w") as f:
            json.dump(ref, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
