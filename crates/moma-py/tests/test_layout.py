"""Pinocchio interop for matrices and for the operational-space quantities: the mass
matrix and frame Jacobians of the shared planar Pinocchio dumps (crba, LOCAL_WORLD_ALIGNED
frame Jacobians, in Pinocchio's layout) from moma's, and `osc(layout="pinocchio")` on
the TIAGo planar dump against Pinocchio + numpy and against `moma osc --layout pinocchio`."""

import numpy as np
import pytest

import moma
from conftest import DATA, URDF, load_json, run_cli

OSC_KEYS = [
    "task_inertia", "dynamically_consistent_inverse", "nullspace_projector",
    "acceleration_bias", "task_force", "torque",
]


@pytest.mark.parametrize("name", ["tiago_planar.json", "panda_planar.json"])
def test_mass_matrix_and_jacobians_match_pinocchio(name):
    ref = load_json(DATA / "pinocchio" / name)
    model = moma.Model.from_urdf(DATA / "pinocchio" / ref["urdf"], root="planar")
    data = model.create_data()
    for s in ref["states"]:
        q = moma.from_pinocchio(model, s["q"])["q"]
        h = moma.crba(model, data, q)
        frames = [s[k]["name"] for k in ("ee_frame", "last_frame")]
        for f in frames:
            j = moma.frame_jacobian(model, data, q, f)
            out = moma.to_pinocchio(model, q, mass_matrix=h, jacobian=j)
            np.testing.assert_allclose(out["mass_matrix"], s["crba_M"], rtol=1e-9, atol=1e-9)
            want_j = next(s[k]["jacobian_local_world_aligned"] for k in ("ee_frame", "last_frame")
                          if s[k]["name"] == f)
            np.testing.assert_allclose(out["jacobian"], want_j, rtol=1e-9, atol=1e-9)
            # and back: Pinocchio's matrices in moma's layout are moma's
            back = moma.from_pinocchio(model, s["q"], mass_matrix=s["crba_M"], jacobian=want_j)
            np.testing.assert_allclose(back["mass_matrix"], h, rtol=1e-9, atol=1e-9)
            np.testing.assert_allclose(back["jacobian"], j, rtol=1e-9, atol=1e-9)
        # the base heading matters: the conversion is not the identity on these states
        assert np.abs(out["mass_matrix"] - h).max() > 1e-6
        # a Jacobian of any number of rows: its columns transform
        two = moma.to_pinocchio(model, q, jacobian=j[:2])["jacobian"]
        np.testing.assert_array_equal(two, out["jacobian"][:2])


def test_matrix_errors():
    model = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    q, nv = model.neutral(), model.nv
    with pytest.raises(moma.MomaError, match=r"^to_pinocchio mass_matrix: expected shape"):
        moma.to_pinocchio(model, q, mass_matrix=np.zeros((nv, nv - 1)))
    with pytest.raises(moma.MomaError, match=r"^from_pinocchio jacobian: expected shape"):
        qp = moma.to_pinocchio(model, q)["q"]
        moma.from_pinocchio(model, qp, jacobian=np.zeros((6, nv + 1)))
    bad = np.eye(nv)
    bad[3, 4] = np.inf
    with pytest.raises(moma.MomaError, match=r"mass_matrix\[3, 4\]"):
        moma.to_pinocchio(model, q, mass_matrix=bad)


def test_osc_planar_root_in_pinocchio_layout(moma_bin, tmp_path):
    ref = load_json(DATA / "control" / "osc_tiago_planar.json")
    model = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    data = model.create_data()
    states = [{k: s[k] for k in ("q", "v", "task_acceleration", "null_torque")}
              for s in ref["states"]]
    path = tmp_path / "states.json"
    import json
    path.write_text(json.dumps({"states": states}))
    cli = run_cli(moma_bin, "osc", URDF / "tiago.urdf", "--root", "planar", "--frame",
                  ref["frame"], "--states", path, "--layout", "pinocchio")
    for s, want, c in zip(states, ref["states"], cli["states"]):
        got = moma.osc(model, data, s["q"], s["v"], ref["frame"], s["task_acceleration"],
                       s["null_torque"], layout="pinocchio")
        assert got == c
        for k in OSC_KEYS:
            np.testing.assert_allclose(np.array(got[k]), np.array(want[k]), rtol=1e-9,
                                       atol=1e-9, err_msg=k)
        # moma's layout: Λ and F unchanged, τ and J̄ through T
        st = moma.from_pinocchio(model, s["q"], s["v"], tau=s["null_torque"])
        mom = moma.osc(model, data, st["q"], st["v"], ref["frame"], s["task_acceleration"],
                       st["tau"])
        np.testing.assert_allclose(mom["task_inertia"], got["task_inertia"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(mom["task_force"], got["task_force"], rtol=1e-9, atol=1e-9)
        tau_p = moma.to_pinocchio(model, st["q"], tau=mom["torque"])["tau"]
        np.testing.assert_allclose(tau_p, got["torque"], rtol=1e-9, atol=1e-9)
    with pytest.raises(moma.MomaError, match='osc layout: expected "moma" or "pinocchio"'):
        moma.osc(model, data, states[0]["q"], None, ref["frame"], np.zeros(6), layout="pin")
