"""moma's contact plant against MuJoCo on a robot of the comparison, under the same torques.

Robots (ROBOTS below): `diffdrive_arm` (scenarios/robots/diffdrive_arm.urdf, MuJoCo model
bench/mujoco_contact.xml) and `mobile_manipulator` (the UR5-class mobile manipulator of
scenarios/robots/mobile_manipulator.urdf, bench/mujoco_contact_mobile_manipulator.xml).

Reads the trajectories written by `cargo run --release --example contact_rollout -- ROBOT DIR`
(DIR/contact_{roll,brake,spin}.json: each carries its robot, torque schedule, arm joints, PD
gains and friction coefficient), replays every scenario in MuJoCo on the robot's model with
the same torque law (wheel torques linear between the knots, arm u = kp (q_ref - q) - kd
qdot from MuJoCo's own state, every step; joints matched by name), and prints the
differences:

  roll   largest base position (m), yaw (rad) and wheel-speed (rad/s) difference over the
         run, sampled every 10 ms;
  brake  the time the first contact lifts off (its lowest point 1 mm above the ground) after
         the settling time, the time its normal force first reaches zero, and the time a
         loaded wheel's contact point first slides at 0.2 m/s;
  spin   the time a loaded wheel's contact point first slides at 0.2 m/s (the same
         threshold on both; four times the regularisation velocity of moma's friction).

With --reference FILE it also writes the MuJoCo figures the Rust test
crates/moma/tests/contact_mujoco.rs checks against.

With --time it also times mj_step on the robot's model (semi-implicit Euler, 0.1 ms) in a C
loop (mujoco.rollout): 5000 steps from the `roll` replay's state at 0.5 s with the
controls that replay applied next (the wheels rolling, the arm held), median of 7 repeats.

Usage: python bench/mujoco_contact_compare.py ROBOT DIR [--reference FILE] [--time]
"""

import argparse
import json
import math
import os

import mujoco
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
# Per robot: the MuJoCo model, and the geoms of moma's contacts in moma's order (the two
# wheels, then the casters).
ROBOTS = {
    "diffdrive_arm": ("mujoco_contact.xml", ["left_wheel", "right_wheel", "caster"]),
    "mobile_manipulator": ("mujoco_contact_mobile_manipulator.xml", [
        "left_wheel", "right_wheel", "caster_front_left", "caster_front_right",
        "caster_rear_left", "caster_rear_right"]),
}
WHEEL_JOINTS = ("left_wheel_joint", "right_wheel_joint")


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


def model_xml(robot="diffdrive_arm"):
    """The text of the robot's MuJoCo model (bench/mujoco_contact_settings.py varies it)."""
    with open(os.path.join(HERE, ROBOTS[robot][0])) as f:
        return f.read()


def replay(sc, xml=None, probe=None):
    """Replays scenario `sc` on the model `xml` (default: the model of the scenario's
    robot). Each record carries per contact (in moma's order) the normal force and the
    magnitude of the tangential force, from mj_contactForce. `probe(m, d)`, if given, is
    called after every step."""
    robot = sc["robot"]
    m = mujoco.MjModel.from_xml_string(xml if xml is not None else model_xml(robot))
    d = mujoco.MjData(m)
    mu = sc["mu"]
    for g in ("floor", "left_wheel", "right_wheel"):
        m.geom_friction[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g)][0] = mu
    dt = sc["params"]["dt"]
    assert abs(m.opt.timestep - dt) < 1e-15, "the MJCF step must be moma's"
    geom_names = ROBOTS[robot][1]
    assert len(geom_names) == len(sc["contacts"]), (geom_names, sc["contacts"])
    geoms = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, g) for g in geom_names]
    ncontacts = len(geoms)
    wheel_bodies = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, b) for b in ("left_wheel", "right_wheel")]
    wheel_r = sc["wheel_radius"]

    def joint(name):
        j = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, name)
        assert j >= 0, name
        act = [a for a in range(m.nu) if m.actuator_trnid[a][0] == j]
        assert len(act) == 1, name
        return m.jnt_qposadr[j], m.jnt_dofadr[j], act[0]

    wheel_q, wheel_v, wheel_u = (np.array(x) for x in zip(*(joint(n) for n in WHEEL_JOINTS)))
    arm_q, arm_v, arm_u = (np.array(x) for x in zip(*(joint(n) for n in sc["arm_joints"])))
    arm_ref = np.array(sc["arm_ref"])
    base = sc["base_q0"]  # x, y, z, qx, qy, qz, qw
    d.qpos[:] = 0
    d.qpos[0:3] = base[0:3]
    d.qpos[3:7] = [base[6], base[3], base[4], base[5]]
    d.qpos[arm_q] = arm_ref
    mujoco.mj_forward(m, d)
    kp, kd = np.array(sc["kp"]), np.array(sc["kd"])
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
            normal = [0.0] * ncontacts
            tangential = [0.0] * ncontacts
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
                vp = v + np.cross(w, np.array([0.0, 0.0, -wheel_r]))
                slip.append(float(np.hypot(vp[0], vp[1])))
            lowest = [float(d.geom_xpos[g][2] - m.geom_size[g][0]) for g in geoms]
            if t > sc["settle"]:
                for j in range(ncontacts):
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
                    "wheel_speeds": [float(x) for x in d.qvel[wheel_v]],
                    "arm_q": [float(x) for x in d.qpos[arm_q]],
                    "normal": normal, "tangential": tangential, "slip_speed": slip,
                })
        if k < nsteps:
            d.ctrl[wheel_u] = wheel_torques(sc["wheel_knots"], t)
            d.ctrl[arm_u] = kp * (arm_ref - d.qpos[arm_q]) - kd * d.qvel[arm_v]
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


def time_step(roll, start=5000, steps=5000, repeats=7):
    """mj_step's cost on the robot of the `roll` scenario: `steps` steps from the replay's
    state after `start` steps, with the controls the replay applied next."""
    import statistics
    import time

    from mujoco import rollout

    robot = roll["robot"]
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    saved = {"ctrl": []}

    def probe(m, d):
        n = int(round(d.time / m.opt.timestep))
        if n == start:
            saved["state"] = np.empty(mujoco.mj_stateSize(m, spec))
            mujoco.mj_getState(m, d, saved["state"], spec)
        elif start < n <= start + steps:
            saved["ctrl"].append(d.ctrl.copy())

    replay(roll, probe=probe)
    m = mujoco.MjModel.from_xml_string(model_xml(robot))
    d = mujoco.MjData(m)
    ctrl = np.array(saved["ctrl"])
    assert ctrl.shape == (steps, m.nu), ctrl.shape
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        rollout.rollout(m, d, saved["state"], ctrl)
        times.append((time.perf_counter() - t0) / steps)
    return {"model": ROBOTS[robot][0], "integrator": "Euler", "timestep": m.opt.timestep,
            "median_us_per_step": statistics.median(times) * 1e6}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("robot", choices=sorted(ROBOTS))
    ap.add_argument("dir")
    ap.add_argument("--reference")
    ap.add_argument("--time", action="store_true")
    a = ap.parse_args()
    xml = ROBOTS[a.robot][0]
    out = {"mujoco_version": mujoco.__version__, "robot": a.robot}
    ref = {"source": f"MuJoCo {mujoco.__version__} (PyPI), bench/{xml}, "
                     f"bench/mujoco_contact_compare.py {a.robot}"}
    scen = {}
    for name in ("roll", "brake", "spin"):
        with open(os.path.join(a.dir, f"contact_{name}.json")) as f:
            sc = json.load(f)
        if sc.get("robot") != a.robot:
            raise SystemExit(f"{a.dir}/contact_{name}.json is of robot {sc.get('robot')!r}, not {a.robot!r}")
        scen[name] = sc
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
        out["mj_step"] = time_step(scen["roll"])
    print(json.dumps(out, indent=2))
    if a.reference:
        with open(a.reference, "w") as f:
            json.dump(ref, f, indent=2)
            f.write("\n")


if __name__ == "__main__":
    main()
