"""Type stubs of the moma package (the Rust extension moma._moma)."""

from os import PathLike
from typing import Any, Literal, Mapping, Optional, Sequence, Union, overload

import numpy as np
import numpy.typing as npt

from . import sweep as sweep

__version__: str

ArrayLike = npt.ArrayLike
F64 = npt.NDArray[np.float64]
Path = Union[str, PathLike[str]]
Root = Literal["fixed", "planar", "free-flyer"]

class MomaError(Exception):
    """Invalid input or a failing solver; the message is the moma library's."""

class Model:
    """A robot model (immutable): kinematic tree, inertias, frames, limits, gravity."""
    @staticmethod
    def from_urdf(path: Path, root: Root = "fixed") -> Model: ...
    @staticmethod
    def from_urdf_string(text: str, root: Root = "fixed", source: str = "<string>") -> Model: ...
    def create_data(self) -> Data: ...
    def neutral(self) -> F64: ...
    @property
    def name(self) -> str: ...
    @property
    def root(self) -> str: ...
    @property
    def nq(self) -> int: ...
    @property
    def nv(self) -> int: ...
    @property
    def njoints(self) -> int: ...
    @property
    def joint_names(self) -> list[str]: ...
    @property
    def frame_names(self) -> list[str]: ...
    @property
    def gravity(self) -> F64: ...
    @property
    def lower_position_limit(self) -> F64: ...
    @property
    def upper_position_limit(self) -> F64: ...

class Data:
    """The workspace of one Model's algorithms (model.create_data())."""
    @property
    def tau(self) -> F64: ...
    @property
    def ddq(self) -> F64: ...
    @property
    def mass_matrix(self) -> F64: ...

class Map:
    """An occupancy grid: ROS map (world metres) or Moving AI map (cells)."""
    @property
    def width(self) -> int: ...
    @property
    def height(self) -> int: ...
    @property
    def resolution(self) -> float: ...
    @property
    def origin(self) -> tuple[float, float, float]: ...
    @property
    def kind(self) -> Literal["ros", "movingai"]: ...
    @property
    def cells(self) -> npt.NDArray[np.int8]: ...

class GeometryModel:
    """A robot's collision geometry (URDF <collision>, meshes as convex hulls)."""
    @staticmethod
    def from_urdf(
        model: Model, path: Path, srdf: Optional[Path] = None, package_dirs: Sequence[Path] = ()
    ) -> GeometryModel: ...
    @property
    def links(self) -> list[str]: ...
    @property
    def pairs_enabled(self) -> list[tuple[str, str]]: ...

class Scene:
    """Scene objects from a MoveIt planning-scene YAML (MotionBenchMaker)."""
    @staticmethod
    def from_yaml(
        path: Path, world_frames: Sequence[str] = ("world",), package_dirs: Sequence[Path] = ()
    ) -> Scene: ...
    @property
    def ids(self) -> list[str]: ...

def distances(
    model: Model,
    geom: GeometryModel,
    q: ArrayLike,
    scene: Optional[Scene] = None,
    all_pairs: bool = False,
    gradient: bool = False,
    mesh: Literal["convex", "exact"] = "convex",
) -> dict[str, Any]:
    """Signed distances: keys pairs, distance (n,), witness_a, witness_b (n, 3), min_distance, in_collision, closest; gradient (nv,) of min_distance with gradient=True; mesh="exact" for triangle-mesh distances (self and scene pairs)."""

def footprint(
    model: Model, geom: GeometryModel, q: ArrayLike, frame: Optional[Literal["base", "world"]] = None
) -> F64:
    """Planar footprint (m, 2), counter-clockwise: base frame for a planar/free-flyer root, world for a fixed one."""

def plan_motion(
    model: Model,
    geom: GeometryModel,
    scene: Optional[Scene],
    group: list[str],
    start: ArrayLike,
    goal_state: Optional[ArrayLike] = None,
    goal_pose: Optional[ArrayLike] = None,
    frame: Optional[str] = None,
    position_tolerance: float = 0.01,
    orientation_tolerance: float = 0.01,
    time_limit: float = 1.0,
    seed: int = 0,
    margin: float = 0.002,
    max_acceleration: Optional[Union[float, list[float]]] = None,
) -> dict[str, Any]:
    """Collision-free, time-optimal motion of a joint group to goal_state or to goal_pose of frame (as moma motion): keys solved, reason, planning_time_s, path (n, nq), trajectory {t (m,), q (m, nq)}, duration_s, min_distance, closest_pair, checks, iterations, ik_attempts, ik_solutions, goal_state, group, seed, margin, velocity_limits, acceleration_limits, mesh_surface_links."""

def place(
    model: Model,
    geom: GeometryModel,
    scene: Scene,
    group: list[str],
    wheels: tuple[str, str],
    grasp_pose: Optional[ArrayLike] = None,
    frame: Optional[str] = None,
    query: Optional[Path] = None,
    query_index: int = 0,
    position_tolerance: float = 0.01,
    orientation_tolerance: float = 0.01,
    casters: Optional[Union[Path, Sequence[Sequence[float]]]] = None,
    payload: float = 0.0,
    payload_offset: Optional[ArrayLike] = None,
    posture: Optional[ArrayLike] = None,
    area: Optional[ArrayLike] = None,
    step: float = 0.1,
    headings: int = 16,
    ik_attempts: int = 8,
    seed: int = 0,
    margin: float = 0.005,
    weights: tuple[float, float, float] = (1.0, 1.0, 1.0),
    max_samples: int = 200000,
    candidates: int = 20,
) -> dict[str, Any]:
    """Base placement for a grasp (as moma place; planar-root model): keys found, reason, candidates {base (n, 3), q (n, nq), manipulability, clearance, tip_over_margin, score (n,), grasp_error (n, 2), closest}, counts, reach, best_position_error, grid, grasp, payload_kg, payload_offset (3,), support (m, 2)."""

def rnea(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> F64:
    """Inverse dynamics: tau = M(q) a + C(q, v) v + g(q) (nv)."""

def crba(model: Model, data: Data, q: ArrayLike) -> F64:
    """Joint-space inertia matrix M(q) (nv x nv)."""

def aba(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> F64:
    """Forward dynamics: ddq (nv)."""

def rnea_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike) -> tuple[F64, F64, F64]:
    """Analytical derivatives of tau = RNEA(q, v, a): (dtau_dq, dtau_dv, M), nv x nv
    each; dq along the tangent q (+) dq (moma's layout)."""

def aba_derivatives(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> tuple[F64, F64, F64]:
    """Analytical derivatives of ddq = ABA(q, v, tau): (dddq_dq, dddq_dv, M^-1), nv x nv
    each (moma's layout)."""

def frame_jacobian(model: Model, data: Data, q: ArrayLike, frame: str) -> F64:
    """6 x nv Jacobian of a frame, LOCAL_WORLD_ALIGNED ([p_dot; omega], world axes)."""

def rnea_batch(model: Model, data: Data, q: ArrayLike, v: ArrayLike, a: ArrayLike, out: F64 | None = None) -> F64:
    """rnea per row: q (n, nq), v and a (n, nv) -> (n, nv); GIL released. `out`: a
    writeable C-contiguous float64 (n, nv) array, not an input, that receives the torques
    and is returned (NaN after an error)."""

def aba_batch(model: Model, data: Data, q: ArrayLike, v: ArrayLike, tau: ArrayLike) -> F64:
    """aba per row -> (n, nv); GIL released."""

def crba_batch(model: Model, data: Data, q: ArrayLike) -> F64:
    """crba per row -> (n, nv, nv); GIL released."""

def frame_jacobian_batch(model: Model, data: Data, q: ArrayLike, frame: str) -> F64:
    """frame_jacobian per row -> (n, 6, nv); GIL released."""

def stability(
    model: Model,
    data: Data,
    q: ArrayLike,
    v: Optional[ArrayLike] = None,
    a: Optional[ArrayLike] = None,
    *,
    support: Sequence[Sequence[float]],
    mhs_bodies: str = "all",
    gravity: Optional[Sequence[float]] = None,
    external: Optional[Sequence[Mapping[str, Sequence[float]]]] = None,
) -> dict[str, Any]:
    """Tip-over measures of one state: the dict of `moma stability`'s states[i]."""

def stability_batch(
    model: Model,
    data: Data,
    q: ArrayLike,
    v: Optional[ArrayLike] = None,
    a: Optional[ArrayLike] = None,
    *,
    support: Sequence[Sequence[float]],
    mhs_bodies: str = "all",
    gravity: Optional[Sequence[float]] = None,
) -> dict[str, npt.NDArray[Any]]:
    """Tip-over measures per row, as arrays (NaN / -1 where undefined); GIL released."""

def space(
    model: Model,
    data: Data,
    q: ArrayLike,
    qdot_joints: ArrayLike,
    frame: str,
    momentum: Optional[Mapping[str, Sequence[float]]] = None,
) -> dict[str, Any]:
    """Free-floating quantities of one state: the dict of `moma space`'s states[i]."""

def osc(
    model: Model,
    data: Data,
    q: ArrayLike,
    v: Optional[ArrayLike],
    frame: str,
    task_acceleration: ArrayLike,
    null_torque: Optional[ArrayLike] = None,
    rows: str = "full",
    *,
    layout: Literal["moma", "pinocchio"] = "moma",
) -> dict[str, Any]:
    """Operational-space quantities of one state: the dict of `moma osc`'s states[i]
    (layout="pinocchio": q, v, null_torque and J-bar, N, tau, J-dot v in Pinocchio's)."""

def load_map(path: Path, resolution: Optional[float] = None) -> Map:
    """Loads a ROS YAML, Moving AI .map or bare PGM/PNG map."""

@overload
def plan(
    grid: Map,
    start: Sequence[float],
    goal: Sequence[float],
    radius: float = 0.0,
    unknown: Literal["obstacle", "free"] = "obstacle",
    smooth: bool = True,
    check_footprint: None = None,
    check_padding: None = None,
) -> Optional[F64]:
    """A* + shortcut smoothing for a disk robot: (n, 2) waypoints, or None."""
@overload
def plan(
    grid: Map,
    start: Sequence[float],
    goal: Sequence[float],
    radius: float = 0.0,
    unknown: Literal["obstacle", "free"] = "obstacle",
    smooth: bool = True,
    *,
    check_footprint: Sequence[Sequence[float]],
    check_padding: Optional[float] = None,
) -> Optional[dict[str, Any]]:
    """As moma plan --check-footprint: keys status ("found" | "colliding"), waypoints (n, 2), check {kind, vertices, padding, colliding}; None when unreachable."""

Cell = Union[int, float, bool, str, None]

class Table:
    """A sweep's results table; CSV as `moma sweep` writes it."""
    def __init__(self, columns: Sequence[str], rows: Sequence[Sequence[Cell]]) -> None: ...
    @staticmethod
    def read_csv(path: Path) -> Table: ...
    @staticmethod
    def merge(tables: Sequence[Table]) -> Table: ...
    @property
    def columns(self) -> list[str]: ...
    @property
    def rows(self) -> list[list[Cell]]: ...
    def indices(self) -> list[int]: ...
    def without_timing(self) -> Table: ...
    def to_csv(self) -> str: ...
    def write_csv(self, path: Path) -> None: ...
    def __len__(self) -> int: ...

class Sweep:
    """A validated sweep file: points, columns, evaluation on a rayon pool."""
    @staticmethod
    def from_file(path: Path) -> Sweep: ...
    @property
    def study(self) -> str: ...
    @property
    def columns(self) -> list[str]: ...
    def run(self, indices: Optional[Sequence[int]] = None, threads: int = 0) -> Table: ...
    def shard_indices(self, k: int, n: int) -> list[int]: ...
    def __len__(self) -> int: ...

def run_mission(path: Path) -> dict[str, Any]:
    """Runs a mission file end to end; the summary dict with the run's wall times
    (`wall_time_s`, `wall_time`), no files written."""

def simulate(path: Path) -> dict[str, Any]:
    """Runs a `moma simulate` scenario file as the command does; `t` (n,), `q`, `v`, `u`
    (n rows each) with their names, `errors` and `error_names` with a controller, and the
    summary values of the run (`mpc` for law mpc, `contact` for the contact plant); no
    files written."""

def to_pinocchio(
    model: Model,
    q: ArrayLike,
    v: Optional[ArrayLike] = None,
    a: Optional[ArrayLike] = None,
    tau: Optional[ArrayLike] = None,
    *,
    mass_matrix: Optional[ArrayLike] = None,
    jacobian: Optional[ArrayLike] = None,
) -> dict[str, F64]:
    """moma's q (and v, a, tau, mass_matrix, jacobian) in Pinocchio's layout; a needs v."""

def from_pinocchio(
    model: Model,
    q: ArrayLike,
    v: Optional[ArrayLike] = None,
    a: Optional[ArrayLike] = None,
    tau: Optional[ArrayLike] = None,
    *,
    mass_matrix: Optional[ArrayLike] = None,
    jacobian: Optional[ArrayLike] = None,
) -> dict[str, F64]:
    """A Pinocchio q (and v, a, tau, mass_matrix, jacobian) in moma's layout; a needs v."""

def eval_cases(
    doc: Union[Path, Mapping[str, Any]], tol: float = 1e-12
) -> dict[str, Any]:
    """The chapter models on a case document (a path or the parsed dict), as `moma eval`."""

def eval_case(model: str, case: Mapping[str, Any], tol: float = 1e-12) -> dict[str, Any]:
    """One case of one chapter model (canonical name or alias m1..m6), outputs filled in."""

def chapter_models() -> list[str]:
    """Canonical names of the chapter models, with "unicycle_control"."""
