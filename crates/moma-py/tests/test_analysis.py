"""Tip-over stability, free-floating and operational-space results against the public
reference cases and the command line (same per-state documents), batched against
looped, and their error messages."""

import numpy as np
import pytest

import moma
from conftest import DATA, EXAMPLES, URDF, assert_close, load_json, run_cli

PANDA = URDF / "panda.urdf"
SUPPORT = [[0.35, -0.25], [-0.3, 0.25], [0.35, 0.25], [-0.3, -0.25]]


def test_stability_public_cases():
    cases = load_json(DATA / "stability" / "multibody_public.json")["cases"]
    assert cases
    for c in cases:
        model = moma.Model.from_urdf(DATA / c["urdf"], root=c["root"])
        st = c["state"]
        got = moma.stability(
            model, model.create_data(), st["q"], st.get("v"), st.get("a"),
            support=c["support_base"], mhs_bodies=c["mhs_bodies"], gravity=c["gravity"],
            external=st.get("external"),
        )
        assert_close(got, c["expected"], rtol=1e-9, atol=1e-9)


def test_stability_equals_cli(moma_bin):
    states_file = EXAMPLES / "panda_stability_states.json"
    cli = run_cli(
        moma_bin, "stability", PANDA, "--root", "planar",
        "--support", ";".join(f"{x},{y}" for x, y in SUPPORT), "--states", states_file,
    )
    model = moma.Model.from_urdf(PANDA, root="planar")
    data = model.create_data()
    states = load_json(states_file)["states"]
    assert len(cli["states"]) == len(states) >= 2
    for s, expected in zip(states, cli["states"]):
        got = moma.stability(
            model, data, s["q"], s.get("v"), s.get("a"), support=SUPPORT,
            external=s.get("external"),
        )
        assert got == expected
    assert "acceleration_limits" in cli["states"][0]


def test_stability_batch_equals_loop():
    model = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    data = model.create_data()
    rng = np.random.default_rng(11)
    n = 25
    q = np.tile(model.neutral(), (n, 1))
    q[:, 3:] += rng.uniform(-1.0, 1.0, (n, model.nq - 3))
    a = np.zeros((n, model.nv))
    a[:, 0] = rng.uniform(-6.0, 6.0, n)
    support = [[0.25, 0.2], [-0.25, 0.2], [-0.25, -0.2], [0.25, -0.2]]
    b = moma.stability_batch(model, data, q, None, a, support=support, mhs_bodies="all")
    assert b["stable"].dtype == bool and b["zmp_critical_edge"].dtype == np.int64
    assert 0 < b["stable"].sum() < n, "the sample should hold stable and tipping states"
    for k in range(n):
        one = moma.stability(model, data, q[k], None, a[k], support=support)
        assert b["total_mass"][k] == one["total_mass"]
        assert list(b["com"][k]) == one["com"]
        for key in ("zmp_margin", "force_angle_min", "force_angle_alpha", "force_angle_beta_min", "mhs_min"):
            want = one[key]
            assert (np.isnan(b[key][k]) and want is None) or b[key][k] == want, key
        assert list(b["zmp"][k]) == one["zmp"]
        assert b["zmp_critical_edge"][k] == one["zmp_critical_edge"]
        assert b["stable"][k] == one["stable"]


def test_space_public_cases():
    cases = load_json(DATA / "space" / "multibody_public.json")["cases"]
    for c in cases:
        model = moma.Model.from_urdf(DATA / c["urdf"], root="free-flyer")
        st = c["state"]
        got = moma.space(model, model.create_data(), st["q"], st["qdot_joints"], c["frame"], st.get("momentum"))
        assert_close(got, c["expected"], rtol=1e-9, atol=1e-9)


def test_space_equals_cli(moma_bin):
    states_file = EXAMPLES / "panda_space_states.json"
    cli = run_cli(moma_bin, "space", PANDA, "--frame", "panda_hand_tcp", "--states", states_file)
    model = moma.Model.from_urdf(PANDA, root="free-flyer")
    data = model.create_data()
    for s, expected in zip(load_json(states_file)["states"], cli["states"]):
        got = moma.space(model, data, s["q"], s["qdot_joints"], frame="panda_hand_tcp", momentum=s.get("momentum"))
        assert got == expected


def test_osc_public_cases():
    for c in load_json(DATA / "control" / "osc_public.json")["cases"]:
        model = moma.Model.from_urdf(DATA / c["urdf"], root=c["root"])
        st = c["state"]
        got = moma.osc(model, model.create_data(), st["q"], st.get("v"), c["frame"], st["task_acceleration"], st.get("null_torque"))
        assert_close(got, c["expected"], rtol=1e-8, atol=1e-8)


def test_osc_equals_cli(moma_bin):
    states_file = EXAMPLES / "panda_osc_states.json"
    cli = run_cli(moma_bin, "osc", PANDA, "--root", "fixed", "--frame", "panda_hand_tcp", "--states", states_file)
    model = moma.Model.from_urdf(PANDA, root="fixed")
    data = model.create_data()
    for s, expected in zip(load_json(states_file)["states"], cli["states"]):
        got = moma.osc(model, data, s["q"], s.get("v"), "panda_hand_tcp", s["task_acceleration"], s.get("null_torque"))
        assert got == expected


def test_analysis_error_messages():
    model = moma.Model.from_urdf(PANDA, root="planar")
    data = model.create_data()
    q = model.neutral()
    with pytest.raises(moma.MomaError, match="^support: "):
        moma.stability(model, data, q, support=[[0, 0], [1, 0]])
    with pytest.raises(moma.MomaError, match="^mhs_bodies: "):
        moma.stability(model, data, q, support=SUPPORT, mhs_bodies="some")
    with pytest.raises(moma.MomaError, match=r'^external\[0\]: missing field "force"$'):
        moma.stability(model, data, q, support=SUPPORT, external=[{"point": [0, 0, 0]}])
    with pytest.raises(moma.MomaError, match=r"^stability q: expected length 12, got 9$"):
        moma.stability(model, data, q[:9], support=SUPPORT)
    fixed = moma.Model.from_urdf(PANDA, root="fixed")
    fd = fixed.create_data()
    with pytest.raises(moma.MomaError, match="free"):
        moma.space(fixed, fd, fixed.neutral(), np.zeros(3), "panda_hand_tcp")
    ff = moma.Model.from_urdf(PANDA, root="free-flyer")
    with pytest.raises(moma.MomaError, match=r"^space qdot_joints: expected length 9, got 2$"):
        moma.space(ff, ff.create_data(), ff.neutral(), [0.0, 0.0], "panda_hand_tcp")
    with pytest.raises(moma.MomaError, match=r"^osc task_acceleration: expected 6 values \(or 3, one per selected row\), got 4$"):
        moma.osc(fixed, fd, fixed.neutral(), None, "panda_hand_tcp", [0, 0, 0, 0], rows="position")
    with pytest.raises(moma.MomaError, match=r"^osc: task Jacobian of frame 'panda_link0' is singular"):
        moma.osc(fixed, fd, fixed.neutral(), None, "panda_link0", np.zeros(6))
    with pytest.raises(moma.MomaError, match="^rows: "):
        moma.osc(fixed, fd, fixed.neutral(), None, "panda_hand_tcp", np.zeros(6), rows="diagonal")
