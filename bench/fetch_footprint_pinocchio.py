"""Fetch's footprint at a posture, computed independently of moma: Pinocchio places the
URDF's collision meshes (planar root at the origin, joints set by name), the STL files
are read here with `struct`, and the footprint's radius about base_link's origin is the
largest horizontal distance of a placed mesh vertex (the farthest point of a convex hull
is one of its vertices, so moma's hull-based footprint must give the same value).

Usage: python bench/fetch_footprint_pinocchio.py [JOINT=VALUE ...]
Needs `pip install pin` (Pinocchio 4.1). Prints the radius and the x, y extent.
"""

import math
import os
import struct
import sys

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
FETCH = os.path.join(HERE, "..", "crates", "moma", "tests", "data", "robots", "fetch")
URDF = os.path.join(FETCH, "fetch_description", "robots", "fetch.urdf")


def stl_vertices(path):
    data = open(path, "rb").read()
    n = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else -1
    if len(data) == 84 + 50 * n:
        out = []
        for k in range(n):
            v = struct.unpack_from("<12f", data, 84 + 50 * k)
            out.extend([v[3:6], v[6:9], v[9:12]])
        return np.array(out, dtype=float)
    out = [
        [float(t) for t in line.split()[1:4]]
        for line in data.decode().splitlines()
        if line.strip().startswith("vertex")
    ]
    return np.array(out, dtype=float)


def main():
    posture = {}
    for arg in sys.argv[1:]:
        name, value = arg.split("=")
        posture[name] = float(value)
    model = pin.buildModelFromUrdf(URDF, pin.JointModelPlanar())
    geom = pin.buildGeomFromUrdf(model, URDF, pin.GeometryType.COLLISION, [FETCH])
    q = pin.neutral(model)
    for name, value in posture.items():
        j = model.getJointId(name)
        jm = model.joints[j]
        if jm.nq == 2:  # continuous: cos, sin
            q[jm.idx_q : jm.idx_q + 2] = [math.cos(value), math.sin(value)]
        else:
            q[jm.idx_q] = value
    data = model.createData()
    gdata = geom.createData()
    pin.updateGeometryPlacements(model, data, geom, gdata, q)
    radius, lo, hi = 0.0, np.full(2, np.inf), np.full(2, -np.inf)
    for k, g in enumerate(geom.geometryObjects):
        m = gdata.oMg[k]
        v = stl_vertices(g.meshPath) * g.meshScale
        w = (m.rotation @ v.T).T + m.translation
        radius = max(radius, float(np.max(np.hypot(w[:, 0], w[:, 1]))))
        lo = np.minimum(lo, w[:, :2].min(axis=0))
        hi = np.maximum(hi, w[:, :2].max(axis=0))
    print(f"posture {posture}")
    print(f"radius {radius!r}")
    print(f"x [{lo[0]!r}, {hi[0]!r}]  y [{lo[1]!r}, {hi[1]!r}]")


if __name__ == "__main__":
    main()
