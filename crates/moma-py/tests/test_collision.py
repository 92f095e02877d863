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
