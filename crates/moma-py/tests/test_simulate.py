"""moma.simulate runs a scenario file as `moma simulate FILE` does: the same recorded
samples as the command's trajectory.csv (t, q, v, u columns, written with shortest
round-trip formatting), the same final state and error messages."""

import subprocess

import numpy as np
import pytest

import moma
from conftest import REPO, load_json, run_cli


def cli_run(moma_bin, scenario, out):
    run_cli(moma_bin, "simulate", scenario, "--output", out, "--quiet", parse=False)
    table = np.loadtxt(out / "trajectory.csv", delimiter=",", skiprows=1, ndmin=2)
    return table, load_json(out / "summary.json")


@pytest.mark.parametrize(
    "name", ["default.toml", "control_kanayama.toml"]
)
def test_simulate_equals_cli_trajectory(name, moma_bin, tmp_path):
    scenario = REPO / "scenarios" / name
    table, summary = cli_run(moma_bin, scenario, tmp_path)
    r = moma.simulate(scenario)
    n, nq, nv, nu = len(r["t"]), r["q"].shape[1], r["v"].shape[1], r["u"].shape[1]
    assert r["q"].shape == (n, nq) and r["v"].shape == (n, nv) and r["u"].shape == (n, nu)
    assert table.shape[0] == n == r["samples"] == summary["samples"]
    assert r["q_names"] == summary["q_names"] and r["v_names"] == summary["v_names"]
    got = np.hstack([r["t"][:, None], r["q"], r["v"], r["u"]])
    np.testing.assert_allclose(got, table[:, : 1 + nq + nv + nu], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(r["final_q"], summary["final_q"], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(r["final_v"], summary["final_v"], rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(r["q"][-1], r["final_q"])
    for key in ["scenario", "robot", "duration", "accepted_steps", "rejected_steps"]:
        assert r[key] == summary[key], key
    if "law" in summary:
        assert r["law"] == summary["law"] and r["error_names"] == summary["error_names"]
        assert r["errors"].shape == (n, len(summary["error_names"]))
        np.testing.assert_allclose(r["errors"][0], summary["initial_error"], rtol=1e-12)
        np.testing.assert_allclose(r["errors"][-1], summary["final_error"], rtol=1e-12)
    else:
        assert "errors" not in r and "error_names" not in r


def test_simulate_error_names_file_and_field(moma_bin, tmp_path):
    text = (REPO / "scenarios" / "default.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace("duration = 5.0", "duration = -1.0", 1))
    with pytest.raises(moma.MomaError, match=r"bad\.toml.*duration") as e:
        moma.simulate(bad)
    cli = subprocess.run([str(moma_bin), "simulate", str(bad)], capture_output=True, text=True)
    assert cli.returncode != 0
    assert cli.stderr.strip() == f"error: {e.value}"
    with pytest.raises(moma.MomaError, match=r"missing\.toml"):
        moma.simulate(tmp_path / "missing.toml")


def test_simulate_contact_plant_equals_cli(moma_bin, tmp_path):
    scenario = REPO / "scenarios" / "contact_brake_arm_extended.toml"
    table, summary = cli_run(moma_bin, scenario, tmp_path)
    r = moma.simulate(scenario)
    nq, nv, nu = r["q"].shape[1], r["v"].shape[1], r["u"].shape[1]
    got = np.hstack([r["t"][:, None], r["q"], r["v"], r["u"]])
    np.testing.assert_allclose(got, table[:, : 1 + nq + nv + nu], rtol=1e-12, atol=1e-15)
    for key in ["contact", "contact_steps", "first_lift_off", "first_slip", "contacts",
                "max_tilt_rad", "final_q", "final_v", "samples"]:
        assert r[key] == summary[key], key


def test_simulate_mpc_object_equals_cli(moma_bin, tmp_path):
    scenario = REPO / "scenarios" / "mpc_reach_on_the_move.toml"
    _, summary = cli_run(moma_bin, scenario, tmp_path)
    r = moma.simulate(scenario)
    timing = "solve_time_s"
    assert set(r["mpc"]) == set(summary["mpc"])
    assert {k: v for k, v in r["mpc"].items() if k != timing} == {
        k: v for k, v in summary["mpc"].items() if k != timing
    }
    np.testing.assert_allclose(r["errors"][-1], summary["final_error"], rtol=1e-12)
