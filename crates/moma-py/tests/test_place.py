"""Base placement from Python: `moma.place` on Fetch at MotionBenchMaker's small
bookshelf gives the same ranked candidates as `moma place` for the same inputs, the
same reason when no pose works, and raises MomaError for bad input."""

import json
import subprocess

import numpy as np
import pytest

import moma
from conftest import DATA

FETCH = DATA / "robots" / "fetch"
FETCH_URDF = FETCH / "fetch_description" / "robots" / "fetch.urdf"
MBM = DATA / "scenes" / "motion_bench_maker"
QUERY = MBM / "configs" / "scenes" / "bookshelf" / "hard_queries_small.yaml"
DRAWN = MBM / "fetch_queries" / "scenes" / "bookshelf_small-Front-Can1-0.yaml"
NOMINAL = MBM / "configs" / "scenes" / "bookshelf" / "scene_small.yaml"
WHEELS = ("l_wheel_joint", "r_wheel_joint")
AREA = [-0.2, 0.0, 0.3, 0.6]


@pytest.fixture(scope="module")
def robot():
    model = moma.Model.from_urdf(FETCH_URDF, "planar")
    geom = moma.GeometryModel.from_urdf(
        model, FETCH_URDF, srdf=FETCH / "fetch.srdf", package_dirs=[FETCH]
    )
    group = json.loads((MBM / "fetch_queries" / "queries.json").read_text())["group"]
    return model, geom, group


def scene(path):
    return moma.Scene.from_yaml(path, world_frames=["world", "base_link"])


def place(robot, scene_path, **kw):
    model, geom, group = robot
    return moma.place(
        model, geom, scene(scene_path), group, WHEELS, query=QUERY, frame="gripper_link",
        casters=FETCH / "casters.toml", payload=0.35, area=AREA, headings=8, **kw,
    )


def cli(moma_bin, scene_path, out, group):
    r = subprocess.run(
        [str(moma_bin), "place", str(FETCH_URDF), "--srdf", str(FETCH / "fetch.srdf"),
         "--package-dir", str(FETCH), "--scene", str(scene_path), "--query", str(QUERY),
         "--frame", "gripper_link", "--group", ",".join(group), "--wheels", ",".join(WHEELS),
         "--casters", str(FETCH / "casters.toml"), "--payload", "0.35",
         "--area=" + ",".join(map(str, AREA)), "--headings", "8", "--output", str(out)],
        capture_output=True, text=True,
    )
    return r.returncode, json.loads(out.read_text())


def test_can1_candidates_equal_the_cli(robot, moma_bin, tmp_path):
    r = place(robot, DRAWN)
    assert r["found"] is True and r["reason"] is None
    code, c = cli(moma_bin, DRAWN, tmp_path / "p.json", robot[2])
    assert code == 0
    cand = r["candidates"]
    n = len(c["candidates"])
    assert n > 0 and cand["base"].shape == (n, 3) and cand["q"].shape == (n, robot[0].nq)
    # The same candidates in the same order: the same base poses and postures bit for
    # bit; the measures to rounding (the extension module is a separate build of the
    # library, whose floating-point results may differ in the last bits).
    np.testing.assert_array_equal(cand["base"], [x["base"] for x in c["candidates"]])
    np.testing.assert_array_equal(cand["q"], [x["q"] for x in c["candidates"]])
    for key in ("score", "clearance", "manipulability", "tip_over_margin"):
        np.testing.assert_allclose(cand[key], [x[key] for x in c["candidates"]],
                                   rtol=1e-12, atol=0)
    assert cand["closest"] == [tuple(x["closest"]) for x in c["candidates"]]
    assert r["counts"] == c["counts"]
    assert r["grasp"]["object"] == c["grasp"]["object"] == "Can1"
    np.testing.assert_array_equal(r["grasp"]["pose"], c["grasp"]["pose"])
    np.testing.assert_array_equal(r["payload_offset"], c["payload_offset"])
    np.testing.assert_array_equal(r["support"], c["support"])
    # Best first, and the best one is usable: clear of the margin, upright, on target.
    assert np.all(np.diff(cand["score"]) <= 0)
    assert cand["clearance"][0] > 0.005 and cand["tip_over_margin"][0] > 0
    assert cand["grasp_error"][0, 0] <= r["grasp"]["position_tolerance"]


def test_no_candidate_gives_the_cli_reason(robot, moma_bin, tmp_path):
    # The nominal scene puts Can2 where the grasp of Can1's query is.
    r = place(robot, NOMINAL)
    assert r["found"] is False
    assert r["candidates"]["base"].shape == (0, 3)
    assert "reached only in collision" in r["reason"]
    code, c = cli(moma_bin, NOMINAL, tmp_path / "n.json", robot[2])
    assert code == 3
    assert r["reason"] == c["reason"]


def test_casters_as_points_equal_the_file(robot):
    a = place(robot, DRAWN, candidates=3)
    model, geom, group = robot
    b = moma.place(
        model, geom, scene(DRAWN), group, WHEELS, query=QUERY, frame="gripper_link",
        casters=[[0.15, 0.12], [0.15, -0.12], [-0.2, 0.12], [-0.2, -0.12]],
        payload=0.35, area=AREA, headings=8, candidates=3,
    )
    np.testing.assert_array_equal(a["support"], b["support"])
    # the same candidates; scores to rounding (GJK's iterations may end a step apart)
    np.testing.assert_array_equal(a["candidates"]["base"], b["candidates"]["base"])
    np.testing.assert_allclose(a["candidates"]["score"], b["candidates"]["score"], rtol=1e-12)


def test_bad_input_raises(robot):
    model, geom, group = robot
    s = scene(DRAWN)
    pose = [0.5, 0.0, 0.8]
    casters = FETCH / "casters.toml"
    with pytest.raises(moma.MomaError, match="no_such_joint"):
        moma.place(model, geom, s, group + ["no_such_joint"], WHEELS, grasp_pose=pose,
                   frame="gripper_link")
    with pytest.raises(moma.MomaError, match="not both"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, query=QUERY,
                   frame="gripper_link")
    with pytest.raises(moma.MomaError, match="grasp_pose or query"):
        moma.place(model, geom, s, group, WHEELS, frame="gripper_link")
    with pytest.raises(moma.MomaError, match="frame"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose)
    with pytest.raises(moma.MomaError, match="nowhere_wheel"):
        moma.place(model, geom, s, group, ("nowhere_wheel", "r_wheel_joint"),
                   grasp_pose=pose, frame="gripper_link")
    with pytest.raises(moma.MomaError, match="payload"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, frame="gripper_link",
                   casters=casters, payload=-1.0)
    with pytest.raises(moma.MomaError, match="area"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, frame="gripper_link",
                   casters=casters, area=[0.0, 0.0, 1.0])
    with pytest.raises(moma.MomaError, match=r"casters\[1\]"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, frame="gripper_link",
                   casters=[[0.1, 0.1], [0.2]])
    with pytest.raises(moma.MomaError, match="posture"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, frame="gripper_link",
                   casters=casters, posture=[0.0, 1.0])
    fixed = moma.Model.from_urdf(FETCH_URDF, "fixed")
    fixed_geom = moma.GeometryModel.from_urdf(fixed, FETCH_URDF, package_dirs=[FETCH])
    with pytest.raises(moma.MomaError, match="support polygon"):
        moma.place(model, geom, s, group, WHEELS, grasp_pose=pose, frame="gripper_link")
    with pytest.raises(moma.MomaError, match="planar"):
        moma.place(fixed, fixed_geom, s, group, WHEELS, grasp_pose=pose,
                   frame="gripper_link")
