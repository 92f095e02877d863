"""Collision geometry from Python: Fetch's self-distances against the coal reference and
the scene query, with the same fields as `moma collision`."""

import json
from pathlib import Path

import numpy as np
import pytest

import moma

DATA = Path(__file__).resolve().parents[2] / "moma" / "tests" / "data"
FETCH = DATA / "robots" / "fetch"
URDF = FETCH / "fetch_description" / "robots" / "fetch.urdf"


@pytest.fixture(scope="module")
def fetch():
    model = moma.Model.from_urdf(URDF, "fixed")
    geom = moma.GeometryModel.from_urdf(
        model, URDF, srdf=FETCH / "fetch.srdf", package_dirs=[FETCH]
    )
    return model, geom


def test_self_distances_match_coal(fetch):
    model, geom = fetch
    ref = json.loads((DATA / "collision" / "fetch_self_public.json").read_text())
    assert len(geom.pairs_enabled) == ref["n_enabled_pairs"] == 76
    enabled = {tuple(sorted(p)) for p, e in zip(ref["pairs"], ref["pair_enabled"]) if e}
    assert {tuple(sorted(p)) for p in geom.pairs_enabled} == enabled
    for state in ref["states"][:5]:
        q = moma.from_pinocchio(model, np.array(state["q"]))["q"]
        out = moma.distances(model, geom, q, all_pairs=True)
        assert out["witness_a"].shape == (210, 3)
        got = {tuple(p): d for p, d in zip(out["pairs"], out["distance"])}
        for (a, b), want in zip(ref["pairs"], state["distance_convex"]):
            d = got.get((a, b), got.get((b, a)))
            assert abs(d - want) <= 1e-6, (a, b, d, want)
        enabled_only = moma.distances(model, geom, q)
        assert abs(enabled_only["min_distance"] - state["min_enabled_convex"]) <= 1e-6
        assert enabled_only["in_collision"] == state["in_collision_enabled"]


def test_scene_and_bad_input(fetch, tmp_path):
    model, geom = fetch
    scene = moma.Scene.from_yaml(
        DATA / "scenes/motion_bench_maker/configs/scenes/cage/scene_cage.yaml",
        world_frames=["base_link"],
    )
    out = moma.distances(model, geom, np.zeros(model.nq), scene=scene)
    n_scene = len(geom.links) * len(scene.ids)
    assert len(out["pairs"]) == 76 + n_scene
    assert out["distance"].shape == (76 + n_scene,)
    assert out["min_distance"] == pytest.approx(out["distance"].min())
    bad = tmp_path / "s.yaml"
    bad.write_text(
        "world:\n  collision_objects:\n    - header: {frame_id: odom}\n      id: B\n"
        "      primitives: [{type: box, dimensions: [1, 1, 1]}]\n"
        "      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n"
    )
    with pytest.raises(moma.MomaError, match="unknown frame 'odom'"):
        moma.Scene.from_yaml(bad, world_frames=["base_link"])
    with pytest.raises(moma.MomaError, match="cannot resolve"):
        moma.GeometryModel.from_urdf(model, URDF)


def _inside(poly, p, tol=1e-9):
    a, b = poly, np.roll(poly, -1, axis=0)
    cross = (b[:, 0] - a[:, 0]) * (p[1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (p[0] - a[:, 0])
    return bool(np.all(cross >= -tol))


def test_gradient_matches_finite_differences(fetch):
    model, geom = fetch
    scene = moma.Scene.from_yaml(
        DATA / "scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml",
        world_frames=["base_link"],
    )
    rng = np.random.default_rng(11)
    lo = np.array([0, 0, 0.0, 0.0, -1.5, -0.7, -1.5, -1.2, -3, -2.2, -3, -2.1, -3, 0, 0])
    hi = np.array([0, 0, 0.38, 0.4, 1.5, 1.4, 1.5, 1.5, 3, 2.2, 3, 2.1, 3, 0.05, 0.05])
    assert model.nq == model.nv == lo.size
    h, checked = 1e-6, 0
    for _ in range(40):
        q = rng.uniform(lo, hi)
        out = moma.distances(model, geom, q, scene=scene, gradient=True)
        # Away from contact, where the closest features are unique.
        if out["min_distance"] < 0.01:
            continue
        g = out["gradient"]
        assert g.shape == (model.nv,)
        for k in range(model.nv):
            e = np.zeros(model.nv)
            e[k] = h
            p = moma.distances(model, geom, q + e, scene=scene)
            m = moma.distances(model, geom, q - e, scene=scene)
            if p["closest"] != out["closest"] or m["closest"] != out["closest"]:
                continue
            dp, d0, dm = p["min_distance"], out["min_distance"], m["min_distance"]
            if abs((dp - d0) / h - (d0 - dm) / h) > 1e-3:
                continue  # a kink: the closest features switch within ±h
            fd = (dp - dm) / (2 * h)
            assert abs(fd - g[k]) <= 1e-5 * (1 + abs(fd)), (q, k, g[k], fd)
            checked += abs(g[k]) > 1e-3
    assert checked >= 20, checked


def test_footprint_contains_the_geometry_and_follows_the_base(fetch):
    model, geom = fetch
    q = np.array([0, 0, 0.3, 0.1, 0.2, 0.1, 0.5, -0.3, 0.4, 1.2, 0.3, 0.8, 0.2, 0.03, 0.03])
    fp = moma.footprint(model, geom, q)
    assert fp.ndim == 2 and fp.shape[1] == 2 and fp.shape[0] >= 3
    # Counter-clockwise, and every witness point (on the robot's surfaces) projects inside.
    area = 0.5 * np.sum(fp[:, 0] * np.roll(fp[:, 1], -1) - np.roll(fp[:, 0], -1) * fp[:, 1])
    assert area > 0.2
    out = moma.distances(model, geom, q, all_pairs=True)
    for w in np.vstack([out["witness_a"], out["witness_b"]]):
        assert _inside(fp, w[:2]), w
    # On a planar base at (1, 2, 0.7) the base-frame footprint is the same polygon, and
    # the world-frame one is it moved by the base.
    planar = moma.Model.from_urdf(URDF, "planar")
    pgeom = moma.GeometryModel.from_urdf(
        planar, URDF, srdf=FETCH / "fetch.srdf", package_dirs=[FETCH]
    )
    qp = np.concatenate([[1.0, 2.0, 0.7], q])
    base = moma.footprint(planar, pgeom, qp)
    world = moma.footprint(planar, pgeom, qp, frame="world")
    assert all(_inside(fp, p) for p in base) and all(_inside(base, p) for p in fp)
    c, s = np.cos(0.7), np.sin(0.7)
    moved = fp @ np.array([[c, s], [-s, c]]) + [1.0, 2.0]
    assert all(_inside(world, p, 1e-8) for p in moved)
    assert all(_inside(moved, p, 1e-8) for p in world)
    with pytest.raises(moma.MomaError, match="'base' needs a planar"):
        moma.footprint(model, geom, q, frame="base")
    with pytest.raises(moma.MomaError, match="'side' is not"):
        moma.footprint(planar, pgeom, qp, frame="side")


def test_exact_meshes_match_coal(fetch):
    model, geom = fetch
    ref = json.loads((DATA / "collision" / "fetch_self_public.json").read_text())
    state = next(s for s in ref["states"] if s["in_collision_enabled_mesh"])
    q = moma.from_pinocchio(model, np.array(state["q"]))["q"]
    out = moma.distances(model, geom, q, mesh="exact")
    got = {tuple(sorted(p)): d for p, d in zip(out["pairs"], out["distance"])}
    n = 0
    for (a, b), want, on in zip(ref["pairs"], state["distance_mesh"], ref["pair_enabled"]):
        if on:
            assert abs(got[tuple(sorted((a, b)))] - want) <= 1e-6, (a, b)
            n += 1
    assert n == 76 and out["in_collision"] and out["min_distance"] == 0.0
    with pytest.raises(moma.MomaError, match="'hull' is not"):
        moma.distances(model, geom, q, mesh="hull")


def test_exact_meshes_against_a_scene_match_coal(fetch):
    model, geom = fetch
    ref = json.loads((DATA / "collision" / "fetch_scene_public.json").read_text())
    scene = moma.Scene.from_yaml(
        DATA / "scenes/motion_bench_maker/configs/scenes/cage/scene_cage.yaml",
        world_frames=["base_link"],
    )
    # a cage state whose arm crosses the bars (coal: six link meshes touch them)
    state = next(s for s in ref["states"] if s["scene"] == "cage" and s["label"] == "random_001")
    q = moma.from_pinocchio(model, np.array(state["q"]))["q"]
    out = moma.distances(model, geom, q, scene=scene, mesh="exact")
    got = dict(zip(out["pairs"], out["distance"]))
    for (link, obj), want in zip(ref["scenes"]["cage"]["pairs"], state["distance_mesh"]):
        d = got[(link, obj)]
        assert (d == 0.0) if want == 0.0 else abs(d - want) <= 1e-6, (link, obj, d, want)
    assert out["in_collision"] and out["min_distance"] == 0.0
