"""Local worker processes, for real: outcomes, a worker killed mid-photo, a photo changed under the batch."""

import json
from pathlib import Path

from batch_helpers import sha256, tiny_jpeg
from forensics_core.analysis import Options
from forensics_core.batch.local import LocalPool
from forensics_core.batch.plan import Job
from forensics_core.batch.work import Settings, preload, process_photo


def _jobs(tmp_path, names):
    jobs = []
    for seed, name in enumerate(names):
        photo = tmp_path / "in" / name
        photo.parent.mkdir(exist_ok=True)
        photo.write_bytes(tiny_jpeg(seed))
        jobs.append(Job(str(photo), sha256(photo), str(tmp_path / "out" / photo.stem)))
    return jobs


def test_workers_analyse_each_photo_once_and_write_its_findings(tmp_path, steady_host):
    jobs = _jobs(tmp_path, ["a.jpg", "b.jpg", "c.jpg"])
    preload(steady_host, None)
    with LocalPool(2, Settings(Options(detectors=["steady"]))) as pool:
        finished = list(pool.run(jobs))
    assert sorted(f.job.path for f in finished) == sorted(j.path for j in jobs)
    for f in finished:
        assert f.outcome.error is None and f.attempts == 1
        assert f.outcome.verdict and f.outcome.detectors[0][:2] == ("steady", "ok")
        doc = json.loads((Path(f.job.folder) / "findings.json").read_text())
        assert doc["evidence"]["sha256"] == f.job.sha256


def test_a_worker_killed_mid_photo_costs_that_photo_only_after_one_retry(tmp_path, steady_host, monkeypatch):
    log = tmp_path / "attempts.log"
    monkeypatch.setenv("BATCH_TEST_KILL", "kill_me")
    monkeypatch.setenv("BATCH_TEST_LOG", str(log))
    jobs = _jobs(tmp_path, ["a.jpg", "kill_me.jpg", "b.jpg", "c.jpg"])
    preload(steady_host, None)
    with LocalPool(2, Settings(Options(detectors=["steady"]))) as pool:
        finished = {f.job.path: f for f in pool.run(jobs)}
    killed = finished[jobs[1].path]
    assert killed.attempts == 2
    assert killed.outcome.error == ("the worker analysing it died 2 times; the last was killed by SIGKILL "
                                    "(out of memory?)")
    assert all(finished[j.path].outcome.error is None and finished[j.path].attempts == 1 for j in jobs if j != jobs[1])
    tries = [line.split() for line in log.read_text().splitlines() if line.startswith("kill_me")]
    assert len(tries) == 2 and tries[0][1] != tries[1][1]  # two different worker processes
    assert not (tmp_path / "out" / "kill_me").exists() or not list((tmp_path / "out" / "kill_me").glob("findings.json"))


def test_a_photo_changed_after_hashing_is_refused(tmp_path, steady_host):
    (job,) = _jobs(tmp_path, ["a.jpg"])
    (tmp_path / "in" / "a.jpg").write_bytes(tiny_jpeg(99))
    preload(steady_host, None)
    outcome = process_photo(job, Settings(Options(detectors=["steady"])))
    assert outcome.error == "changed while the batch ran (its SHA-256 is not the one taken at the start)"
    assert not (tmp_path / "out" / "a").exists()
