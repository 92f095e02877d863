"""Maps and planning against the command line (`moma plan`'s smoothed waypoints)."""

import json

import numpy as np
import pytest

import moma
from conftest import DATA, run_cli

TURTLEBOT = DATA / "planning" / "rosmaps" / "turtlebot3" / "map.yaml"
ROOM = DATA / "planning" / "movingai" / "32room_000.map"


def test_load_map_metadata():
    m = moma.load_map(TURTLEBOT)
    assert m.kind == "ros" and m.resolution > 0
    assert m.cells.shape == (m.height, m.width) and m.cells.dtype == np.int8
    r = moma.load_map(ROOM)
    assert r.kind == "movingai" and r.resolution == 1.0


def test_plan_equals_cli_on_ros_map(moma_bin, tmp_path):
    out = tmp_path / "path.json"
    run_cli(moma_bin, "plan", TURTLEBOT, "--start=-2,-0.5", "--goal", "1.5,0.5", "--radius", "0.1", "--output", out, parse=False)
    cli = json.loads(out.read_text())
    grid = moma.load_map(TURTLEBOT)
    path = moma.plan(grid, [-2.0, -0.5], [1.5, 0.5], radius=0.1)
    assert path.shape == (len(cli["waypoints"]), 2)
    assert path.tolist() == cli["waypoints"]
    raw = moma.plan(grid, [-2.0, -0.5], [1.5, 0.5], radius=0.1, smooth=False)
    assert raw.shape[0] == len(cli["cells"]) > path.shape[0]


def test_plan_equals_cli_on_movingai_map(moma_bin, tmp_path):
    out = tmp_path / "path.json"
    # the last problem of the map's scenario file (the longest)
    last = (ROOM.parent / (ROOM.name + ".scen")).read_text().split("\n")
    f = [ln.split("\t") for ln in last if ln.strip() and not ln.startswith("version")][-1]
    start, goal = [int(f[4]), int(f[5])], [int(f[6]), int(f[7])]
    run_cli(moma_bin, "plan", ROOM, "--start", f"{start[0]},{start[1]}", "--goal", f"{goal[0]},{goal[1]}", "--output", out, parse=False)
    cli = json.loads(out.read_text())
    path = moma.plan(moma.load_map(ROOM), start, goal)
    assert path.shape[0] > 3
    assert path.tolist() == cli["waypoints"]


def write_split_map(path):
    rows = ["....@....", "....@....", "....@...."]
    path.write_text("type octile\nheight 3\nwidth 9\nmap\n" + "\n".join(rows) + "\n")
    return path


def test_plan_unreachable_is_none(tmp_path):
    grid = moma.load_map(write_split_map(tmp_path / "split.map"))
    assert moma.plan(grid, [0, 1], [8, 1]) is None
    assert moma.plan(grid, [0, 1], [3, 1]).tolist()[-1] == [3.0, 1.0]


def test_plan_errors(tmp_path):
    grid = moma.load_map(write_split_map(tmp_path / "split.map"))
    with pytest.raises(moma.MomaError, match=r"^planning: goal at cell \(4, 1\) lies in an obstacle$"):
        moma.plan(grid, [0, 1], [4, 1])
    with pytest.raises(moma.MomaError, match=r"must be a cell of the 9 x 3 map"):
        moma.plan(grid, [0.5, 1], [3, 1])
    with pytest.raises(moma.MomaError, match=r"closer than the robot radius 1.5 cells"):
        moma.plan(grid, [0, 1], [3, 1], radius=1.5)
    with pytest.raises(moma.MomaError, match="cannot read"):
        moma.load_map(tmp_path / "missing.yaml")
