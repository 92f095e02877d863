"""Per-call cost of moma.rnea from Python against Pinocchio's Python bindings, in the
same process and interleaved rounds, and the batched form against a Python loop.

Run from the repository root in an environment holding both packages, e.g.:

    scripts/test                              # builds moma into .venv
    .venv/bin/pip install pin==4.1.0
    .venv/bin/python crates/moma-py/bench/rnea_vs_pin.py [--rounds 15] [--calls 20000]

Prints medians over rounds (each round times `calls` calls cycling through 100 seeded
random states) in nanoseconds per call / per state, and the ratios.
"""

import argparse
import json
import os
import statistics
import time
from pathlib import Path

# numpy's OpenBLAS starts a worker thread per core that can spin on a core the batch's
# rayon workers need (and is counted in the process CPU time); nothing here uses BLAS.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np

import moma

REPO = Path(__file__).resolve().parents[3]
URDF = REPO / "crates" / "moma" / "tests" / "data" / "pinocchio" / "urdf"


# CPU time of this process: on a shared, loaded machine wall time mostly measures the
# other processes. It sums over threads, so it is a per-state cost, not a latency; pass
# --wall for wall-clock time (the parallel batch's latency).
CLOCK = time.process_time_ns


def per_call(fn, states, calls):
    n = len(states)
    t0 = CLOCK()
    for i in range(calls):
        fn(*states[i % n])
    return (CLOCK() - t0) / calls


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--rounds", type=int, default=15)
    ap.add_argument("--calls", type=int, default=20000)
    ap.add_argument("--batch", type=int, default=10000)
    ap.add_argument("--wall", action="store_true", help="wall-clock instead of CPU time")
    ap.add_argument("--json", help="also write the medians (ns) to this JSON file")
    ap.add_argument("--no-tiago", action="store_true", help="skip the TIAGo stability sweep")
    args = ap.parse_args()
    global CLOCK
    if args.wall:
        CLOCK = time.perf_counter_ns

    import pinocchio as pin

    path = str(URDF / "panda.urdf")
    model = moma.Model.from_urdf(path, root="fixed")
    data = model.create_data()
    pmodel = pin.buildModelFromUrdf(path)
    pdata = pmodel.createData()
    assert (pmodel.nq, pmodel.nv) == (model.nq, model.nv)

    rng = np.random.default_rng(7)
    lo, hi = model.lower_position_limit, model.upper_position_limit
    n = 100
    qs = rng.uniform(lo, hi, (n, model.nq))
    vs = rng.normal(size=(n, model.nv))
    as_ = rng.normal(size=(n, model.nv))
    states = [(qs[i], vs[i], as_[i]) for i in range(n)]
    for q, v, a in states:
        np.testing.assert_allclose(moma.rnea(model, data, q, v, a), pin.rnea(pmodel, pdata, q, v, a), rtol=1e-9, atol=1e-9)

    def m_rnea(q, v, a):
        return moma.rnea(model, data, q, v, a)

    def p_rnea(q, v, a):
        return pin.rnea(pmodel, pdata, q, v, a)

    nb = args.batch
    bq = rng.uniform(lo, hi, (nb, model.nq))
    bv = rng.normal(size=(nb, model.nv))
    ba = rng.normal(size=(nb, model.nv))
    assert np.array_equal(moma.rnea_batch(model, data, bq[:5], bv[:5], ba[:5])[3], moma.rnea(model, data, bq[3], bv[3], ba[3]))

    out = np.empty((nb, model.nv))
    t_m, t_p, t_batch, t_out, t_loop = [], [], [], [], []
    for _ in range(args.rounds):
        t_m.append(per_call(m_rnea, states, args.calls))
        t_p.append(per_call(p_rnea, states, args.calls))
        t0 = CLOCK()
        moma.rnea_batch(model, data, bq, bv, ba)
        t_batch.append((CLOCK() - t0) / nb)
        # the same batch into a reused output array (after the Pinocchio loop again, so
        # that it starts as cold as the first)
        per_call(p_rnea, states, args.calls // 4)
        t0 = CLOCK()
        try:
            moma.rnea_batch(model, data, bq, bv, ba, out=out)
            t_out.append((CLOCK() - t0) / nb)
        except TypeError:  # a build from before `out=`
            pass
        t0 = CLOCK()
        for i in range(nb):
            moma.rnea(model, data, bq[i], bv[i], ba[i])
        t_loop.append((CLOCK() - t0) / nb)

    med = statistics.median
    clock = "wall-clock" if args.wall else "process CPU"
    print(f"Panda rnea from Python, {args.rounds} rounds, {clock} time, medians (ns per call / per state):")
    print(f"  moma.rnea            {med(t_m):8.0f}")
    print(f"  pinocchio.rnea       {med(t_p):8.0f}")
    print(f"  ratio moma/pinocchio {med(t_m) / med(t_p):8.3f}")
    print(f"  moma.rnea_batch      {med(t_batch):8.0f}   ({nb} states per call)")
    if t_out:
        print(f"  moma.rnea_batch(out=) {med(t_out):7.0f}   (into a reused array)")
    print(f"  Python loop of moma.rnea over the same states {med(t_loop):8.0f}")
    print(f"  batch speed-up       {med(t_loop) / med(t_batch):8.1f}x")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(
                {
                    "clock": clock,
                    "threads": os.environ.get("RAYON_NUM_THREADS", "all"),
                    "moma.rnea": med(t_m),
                    "pinocchio.rnea": med(t_p),
                    "moma.rnea_batch": med(t_batch),
                    **({"moma.rnea_batch out": med(t_out)} if t_out else {}),
                    "loop": med(t_loop),
                },
                f,
            )
    if args.no_tiago:
        return

    # 10,000 stability evaluations on TIAGo (planar base), one stability_batch call.
    tiago = moma.Model.from_urdf(URDF / "tiago.urdf", root="planar")
    td = tiago.create_data()
    tq = np.tile(tiago.neutral(), (10000, 1))
    tq[:, 3:] += rng.uniform(-1.0, 1.0, (10000, tiago.nq - 3))
    ta = np.zeros((10000, tiago.nv))
    ta[:, 0] = rng.uniform(-5.0, 5.0, 10000)
    support = [[0.25, 0.2], [-0.25, 0.2], [-0.25, -0.2], [0.25, -0.2]]
    ts, tw = [], []
    for _ in range(5):
        t0, w0 = time.process_time(), time.perf_counter()
        moma.stability_batch(tiago, td, tq, None, ta, support=support)
        ts.append(time.process_time() - t0)
        tw.append(time.perf_counter() - w0)
    print(f"  TIAGo stability_batch, 10,000 states: median {med(ts) * 1e3:.1f} ms CPU, {med(tw) * 1e3:.1f} ms wall, over 5 runs")


if __name__ == "__main__":
    main()
