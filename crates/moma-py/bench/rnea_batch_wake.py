"""Where the two-thread batch loses its wall time: moma.rnea_batch on Panda timed
back to back (the pool's workers awake), after 50 ms asleep, and after 50 ms of
single-threaded Python (as in rnea_vs_pin.py, where each batch follows a Python loop).
Run it once with RAYON_NUM_THREADS=1 and once with 2:

    RAYON_NUM_THREADS=2 .venv/bin/python crates/moma-py/bench/rnea_batch_wake.py [STATES]
"""
import os
import statistics
import sys
import time

os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
import numpy as np

import moma

from pathlib import Path

URDF = Path(__file__).resolve().parents[3] / "crates/moma/tests/data/pinocchio/urdf/panda.urdf"
model = moma.Model.from_urdf(str(URDF), root="fixed")
data = model.create_data()
rng = np.random.default_rng(7)
nb = int(sys.argv[1]) if len(sys.argv) > 1 else 10000
bq = rng.uniform(model.lower_position_limit, model.upper_position_limit, (nb, model.nq))
bv = rng.normal(size=(nb, model.nv)); ba = rng.normal(size=(nb, model.nv))
def t(f, reps=30):
    out = []
    for _ in range(reps):
        w0 = time.perf_counter_ns(); c0 = time.process_time_ns()
        f()
        out.append(((time.perf_counter_ns() - w0) / nb, (time.process_time_ns() - c0) / nb))
    return statistics.median(x[0] for x in out), statistics.median(x[1] for x in out)
f = lambda: moma.rnea_batch(model, data, bq, bv, ba)
print("back-to-back: wall %.0f ns/state, cpu %.0f ns/state" % t(f))
def after_sleep():
    time.sleep(0.05); w0 = time.perf_counter_ns(); f(); return (time.perf_counter_ns() - w0) / nb
print("after 50 ms idle: wall %.0f ns/state" % statistics.median(after_sleep() for _ in range(20)))
def after_spin():
    e = time.perf_counter() + 0.05
    while time.perf_counter() < e: pass
    w0 = time.perf_counter_ns(); f(); return (time.perf_counter_ns() - w0) / nb
print("after 50 ms python spin: wall %.0f ns/state" % statistics.median(after_spin() for _ in range(20)))
