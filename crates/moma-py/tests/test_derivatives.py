"""rnea_derivatives / aba_derivatives against Pinocchio 4.1's computeRNEADerivatives /
computeABADerivatives (tests/data/derivatives of the library; the fixed- and free-flyer-
rooted arms, whose Pinocchio layout is moma's), against central finite differences of
moma.rnea / moma.aba, and their errors."""

import numpy as np
import pytest

import moma
from conftest import DATA, load_json

ROOTS = {"fixed": "fixed", "free-flyer": "free-flyer", "planar": "planar"}
KEYS_RNEA = ("drnea_dq", "drnea_dv", "drnea_da")
KEYS_ABA = ("daba_dq", "daba_dv", "daba_dtau")


def close(got, want):
    want = np.asarray(want)
    scale = max(1.0, np.abs(want).max())
    assert got.shape == want.shape
    assert np.abs(got - want).max() <= 1e-8 * scale


@pytest.mark.parametrize(
    "name", ["panda.json", "panda_freeflyer.json", "ur5_fixed.json", "ur5_freeflyer.json"]
)
def test_derivatives_match_pinocchio(name):
    ref = load_json(DATA / "derivatives" / name)
    model = moma.Model.from_urdf(DATA / "derivatives" / ref["urdf"], root=ROOTS[ref["root"]])
    data = model.create_data()
    for s in ref["states"]:
        q, v, a, tau = (np.array(s[k]) for k in ("q", "v", "a", "tau"))
        for got, key in zip(moma.rnea_derivatives(model, data, q, v, a), KEYS_RNEA):
            close(got, s[key])
        for got, key in zip(moma.aba_derivatives(model, data, q, v, tau), KEYS_ABA):
            close(got, s[key])


def test_finite_differences_on_a_planar_root():
    # moma's layout: world-axes planar velocity, q + dq (no free-flyer: plain addition
    # is the tangent perturbation here)
    model = moma.Model.from_urdf(DATA / "pinocchio" / "urdf" / "ur5_robot.urdf", root="planar")
    data = model.create_data()
    rng = np.random.default_rng(3)
    nv = model.nv
    q, v, a, tau = (rng.uniform(-1, 1, nv) for _ in range(4))
    dq, dv, da = moma.rnea_derivatives(model, data, q, v, a)
    bq, bv, bt = moma.aba_derivatives(model, data, q, v, tau)
    h = 1e-6
    eye = np.eye(nv) * h
    fd = lambda f: np.column_stack([(f(e) - f(-e)) / (2 * h) for e in eye])  # noqa: E731
    for got, want in [
        (dq, fd(lambda e: moma.rnea(model, data, q + e, v, a))),
        (dv, fd(lambda e: moma.rnea(model, data, q, v + e, a))),
        (da, fd(lambda e: moma.rnea(model, data, q, v, a + e))),
        (bq, fd(lambda e: moma.aba(model, data, q + e, v, tau))),
        (bv, fd(lambda e: moma.aba(model, data, q, v + e, tau))),
        (bt, fd(lambda e: moma.aba(model, data, q, v, tau + e))),
    ]:
        assert np.abs(got - want).max() <= 1e-6 * max(1.0, np.abs(want).max())


def test_bad_input_raises():
    model = moma.Model.from_urdf(DATA / "pinocchio" / "urdf" / "panda.urdf", root="fixed")
    data = model.create_data()
    z = np.zeros(model.nv)
    with pytest.raises(moma.MomaError, match="rnea_derivatives v"):
        moma.rnea_derivatives(model, data, z, np.zeros(3), z)
    with pytest.raises(moma.MomaError, match="aba_derivatives"):
        moma.aba_derivatives(model, data, z, z, np.full(model.nv, np.nan))
    other = moma.Model.from_urdf(DATA / "pinocchio" / "urdf" / "ur5_robot.urdf", root="fixed")
    with pytest.raises(moma.MomaError, match="another model"):
        moma.rnea_derivatives(other, data, np.zeros(6), np.zeros(6), np.zeros(6))
