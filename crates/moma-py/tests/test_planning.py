"""Maps and planning against the command line (`moma plan`'s smoothed waypoints)."""

import json
import subprocess

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


def write_one_obstacle_map(path):
    """30 x 12 cells, one obstacle at (15, 7), two rows above the path along row 5."""
    rows = ["".join("@" if (x, y) == (15, 7) else "." for x in range(30)) for y in range(12)]
    path.write_text("type octile\nheight 12\nwidth 30\nmap\n" + "\n".join(rows) + "\n")
    return path


ALONG = [[-2.5, -1], [2.5, -1], [2.5, 1], [-2.5, 1]]    # 5 cells along the heading, 2 across
ACROSS = [[-1, -2.5], [1, -2.5], [1, 2.5], [-1, 2.5]]   # 2 along, 5 across


def cli_check(moma_bin, grid_path, out, polygon, padding=None):
    """`moma plan --radius 0.5 --check-footprint` from (3, 5) to (27, 5): exit code and path.json."""
    args = [str(moma_bin), "plan", str(grid_path), "--start", "3,5", "--goal", "27,5",
            "--radius", "0.5", "--output", str(out),
            "--check-footprint", ";".join(f"{x},{y}" for x, y in polygon)]
    if padding is not None:
        args += ["--check-padding", str(padding)]
    done = subprocess.run(args, capture_output=True, text=True)
    return done.returncode, json.loads(out.read_text())


@pytest.mark.parametrize("polygon, padding, status", [
    (ALONG, None, "found"),
    (ACROSS, None, "colliding"),
    (ALONG, 0.6, "colliding"),
])
def test_plan_checks_the_path_with_a_polygon_as_the_cli(moma_bin, tmp_path, polygon, padding, status):
    grid_path = write_one_obstacle_map(tmp_path / "one.map")
    code, cli = cli_check(moma_bin, grid_path, tmp_path / "path.json", polygon, padding)
    assert code == (0 if status == "found" else 3)
    assert cli["status"] == status
    kw = {} if padding is None else {"check_padding": padding}
    r = moma.plan(moma.load_map(grid_path), [3, 5], [27, 5], radius=0.5, check_footprint=polygon, **kw)
    assert r["status"] == status
    assert r["waypoints"].tolist() == cli["waypoints"]
    assert r["check"] == cli["robot"]["check"]
    assert (r["check"]["colliding"] == []) == (status == "found")


def test_plan_check_refuses_a_colliding_start_or_goal_and_bad_input(tmp_path):
    grid = moma.load_map(write_one_obstacle_map(tmp_path / "one.map"))
    # (15, 5): the disk fits, the chassis 5 cells wide across the path does not
    with pytest.raises(moma.MomaError, match=r"^planning: start: the footprint polygon .*\(none was given\)"):
        moma.plan(grid, [15, 5], [27, 5], radius=0.5, check_footprint=ACROSS)
    with pytest.raises(moma.MomaError, match=r"^planning: goal: the footprint polygon"):
        moma.plan(grid, [3, 5], [15, 5], radius=0.5, check_footprint=ACROSS)
    concave = [[-1, -1], [1, -1], [0.2, 0], [1, 1], [-1, 1]]
    with pytest.raises(moma.MomaError, match=r"check_footprint.*convex"):
        moma.plan(grid, [3, 5], [27, 5], check_footprint=concave)
    with pytest.raises(moma.MomaError, match=r"check_footprint"):
        moma.plan(grid, [3, 5], [27, 5], check_footprint=[[0, 0], [1, 0]])
    for bad in (-0.1, float("nan")):
        with pytest.raises(moma.MomaError, match=r"check_padding"):
            moma.plan(grid, [3, 5], [27, 5], check_footprint=ALONG, check_padding=bad)
    with pytest.raises(moma.MomaError, match=r"check_padding.*check_footprint"):
        moma.plan(grid, [3, 5], [27, 5], check_padding=0.1)
    # without the check: the waypoints alone, as before
    assert moma.plan(grid, [3, 5], [27, 5], radius=0.5).shape == (2, 2)
