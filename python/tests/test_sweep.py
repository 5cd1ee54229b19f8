"""Sweeps from Python against `lsdc sweep`'s file, bit for bit: whole, by shards gathered, and
spread over a Dask LocalCluster."""

import math

import numpy as np
import pytest

import lsdc

GRID = ["swing.q=0.1:1.5:8"]


@pytest.fixture(scope="module")
def cli_runs(example, run_cli, tmp_path_factory):
    path = tmp_path_factory.mktemp("sweep") / "runs.csv"
    run_cli("sweep", example("pendulum.lsd"), "--grid", GRID[0], "--duration", 1, "-o", path)
    return path.read_text()


def test_whole_sweep_equals_the_file(example, cli_runs):
    table = lsdc.load(example("pendulum.lsd")).sweep(grid=GRID, duration=1.0)
    assert table.csv == cli_runs
    columns = table.columns()
    assert list(columns["run"]) == list(range(8))
    assert columns["status"] == ["ok"] * 8
    np.testing.assert_allclose(columns["swing.q"], np.linspace(0.1, 1.5, 8), rtol=1e-15)
    # A pendulum conserves its energy: the largest angle reached is the one it starts from.
    np.testing.assert_allclose(columns["max(swing.q)"], columns["swing.q"], rtol=1e-6)
    assert len(table) == 8 and table.names[0] == "run"


def test_grid_as_a_mapping(example, cli_runs):
    table = lsdc.load(example("pendulum.lsd")).sweep(grid={"swing.q": (0.1, 1.5, 8)}, duration=1.0)
    assert table.csv == cli_runs


def test_shards_gathered(example, cli_runs):
    program = lsdc.load(example("pendulum.lsd"))
    parts = [program.sweep(grid=GRID, duration=1.0, shard=(k, 3), threads=1) for k in (3, 1, 2)]
    assert sum(len(p) for p in parts) == 8
    assert lsdc.gather(parts).csv == cli_runs
    with pytest.raises(lsdc.LsdcError, match="run 0 is in no part"):
        lsdc.gather(parts[:1])
    with pytest.raises(ValueError, match="shard"):
        program.sweep(grid=GRID, shard=(0, 3))


def test_design_errors(example):
    program = lsdc.load(example("pendulum.lsd"))
    with pytest.raises(ValueError, match="no runs"):
        program.sweep()
    with pytest.raises(ValueError, match="`vary` needs `sample`"):
        program.sweep(vary={"swing.q": "uniform(0, 1)"})
    with pytest.raises(lsdc.ProgramError):
        program.sweep(grid=["swing.p=0:1:2"])


def test_dask_local_cluster(example, cli_runs):
    distributed = pytest.importorskip("dask.distributed")
    import lsdc.dask

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster:
        with distributed.Client(cluster) as client:
            table = lsdc.dask.sweep(client, example("pendulum.lsd"), grid=GRID, duration=1.0, parts=3)
    assert table.csv == cli_runs


def test_sample_design_equals_the_file(example, run_cli, tmp_path):
    path = tmp_path / "sample.csv"
    run_cli("sweep", example("pendulum.lsd"), "--vary", "swing.q=uniform(0.1, 1)", "--sample", 5,
            "--design", "latin", "--seed", 7, "--duration", 0.5, "-o", path)
    table = lsdc.load(example("pendulum.lsd")).sweep(
        vary={"swing.q": "uniform(0.1, 1)"}, sample=5, design="latin", seed=7, duration=0.5)
    assert table.csv == path.read_text()
    assert not any(math.isnan(x) for x in table.columns()["end(swing.q)"])
