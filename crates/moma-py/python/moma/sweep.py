"""Sweeps from Python: ``moma.sweep.run(path, backend="local" | "ray", ...)``.

A sweep file (the TOML of ``moma sweep``; examples in scenarios/sweeps/) defines a grid or a seeded
random sample of the parameters of a stability or placement study. Every point is
evaluated by the Rust evaluator; the results table has one row per point, sorted by
index, and its columns other than the ``*_time_s`` timings are identical whatever the
backend, the shard count and the thread count.

* ``backend="local"`` (the default) runs on all cores of this machine (rayon).
* ``backend="ray"`` splits the points into chunks evaluated by ``ray.remote`` tasks,
  each calling the Rust evaluator on one core. Ray is started with ``ray.init()`` (a
  local cluster on this machine) unless it is already initialised or ``address`` names
  a running cluster (``"auto"``, or ``"ray://HEAD:10001"``). Every node needs the moma
  package installed and the sweep file, with the files it names, at the same path.
"""

from pathlib import Path

from ._moma import MomaError, Sweep, Table

__all__ = ["load", "merge", "run"]


def load(path):
    """Loads and validates a sweep file (``moma.Sweep``)."""
    return Sweep.from_file(path)


def merge(tables):
    """Joins shard tables (equal headers, disjoint indices covering 0..n)."""
    return Table.merge(list(tables))


def _evaluate_chunk(path, indices):
    """One Ray task: the rows of `indices`, evaluated on one thread."""
    from moma._moma import Sweep as _Sweep

    return _Sweep.from_file(path).run(list(indices), 1).rows


def run(path, backend="local", *, shard=None, threads=0, address=None, chunks=None):
    """Runs the sweep file `path` and returns its ``moma.Table``.

    shard: ``(k, n)`` runs only the k-th of n disjoint shards (points i with
    i mod n = k - 1), as ``moma sweep --shard k/n``; join the shard tables with
    ``merge``. threads: local threads (0: all cores). address: the Ray cluster (None:
    ``ray.init()`` on this machine). chunks: number of Ray tasks (default: 4 per CPU of
    the cluster).
    """
    sweep = Sweep.from_file(path)
    indices = None if shard is None else sweep.shard_indices(*shard)
    if backend == "local":
        return sweep.run(indices, threads)
    if backend != "ray":
        raise MomaError(f"backend: '{backend}' is not one of local, ray")
    try:
        import ray
    except ImportError as e:
        raise MomaError(f"backend='ray' needs the ray package (pip install ray): {e}") from e
    if not ray.is_initialized():
        if address is None:
            ray.init()
        else:
            ray.init(address=address)
    points = list(range(len(sweep))) if indices is None else list(indices)
    if chunks is None:
        chunks = 4 * max(1, int(ray.cluster_resources().get("CPU", 1)))
    chunks = max(1, min(int(chunks), len(points)))
    size = -(-len(points) // chunks)
    task = ray.remote(_evaluate_chunk)
    source = str(Path(path).resolve())
    futures = [task.remote(source, points[k : k + size]) for k in range(0, len(points), size)]
    rows = [row for part in ray.get(futures) for row in part]
    rows.sort(key=lambda r: r[0])
    return Table(sweep.columns, rows)
