"""moma: kinematics, dynamics, tip-over stability, control and planning of wheeled
mobile manipulators and free-floating space manipulators.

The Python face of the moma Rust library: an immutable ``Model``, a reusable ``Data``
workspace, and free functions ``algo(model, data, ...)`` taking and returning numpy
arrays. Errors raise ``moma.MomaError`` with the library's message. The ``*_batch``
functions take one state per row and loop in Rust with the GIL released.
"""

from ._moma import (
    Data,
    Map,
    Model,
    MomaError,
    Sweep,
    Table,
    __version__,
    aba,
    aba_batch,
    aba_derivatives,
    chapter_models,
    crba,
    crba_batch,
    eval_case,
    eval_cases,
    frame_jacobian,
    frame_jacobian_batch,
    from_pinocchio,
    load_map,
    osc,
    plan,
    rnea,
    rnea_batch,
    rnea_derivatives,
    run_mission,
    space,
    stability,
    stability_batch,
    to_pinocchio,
)
from . import sweep

__all__ = [
    "Data",
    "Map",
    "Model",
    "MomaError",
    "Sweep",
    "Table",
    "__version__",
    "aba",
    "aba_batch",
    "aba_derivatives",
    "chapter_models",
    "crba",
    "crba_batch",
    "eval_case",
    "eval_cases",
    "frame_jacobian",
    "frame_jacobian_batch",
    "from_pinocchio",
    "load_map",
    "osc",
    "plan",
    "rnea",
    "rnea_batch",
    "rnea_derivatives",
    "run_mission",
    "space",
    "stability",
    "stability_batch",
    "sweep",
    "to_pinocchio",
]
