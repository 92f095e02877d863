"""Which part of MuJoCo's contact decides the `brake` and `spin` events of the contact
comparison on the diff-drive arm: replays the scenarios of `cargo run --release --example
contact_rollout -- diffdrive_arm DIR` (DIR/contact_{brake,spin}.json) on
bench/mujoco_contact.xml with one setting changed at a time, and prints one row per setting:

  brake  the first slip (a loaded wheel's contact point at 0.2 m/s), the caster's lift-off
         (lowest point 1 mm up) and the time its normal force first reaches zero; the left
         wheel's normal force N and tangential force T at 1.31 s and 1.33 s (the wheels are
         symmetric) and the moma trajectory's, for the record;
  spin   the first time a contact's normal force is zero (a wheel, bouncing), and the first
         slip.

Then, to show where MuJoCo's wheel normal force departs from a spring's, the left wheel's
contact at a few instants: penetration delta (from the normal row's efc_pos), N and T
(mj_contactForce), the slip speed (the friction rows' efc_vel), and k delta + c delta_dot
(delta_dot from the normal row's efc_vel) with moma's default k and c: in `brake` on the
shipped model and on the penalty setting, and in `spin` on the shipped model. --probes-only prints only these.

Settings: the shipped model; the pyramidal cone; impratio 10 and 100; 10 noslip iterations;
condim 4 (torsional friction 0.01) and 6 (and rolling friction 0.001) on the wheels;
cylinder wheels; solref time constants 0.02 s and 0.05 s; constraint impedance 0.5 and 0.1
(solimp); and a penalty contact: impedance 0.001 with solref given directly as stiffness
and damping scaled by each contact's approximate inverse mass (MuJoCo's body_invweight0),
so that the normal force is k delta + c delta_dot with moma's default k and c.

With --robot mobile_manipulator (DIR from `contact_rollout -- mobile_manipulator DIR`) it
prints instead one row per setting of the mobile manipulator's disagreements
(bench/mujoco_contact_mobile_manipulator.xml): the brake's rear-caster lift-off, the
turn's (`spin`) slip onset, and the roll's largest differences from moma's trajectory
(base position, heading, wheel speeds), for the shipped model, the pyramidal cone,
impratio 10 and 0.1, 10 noslip iterations, a 25 us step, and solimp 0.99-0.999 and 0.5.

Usage: python bench/mujoco_contact_settings.py DIR [--robot diffdrive_arm|mobile_manipulator]
"""

import argparse
import json
import math
import os
import re

import mujoco
import numpy as np

from mujoco_contact_compare import compare_roll, model_xml, replay

WHEEL_GEOM = re.compile(r'(<geom name="(?:left|right)_wheel") type="sphere" size="0\.08" condim="3" friction="1 0 0"')
DEFAULT = '<geom solref="0.01 1" solimp="0.95 0.99 0.001"/>'
CASTER = 'condim="1" priority="1"'


def sub(pattern, repl, count):
    """An edit replacing `pattern` (regex) by `repl`, checking it matched `count` times."""
    def edit(xml):
        out, n = re.subn(pattern, repl, xml)
        assert n == count, (pattern, n)
        return out
    return edit


def option(attrs):
    return sub(r'cone="elliptic"/>', f'cone="elliptic" {attrs}/>', 1)


def wheels(attrs):
    return sub(WHEEL_GEOM, lambda mt: mt.group(0).replace(
        'condim="3" friction="1 0 0"', attrs), 2)


def penalty(stiffness=1e5, damping=2e3, impedance=0.001):
    """Normal force k delta + c delta_dot: with impedance d, MuJoCo's force on a row is
    d (a_ref - a0) / A_hat with a_ref = -(damping v + stiffness r) / d for solref given as
    (-stiffness, -damping); A_hat, the row's approximate inverse mass, is fixed per body pair
    (body_invweight0), so solref (-k A_hat, -c A_hat) gives k delta + c delta_dot up to d a0."""
    m = mujoco.MjModel.from_xml_string(model_xml())
    def inv_mass(body):
        return m.body_invweight0[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, body)][0]
    aw, ac = inv_mass("left_wheel"), inv_mass("base")
    assert abs(aw - inv_mass("right_wheel")) < 1e-12
    def edit(xml):
        xml = sub(re.escape(DEFAULT), f'<geom solimp="{impedance} {impedance} 0.001"/>', 1)(xml)
        xml = sub(WHEEL_GEOM, lambda mt: mt.group(0)
                  + f' priority="1" solref="{-stiffness * aw} {-damping * aw}"', 2)(xml)
        return sub(re.escape(CASTER), CASTER + f' solref="{-stiffness * ac} {-damping * ac}"', 1)(xml)
    return edit


SETTINGS = [
    ("shipped (elliptic, solref 0.01 1, solimp 0.95 0.99 0.001, condim 3, spheres)", None),
    ("cone pyramidal", sub('cone="elliptic"', 'cone="pyramidal"', 1)),
    ("impratio 10", option('impratio="10"')),
    ("impratio 100", option('impratio="100"')),
    ("noslip_iterations 10", option('noslip_iterations="10"')),
    ("wheels condim 4 (torsional 0.01)", wheels('condim="4" friction="1 0.01 0"')),
    ("wheels condim 6 (torsional 0.01, rolling 0.001)", wheels('condim="6" friction="1 0.01 0.001"')),
    ("cylinder wheels", sub(WHEEL_GEOM, lambda mt: mt.group(1)
                             + ' type="cylinder" size="0.08 0.02" euler="90 0 0" condim="3" friction="1 0 0"', 2)),
    ("solref 0.02 1", sub(re.escape('solref="0.01 1"'), 'solref="0.02 1"', 1)),
    ("solref 0.05 1", sub(re.escape('solref="0.01 1"'), 'solref="0.05 1"', 1)),
    ("solimp 0.5 0.5 (impedance 0.5)", sub(re.escape('solimp="0.95 0.99 0.001"'), 'solimp="0.5 0.5 0.001"', 1)),
    ("solimp 0.1 0.1 (impedance 0.1)", sub(re.escape('solimp="0.95 0.99 0.001"'), 'solimp="0.1 0.1 0.001"', 1)),
    ("penalty: impedance 0.001, k = 1e5 N/m, c = 2e3 N s/m", penalty()),
]


def wheel_rows(times, stiffness=1e5, damping=2e3):
    """A probe for replay() printing the left wheel's contact at the given times."""
    force = np.zeros(6)

    def probe(m, d):
        if not any(abs(d.time - t) < 5e-5 for t in times):
            return
        g = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "left_wheel")
        for i in range(d.ncon):
            c = d.contact[i]
            if g in (c.geom1, c.geom2):
                a = c.efc_address
                mujoco.mj_contactForce(m, d, i, force)
                depth, rate = -d.efc_pos[a], -d.efc_vel[a]
                slip = math.hypot(d.efc_vel[a + 1], d.efc_vel[a + 2])
                print(f"  t = {d.time:.4f} s: penetration {depth * 1e3:.3f} mm, N {force[0]:.1f} N, "
                      f"T {math.hypot(force[1], force[2]):.1f} N, slip {slip:.3f} m/s, "
                      f"k delta + c delta_dot {stiffness * depth + damping * rate:.1f} N")
                return
        print(f"  t = {d.time:.4f} s: no contact")
    return probe


def at(records, t, key, j):
    return next(r[key][j] for r in records if abs(r["t"] - t) < 1e-6)


def event(e):
    return f'{e["t"]:.4f}' if e else "none"


MOBILE_MANIPULATOR_SETTINGS = [
    ("shipped (elliptic, impratio 1, 0.1 ms)", None, None),
    ("cone pyramidal", sub('cone="elliptic"', 'cone="pyramidal"', 1), None),
    ("impratio 10", option('impratio="10"'), None),
    ("impratio 0.1", option('impratio="0.1"'), None),
    ("noslip_iterations 10", option('noslip_iterations="10"'), None),
    ("timestep 25 us", sub('timestep="0.0001"', 'timestep="0.000025"', 1), 2.5e-5),
    ("solimp 0.99 0.999", sub(re.escape('solimp="0.95 0.99 0.001"'), 'solimp="0.99 0.999 0.001"', 1), None),
    ("solimp 0.5 0.5", sub(re.escape('solimp="0.95 0.99 0.001"'), 'solimp="0.5 0.5 0.001"', 1), None),
]


def mobile_manipulator_table(d):
    """The mobile manipulator's rows (one per setting, as the module says)."""
    scen = {}
    for name in ("roll", "brake", "spin"):
        with open(os.path.join(d, f"contact_{name}.json")) as f:
            scen[name] = json.load(f)
    print(f"MuJoCo {mujoco.__version__}; moma: brake lift {event(scen['brake']['first_lift'])}, "
          f"spin slip {event(scen['spin']['first_slip'])}")
    print("| MuJoCo setting | brake: rear caster lift-off (s) | turn: slip onset (s) "
          "| roll: position / heading / wheel speed |")
    print("| --- | --- | --- | --- |")
    for label, edit, dt in MOBILE_MANIPULATOR_SETTINGS:
        xml = model_xml("mobile_manipulator")
        if edit:
            xml = edit(xml)
        res = {}
        for name, sc in scen.items():
            if dt:
                sc = dict(sc, params=dict(sc["params"], dt=dt))
            res[name] = replay(sc, xml)
        r = compare_roll(scen["roll"], res["roll"])
        print(f'| {label} | {event(res["brake"]["first_lift"])} | {event(res["spin"]["first_slip"])} '
              f'| {r["max_position_diff_m"] * 1e3:.2f} mm / {r["max_yaw_diff_rad"] * 1e3:.2f} mrad '
              f'/ {r["max_wheel_speed_diff_rad_s"]:.3f} rad/s |', flush=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("dir")
    ap.add_argument("--probes-only", action="store_true")
    ap.add_argument("--robot", choices=["diffdrive_arm", "mobile_manipulator"], default="diffdrive_arm")
    a = ap.parse_args()
    if a.robot == "mobile_manipulator":
        mobile_manipulator_table(a.dir)
        return
    scen = {}
    for name in ("brake", "spin"):
        with open(os.path.join(a.dir, f"contact_{name}.json")) as f:
            scen[name] = json.load(f)
    if not a.probes_only:
        table(scen)
    probes(scen)


def table(scen):
    """The table of settings (one row each, as the module says)."""
    b = scen["brake"]
    mo = b["records"]
    print(f"MuJoCo {mujoco.__version__}; moma (stiffness {b['params']['stiffness']:g} N/m, "
          f"damping {b['params']['damping']:g} N s/m): brake slip {event(b['first_slip'])}, "
          f"lift {event(b['first_lift'])}, caster unloaded {event(b['first_unloaded'])}, "
          f"wheel N at 1.31 s {at(mo, 1.31, 'normal', 0):.1f} N; "
          f"spin slip {event(scen['spin']['first_slip'])}")
    print("| setting | brake: slip | lift-off | caster N = 0 | wheel N / T at 1.31 s | at 1.33 s "
          "| spin: N = 0 | slip |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for label, edit in SETTINGS:
        xml = model_xml()
        if edit:
            xml = edit(xml)
        br = replay(scen["brake"], xml)
        sp = replay(scen["spin"], xml)
        rec = br["records"]
        nt = [f'{at(rec, t, "normal", 0):.1f} / {at(rec, t, "tangential", 0):.1f}' for t in (1.31, 1.33)]
        print(f'| {label} | {event(br["first_slip"])} | {event(br["first_lift"])} '
              f'| {event(br["first_unloaded"])} | {nt[0]} N | {nt[1]} N '
              f'| {event(sp["first_unloaded"])} | {event(sp["first_slip"])} |', flush=True)


def probes(scen):
    print("brake, shipped model, left wheel:")
    replay(scen["brake"], model_xml(), wheel_rows([1.2999, 1.3001, 1.3002, 1.3005, 1.301]))
    print("brake, penalty setting, left wheel:")
    replay(scen["brake"], penalty()(model_xml()), wheel_rows([1.2999, 1.3005, 1.301, 1.31]))
    print("spin, shipped model, left wheel:")
    replay(scen["spin"], model_xml(), wheel_rows([0.955, 1.0, 1.05, 1.055, 1.06, 1.11, 1.4953]))


if __name__ == "__main__":
    main()
