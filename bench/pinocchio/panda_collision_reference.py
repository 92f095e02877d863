#!/usr/bin/env python3
"""Reference distances for Panda's collision geometry with Pinocchio + coal (the wheel
run.sh installs): every pair of links, meshes as their convex hulls (coal's qhull), GJK
and EPA converged to a 1e-12 m absolute duality gap, on a few seeded random states.
Writes the JSON that crates/moma/tests/collision_panda.rs reads:

    python panda_collision_reference.py PANDA.urdf PACKAGE_DIR OUT.json [N [SEED]]

`pairs`: [linkA, linkB] (link = the geometry's parent frame), and per state `q`
(Pinocchio layout = moma's for Panda: revolute and prismatic joints only) and
`distance_convex`: per link pair the minimum over its elements' signed distances.
"""
import json
import sys

import coal
import numpy as np
import pinocchio as pin


def main(urdf, package_dir, out, n=5, seed=3):
    model = pin.buildModelFromUrdf(urdf)
    geom = pin.buildGeomFromUrdf(model, urdf, pin.COLLISION, package_dirs=[package_dir])
    for g in geom.geometryObjects:
        if isinstance(g.geometry, coal.BVHModelBase):
            g.geometry.buildConvexHull(True, "Qt")
            g.geometry = g.geometry.convex
    geom.removeAllCollisionPairs()
    links = [model.frames[g.parentFrame].name for g in geom.geometryObjects]
    for i in range(geom.ngeoms):
        for j in range(i + 1, geom.ngeoms):
            if links[i] != links[j]:
                geom.addCollisionPair(pin.CollisionPair(i, j))
    gdata = pin.GeometryData(geom)
    for r in gdata.distanceRequests:
        r.gjk_tolerance = 1e-12
        r.epa_tolerance = 1e-12
        r.gjk_max_iterations = 1000
        r.epa_max_iterations = 1000
        r.gjk_convergence_criterion = coal.GJKConvergenceCriterion.DualityGap
        r.gjk_convergence_criterion_type = coal.GJKConvergenceCriterionType.Absolute
    data = model.createData()
    rng = np.random.default_rng(seed)
    pair_names = sorted({tuple(sorted((links[cp.first], links[cp.second]))) for cp in geom.collisionPairs})
    states = []
    for _ in range(n):
        q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
        pin.computeDistances(model, data, geom, gdata, q)
        best = {}
        for cp, res in zip(geom.collisionPairs, gdata.distanceResults):
            key = tuple(sorted((links[cp.first], links[cp.second])))
            best[key] = min(best.get(key, np.inf), res.min_distance)
        states.append({"q": q.tolist(), "distance_convex": [best[p] for p in pair_names]})
    doc = {
        "source": f"Pinocchio {pin.__version__} + coal {coal.__version__}: hulls by qhull, "
        "GJK/EPA to a 1e-12 m absolute duality gap, 1000 iterations; "
        f"bench/pinocchio/panda_collision_reference.py, seed {seed}",
        "pairs": [list(p) for p in pair_names],
        "states": states,
    }
    with open(out, "w") as f:
        json.dump(doc, f, indent=1)


if __name__ == "__main__":
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], sys.argv[3], *(int(a) for a in sys.argv[4:6]))
