#!/usr/bin/env python3
"""Coal's exact-mesh self distances on Fetch, for the side-by-side with moma's
`fetch/self_distance_enabled_exact` (crates/moma/benches/collision.rs): the same 100 states
(crates/moma/benches/data/fetch_states_pinocchio.txt, Pinocchio's layout), Fetch's STL
meshes as coal BVH models (OBBRSS), every link pair minus the SRDF's disabled ones (76),
Pinocchio's computeDistances(model, data, geom, gdata, q) per state (placements included,
coal's default request as Pinocchio sets it). Run with the venv run.sh installs:

    python fetch_exact_coal_timing.py [REPETITIONS]

Prints the median over REPETITIONS (default 5) passes of the mean time per state, each
pass's mean, and the mean minimum distance (a check that both sides measure the same).
"""
import os
import statistics
import sys
import time

import numpy as np
import pinocchio as pin

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "crates", "moma")
FETCH = os.path.join(ROOT, "tests", "data", "robots", "fetch")


def main(reps=5):
    urdf = os.path.join(FETCH, "fetch_description", "robots", "fetch.urdf")
    model = pin.buildModelFromUrdf(urdf)
    geom = pin.buildGeomFromUrdf(model, urdf, pin.COLLISION, package_dirs=[FETCH])
    geom.addAllCollisionPairs()
    pin.removeCollisionPairs(model, geom, os.path.join(FETCH, "fetch.srdf"))
    data, gdata = model.createData(), pin.GeometryData(geom)
    states = [
        np.array([float(x) for x in line.split()])
        for line in open(os.path.join(ROOT, "benches", "data", "fetch_states_pinocchio.txt"))
        if line.strip() and not line.startswith("#")
    ]
    assert len(states) == 100 and len(geom.collisionPairs) == 76, (len(states), len(geom.collisionPairs))
    mins = []
    for q in states:
        k = pin.computeDistances(model, data, geom, gdata, q)
        mins.append(gdata.distanceResults[k].min_distance)
    passes = []
    for _ in range(reps):
        t = time.perf_counter()
        for q in states:
            pin.computeDistances(model, data, geom, gdata, q)
        passes.append((time.perf_counter() - t) / len(states) * 1e6)
    print(f"# mean min enabled mesh distance over the states {np.mean(mins):.9f}")
    print(f"# passes (us per state): {', '.join(f'{p:.0f}' for p in passes)}")
    print(f"fetch self_distances_mesh 76 pairs median {statistics.median(passes):.0f} us per state")


if __name__ == "__main__":
    main(*(int(a) for a in sys.argv[1:2]))
