"""Rigid-body algorithms against the Pinocchio 4.1 dumps, batched against looped, and
the error messages of bad input."""

import numpy as np
import pytest

import moma
from conftest import DATA, URDF, load_json

# Robots whose Pinocchio state layout is moma's (fixed or free-flyer roots without
# continuous joints), so the dumps apply as they are.
DUMPS = ["panda.json", "ur5.json", "anymal_c_freeflyer.json", "g1_29dof_freeflyer.json"]


def model_of(ref):
    root = {"fixed": "fixed", "freeflyer": "free-flyer", "planar": "planar"}[ref["root_joint"]]
    return moma.Model.from_urdf(DATA / "pinocchio" / ref["urdf"], root=root)


@pytest.mark.parametrize("name", DUMPS)
def test_rigid_body_matches_pinocchio(name):
    ref = load_json(DATA / "pinocchio" / name)
    model = model_of(ref)
    assert (model.nq, model.nv) == (ref["nq"], ref["nv"])
    data = model.create_data()
    for s in ref["states"]:
        q, v, a, tau = (np.array(s[k]) for k in ("q", "v", "a", "tau_in"))
        np.testing.assert_allclose(moma.rnea(model, data, q, v, a), s["rnea_tau"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(data.tau, s["rnea_tau"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(moma.crba(model, data, q), s["crba_M"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(moma.aba(model, data, q, v, tau), s["aba_ddq"], rtol=1e-8, atol=1e-8)
        jacs = []
        for key in ("ee_frame", "last_frame"):
            if key in s:
                jacs.append((s[key]["name"], s[key]["jacobian_local_world_aligned"]))
        for j in s.get("jacobians", []):
            jacs.append((j["name"], j["local_world_aligned"]))
        assert jacs
        for frame, jref in jacs:
            j = moma.frame_jacobian(model, data, q, frame)
            assert j.shape == (6, model.nv)
            np.testing.assert_allclose(j, jref, rtol=1e-9, atol=1e-9)


def random_states(model, n, seed):
    rng = np.random.default_rng(seed)
    q = np.tile(model.neutral(), (n, 1))
    lo, hi = model.lower_position_limit, model.upper_position_limit
    for i in range(model.nq):
        if np.isfinite(lo[i]) and np.isfinite(hi[i]) and hi[i] > lo[i] and hi[i] - lo[i] < 100:
            q[:, i] = rng.uniform(lo[i], hi[i], n)
    v = rng.normal(size=(n, model.nv))
    a = rng.normal(size=(n, model.nv))
    return q, v, a


@pytest.mark.parametrize("urdf,root", [("panda.urdf", "fixed"), ("tiago.urdf", "planar"), ("anymal_c.urdf", "free-flyer")])
def test_batches_equal_loops(urdf, root):
    model = moma.Model.from_urdf(URDF / urdf, root=root)
    data = model.create_data()
    q, v, a = random_states(model, 7, 3)
    tau = moma.rnea_batch(model, data, q, v, a)
    ddq = moma.aba_batch(model, data, q, v, a)
    m = moma.crba_batch(model, data, q)
    frame = model.frame_names[-1]
    j = moma.frame_jacobian_batch(model, data, q, frame)
    assert tau.shape == (7, model.nv) and m.shape == (7, model.nv, model.nv) and j.shape == (7, 6, model.nv)
    for k in range(7):
        assert np.array_equal(tau[k], moma.rnea(model, data, q[k], v[k], a[k]))
        assert np.array_equal(ddq[k], moma.aba(model, data, q[k], v[k], a[k]))
        assert np.array_equal(m[k], moma.crba(model, data, q[k]))
        assert np.array_equal(j[k], moma.frame_jacobian(model, data, q[k], frame))


def test_parallel_batch_equals_loop_and_names_the_first_bad_row():
    # above the size at which the batch shares its blocks between the caller and the pool
    model = moma.Model.from_urdf(URDF / "panda.urdf")
    data = model.create_data()
    q, v, a = random_states(model, 5000, 11)
    tau = moma.rnea_batch(model, data, q, v, a)
    for k in range(0, 5000, 7):
        assert np.array_equal(tau[k], moma.rnea(model, data, q[k], v[k], a[k]))
    v[4321, 0] = np.nan
    a[3000, 2] = -np.inf
    with pytest.raises(moma.MomaError, match=r"^non-finite value in rnea_batch row 3000 a\[2\]$"):
        moma.rnea_batch(model, data, q, v, a)


def test_rnea_batch_writes_into_out():
    model = moma.Model.from_urdf(URDF / "panda.urdf")
    data = model.create_data()
    q, v, a = random_states(model, 3000, 12)
    want = moma.rnea_batch(model, data, q, v, a)
    out = np.full((3000, model.nv), 7.0)
    got = moma.rnea_batch(model, data, q, v, a, out=out)
    assert got is out and np.array_equal(out, want)
    with pytest.raises(moma.MomaError, match=r"^rnea_batch out: expected shape \(3000, 9\), got \[3000, 8\]$"):
        moma.rnea_batch(model, data, q, v, a, out=np.zeros((3000, 8)))
    with pytest.raises(moma.MomaError, match=r"^rnea_batch out: not writeable, or shares memory with an input"):
        moma.rnea_batch(model, data, q, v, v, out=v)
    frozen = np.zeros((3000, 9))
    frozen.flags.writeable = False
    with pytest.raises(moma.MomaError, match=r"^rnea_batch out: not writeable"):
        moma.rnea_batch(model, data, q, v, a, out=frozen)
    with pytest.raises(moma.MomaError, match=r"^rnea_batch out: expected a C-contiguous array$"):
        moma.rnea_batch(model, data, q, v, a, out=np.zeros((9, 3000)).T)
    v[2500, 3] = np.nan
    with pytest.raises(moma.MomaError, match=r"^non-finite value in rnea_batch row 2500 v\[3\]$"):
        moma.rnea_batch(model, data, q, v, a, out=out)
    assert np.isnan(out).all()


def test_inputs_accept_lists_and_non_contiguous_arrays():
    model = moma.Model.from_urdf(URDF / "panda.urdf")
    data = model.create_data()
    q, v, a = random_states(model, 4, 5)
    ref = moma.rnea(model, data, q[1], v[1], a[1])
    assert np.array_equal(moma.rnea(model, data, list(q[1]), list(v[1]), list(a[1])), ref)
    wide = np.zeros((4, 2 * model.nq))
    wide[:, ::2] = q
    assert np.array_equal(moma.rnea(model, data, wide[1, ::2], v[1], a[1]), ref)
    assert np.array_equal(moma.rnea_batch(model, data, wide[:, ::2], v, a)[1], ref)


def test_model_metadata():
    model = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    assert model.root == "planar" and model.name == "tiago"
    assert model.nq == len(model.neutral())
    assert model.joint_names[0] == "universe"
    assert "moma.Model(name='tiago', root='planar'" in repr(model)
    np.testing.assert_allclose(model.gravity, [0, 0, -9.81])


def test_error_messages():
    model = moma.Model.from_urdf(URDF / "panda.urdf")
    data = model.create_data()
    z = np.zeros(model.nv)
    with pytest.raises(moma.MomaError, match=r"^rnea q: expected length 9, got 3$"):
        moma.rnea(model, data, [0.0, 0.0, 0.0], z, z)
    with pytest.raises(moma.MomaError, match=r"^aba tau: expected length 9, got 2$"):
        moma.aba(model, data, z, z, [1.0, 2.0])
    bad = z.copy()
    bad[4] = np.nan
    with pytest.raises(moma.MomaError, match=r"^non-finite value in rnea v\[4\]$"):
        moma.rnea(model, data, z, bad, z)
    with pytest.raises(moma.MomaError, match=r"^unknown frame 'no_such_frame'$"):
        moma.frame_jacobian(model, data, z, "no_such_frame")
    other = moma.Model.from_urdf(URDF / "panda.urdf").create_data()
    with pytest.raises(moma.MomaError, match="data was created by another model"):
        moma.crba(model, other, z)
    qs = np.zeros((3, model.nq))
    qs[2, 1] = np.inf
    with pytest.raises(moma.MomaError, match=r"^non-finite value in rnea_batch row 2 q\[1\]$"):
        moma.rnea_batch(model, data, qs, np.zeros((3, 9)), np.zeros((3, 9)))
    with pytest.raises(moma.MomaError, match=r"rnea_batch v: expected 3 rows \(as q\), got 2"):
        moma.rnea_batch(model, data, np.zeros((3, 9)), np.zeros((2, 9)), np.zeros((3, 9)))
    with pytest.raises(moma.MomaError, match=r"crba_batch q: expected shape \(n, 9\), got \(3, 4\)"):
        moma.crba_batch(model, data, np.zeros((3, 4)))
    with pytest.raises(moma.MomaError, match=r"root joint.*'wheels' is not one of fixed, planar, free-flyer"):
        moma.Model.from_urdf(URDF / "panda.urdf", root="wheels")
    with pytest.raises(moma.MomaError, match=r"nope\.urdf: cannot read file"):
        moma.Model.from_urdf(URDF / "nope.urdf")
    ff = moma.Model.from_urdf(URDF / "panda.urdf", root="free-flyer")
    q = ff.neutral()
    q[6] = 2.0
    with pytest.raises(moma.MomaError, match="rnea"):
        moma.rnea(ff, ff.create_data(), q, np.zeros(ff.nv), np.zeros(ff.nv))
    assert issubclass(moma.MomaError, Exception)


@pytest.mark.parametrize("name", ["tiago_planar.json", "panda_planar.json"])
def test_pinocchio_layout_on_planar_dumps(name):
    """Pinocchio's states fed as they are: converted in, computed, converted out."""
    ref = load_json(DATA / "pinocchio" / name)
    model = model_of(ref)
    data = model.create_data()
    assert model.nv == ref["nv"]
    for s in ref["states"]:
        st = moma.from_pinocchio(model, s["q"], s["v"], s["a"], s["tau_in"])
        assert st["q"].shape == (model.nq,)
        tau = moma.rnea(model, data, st["q"], st["v"], st["a"])
        back = moma.to_pinocchio(model, st["q"], st["v"], st["a"], tau)
        np.testing.assert_allclose(back["tau"], s["rnea_tau"], rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(back["q"], s["q"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(back["v"], s["v"], rtol=0, atol=1e-12)
        np.testing.assert_allclose(back["a"], s["a"], rtol=0, atol=1e-12)
        ddq = moma.aba(model, data, st["q"], st["v"], st["tau"])
        pin_ddq = moma.to_pinocchio(model, st["q"], st["v"], ddq)["a"]
        np.testing.assert_allclose(pin_ddq, s["aba_ddq"], rtol=1e-8, atol=1e-8)


def test_pinocchio_layout_errors():
    model = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    q = model.neutral()
    with pytest.raises(moma.MomaError, match="converting a needs v"):
        moma.to_pinocchio(model, q, a=np.zeros(model.nv))
    qp = moma.to_pinocchio(model, q)["q"]
    assert len(qp) > model.nq
    bad = qp.copy()
    bad[2] = 3.0
    with pytest.raises(moma.MomaError, match="^from_pinocchio: "):
        moma.from_pinocchio(model, bad)
    with pytest.raises(moma.MomaError, match=r"^from_pinocchio: .*expected length"):
        moma.from_pinocchio(model, qp[:-1])
