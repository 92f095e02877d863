"""Shared by generate_tiago.py and generate_more.py: the parts of a Pinocchio reference
file both write, in the schema of the shared reference files (panda.json, ...)."""
import numpy as np
import pinocchio as pin


def joint_table(model):
    """Every joint but the universe: name, Pinocchio type, q/v indices and sizes, parent."""
    joints = []
    for j in range(1, model.njoints):
        jm = model.joints[j]
        joints.append({"name": model.names[j], "type": jm.shortname(), "idx_q": jm.idx_q,
                       "idx_v": jm.idx_v, "nq": jm.nq, "nv": jm.nv,
                       "parent": model.names[model.parents[j]]})
    return joints


def random_state(model, data, rng, coriolis=False):
    """One seeded random state (q = neutral ⊕ U(−π, π)^nv; v, a, τ ~ U(−1, 1)) with rnea,
    crba (symmetrised from the upper triangle), aba, nonLinearEffects,
    computeGeneralizedGravity, computeCoriolisMatrix (if `coriolis`), centerOfMass and
    ccrba."""
    nv = model.nv
    q = pin.integrate(model, pin.neutral(model), rng.uniform(-np.pi, np.pi, nv))
    v = rng.uniform(-1, 1, nv)
    a = rng.uniform(-1, 1, nv)
    tau_in = rng.uniform(-1, 1, nv)
    s = {"q": q.tolist(), "v": v.tolist(), "a": a.tolist(), "tau_in": tau_in.tolist()}
    s["rnea_tau"] = pin.rnea(model, data, q, v, a).tolist()
    M = np.asarray(pin.crba(model, data, q)).reshape(nv, nv)
    s["crba_M"] = (np.triu(M) + np.triu(M, 1).T).tolist()
    s["aba_ddq"] = pin.aba(model, data, q, v, tau_in).tolist()
    s["nle"] = pin.nonLinearEffects(model, data, q, v).tolist()
    s["gravity_torque"] = pin.computeGeneralizedGravity(model, data, q).tolist()
    if coriolis:
        s["coriolis_C"] = np.asarray(
            pin.computeCoriolisMatrix(model, data, q, v)).reshape(nv, nv).tolist()
    s["com"] = pin.centerOfMass(model, data, q).tolist()
    s["centroidal_map_Ag"] = np.asarray(pin.ccrba(model, data, q, v)).reshape(6, nv).tolist()
    return s, q, v
