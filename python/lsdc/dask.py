"""A sweep spread over a Dask cluster: the design cut into shards (as ``lsdc sweep --shard
K/N`` cuts it), each shard run by a worker with lsdc's own threads, the shards' tables
gathered into the whole sweep's, identical bit for bit to the table ``lsdc sweep`` writes in
one process (the same runs: a run's record depends on nothing but its values).

>>> from dask.distributed import Client, LocalCluster
>>> import lsdc.dask
>>> with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
...     table = lsdc.dask.sweep(client, "examples/pendulum.lsd",
...                             grid=["swing.q=0.1:1.5:8"], duration=1.0, parts=4)
>>> table.csv == open("runs.csv").read()   # lsdc sweep ... -o runs.csv

The same code runs on a cluster of many machines (a ``dask.distributed.Client`` connected
to its scheduler), as long as every worker has the ``lsdc`` package and reads the program's
files at the same path. Each task returns its shard's table as CSV text (numbers in Rust's
shortest exponent form, which reads back to the same bits), so nothing is lost in transit.
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence


def run_shard(path: str, shard: tuple, load_options: dict, sweep_options: dict) -> str:
    """Runs one shard of the sweep of the program at ``path`` (a Dask task): its table of
    runs as CSV text."""
    import lsdc

    program = lsdc.load(path, **load_options)
    table = program.sweep(shard=shard, **sweep_options)
    return table.csv


def sweep(
    client: Any,
    path: "str | os.PathLike[str]",
    *,
    parts: Optional[int] = None,
    threads_per_part: Optional[int] = 1,
    library_path: Sequence[str] = (),
    scene: Optional[str] = None,
    **sweep_options: Any,
):
    """Runs the sweep ``Program.sweep(**sweep_options)`` of the program at ``path`` on the
    workers of ``client`` (a ``dask.distributed.Client``): ``parts`` shards (default: one per
    worker thread), each run with ``threads_per_part`` of lsdc's threads, then gathered.
    Returns the whole sweep's ``SweepTable``."""
    import lsdc

    if "shard" in sweep_options:
        raise ValueError("`shard`: lsdc.dask.sweep makes the shards itself (`parts`)")
    if parts is None:
        parts = max(1, sum(client.nthreads().values()))
    if parts < 1:
        raise ValueError("`parts` must be at least 1")
    path = os.fspath(os.path.abspath(path))
    load_options = {"library_path": [os.fspath(p) for p in library_path], "scene": scene}
    options = dict(sweep_options, threads=threads_per_part)
    futures = [
        client.submit(run_shard, path, (k, parts), load_options, options, pure=False)
        for k in range(1, parts + 1)
    ]
    texts = client.gather(futures)
    return lsdc.gather([lsdc.SweepTable.from_csv(text) for text in texts])
