"""Shared paths and helpers of the moma Python tests.

The reference files are the repository's copies (crates/moma/tests/data, whose README
files name their sources); the command line is the release binary that the README's
test command builds before pytest runs (override with MOMA_BIN).
"""

import json
import math
import os
import subprocess
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[3]
DATA = REPO / "crates" / "moma" / "tests" / "data"
URDF = DATA / "pinocchio" / "urdf"
EXAMPLES = REPO / "docs" / "examples"


def load_json(path):
    with open(path) as f:
        return json.load(f)


@pytest.fixture(scope="session")
def moma_bin():
    exe = Path(os.environ.get("MOMA_BIN", REPO / "target" / "release" / "moma"))
    assert exe.is_file(), (
        f"the moma binary {exe} is missing: build it with "
        "`cargo build --release --locked -p moma-cli` (scripts/test does) or set MOMA_BIN"
    )
    return exe


def run_cli(exe, *args, parse=True):
    """Runs the CLI and returns its parsed JSON standard output (or the text)."""
    out = subprocess.run([str(exe), *map(str, args)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout) if parse else out.stdout


def assert_close(actual, expected, rtol=1e-9, atol=1e-9, path="$"):
    """Recursive comparison of a result against a reference document: every key of the
    reference must be present; numbers within tolerance; None, bools and ints exact."""
    if isinstance(expected, dict):
        assert isinstance(actual, dict), f"{path}: expected an object, got {actual!r}"
        for k, v in expected.items():
            assert k in actual, f"{path}: missing key {k!r}"
            assert_close(actual[k], v, rtol, atol, f"{path}.{k}")
    elif isinstance(expected, (list, tuple)):
        actual = list(actual)
        assert len(actual) == len(expected), f"{path}: length {len(actual)} != {len(expected)}"
        for i, (a, e) in enumerate(zip(actual, expected)):
            assert_close(a, e, rtol, atol, f"{path}[{i}]")
    elif expected is None or isinstance(expected, (bool, str)):
        assert actual == expected, f"{path}: {actual!r} != {expected!r}"
    elif isinstance(expected, int) and isinstance(actual, int):
        assert actual == expected, f"{path}: {actual} != {expected}"
    else:
        a, e = float(actual), float(expected)
        assert math.isclose(a, e, rel_tol=rtol, abs_tol=atol), f"{path}: {a!r} != {e!r}"
