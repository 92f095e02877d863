"""Arm motion planning from Python: a shipped MotionBenchMaker table query solved by
`moma.plan_motion`, the same path as `moma motion` with the same seed, the scene's meshes
as hulls or as triangles (`mesh`), and bad input."""

import json

import numpy as np
import pytest

import moma
from conftest import DATA, run_cli

FETCH = DATA / "robots" / "fetch"
FETCH_URDF = FETCH / "fetch_description" / "robots" / "fetch.urdf"
QUERIES = DATA / "scenes" / "motion_bench_maker" / "fetch_queries"
QUERY = "table_pick-Front-Can1-0"
SEED = 7


@pytest.fixture(scope="module")
def problem():
    model = moma.Model.from_urdf(FETCH_URDF, "fixed")
    geom = moma.GeometryModel.from_urdf(
        model, FETCH_URDF, srdf=FETCH / "fetch.srdf", package_dirs=[FETCH]
    )
    queries = json.loads((QUERIES / "queries.json").read_text())
    query = next(q for q in queries["queries"] if q["name"] == QUERY)
    scene_path = QUERIES / query["scene"]
    scene = moma.Scene.from_yaml(scene_path, world_frames=["world", "base_link"])
    return model, geom, scene, scene_path, queries["group"], query


@pytest.fixture(scope="module")
def solved(problem):
    model, geom, scene, _, group, q = problem
    return moma.plan_motion(
        model, geom, scene, group, q["start"], goal_state=q["goal_state"],
        time_limit=30.0, seed=SEED,
    )


def test_table_query_solved_clear_and_within_limits(problem, solved):
    model, geom, scene, _, group, q = problem
    r = solved
    assert r["solved"] is True and r["reason"] is None
    path, traj = r["path"], r["trajectory"]
    assert path.ndim == 2 and path.shape[1] == model.nq and path.shape[0] >= 2
    np.testing.assert_array_equal(path[0], q["start"])
    np.testing.assert_array_equal(path[-1], q["goal_state"])
    t, tq = traj["t"], traj["q"]
    assert t.shape == (tq.shape[0],) and tq.shape[1] == model.nq
    assert t[0] == 0.0 and np.all(np.diff(t) > 0)
    assert r["duration_s"] == pytest.approx(t[-1])
    np.testing.assert_allclose(tq[0], q["start"], atol=1e-9)
    np.testing.assert_allclose(tq[-1], q["goal_state"], atol=1e-9)
    assert r["group"] == group and r["seed"] == SEED
    assert r["checks"] > 0 and r["planning_time_s"] > 0
    assert r["min_distance"] > 0
    # The joints outside the group never move.
    outside = [i for i, name in enumerate(json.loads(
        (QUERIES / "queries.json").read_text())["joint_order"]) if name not in group]
    np.testing.assert_array_equal(tq[:, outside], np.tile(np.array(q["start"])[outside],
                                                          (len(t), 1)))
    # Every sample is clear of the scene by the collision module's own query.
    ids = set(scene.ids)
    for k in range(0, len(t), 5):
        d = moma.distances(model, geom, tq[k], scene=scene)
        scene_d = [x for (a, b), x in zip(d["pairs"], d["distance"]) if b in ids]
        assert min(scene_d) > 0, (k, t[k])


def test_same_seed_same_path_and_same_as_the_cli(problem, solved, moma_bin, tmp_path):
    model, geom, scene, scene_path, group, q = problem
    again = moma.plan_motion(
        model, geom, scene, group, q["start"], goal_state=q["goal_state"],
        time_limit=30.0, seed=SEED,
    )
    np.testing.assert_array_equal(again["path"], solved["path"])
    np.testing.assert_array_equal(again["trajectory"]["q"], solved["trajectory"]["q"])
    assert again["checks"] == solved["checks"]
    start, goal, out = tmp_path / "s.json", tmp_path / "g.json", tmp_path / "o.json"
    start.write_text(json.dumps({"states": [{"q": q["start"]}]}))
    goal.write_text(json.dumps({"states": [{"q": q["goal_state"]}]}))
    run_cli(
        moma_bin, "motion", FETCH_URDF, "--root", "fixed", "--srdf", FETCH / "fetch.srdf",
        "--package-dir", FETCH, "--scene", scene_path, "--group", ",".join(group),
        "--start", start, "--goal-state", goal, "--time-limit", "30", "--seed", str(SEED),
        "--output", out, parse=False,
    )
    cli = json.loads(out.read_text())
    np.testing.assert_array_equal(solved["path"], np.array(cli["path"]))
    np.testing.assert_array_equal(solved["trajectory"]["t"], np.array(cli["trajectory"]["t"]))
    assert solved["checks"] == cli["checks"]
    assert solved["min_distance"] == cli["min_distance"]
    assert solved["mesh_surface_links"] == cli["mesh_surface_links"]


def test_goal_pose_unreachable_is_reported_not_raised(problem):
    model, geom, scene, _, group, q = problem
    r = moma.plan_motion(
        model, geom, scene, group, q["start"], goal_pose=[5.0, 0.0, 1.0],
        frame="gripper_link", time_limit=5.0, seed=1,
    )
    assert r["solved"] is False
    assert "unreachable" in r["reason"]
    assert r["path"].shape == (0, model.nq) and r["trajectory"]["t"].shape == (0,)


def test_bad_input_raises(problem):
    model, geom, scene, _, group, q = problem
    start, goal = q["start"], q["goal_state"]
    with pytest.raises(moma.MomaError, match="no_such_joint"):
        moma.plan_motion(model, geom, scene, group + ["no_such_joint"], start,
                         goal_state=goal)
    with pytest.raises(moma.MomaError, match="start"):
        moma.plan_motion(model, geom, scene, group, start[:-1], goal_state=goal)
    with pytest.raises(moma.MomaError, match="not both"):
        moma.plan_motion(model, geom, scene, group, start, goal_state=goal,
                         goal_pose=[0.7, 0.0, 1.0], frame="gripper_link")
    with pytest.raises(moma.MomaError, match="goal_state or goal_pose"):
        moma.plan_motion(model, geom, scene, group, start)
    with pytest.raises(moma.MomaError, match="nowhere_link"):
        moma.plan_motion(model, geom, scene, group, start, goal_pose=[0.7, 0.0, 1.0],
                         frame="nowhere_link")
    with pytest.raises(moma.MomaError, match="frame"):
        moma.plan_motion(model, geom, scene, group, start, goal_pose=[0.7, 0.0, 1.0])
    with pytest.raises(moma.MomaError, match="time_limit"):
        moma.plan_motion(model, geom, scene, group, start, goal_state=goal, time_limit=0)
    with pytest.raises(moma.MomaError, match="max_acceleration"):
        moma.plan_motion(model, geom, scene, group, start, goal_state=goal,
                         max_acceleration=[1.0, 2.0])
    # A non-finite start coordinate.
    inside = list(start)
    inside[2] = float("nan")
    with pytest.raises(moma.MomaError, match="start"):
        moma.plan_motion(model, geom, scene, group, inside, goal_state=goal)


def test_mesh_exact_plans_between_plates_whose_hull_holds_the_arm(problem):
    # concave_plates: table_pick-Front-Can1-0's scene plus two plates 1.4 m apart (one
    # mesh); their convex hull holds the tucked arm, their triangles are 0.441 m from it
    # (coal, the scene file's header). As `moma motion --mesh`.
    model, geom, _, _, group, q = problem
    plates = moma.Scene.from_yaml(
        DATA / "scenes" / "motion_bench_maker" / "concave_plates" / "scene.yaml",
        world_frames=["world", "base_link"],
    )
    with pytest.raises(moma.MomaError, match="scene object 'plates' intersects link"):
        moma.plan_motion(model, geom, plates, group, q["start"], goal_state=q["goal_state"],
                         mesh="convex")
    r = moma.plan_motion(model, geom, plates, group, q["start"], goal_state=q["goal_state"],
                         time_limit=30.0, seed=SEED, mesh="exact")
    assert r["solved"] is True, r["reason"]
    np.testing.assert_array_equal(r["path"][0], q["start"])
    np.testing.assert_array_equal(r["path"][-1], q["goal_state"])
    assert r["min_distance"] > 0
    # Time to spare: the minimum covers every waypoint and every sample.
    assert r["min_distance_states"] == r["path"].shape[0] + r["trajectory"]["t"].shape[0]
    # The collision module's exact measure agrees that the samples clear the plates.
    for k in range(0, len(r["trajectory"]["t"]), 10):
        d = moma.distances(model, geom, r["trajectory"]["q"][k], scene=plates, mesh="exact")
        plate = [x for (_, b), x in zip(d["pairs"], d["distance"]) if b == "plates"]
        assert min(plate) > 0, k


def test_mesh_other_than_convex_or_exact_is_a_value_error(problem):
    model, geom, scene, _, group, q = problem
    with pytest.raises(ValueError, match="mesh: 'hull' is not 'convex' or 'exact'"):
        moma.plan_motion(model, geom, scene, group, q["start"], goal_state=q["goal_state"],
                         mesh="hull")
