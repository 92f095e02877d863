#!/usr/bin/env python3
"""Reference distances for Panda's collision geometry with Pinocchio + coal (the wheel
run.sh installs; PyYAML from the same venv), in the schema of the Fetch reference files
(crates/moma/tests/data/collision/SOURCES.md), for crates/moma/tests/collision_coal.rs
(convex hulls) and crates/moma/tests/collision_exact.rs (triangle meshes):

    python panda_collision_reference.py PANDA.urdf PACKAGE_DIR PANDA.srdf SCENE.yaml OUT_DIR [SEED]

writes OUT_DIR/panda_self.json (every link pair, SRDF-enabled pairs, per state the signed
distance between convex hulls, witness points, their uniqueness, the minimum over the
enabled pairs and the in-collision verdict, and the same for the triangle meshes:
distance_mesh, its minimum and verdict) and OUT_DIR/panda_scene.json (every link x every
object of the MoveIt-style SCENE.yaml, whose poses are in panda_link0 = world).

distance_convex: meshes are their convex hulls (coal's qhull), primitives are kept; GJK
and EPA run to a 1e-12 m absolute duality gap, 1000 iterations. distance_mesh: meshes are
coal's BVH models of the triangles (OBBRSS), primitives are kept, the request unsigned
(coal's signed request gives a mesh against a box the depth of its deepest triangle,
negative; between two meshes it gives 0 when triangles cross either way), GJK to the same
gap; a value <= 1e-10 m is written 0 (touching). A link with several elements (the finger
boxes) is at the minimum over its element pairs, with that pair's witness points.
States: seeded uniform draws in the joint limits, then states bisected between a free and
a colliding draw until both ends are within 3 mm of contact (kind 'near_contact', on the
hulls' signed distance; kind 'near_contact_mesh', on the meshes' distance: the colliding
end touches, the free end is within 3 mm).
"""
import json
import sys
import xml.etree.ElementTree as ET

import coal
import numpy as np
import pinocchio as pin
import yaml

TOL_FEATURE = 1e-5  # hull vertices this close to the supporting plane form the feature
NEAR = 3e-3  # near-contact states: |min distance| below this
TOUCH = 1e-10  # mesh distances at most this are written 0 (touching)


def request(signed=True):
    r = coal.DistanceRequest()
    r.enable_signed_distance = signed
    r.gjk_tolerance = 1e-12
    r.epa_tolerance = 1e-12
    r.gjk_max_iterations = 1000
    r.epa_max_iterations = 1000
    r.gjk_convergence_criterion = coal.GJKConvergenceCriterion.DualityGap
    r.gjk_convergence_criterion_type = coal.GJKConvergenceCriterionType.Absolute
    return r


def local_vertices(shape):
    if isinstance(shape, coal.Box):
        h = shape.halfSide
        return np.array([[sx * h[0], sy * h[1], sz * h[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    return np.array(shape.points())


def feature(points, u, side):
    """Rank (0 vertex, 1 edge, 2 face) and direction of the supporting feature."""
    s = points @ u
    f = points[s >= s.max() - TOL_FEATURE] if side > 0 else points[s <= s.min() + TOL_FEATURE]
    if len(f) == 1:
        return 0, None
    _, sv, vt = np.linalg.svd(f - f.mean(axis=0))
    if sv[1] <= TOL_FEATURE:
        return 1, vt[0]
    return 2, None


def unique_witness(va, vb, wa, wb, d):
    if d <= 1e-6:
        return None
    u = (wb - wa) / d
    ra, ea = feature(va, u, 1)
    rb, eb = feature(vb, u, -1)
    if ra == 0 or rb == 0:
        return True
    if ra == 1 and rb == 1:
        return bool(np.linalg.norm(np.cross(ea, eb)) > 1e-3)
    return False


class Element:
    def __init__(self, shape, local_vertices_):
        self.shape = shape
        self.local = local_vertices_
        self.tf = coal.Transform3s()

    def place(self, se3):
        self.tf = coal.Transform3s(se3.rotation, se3.translation)
        self.world = self.local @ se3.rotation.T + se3.translation


def pair_distance(req, elems_a, elems_b):
    """Minimum over element pairs: distance, witnesses (world), uniqueness."""
    best = None
    for a in elems_a:
        for b in elems_b:
            res = coal.DistanceResult()
            coal.distance(a.shape, a.tf, b.shape, b.tf, req, res)
            if best is None or res.min_distance < best[0]:
                best = (res.min_distance, np.array(res.getNearestPoint1()), np.array(res.getNearestPoint2()), a, b)
    d, wa, wb, a, b = best
    return d, wa, wb, unique_witness(a.world, b.world, wa, wb, d)


def mesh_distance(req, elems_a, elems_b):
    """Minimum over element pairs of the triangle meshes' (or primitives') distance, 0 when touching."""
    best = np.inf
    for a in elems_a:
        for b in elems_b:
            res = coal.DistanceResult()
            best = min(best, coal.distance(a.shape, a.tf, b.shape, b.tf, req, res))
    return 0.0 if best <= TOUCH else best


def r12(x):
    return float(round(float(x), 12))


class Panda:
    def __init__(self, urdf, package_dir):
        self.model = pin.buildModelFromUrdf(urdf)
        self.geom = pin.buildGeomFromUrdf(self.model, urdf, pin.COLLISION, package_dirs=[package_dir])
        self.data = self.model.createData()
        self.gdata = pin.GeometryData(self.geom)
        self.links, self.elements, self.meshes = [], {}, {}
        for g in self.geom.geometryObjects:
            shape = mesh = g.geometry
            if isinstance(shape, coal.BVHModelBase):
                shape.buildConvexHull(True, "Qt")
                shape = shape.convex
            link = self.model.frames[g.parentFrame].name
            if link not in self.elements:
                self.links.append(link)
                self.elements[link] = []
                self.meshes[link] = []
            self.elements[link].append(Element(shape, local_vertices(shape)))
            self.meshes[link].append(Element(mesh, local_vertices(shape)))
        self.req = request()
        self.req_mesh = request(signed=False)

    def place(self, q):
        pin.updateGeometryPlacements(self.model, self.data, self.geom, self.gdata, q)
        k = {}
        for g, m in zip(self.geom.geometryObjects, self.gdata.oMg):
            link = self.model.frames[g.parentFrame].name
            i = k.get(link, 0)
            self.elements[link][i].place(m)
            self.meshes[link][i].place(m)
            k[link] = i + 1

    def q_by_joint(self, q):
        return {self.model.names[j]: float(q[self.model.joints[j].idx_q]) for j in range(1, self.model.njoints)}


def self_state(p, pairs, enabled, q):
    p.place(q)
    out = {"distance_convex": [], "witness_a": [], "witness_b": [], "witness_unique": []}
    for a, b in pairs:
        d, wa, wb, u = pair_distance(p.req, p.elements[a], p.elements[b])
        out["distance_convex"].append(r12(d))
        out["witness_a"].append([r12(x) for x in wa])
        out["witness_b"].append([r12(x) for x in wb])
        out["witness_unique"].append(u)
    out["distance_mesh"] = [r12(mesh_distance(p.req_mesh, p.meshes[a], p.meshes[b])) for a, b in pairs]
    de = [(d, k) for k, d in enumerate(out["distance_convex"]) if enabled[k]]
    m, k = min(de)
    out["min_enabled_convex"] = m
    out["min_enabled_pair"] = list(pairs[k])
    out["in_collision_enabled"] = m < 0
    out["colliding_enabled_pairs"] = [list(pairs[k]) for d, k in de if d < 0]
    dm = [(d, k) for k, d in enumerate(out["distance_mesh"]) if enabled[k]]
    m, k = min(dm)
    out["min_enabled_mesh"] = m
    out["min_enabled_mesh_pair"] = list(pairs[k])
    out["in_collision_enabled_mesh"] = m == 0
    return out


def scene_state(p, pairs, objects, q):
    p.place(q)
    out = {"distance_convex": [], "witness_a": [], "witness_b": [], "witness_unique": []}
    for link, oid in pairs:
        d, wa, wb, u = pair_distance(p.req, p.elements[link], [objects[oid]])
        out["distance_convex"].append(r12(d))
        out["witness_a"].append([r12(x) for x in wa])
        out["witness_b"].append([r12(x) for x in wb])
        out["witness_unique"].append(u)
    out["distance_mesh"] = [r12(mesh_distance(p.req_mesh, p.meshes[link], [objects[oid]])) for link, oid in pairs]
    m, k = min((d, k) for k, d in enumerate(out["distance_convex"]))
    out["min_distance"] = m
    out["min_pair"] = list(pairs[k])
    out["in_collision"] = m < 0
    out["colliding_pairs"] = [list(pairs[k]) for k, d in enumerate(out["distance_convex"]) if d < 0]
    m, k = min((d, k) for k, d in enumerate(out["distance_mesh"]))
    out["min_distance_mesh"] = m
    out["min_pair_mesh"] = list(pairs[k])
    out["in_collision_mesh"] = m == 0
    return out


def near_contact(min_of, q_free, q_hit):
    """Bisects the segment q_free -> q_hit until both ends are within NEAR of contact."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        a, b = min_of(q_free + lo * (q_hit - q_free)), min_of(q_free + hi * (q_hit - q_free))
        if a < NEAR and b > -NEAR:
            break
        mid = 0.5 * (lo + hi)
        if min_of(q_free + mid * (q_hit - q_free)) <= 0:
            hi = mid
        else:
            lo = mid
    return q_free + lo * (q_hit - q_free), q_free + hi * (q_hit - q_free)


def near_states(draws, n_near, min_of):
    """Bisected pairs between the free draws and the colliding ones (min <= 0) in turn."""
    mins = [min_of(q) for q in draws]
    free = [q for q, m in zip(draws, mins) if m > 0]
    hit = [q for q, m in zip(draws, mins) if m <= 0]
    near = []
    for i in range(min(n_near, len(free)) if hit else 0):
        near.extend(near_contact(min_of, free[i], hit[i % len(hit)]))
    return near


def states_with_contacts(p, rng, n_random, n_near, min_of, min_mesh_of):
    draws = [rng.uniform(p.model.lowerPositionLimit, p.model.upperPositionLimit) for _ in range(n_random)]
    return (
        [("random", q) for q in draws]
        + [("near_contact", q) for q in near_states(draws, n_near, min_of)]
        + [("near_contact_mesh", q) for q in near_states(draws, n_near, min_mesh_of)]
    )


def source(seed):
    return {
        "generator": "bench/pinocchio/panda_collision_reference.py",
        "pinocchio": pin.__version__,
        "coal": coal.__version__,
        "numpy": np.__version__,
        "seed": seed,
        "rng": "numpy.random.default_rng(seed) (PCG64); one rng.uniform(lower, upper) over q per state",
        "coal_request": {
            "enable_signed_distance": True,
            "gjk_convergence_criterion": "DualityGap",
            "gjk_convergence_criterion_type": "Absolute",
            "gjk_tolerance": 1e-12,
            "epa_tolerance": 1e-12,
            "gjk_max_iterations": 1000,
            "epa_max_iterations": 1000,
        },
        "convex_hull": 'coal BVHModel.buildConvexHull(True, "Qt") -> BVHModel.convex (qhull)',
        "example_robot_data": "5.0.0",
    }


NOTES = [
    "Fixed root: panda_link0 is the world frame; q in Pinocchio's layout (= moma's for Panda), q_by_joint by name.",
    "A link may carry several elements (Panda: 4 boxes per finger): the link pair's distance is the minimum over element pairs, witnesses those of the minimising pair.",
    "distance_convex: signed distance between convex hulls (coal qhull), primitives kept; negative = -penetration depth (EPA).",
    "witness_a on the first of the pair, witness_b on the second (world frame). witness_unique (distance_convex > 1e-6 only, else null): true when the supporting feature (hull vertices within 1e-5 m of the supporting plane) of one side is a single vertex, or both are non-parallel edges (|sin| > 1e-3).",
    "States: seeded uniform draws in the URDF limits (kind 'random'), then pairs of states bisected between a free draw and a colliding one (the colliding draws taken in turn) until both are within 3 mm of contact (kind 'near_contact', on distance_convex; kind 'near_contact_mesh', on distance_mesh: one end touching, the other within 3 mm).",
    "distance_mesh: distance between the triangle meshes (coal BVHModelOBBRSS; primitives kept), unsigned request (GJK to the same 1e-12 m gap), 0 when triangles touch or cross or a triangle touches or enters a primitive (values <= 1e-10 m written 0). A surface distance: a mesh wholly inside another is at a positive distance. min_enabled_mesh / min_distance_mesh: its minimum (enabled pairs / every scene pair); in_collision_enabled_mesh / in_collision_mesh: that minimum is 0.",
]


def dump(doc, path):
    """The document with one state per line (the files stay small and diff by state)."""
    states = doc.pop("states")
    head = json.dumps(doc, indent=1)[:-2]
    lines = ",\n".join("  " + json.dumps(s, separators=(",", ":")) for s in states)
    with open(path, "w") as f:
        f.write(f'{head},\n "states": [\n{lines}\n ]\n}}\n')


def main(urdf, package_dir, srdf, scene_yaml, out_dir, seed=3):
    p = Panda(urdf, package_dir)
    pairs = [(p.links[i], p.links[j]) for i in range(len(p.links)) for j in range(i + 1, len(p.links))]
    disabled = {
        frozenset((d.get("link1"), d.get("link2"))) for d in ET.parse(srdf).getroot().iter("disable_collisions")
    }
    enabled = [frozenset(pr) not in disabled for pr in pairs]
    rng = np.random.default_rng(seed)

    def min_self(q):
        p.place(q)
        return min(pair_distance(p.req, p.elements[a], p.elements[b])[0] for (a, b), e in zip(pairs, enabled) if e)

    def min_self_mesh(q):
        p.place(q)
        return min(mesh_distance(p.req_mesh, p.meshes[a], p.meshes[b]) for (a, b), e in zip(pairs, enabled) if e)

    states = []
    for i, (kind, q) in enumerate(states_with_contacts(p, rng, 50, 6, min_self, min_self_mesh)):
        s = {"index": i, "kind": kind, "label": f"{kind}_{i:03d}", "q": q.tolist(), "q_by_joint": p.q_by_joint(q)}
        s.update(self_state(p, pairs, enabled, q))
        states.append(s)
    doc = {
        "source": source(seed),
        "notes": NOTES + ["SRDF: example-robot-data's panda_description/srdf/panda.srdf (copied to tests/data/robots/panda)."],
        "robot": "panda",
        "urdf": "pinocchio/urdf/panda.urdf",
        "root": "fixed (no root joint): panda_link0 = world",
        "srdf_disabled": sorted(sorted(d) for d in disabled),
        "pairs": [list(pr) for pr in pairs],
        "pair_enabled": enabled,
        "n_pairs": len(pairs),
        "n_enabled_pairs": sum(enabled),
        "links_with_collision": p.links,
        "nq": p.model.nq,
        "states": states,
    }
    dump(doc, f"{out_dir}/panda_self.json")

    objects, described = {}, []
    for o in yaml.safe_load(open(scene_yaml))["world"]["collision_objects"]:
        assert o["header"]["frame_id"] == "panda_link0" and o["primitives"][0]["type"] == "box"
        pose = o["primitive_poses"][0]
        x, y, z, w = pose["orientation"]
        se3 = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(pose["position"], float))
        shape = coal.Box(*o["primitives"][0]["dimensions"])
        e = Element(shape, local_vertices(shape))
        e.place(se3)
        objects[o["id"]] = e  # a box: the same shape for both definitions
        described.append({"id": o["id"], "type": "box", "dimensions": o["primitives"][0]["dimensions"],
                          "position": pose["position"], "orientation_xyzw": pose["orientation"]})
    scene_pairs = [(link, o["id"]) for link in p.links for o in described]

    def min_scene(q):
        p.place(q)
        return min(pair_distance(p.req, p.elements[a], [objects[b]])[0] for a, b in scene_pairs)

    def min_scene_mesh(q):
        p.place(q)
        return min(mesh_distance(p.req_mesh, p.meshes[a], [objects[b]]) for a, b in scene_pairs)

    states = []
    for i, (kind, q) in enumerate(states_with_contacts(p, rng, 24, 4, min_scene, min_scene_mesh)):
        s = {"scene": "table", "index": i, "kind": kind, "label": f"{kind}_{i:03d}", "q": q.tolist(),
             "q_by_joint": p.q_by_joint(q)}
        s.update(scene_state(p, scene_pairs, objects, q))
        states.append(s)
    doc = {
        "source": source(seed),
        "notes": NOTES + ["Scene: every object's header.frame_id is panda_link0 = world; pairs: every link x every object, min_distance over them, in_collision = min_distance < 0. The random draws continue the self file's rng stream."],
        "robot": "panda",
        "urdf": "pinocchio/urdf/panda.urdf",
        "root": "fixed (no root joint): panda_link0 = world",
        "scenes": {"table": {"scene_yaml": "collision/panda_scene_table.yaml", "objects": described,
                             "pairs": [list(pr) for pr in scene_pairs]}},
        "links_with_collision": p.links,
        "nq": p.model.nq,
        "states": states,
    }
    dump(doc, f"{out_dir}/panda_scene.json")
    print(f"self: {len(pairs)} pairs ({sum(enabled)} enabled); scene: {len(scene_pairs)} pairs, {len(states)} states")


if __name__ == "__main__":
    if len(sys.argv) < 6:
        sys.exit(__doc__)
    main(*sys.argv[1:6], *(int(a) for a in sys.argv[6:7]))
