"""glint.batch on Dask: the same outputs, table and report as `glint batch`, also when a
worker dies in the middle of the run (Dask moves its tasks; the job's atomic writes and
idempotence make the redone inputs identical), and a corrupt file is one failed row.

Needs dask.distributed (crates/python/tests/requirements.txt) and the glint command
(GLINT_BIN, the single-process reference); with CI set, a missing one fails the tests.
The cluster is two worker processes on small volumes. Time added to scripts/test-python
(2026-11-26, 2 shared cores, load ~16): 14.4 s of its 81 s (pytest --durations: the
cluster and the reference run 5.7 s, the killed-worker run 2.3 s, python -m 5.1 s,
closing the cluster 1.3 s); this file alone 16-18 s.
"""

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import nibabel as nib
import numpy as np
import pytest

import glint

from conftest import _missing, run_glint

N_SUBJECTS = 24
SIZE = "48x40"
VIEWS = ["left", "anterior", "superior"]


@pytest.fixture(scope="module")
def distributed():
    try:
        import dask.distributed
    except ImportError:
        _missing("dask.distributed is not installed (pip install glint[dask])")
    return dask.distributed


@pytest.fixture(scope="module")
def client(distributed):
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                       dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """A BIDS dataset of N_SUBJECTS small T1w volumes (a noisy ellipsoid of another
    size each) and one corrupt file."""
    root = tmp_path_factory.mktemp("study")
    (root / "dataset_description.json").write_text('{"Name": "glint batch test", "BIDSVersion": "1.9.0"}')
    rng = np.random.default_rng(32)
    x, y, z = np.mgrid[-1:1:36j, -1:1:40j, -1:1:32j]
    for s in range(1, N_SUBJECTS + 1):
        r = 0.5 + 0.4 * s / N_SUBJECTS
        vol = 100.0 * ((x / r) ** 2 + (y / 0.9) ** 2 + (z / 0.7) ** 2 < 1) + rng.normal(0, 5, x.shape)
        anat = root / f"sub-{s:02d}" / "anat"
        anat.mkdir(parents=True)
        img = nib.Nifti1Image(vol.astype(np.float32), np.diag([2.0, 2.0, 2.5, 1.0]))
        nib.save(img, anat / f"sub-{s:02d}_T1w.nii.gz")
    bad = root / "sub-99" / "anat"
    bad.mkdir(parents=True)
    (bad / "sub-99_T1w.nii.gz").write_bytes(b"\x1f\x8b\x08\x00" + bytes(rng.integers(0, 256, 500, dtype=np.uint8)))
    return root


@pytest.fixture(scope="module")
def reference(glint_bin, study, tmp_path_factory):
    """The single-process result: `glint batch --jobs 1`."""
    out = tmp_path_factory.mktemp("reference")
    proc = run_glint(glint_bin, "batch", str(study), "-o", str(out), "--size", SIZE,
                     "--views", ",".join(VIEWS), "--slices", "--jobs", "1", "-q")
    assert proc.returncode == 1, proc.stderr  # one failed input
    return out


def rows(out: pathlib.Path):
    lines = (out / "results.jsonl").read_text().splitlines()
    return [json.loads(line) for line in lines]


def without_seconds(row):
    return {k: v for k, v in row.items() if k != "seconds"}


def assert_same_outputs(out: pathlib.Path, reference: pathlib.Path):
    """Same rows (but for their seconds), byte-identical files, no temporary file."""
    got, want = rows(out), rows(reference)
    assert [without_seconds(r) for r in got] == [without_seconds(r) for r in want]
    for row in want:
        if row["outputs"]:
            files = [row["outputs"]["mosaic"], row["outputs"]["slices"], row["outputs"]["scene"]]
            for f in files:
                assert (out / f).read_bytes() == (reference / f).read_bytes(), f
    leftovers = [p for p in out.rglob(".tmp*")]
    assert leftovers == []


def test_a_killed_worker_loses_nothing(client, study, reference, tmp_path):
    out = tmp_path / "dask"
    pids = client.run(os.getpid)
    assert len(pids) == 2
    killed = {}

    def kill_one_worker(outcome):
        # After the fourth input, kill a worker process that has tasks (SIGKILL: no
        # cleanup, as when a node dies); its nanny starts a new one.
        if killed:
            return
        kill_one_worker.seen += 1
        if kill_one_worker.seen < 4:
            return
        for _ in range(100):  # a moment between two tasks: wait for one to start
            busy = {addr: keys for addr, keys in client.processing().items() if keys}
            if busy:
                break
            time.sleep(0.05)
        addr = next(iter(busy or pids))
        os.kill(pids[addr], signal.SIGKILL)
        killed[addr] = (pids[addr], list(busy.get(addr, [])))

    kill_one_worker.seen = 0
    summary = glint.batch(study, glint.Scene(size=[48, 40]), VIEWS, out, client=client,
                          slices=True, on_result=kill_one_worker)
    assert len(killed) == 1, "no worker was killed"
    (pid, tasks), = killed.values()
    assert tasks, "the killed worker had no task"
    with pytest.raises(ProcessLookupError):
        os.kill(pid, 0)
    assert (summary["ok"], summary["failed"]) == (N_SUBJECTS, 1)
    bad = [r for r in summary["rows"] if r["status"] == "failed"]
    assert [r["id"] for r in bad] == ["sub-99_T1w"]
    assert "sub-99_T1w.nii.gz" in bad[0]["error"] and "\n" not in bad[0]["error"]
    assert_same_outputs(out, reference)

    # Again on the same directory: every good input is up to date, nothing changes.
    before = {p: p.stat().st_ino for p in out.rglob("*") if p.is_file()}
    again = glint.batch.run(study, glint.Scene(size=[48, 40]), VIEWS, out, client=client,
                            slices=True)
    assert again["skipped"] == N_SUBJECTS
    assert {p: p.stat().st_ino for p in out.rglob("*") if p.is_file()} == before


def test_python_m_glint_batch_on_a_scheduler(client, study, reference, tmp_path):
    out = tmp_path / "cli"
    address = client.scheduler.address
    proc = subprocess.run(
        [sys.executable, "-m", "glint.batch", str(study), "-o", str(out), "--size", SIZE,
         "--views", ",".join(VIEWS), "--slices", "--scheduler", address, "-q"],
        capture_output=True, text=True, timeout=600, cwd=tmp_path)
    assert proc.returncode == 1, proc.stderr  # the number of failed inputs
    assert_same_outputs(out, reference)
    report = (out / "index.html").read_text()
    assert report.count('<img class="thumb') == 2 * N_SUBJECTS
    assert 'id="row-sub-99_T1w"' in report


def test_bad_arguments_fail_before_any_task(client, study, tmp_path):
    with pytest.raises(ValueError, match="sideways"):
        glint.batch(study, None, ["sideways"], tmp_path / "x", client=client)
    with pytest.raises(ValueError, match="no file matches"):
        glint.batch(tmp_path / "*.nii", None, VIEWS, tmp_path / "y", client=client)
    assert not (tmp_path / "x").exists() and not (tmp_path / "y").exists()
