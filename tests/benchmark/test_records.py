"""The benchmark's JSONL record store and the resume of an interrupted grid."""

import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from pysindy_xl.benchmark.grid import GridSettings
from pysindy_xl.benchmark.records import RecordStore, check_record, read_records
from pysindy_xl.benchmark.runner import run_grid


def record(run_id, status="ok", rmse=0.1):
    return {"run_id": run_id, "trajectory_id": "t", "config": run_id, "status": status,
            "metrics": {"position_rmse": rmse}}


def test_append_and_read_back(tmp_path):
    store = RecordStore(tmp_path / "sub" / "records.jsonl")
    store.append(record("a"))
    store.append(record("b", "invalid"))
    lines = (tmp_path / "sub" / "records.jsonl").read_text().splitlines()
    assert [json.loads(line)["run_id"] for line in lines] == ["a", "b"]
    assert store.finished_ids() == {"a", "b"}
    assert store.finished_ids(retry=["invalid"]) == {"a"}


def test_last_record_of_a_run_wins(tmp_path):
    store = RecordStore(tmp_path / "r.jsonl")
    store.append(record("a", "error"))
    store.append(record("b"))
    store.append(record("a", "ok", 0.3))
    latest = store.records()
    assert [r["run_id"] for r in latest] == ["a", "b"]
    assert latest[0]["status"] == "ok" and latest[0]["metrics"]["position_rmse"] == 0.3


def test_torn_last_line_is_cut_and_the_run_redone(tmp_path):
    path = tmp_path / "r.jsonl"
    good = json.dumps(record("a")) + "\n"
    path.write_text(good + json.dumps(record("b"))[:25])  # writer killed mid-line
    with pytest.warns(RuntimeWarning, match="torn"):
        assert [r["run_id"] for r in read_records(path)] == ["a"]
    with pytest.warns(RuntimeWarning, match="torn last line"):
        store = RecordStore(path)
    assert path.read_text() == good
    assert store.finished_ids() == {"a"}
    store.append(record("b"))
    assert [r["run_id"] for r in read_records(path)] == ["a", "b"]


def test_damaged_line_in_the_middle_is_skipped_with_a_warning(tmp_path):
    path = tmp_path / "r.jsonl"
    path.write_text(json.dumps(record("a")) + "\n{broken\n" + json.dumps(record("b")) + "\n")
    with pytest.warns(RuntimeWarning, match="skipping line 2"):
        assert [r["run_id"] for r in read_records(path)] == ["a", "b"]


def test_bad_records_and_arguments_are_rejected(tmp_path):
    store = RecordStore(tmp_path / "r.jsonl")
    with pytest.raises(ValueError, match="missing fields"):
        store.append({"run_id": "a"})
    with pytest.raises(ValueError, match="status"):
        check_record(record("a", "finished"))
    with pytest.raises(ValueError, match="position_rmse"):
        check_record(record("a", "ok", float("nan")))
    with pytest.raises(ValueError, match="retry"):
        store.finished_ids(retry=["oops"])
    with pytest.raises(ValueError):  # NaN is not JSON
        store.append({**record("a", "invalid"), "metrics": {"x": float("nan")}})
    assert not (tmp_path / "r.jsonl").exists() or read_records(tmp_path / "r.jsonl") == []


def sleepy_task(task, settings, deadline, stage):
    """A fake run: 0.3 s, deterministic error from the run id."""
    time.sleep(0.3)
    rmse = (sum(map(ord, task.run_id)) % 97) / 97 + 0.01
    return {**task.to_dict(), "status": "ok", "metrics": {"position_rmse": rmse},
            "time_s": {"run": 0.3}, "message": None}


SMALL = GridSettings(systems=("cart-pole", "double-pendulum"), forcings=("explicit", "mixed"),
                     noise_levels=(0.0, 0.01), configurations=(("mixed", "mixed"),
                                                               ("mixed", "explicit")),
                     timeout=30.0, name="test")


def test_run_grid_skips_finished_runs(tmp_path):
    path = tmp_path / "records.jsonl"
    first = run_grid(SMALL, path, n_jobs=1, isolation="none", function=sleepy_task, limit=5,
                     progress=False)
    assert first["ran"] == 5 and first["skipped"] == 0
    second = run_grid(SMALL, path, n_jobs=1, isolation="none", function=sleepy_task,
                      progress=False)
    assert second["ran"] == len(SMALL.tasks()) - 5 and second["skipped"] == 5
    ids = [r["run_id"] for r in read_records(path)]
    assert sorted(ids) == sorted(t.run_id for t in SMALL.tasks())
    third = run_grid(SMALL, path, n_jobs=1, isolation="none", function=sleepy_task,
                     progress=False)
    assert third["ran"] == 0 and len(read_records(path)) == len(ids)


RESUME_SCRIPT = textwrap.dedent("""
    import sys, time
    from pysindy_xl.benchmark.grid import GridSettings
    from pysindy_xl.benchmark.runner import run_grid

    def sleepy_task(task, settings, deadline, stage):
        time.sleep(0.4)
        return {**task.to_dict(), "status": "ok", "metrics": {"position_rmse": 0.5},
                "time_s": {"run": 0.4}, "message": None}

    if __name__ == "__main__":
        settings = GridSettings(systems=("cart-pole", "double-pendulum"),
                                forcings=("explicit", "mixed"), noise_levels=(0.0, 0.01),
                                configurations=(("mixed", "mixed"), ("mixed", "explicit")),
                                timeout=30.0, name="test")
        out = run_grid(settings, sys.argv[1], n_jobs=2, function=sleepy_task, progress=False)
        print("RAN", out["ran"], "SKIPPED", out["skipped"])
""")


@pytest.mark.slow
def test_resume_after_kill_no_duplicate_no_loss(tmp_path):
    """Kill -9 a parallel grid (loky workers, forked runs) midway, rerun: exactly once each."""
    script = tmp_path / "grid.py"
    script.write_text(RESUME_SCRIPT)
    path = tmp_path / "records.jsonl"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    process = subprocess.Popen([sys.executable, str(script), str(path)], env=env,
                               start_new_session=True, stdout=subprocess.PIPE,
                               stderr=subprocess.STDOUT)
    try:
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline:
            if path.exists() and len(path.read_text().splitlines()) >= 3:
                break
            if process.poll() is not None:
                pytest.fail("the grid ended before it could be killed: "
                            + process.stdout.read().decode()[-2000:])
            time.sleep(0.05)
        else:
            pytest.fail("no record appeared in 120 s")
    finally:
        # kill the whole session: the grid, its loky workers and their forked runs
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(30)
    n_total = len(SMALL.tasks())
    before = [r["run_id"] for r in read_records(path)]
    assert 3 <= len(before) < n_total
    done = subprocess.run([sys.executable, str(script), str(path)], env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert f"SKIPPED {len(before)}" in done.stdout
    after = [r["run_id"] for r in read_records(path)]
    assert len(after) == len(set(after)) == n_total  # no duplicate
    assert set(before) <= set(after)  # nothing lost
    assert set(after) == {t.run_id for t in SMALL.tasks()}


def test_a_second_grid_on_the_same_output_refuses(tmp_path):
    from pysindy_xl.benchmark.records import GridBusyError, RecordStore

    path = tmp_path / "records.jsonl"
    with RecordStore(path).lock():
        with pytest.raises(GridBusyError, match=r"another grid \(pid \d+\)"):
            with RecordStore(path).lock():
                pass
    with RecordStore(path).lock():  # released when the first grid ends
        pass
