"""The grid on real cluster back ends (Dask LocalCluster, Ray) and BLAS thread limits."""

import importlib.util
import json
import math

import pytest

from pysindy_xl.benchmark.grid import GridSettings
from pysindy_xl.benchmark.runner import (
    blas_thread_limit,
    resolve_blas_threads,
    run_grid,
    run_task,
)

# two real runs (cart-pole, explicit forcing, two catalogs), kept short
SMALL = GridSettings(systems=("cart-pole",), forcings=("explicit",),
                     configurations=(("mixed", "explicit"), ("lagrange", "explicit")),
                     n_trajectories=1, duration=1.0, validation_duration=0.5, timeout=120.0,
                     name="backends")
VOLATILE = ("time_s", "pid", "finished_at")


def comparable(path):
    """Records by run id, without the fields that depend on the machine and the clock."""
    out = {}
    for line in path.read_text().splitlines():
        record = json.loads(line)
        out[record["run_id"]] = {k: v for k, v in record.items() if k not in VOLATILE}
    return out


def same(a, b):
    """Equal records, floats to 1e-9 relative (1e-12 absolute): BLAS may sum differently."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, float) and isinstance(b, float):
        return math.isclose(a, b, rel_tol=1e-9, abs_tol=1e-12)
    return a == b


def blas_probe(task, settings, deadline, stage):
    """A run that reports the BLAS thread count it sees."""
    from threadpoolctl import threadpool_info

    threads = sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})
    return {**task.to_dict(), "status": "error", "message": json.dumps(threads),
            "metrics": {}, "time_s": {}}


# -- threads -----------------------------------------------------------------------------------
def test_blas_threads_resolution():
    assert resolve_blas_threads("auto", 2, None) == 1
    assert resolve_blas_threads("auto", 1, None) is None
    assert resolve_blas_threads("auto", 1, "dask") == 1
    assert resolve_blas_threads(3, 2, None) == 3
    with pytest.raises(ValueError, match="blas_threads"):
        blas_thread_limit(0)


@pytest.fixture
def two_blas_threads():
    """Two BLAS threads in this process (the test configuration runs on one), so that a run
    limited to one thread differs from its caller."""
    from threadpoolctl import threadpool_info, threadpool_limits

    with threadpool_limits(limits=2, user_api="blas"):
        # a library built for one thread stays at one; the others must reach two
        assert 2 in {p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}
        yield


@pytest.mark.parametrize("isolation", ["process", "none"])
def test_blas_limit_reaches_the_run(isolation, two_blas_threads):
    task = SMALL.tasks()[0]
    record = run_task(task, SMALL, isolation=isolation, function=blas_probe, blas_threads=1)
    assert json.loads(record["message"]) == [1]


def test_grid_limits_blas_in_parallel_workers(tmp_path, two_blas_threads):
    path = tmp_path / "records.jsonl"
    summary = run_grid(SMALL, path, n_jobs=2, progress=False, function=blas_probe,
                       isolation="none", blas_threads=1)
    assert summary["ran"] == 2
    assert [json.loads(r["message"]) for r in comparable(path).values()] == [[1], [1]]


# -- Dask --------------------------------------------------------------------------------------
@pytest.mark.skipif(importlib.util.find_spec("distributed") is None,
                    reason="dask.distributed is not installed (pip install 'dask[distributed]')")
@pytest.mark.slow
def test_dask_local_cluster_matches_loky_and_resumes(tmp_path):
    from dask.distributed import LocalCluster

    loky = tmp_path / "loky.jsonl"
    assert run_grid(SMALL, loky, n_jobs=2, progress=False)["ran"] == 2

    records = tmp_path / "dask.jsonl"
    with LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                      dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        first = run_grid(SMALL, records, backend="dask", address=address, n_jobs=2,
                         progress=False, limit=1)
        assert first["ran"] == 1 and first["skipped"] == 0
        # resume: the finished run is skipped, the other one runs
        second = run_grid(SMALL, records, backend="dask", address=address, n_jobs=2,
                          progress=False)
        assert second["skipped"] == 1 and second["ran"] == 1
        third = run_grid(SMALL, records, backend="dask", address=address, progress=False)
        assert third["ran"] == 0 and third["skipped"] == 2
    ours, reference = comparable(records), comparable(loky)
    assert set(ours) == set(reference) and len(ours) == 2
    statuses = sorted(r["status"] for r in ours.values())
    assert statuses == sorted(r["status"] for r in reference.values())
    assert "ok" in statuses
    for run_id, record in ours.items():
        assert same(record, reference[run_id]), run_id


# -- Ray ---------------------------------------------------------------------------------------
@pytest.mark.skipif(importlib.util.find_spec("ray") is None,
                    reason="ray is not installed here (no wheel for this platform/Python, or "
                           "not installed); pip install 'ray[default]' to run this test")
def test_ray_backend_matches_loky(tmp_path):
    import ray

    loky = tmp_path / "loky.jsonl"
    run_grid(SMALL, loky, n_jobs=2, progress=False)
    records = tmp_path / "ray.jsonl"
    ray.init(num_cpus=2, include_dashboard=False)
    try:
        assert run_grid(SMALL, records, backend="ray", n_jobs=2, progress=False)["ran"] == 2
    finally:
        ray.shutdown()
    ours, reference = comparable(records), comparable(loky)
    assert ours.keys() == reference.keys() and len(ours) == 2
    for run_id, record in ours.items():
        assert same(record, reference[run_id]), run_id


def test_blas_threads_command_line_option():
    import argparse

    from pysindy_xl.benchmark.cli import add_parser

    parser = argparse.ArgumentParser(prog="pysindy-xl")
    add_parser(parser.add_subparsers(dest="command"))
    values = [parser.parse_args(["benchmark", "--blas-threads", v]).blas_threads
              for v in ("auto", "none", "2")]
    assert values == ["auto", None, 2]
    assert parser.parse_args(["benchmark"]).blas_threads == "auto"
    for bad in ("0", "many"):
        with pytest.raises(SystemExit):
            parser.parse_args(["benchmark", "--blas-threads", bad])
