#!/usr/bin/env python3
"""Write the Fetch states that both collision benchmarks time (coal_fetch_bench.cpp and
moma's `cargo bench --bench collision`): one state per line, Pinocchio's layout (nq 18:
continuous joints as cos, sin), fixed base. Revolute and prismatic joints uniform within
the URDF limits, continuous joints uniform in [-pi, pi], numpy's PCG64 seeded with SEED.

    python fetch_states.py FETCH_DIR OUT.txt [N [SEED]]
"""
import sys

import numpy as np
import pinocchio as pin


def main(fetch_dir, out, n=100, seed=42):
    model = pin.buildModelFromUrdf(f"{fetch_dir}/fetch_description/robots/fetch.urdf")
    rng = np.random.default_rng(seed)
    rows = []
    for _ in range(n):
        q = pin.neutral(model)
        for j in range(1, model.njoints):
            iq, nqj, nvj = model.idx_qs[j], model.nqs[j], model.nvs[j]
            if nqj == 2 and nvj == 1:
                th = rng.uniform(-np.pi, np.pi)
                q[iq], q[iq + 1] = np.cos(th), np.sin(th)
            elif nqj == 1:
                lo, hi = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
                q[iq] = rng.uniform(lo, hi)
            else:
                sys.exit(f"joint {model.names[j]}: unsupported type")
        rows.append(" ".join(repr(float(x)) for x in q))
    with open(out, "w") as f:
        f.write(
            f"# {n} Fetch states (fixed base), Pinocchio {pin.__version__} layout nq {model.nq}; "
            f"written by bench/pinocchio/fetch_states.py, seed {seed}\n"
        )
        f.write("\n".join(rows) + "\n")


if __name__ == "__main__":
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2], *(int(a) for a in sys.argv[3:5]))
