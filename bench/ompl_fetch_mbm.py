#!/usr/bin/env python3
"""OMPL baseline for Fetch arm planning on the MotionBenchMaker problems.

For every MotionBenchMaker Fetch problem whose scene is a planning-scene YAML (boxes, cylinders,
spheres), plan the `arm_with_torso` group (torso lift + 7 arm joints, from fetch.srdf) from the
problem's start (MotionBenchMaker's tucked default state, or an IK state for a `start_queries`
entry) to an IK goal state of its goal query, with OMPL's RRT-Connect; validity = no contact
between the exact triangle meshes (coal BVH through Pinocchio's computeCollisions with early
exit, through Pinocchio's broad-phase manager) over the SRDF-enabled self pairs and every
(link, scene object) pair. The other joints stay
at MotionBenchMaker's default state. 

IK goal (and start) states: a goal query gives a pose of the end-effector link (`--ee-link`,
default gripper_link: every query offset then is a pre-grasp pose some 20 cm from the object,
while with wrist_roll_link, the SRDF end effector's parent link, the bookshelf goals put the
gripper inside the can) as an offset from an object of the scene. For each query, damped least squares on the
8 group joints from seeded random restarts within the joint limits, until the pose is reached to
1e-5 m / 1e-4 rad and the state is collision-free (exact meshes). The states are written to
`--goals` (default bench/ompl_fetch_mbm_goals.json) and read back from it on later runs, so every
run (and moma's planner, through --goal-state) uses the same goal states.

Continuous joints (upperarm_roll, forearm_roll, wrist_roll) are planned as real coordinates in
[-pi, pi]. Motion validation: OMPL's discrete motion validator at a resolution of
`--resolution` (fraction of the space's maximum extent; default 0.005, MoveIt's default
longest_valid_segment_fraction); the absolute step is printed. Time limit per run `--time`
(default 1 s); `--runs` seeded runs per query (OMPL's global seed is set once, from `--seed`).
Queries: `--samples` scenes per goal query drawn from the problem's variation file (the objects'
own variations; the World variation is not applied), as MotionBenchMaker draws its samples.
Planning time = OMPL's own computation time of the solve call (no path simplification).

    python ompl_fetch_mbm.py [--fetch DIR] [--mbm DIR] [--runs N] [--time S] [--json OUT] [--moma BIN]

With `--moma BIN` the same run also plans every query with moma's CLI (`moma motion`, same scene
objects, start and goal state, time limit; seeds 0..runs-1) and prints its table after OMPL's.

Prints the success rate and the median / 95th-percentile planning time (successful runs) per
scene and overall, and writes the per-run results to --json.
"""
import argparse
import glob
import json
import math
import os
import platform
import sys
import time

import numpy as np
import pinocchio as pin
import yaml

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

GROUP = [
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
]
# MotionBenchMaker configs/robots/fetch.yaml robot_state (tucked arm, torso 0.1 m, fingers open).
DEFAULT_STATE = {
    "l_wheel_joint": 0.0, "r_wheel_joint": 0.0, "torso_lift_joint": 0.1, "bellows_joint": 0.05,
    "head_pan_joint": 0.0, "head_tilt_joint": 0.0, "shoulder_pan_joint": 1.32,
    "shoulder_lift_joint": 1.4, "upperarm_roll_joint": -0.2, "elbow_flex_joint": 1.72,
    "forearm_roll_joint": 0.0, "wrist_flex_joint": 1.66, "wrist_roll_joint": 0.0,
    "l_gripper_finger_joint": 0.05, "r_gripper_finger_joint": 0.05,
}


def pkg_path(uri, mbm_dir):
    prefix = "package://motion_bench_maker/"
    if not uri.startswith(prefix):
        raise ValueError(f"unexpected URI {uri}")
    return os.path.join(mbm_dir, uri[len(prefix):])


def pose_to_se3(position, orientation):
    x, y, z, w = orientation
    return pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(position, float))


class Fetch:
    def __init__(self, fetch_dir):
        urdf = os.path.join(fetch_dir, "fetch_description", "robots", "fetch.urdf")
        self.srdf = os.path.join(fetch_dir, "fetch.srdf")
        self.model = pin.buildModelFromUrdf(urdf)
        self.data = self.model.createData()
        self.geom = pin.buildGeomFromUrdf(self.model, urdf, pin.GeometryType.COLLISION, package_dirs=[fetch_dir])
        self.nrobot = len(self.geom.geometryObjects)
        self.jid = [self.model.getJointId(n) for n in GROUP]
        self.idx_q = [self.model.joints[j].idx_q for j in self.jid]
        self.idx_v = [self.model.joints[j].idx_v for j in self.jid]
        self.continuous = [self.model.joints[j].nq == 2 for j in self.jid]
        lo, hi = [], []
        for j, iq, c in zip(self.jid, self.idx_q, self.continuous):
            if c:
                lo.append(-math.pi)
                hi.append(math.pi)
            else:
                lo.append(self.model.lowerPositionLimit[iq])
                hi.append(self.model.upperPositionLimit[iq])
        self.lo, self.hi = np.array(lo), np.array(hi)
        self.q0 = self.full_q(DEFAULT_STATE)

    def full_q(self, by_name):
        q = pin.neutral(self.model)
        for name, val in by_name.items():
            j = self.model.getJointId(name)
            jm = self.model.joints[j]
            if jm.nq == 2:
                q[jm.idx_q], q[jm.idx_q + 1] = math.cos(val), math.sin(val)
            else:
                q[jm.idx_q] = val
        return q

    def set_group(self, q, x):
        q = q.copy()
        for iq, c, v in zip(self.idx_q, self.continuous, x):
            if c:
                q[iq], q[iq + 1] = math.cos(v), math.sin(v)
            else:
                q[iq] = v
        return q

    def get_group(self, q):
        return np.array([math.atan2(q[iq + 1], q[iq]) if c else q[iq]
                         for iq, c in zip(self.idx_q, self.continuous)])


def load_scene(scene_yaml):
    """The scene YAML's primitives: [{"id", "type", "dimensions", "position", "orientation"}]."""
    with open(scene_yaml) as f:
        doc = yaml.safe_load(f)
    prims = []
    for obj in doc["world"]["collision_objects"]:
        frame = obj.get("header", {}).get("frame_id", "world")
        if frame != "base_link":
            raise ValueError(f"{scene_yaml}: object {obj['id']} in frame {frame}")
        for mesh, pose in zip(obj.get("meshes") or [], obj.get("mesh_poses") or []):
            prims.append({"id": obj["id"], "type": "mesh",
                          "resource": os.path.join(os.path.dirname(os.path.abspath(scene_yaml)), mesh["resource"]),
                          "position": [float(v) for v in pose["position"]],
                          "orientation": [float(v) for v in pose["orientation"]]})
        for prim, pose in zip(obj.get("primitives") or [], obj.get("primitive_poses") or []):
            if prim["type"] not in ("box", "cylinder", "sphere"):
                raise ValueError(f"{scene_yaml}: primitive {prim['type']}")
            prims.append({"id": obj["id"], "type": prim["type"], "dimensions": [float(d) for d in prim["dimensions"]],
                          "position": [float(v) for v in pose["position"]],
                          "orientation": [float(v) for v in pose["orientation"]]})
    return prims


def load_urdf_scene(urdf, mbm_dir, rng=None):
    """A URDF scene (kitchen, table_bars) as scene objects: one mesh per link collision, named
    after its link, posed at the URDF's zero joint positions (world frame; meshes unscaled), or,
    with `rng`, at joint positions drawn uniformly within their limits, as MotionBenchMaker's
    SceneSampler does for a URDF scene (`setToRandomPositions` before it dumps the scene: the
    kitchen's doors open, table_bars's bars slide)."""
    import xml.etree.ElementTree as ET

    model = pin.buildModelFromUrdf(urdf)
    data = model.createData()
    q = pin.neutral(model)
    if rng is not None and model.nq > 0:
        q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
    pin.framesForwardKinematics(model, data, q)
    prims = []
    for link in ET.parse(urdf).getroot().iter("link"):
        for col in link.iter("collision"):
            origin = col.find("origin")
            xyz = [float(v) for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()]
            rpy = [float(v) for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()]
            mesh = col.find("geometry/mesh")
            if mesh is None or mesh.get("scale", "1 1 1").split() != ["1", "1", "1"]:
                raise ValueError(f"{urdf}: link {link.get('name')}: only unscaled mesh collisions are read")
            M = data.oMf[model.getFrameId(link.get("name"))] * pin.SE3(pin.rpy.rpyToMatrix(*rpy), np.array(xyz))
            prims.append({"id": link.get("name"), "type": "mesh", "resource": pkg_path(mesh.get("filename"), mbm_dir),
                          "position": M.translation.tolist(),
                          "orientation": pin.Quaternion(M.rotation).coeffs().tolist()})
    return prims


def in_base_frame(prims, base_offset):
    """The scene objects in the robot's base_link frame when the problem gives a `base_offset`
    (position, orientation [x, y, z, w]): the scene placed at that pose from base_link. (Read the
    other way round, as the robot's pose in the scene, MotionBenchMaker's table_bars puts Fetch's
    default state inside the shelves; read this way, its start and goal queries have
    collision-free IK states.)"""
    if not any(base_offset.get("position", [0, 0, 0])) and list(base_offset.get("orientation", [0, 0, 0, 1])) == [0, 0, 0, 1]:
        return prims
    B = pose_to_se3(base_offset.get("position", [0, 0, 0]), base_offset.get("orientation", [0, 0, 0, 1]))
    out = []
    for p in prims:
        M = B * pose_to_se3(p["position"], p["orientation"])
        out.append(dict(p, position=M.translation.tolist(), orientation=pin.Quaternion(M.rotation).coeffs().tolist()))
    return out


def mbm_draw(entry, rng):
    """One draw of a variation-file entry as MotionBenchMaker's code runs it
    (SceneSampler::Variation::sample): its `type.compare("uniform")` is non-zero for every type
    but "uniform", so an entry of type "uniform" takes the Gaussian branch, a position with
    standard deviation `position` per axis; the orientation is uniform in [-bound, bound] per
    roll, pitch and yaw, composed X·Y·Z (robowflex TF::sampleOrientationUniform)."""
    dp = rng.normal(0.0, 1.0, 3) * np.array(entry["position"], float)
    r = rng.uniform(-1, 1, 3) * np.array(entry["orientation"], float)
    R = pin.utils.rotate("x", r[0]) @ pin.utils.rotate("y", r[1]) @ pin.utils.rotate("z", r[2])
    return pin.SE3(R, dp)


def vary_scene_mbm(prims, variation_yaml, rng, urdf_scene):
    """The scene varied as MotionBenchMaker's SceneSampler::sample does: the "World" entry moves
    every object in the world frame (T·M); each object's own entry moves it in its own frame
    (M·T, robowflex moveObjectLocal), applied here to each of its primitives; a URDF scene's
    objects get only the World entry (its joints are drawn instead: load_urdf_scene)."""
    with open(variation_yaml) as f:
        entries = yaml.safe_load(f) or []
    out = [dict(p) for p in prims]

    def move(p, T, local):
        M = pose_to_se3(p["position"], p["orientation"])
        M = M * T if local else T * M
        p["position"] = M.translation.tolist()
        p["orientation"] = pin.Quaternion(M.rotation).coeffs().tolist()  # x, y, z, w

    world = [e for e in entries if "World" in e["names"]]
    if world:
        T = mbm_draw(world[0], rng)
        for p in out:
            move(p, T, local=False)
    if urdf_scene:
        return out
    for e in entries:
        if "World" in e["names"]:
            continue
        for name in e["names"]:
            T = mbm_draw(e, rng)
            for p in out:
                if p["id"] == name:
                    move(p, T, local=True)
    return out


def vary_scene(prims, variation_yaml, rng):
    """The objects' own variations of the variation file: each named object moved by a uniform
    draw in [-bound, bound] per position axis and per roll/pitch/yaw angle (world axes, about its
    own origin). The "World" entries are not applied: the scene stays where the problem puts it.
    (`vary_scene_mbm` draws as MotionBenchMaker's code does.)"""
    with open(variation_yaml) as f:
        entries = yaml.safe_load(f) or []
    out = [dict(p) for p in prims]
    for e in entries:
        for name in e["names"]:
            if name == "World":
                continue
            dp = rng.uniform(-1, 1, 3) * np.array(e["position"], float)
            rpy = rng.uniform(-1, 1, 3) * np.array(e["orientation"], float)
            R = pin.rpy.rpyToMatrix(*rpy)
            for p in out:
                if p["id"] != name:
                    continue
                M = pose_to_se3(p["position"], p["orientation"])
                p["position"] = (M.translation + dp).tolist()
                p["orientation"] = pin.Quaternion(R @ M.rotation).coeffs().tolist()  # x, y, z, w
    return out


def scene_geometry(fetch, prims):
    """Robot meshes + scene primitives; pairs: SRDF-enabled self pairs + every link x object."""
    import coal

    geom = fetch.geom.copy()
    geom.removeAllCollisionPairs()
    n = fetch.nrobot
    for i in range(n):
        for j in range(i + 1, n):
            geom.addCollisionPair(pin.CollisionPair(i, j))
    pin.removeCollisionPairs(fetch.model, geom, fetch.srdf)
    objects = {}
    for k, p in enumerate(prims):
        d = p.get("dimensions")
        if p["type"] == "mesh":
            shape = coal.MeshLoader().load(p["resource"])
        elif p["type"] == "box":
            shape = coal.Box(d[0], d[1], d[2])
        elif p["type"] == "cylinder":
            shape = coal.Cylinder(d[1], d[0])  # shape_msgs: [height, radius]
        else:
            shape = coal.Sphere(d[0])
        M = pose_to_se3(p["position"], p["orientation"])
        objects.setdefault(p["id"], M)
        gid = geom.addGeometryObject(pin.GeometryObject(f"{p['id']}_{k}", 0, 0, M, shape))
        for i in range(n):
            geom.addCollisionPair(pin.CollisionPair(i, gid))
    return geom, objects


class Checker:
    """Collision-free test with early exit. Pinocchio's broad phase (coal's dynamic AABB tree
    over every geometry object; only the model's collision pairs are tested) gives the same
    verdicts as the loop over all pairs (300 random states of a bookshelf_tall query agree) at
    about a fifth of its cost on these scenes."""

    def __init__(self, fetch, geom):
        self.f, self.geom = fetch, geom
        self.gdata = pin.GeometryData(geom)
        self.manager = pin.BroadPhaseManager_DynamicAABBTreeCollisionManager(fetch.model, geom, self.gdata)
        self.count = 0

    def free(self, q):
        self.count += 1
        return not pin.computeCollisions(self.f.model, self.f.data, self.manager, q, True)


def solve_ik(fetch, checker, ee_frame, target, rng, restarts=300, iters=300):
    """Damped least squares on the group joints from seeded random restarts; collision-free."""
    model, data = fetch.model, fetch.data
    fid = model.getFrameId(ee_frame)
    cols = fetch.idx_v
    for attempt in range(restarts):
        x = rng.uniform(fetch.lo, fetch.hi)
        for _ in range(iters):
            q = fetch.set_group(fetch.q0, x)
            pin.framesForwardKinematics(model, data, q)
            err_M = target.actInv(data.oMf[fid])
            err = pin.log6(err_M).vector
            if np.linalg.norm(err[:3]) < 1e-5 and np.linalg.norm(err[3:]) < 1e-4:
                break
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            J = pin.Jlog6(err_M) @ J[:, cols]
            dx = -J.T @ np.linalg.solve(J @ J.T + 1e-6 * np.eye(6), err)
            x = np.clip(x + dx, fetch.lo, fetch.hi)
        else:
            continue
        q = fetch.set_group(fetch.q0, x)
        if checker.free(q):
            return x, attempt + 1
    return None, restarts


def load_problems(mbm_dir):
    out = []
    for p in sorted(glob.glob(os.path.join(mbm_dir, "configs", "problems", "*_fetch.yaml"))):
        with open(p) as f:
            doc = yaml.safe_load(f)
        name = os.path.basename(p)[: -len("_fetch.yaml")]
        out.append((name, p, doc))
    return out


def compute_goals(fetch, mbm_dir, ee_link, seed, samples, tries=20, urdf_scenes=False, problems=None, draw="uniform"):
    goals = {"note": "", "samples": samples, "ee_link": ee_link, "group": GROUP, "default_state": DEFAULT_STATE, "queries": []}
    rng = np.random.default_rng(seed)
    for name, path, doc in load_problems(mbm_dir):
        if problems is not None and name not in problems:
            continue
        scene = pkg_path(doc["scene"], mbm_dir)
        if not scene.endswith(".yaml") and not urdf_scenes:
            print(f"# {name}: scene {os.path.basename(scene)} is a URDF scene, skipped", file=sys.stderr)
            continue
        bo = doc.get("base_offset", {})
        if bo and (any(bo.get("position", [0, 0, 0])) or list(bo.get("orientation", [0, 0, 0, 1])) != [0, 0, 0, 1]) \
                and not urdf_scenes:
            print(f"# {name}: base_offset not identity, skipped", file=sys.stderr)
            continue
        urdf_scene = not scene.endswith(".yaml")
        nominal = load_urdf_scene(scene, mbm_dir) if urdf_scene else load_scene(scene)
        nominal = in_base_frame(nominal, bo or {})
        with open(pkg_path(doc["queries"], mbm_dir)) as f:
            qdoc = yaml.safe_load(f)
        variation = pkg_path(doc["variation"], mbm_dir)
        for gq in qdoc.get("goal_queries") or []:
            for obj in gq["objects"]:
                for sample in range(samples):
                    found = None
                    for attempt in range(tries):
                        if draw == "mbm":
                            drawn = in_base_frame(load_urdf_scene(scene, mbm_dir, rng), bo or {}) \
                                if urdf_scene else nominal
                            prims = vary_scene_mbm(drawn, variation, rng, urdf_scene)
                        else:
                            prims = vary_scene(nominal, variation, rng)
                        geom, objects = scene_geometry(fetch, prims)
                        checker = Checker(fetch, geom)
                        start = {"kind": "default", "state": {n: DEFAULT_STATE[n] for n in GROUP}}
                        if not checker.free(fetch.q0):
                            continue
                        for sq in qdoc.get("start_queries") or []:
                            off = sq["offset"]
                            target = objects[sq["objects"][0]] * pose_to_se3(off["position"], off["orientation"])
                            x, _ = solve_ik(fetch, checker, ee_link, target, rng, restarts=30)
                            start = None if x is None else {
                                "kind": "ik", "tag": sq.get("tag"), "object": sq["objects"][0],
                                "pose": {"position": target.translation.tolist(),
                                         "orientation_xyzw": pin.Quaternion(target.rotation).coeffs().tolist()},
                                "state": dict(zip(GROUP, map(float, x)))}
                        if start is None:
                            continue
                        off = gq["offset"]
                        target = objects[obj] * pose_to_se3(off["position"], off["orientation"])
                        x, restarts = solve_ik(fetch, checker, ee_link, target, rng, restarts=30)
                        if x is not None:
                            found = (prims, start, target, x, attempt + 1)
                            break
                    entry = {"problem": name, "sample": sample, "scene": os.path.relpath(scene, mbm_dir),
                             "tag": gq.get("tag"), "object": obj, "start": None, "goal_state": None}
                    if found:
                        prims, start, target, x, n_scenes = found
                        entry.update({
                            "scene_objects": prims, "scene_draws": n_scenes, "start": start,
                            "goal_pose": {"position": target.translation.tolist(),
                                          "orientation_xyzw": pin.Quaternion(target.rotation).coeffs().tolist()},
                            "goal_state": dict(zip(GROUP, map(float, x)))})
                    goals["queries"].append(entry)
                    print(f"# {name} {gq.get('tag')} {obj} sample {sample}: "
                          f"{'goal found (scene draw %d)' % found[4] if found else 'NO goal in %d scene draws' % tries}",
                          file=sys.stderr, flush=True)
    goals["note"] = (
        ("Queries of the MotionBenchMaker Fetch problems (the URDF scenes kitchen and table_bars as one mesh "
         "object per link), " if urdf_scenes else
         "Queries of the MotionBenchMaker Fetch problems with primitive scenes (the URDF scenes kitchen and "
         "table_bars are not included), ") +
        "`samples` queries per goal query: each scene drawn from the problem's variation "
        + ("file (the objects' own variations, uniform in [-bound, bound]; the World variation not applied), its "
           if draw != "mbm" else
           "file as MotionBenchMaker's code draws (positions Gaussian with the bound as standard deviation, angles "
           "uniform; the World variation in the world frame, each object's own in its frame; a URDF scene's joints "
           "uniform within their limits and only the World variation), its ") +
        "objects listed in scene_objects (poses in base_link, quaternions [x, y, z, w]). Goal (and start, for "
        "start_queries) states of the arm_with_torso group: the query's pose of ee_link (object pose x offset) "
        f"solved by damped least squares (Pinocchio {pin.__version__}) from seeded random restarts (numpy "
        f"default_rng({seed}), 30 per scene draw, up to {tries} draws) within the URDF limits (continuous joints "
        "in [-pi, pi]) to 1e-5 m / 1e-4 rad; the first collision-free solution (exact meshes: SRDF-enabled self "
        "pairs and every link x scene object pair) is kept; the other joints stay at MotionBenchMaker's "
        "default state (default_state). start_q / goal_q: the same states over every joint in joint_order "
        "(one coordinate per joint, continuous joints as angles). Written by bench/ompl_fetch_mbm.py.")
    return add_full_states(goals, fetch)


def add_full_states(goals, fetch):
    """Full-model states for `--start` / `--goal-state` files: `joint_order` (the model's joints,
    Pinocchio's order), and per query `start_q` / `goal_q` with one coordinate per joint (moma's
    layout: a continuous joint as its angle), the joints outside the group at default_state."""
    model = fetch.model
    names = [model.names[j] for j in range(1, model.njoints)]
    goals["joint_order"] = names
    for qe in goals["queries"]:
        for key, state in (("start_q", (qe.get("start") or {}).get("state")), ("goal_q", qe.get("goal_state"))):
            if state is None:
                qe[key] = None
                continue
            full = dict(goals["default_state"], **state)
            qe[key] = [float(full.get(n, 0.0)) for n in names]
    return goals


def write_goals(path, goals):
    """One query per line (the file is read by people and diffed)."""
    head = {k: v for k, v in goals.items() if k != "queries"}
    with open(path, "w") as f:
        f.write("{\n")
        for k, v in head.items():
            f.write(f" {json.dumps(k)}: {json.dumps(v)},\n")
        f.write(' "queries": [\n')
        f.write(",\n".join("  " + json.dumps(q, separators=(",", ":")) for q in goals["queries"]))
        f.write("\n ]\n}\n")


def run_moma(args, fetch, goals, qe):
    """`moma motion` on the query (same scene objects, start and goal state), one run per seed
    0..runs-1; its planning time is moma's own `planning_time_s` (IK not involved: a goal state)."""
    import subprocess
    import tempfile

    urdf = os.path.join(args.fetch, "fetch_description", "robots", "fetch.urdf")
    srdf = os.path.join(args.fetch, "fetch.srdf")
    tmp = tempfile.mkdtemp(prefix="moma_vs_ompl_")
    scene = os.path.join(tmp, "scene.yaml")
    with open(scene, "w") as f:
        f.write("world:\n  collision_objects:\n")
        for o in qe["scene_objects"]:
            f.write(f"    - header: {{frame_id: base_link}}\n      id: {o['id']}\n      primitives:\n"
                    f"        - type: {o['type']}\n          dimensions: {json.dumps(o['dimensions'])}\n"
                    f"      primitive_poses:\n        - position: {json.dumps(o['position'])}\n"
                    f"          orientation: {json.dumps(o['orientation'])}\n")
    for key in ("start_q", "goal_q"):
        with open(os.path.join(tmp, key + ".json"), "w") as f:
            json.dump({"states": [{"q": qe[key]}]}, f)
    rows = []
    for run in range(args.runs):
        out = os.path.join(tmp, "out.json")
        cmd = [args.moma, "motion", urdf, "--root", "fixed", "--srdf", srdf, "--package-dir", args.fetch,
               "--scene", scene, "--group", ",".join(GROUP), "--start", os.path.join(tmp, "start_q.json"),
               "--goal-state", os.path.join(tmp, "goal_q.json"), "--time-limit", str(args.time),
               "--seed", str(run), "--output", out]
        r = subprocess.run(cmd, capture_output=True, text=True)
        ok, t, checks, reason = False, float("nan"), 0, r.stderr.strip()
        if r.returncode in (0, 3):
            with open(out) as f:
                d = json.load(f)
            ok, t, checks, reason = d["solved"], d["planning_time_s"], d["checks"], d["reason"]
        rows.append({"problem": qe["problem"], "sample": qe["sample"], "tag": qe["tag"], "object": qe["object"],
                     "run": run, "success": bool(ok), "time_s": t, "validity_checks": checks, "reason": reason})
    return rows


def percentile(xs, p):
    return float(np.percentile(np.array(xs), p)) if xs else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--fetch", default=os.path.join(ROOT, "crates/moma/tests/data/robots/fetch"),
                    help="folder with fetch_description/ and fetch.srdf (package dir of the URDF)")
    ap.add_argument("--mbm", default=os.path.join(ROOT, "crates/moma/tests/data/scenes/motion_bench_maker"),
                    help="MotionBenchMaker folder (with configs/problems, configs/scenes)")
    ap.add_argument("--goals", default=os.path.join(HERE, "ompl_fetch_mbm_goals.json"))
    ap.add_argument("--recompute-goals", action="store_true")
    ap.add_argument("--ee-link", default="gripper_link")
    ap.add_argument("--goals-only", action="store_true", help="compute/load the goal states and stop")
    ap.add_argument("--samples", type=int, default=5, help="scene draws (queries) per goal query")
    ap.add_argument("--runs", type=int, default=4, help="seeded planner runs per query")
    ap.add_argument("--time", type=float, default=1.0)
    ap.add_argument("--resolution", type=float, default=0.005)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--json", default=None, help="per-run results (default: no file)")
    ap.add_argument("--moma", default=None,
                    help="moma binary: also plan every query with `moma motion` (same start, goal state, scene, "
                         "time limit; seeds 0..runs-1) in the same run and print its table beside OMPL's")
    args = ap.parse_args()

    from ompl import base as ob
    from ompl import geometric as og
    from ompl import util as ou
    ou.RNG.setSeed(args.seed)  # before any sampling, or OMPL ignores it
    ou.setLogLevel(ou.LogLevel.LOG_ERROR)

    for path in (os.path.join(args.fetch, "fetch_description", "robots", "fetch.urdf"),
                 os.path.join(args.mbm, "configs", "problems")):
        if not os.path.exists(path):
            sys.exit(f"ompl_fetch_mbm.py: {path} not found (give --fetch / --mbm)")
    fetch = Fetch(args.fetch)
    if os.path.exists(args.goals) and not args.recompute_goals:
        with open(args.goals) as f:
            goals = json.load(f)
    else:
        goals = compute_goals(fetch, args.mbm, args.ee_link, args.seed, args.samples)
        write_goals(args.goals, goals)
        print(f"# goal states written to {args.goals}", file=sys.stderr)
    if args.goals_only:
        return

    space = ob.RealVectorStateSpace(len(GROUP))
    bounds = ob.RealVectorBounds(len(GROUP))
    for k in range(len(GROUP)):
        bounds.setLow(k, float(fetch.lo[k]))
        bounds.setHigh(k, float(fetch.hi[k]))
    space.setBounds(bounds)
    extent = space.getMaximumExtent()
    print(f"# OMPL RRT-Connect, time limit {args.time} s, {args.runs} runs per query, seed {args.seed}; "
          f"motion validation resolution {args.resolution} of the maximum extent {extent:.3f} "
          f"= {args.resolution * extent:.4f} (joint-space L2, rad/m)")
    print(f"# validity: exact meshes (coal BVH), pinocchio {pin.__version__}, computeCollisions with early exit through the broad phase (dynamic AABB tree); "
          f"machine {platform.machine()}, {os.cpu_count()} cores, loadavg {os.getloadavg()}")

    results, moma_results = [], []
    for qi, qe in enumerate(goals["queries"]):
        if qe["goal_state"] is None or qe["start"] is None:
            print(f"# {qe['problem']}: no IK state, query skipped")
            continue
        checker = Checker(fetch, scene_geometry(fetch, qe["scene_objects"])[0])
        x_start = np.array([qe["start"]["state"][n] for n in GROUP])
        x_goal = np.array([qe["goal_state"][n] for n in GROUP])
        start_free = checker.free(fetch.set_group(fetch.q0, x_start))
        goal_free = checker.free(fetch.set_group(fetch.q0, x_goal))
        for run in range(args.runs):
            ss = og.SimpleSetup(space)

            def valid(s, checker=checker):
                x = [s[k] for k in range(len(GROUP))]
                return checker.free(fetch.set_group(fetch.q0, x))

            ss.setStateValidityChecker(valid)
            si = ss.getSpaceInformation()
            si.setStateValidityCheckingResolution(args.resolution)
            s0, s1 = space.allocState(), space.allocState()
            for k in range(len(GROUP)):
                s0[k] = float(x_start[k])
                s1[k] = float(x_goal[k])
            ss.setStartAndGoalStates(s0, s1)
            ss.setPlanner(og.RRTConnect(si))
            checker.count = 0
            t0 = time.perf_counter()
            status = ss.solve(args.time)
            wall = time.perf_counter() - t0
            ok = bool(ss.haveExactSolutionPath())
            t = ss.getLastPlanComputationTime()
            n_states = ss.getSolutionPath().getStateCount() if ok else 0
            results.append({"problem": qe["problem"], "sample": qe["sample"], "tag": qe["tag"], "object": qe["object"], "run": run,
                            "success": ok, "status": str(status), "time_s": t, "wall_s": wall,
                            "validity_checks": checker.count, "path_states": n_states,
                            "start_free": start_free, "goal_free": goal_free})
        if args.moma:
            moma_results.extend(run_moma(args, fetch, goals, qe))
    for title, rows in (("OMPL RRT-Connect", results), ("moma motion", moma_results)):
        if not rows:
            continue
        print(f"# {title}")
        print(f"{'problem':18s} {'queries':>7s} {'success':>9s} {'median ms':>10s} {'p95 ms':>8s} {'checks/run':>10s}")
        problems = [p for p in dict.fromkeys(r["problem"] for r in rows)] + ["overall"]
        for prob in problems:
            rs = [r for r in rows if prob == "overall" or r["problem"] == prob]
            ts = [r["time_s"] for r in rs if r["success"]]
            nq = len({(r["problem"], r["sample"], r["object"]) for r in rs})
            print(f"{prob:18s} {nq:7d} {sum(r['success'] for r in rs):4d}/{len(rs):<4d} "
                  f"{percentile(ts, 50) * 1e3:10.1f} {percentile(ts, 95) * 1e3:8.1f} "
                  f"{np.median([r['validity_checks'] for r in rs]):10.0f}", flush=True)
    if args.json:
        with open(args.json, "w") as f:
            json.dump({"settings": vars(args) | {"extent": extent, "pinocchio": pin.__version__},
                       "results": results, "moma_results": moma_results}, f, indent=1)


if __name__ == "__main__":
    main()
