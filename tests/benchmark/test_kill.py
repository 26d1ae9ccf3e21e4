"""Killing a parallel grid leaves no process behind: loky workers and their forked runs die."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from pysindy_xl.benchmark.records import read_records

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads the process tree from /proc")

#: Seconds the grid and its workers get to go once signalled: an event is waited for, and a
#: loaded machine (CI right after a session) may take far longer than an idle one.
EXIT_BOUND = 120

GRID_SCRIPT = textwrap.dedent("""
    import os, sys, time
    from pysindy_xl.benchmark.grid import GridSettings
    from pysindy_xl.benchmark.runner import run_grid

    SETTINGS = GridSettings(systems=("cart-pole",), forcings=("explicit", "mixed"),
                            configurations=(("mixed", "mixed"), ("mixed", "explicit")),
                            timeout=120.0, name="test")
    FAST = {t.run_id for t in SETTINGS.tasks()[:2]}

    def task(task, settings, deadline, stage):
        if task.run_id not in FAST:  # the other runs hang until killed
            open(os.path.join(sys.argv[2], str(os.getpid())), "w").close()
            time.sleep(120)
        return {**task.to_dict(), "status": "ok", "metrics": {"position_rmse": 0.5},
                "time_s": {"run": 0.0}, "message": None}

    if __name__ == "__main__":
        # Ctrl-C as in a terminal: a background job of a non-interactive shell (CI, nohup,
        # "cmd &") starts with SIGINT ignored, and Python then installs no KeyboardInterrupt
        import signal
        signal.signal(signal.SIGINT, signal.default_int_handler)
        run_grid(SETTINGS, sys.argv[1], n_jobs=2, function=task, progress=False)
""")


def descendants(pid):
    """PIDs of every descendant of ``pid`` (from /proc)."""
    children = {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as file:
                stat = file.read()
        except OSError:  # gone meanwhile
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        children.setdefault(ppid, []).append(int(entry))
    found, todo = set(), [pid]
    while todo:
        for child in children.get(todo.pop(), []):
            if child not in found:
                found.add(child)
                todo.append(child)
    return found


def alive(pid):
    """True while ``pid`` runs (a zombie waiting for its reaper counts as dead)."""
    try:
        with open(f"/proc/{pid}/stat") as file:
            return file.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.parametrize("signum", [signal.SIGKILL, signal.SIGTERM, signal.SIGINT],
                         ids=["SIGKILL", "SIGTERM", "SIGINT"])
def test_killing_the_grid_leaves_no_worker_alive(tmp_path, signum):
    script = tmp_path / "grid.py"
    script.write_text(GRID_SCRIPT)
    path, markers = tmp_path / "records.jsonl", tmp_path / "runs"
    markers.mkdir()
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    # the output goes to a file: a pipe nobody reads could fill and block the dying grid
    log = open(tmp_path / "grid.log", "w+b")  # noqa: SIM115 - closed in finally
    process = subprocess.Popen([sys.executable, str(script), str(path), str(markers)], env=env,
                               start_new_session=True, stdout=log, stderr=subprocess.STDOUT)
    tree = set()
    try:
        deadline = time.monotonic() + EXIT_BOUND
        while len(os.listdir(markers)) < 2:  # both workers inside a hanging forked run
            if process.poll() is not None:
                log.seek(0)
                pytest.fail("the grid ended before it could be killed: "
                            + log.read().decode()[-2000:])
            assert time.monotonic() < deadline, f"the runs did not start in {EXIT_BOUND} s"
            time.sleep(0.05)
        tree = descendants(process.pid)
        runs = {int(name) for name in os.listdir(markers)}
        assert runs <= tree and len(tree - runs) >= 2  # 2 loky workers (+ resource trackers)
        os.kill(process.pid, signum)
        killed = time.monotonic()
        process.wait(EXIT_BOUND)
        while any(map(alive, tree)) and time.monotonic() - killed < EXIT_BOUND:
            time.sleep(0.05)
        survivors = {pid for pid in tree if alive(pid)}
        assert not survivors, f"alive {EXIT_BOUND} s after {signum.name}: {sorted(survivors)}"
    finally:  # never leave anything behind, whatever failed
        for pid in [process.pid, *tree]:
            if alive(pid):
                os.kill(pid, signal.SIGKILL)
        process.wait(EXIT_BOUND)
        log.close()
    if signum != signal.SIGKILL:  # the process still ends by the signal it got
        assert process.returncode == -signum
    # the runs that had finished keep their records
    assert len(read_records(path)) == 2
