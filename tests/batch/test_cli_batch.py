"""`forensics batch` as a user meets it: real processes, real files, a real Dask cluster."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from batch_helpers import DATA, fixture_env, popen, run, sha256, summary, temp_files, tiny_jpeg
from forensics_core.batch.resume import OutputLock
from forensics_core.verify import verify_bundle
from processes import alive

CALIBRATION = DATA / "calibration"


def _mixed_folder(root: Path) -> Path:
    root.mkdir(parents=True)
    for name in ("left01.jpg", "left02.jpg"):
        shutil.copyfile(CALIBRATION / name, root / name)
    shutil.copyfile(CALIBRATION / "left01.jpg", root / "copy of left01.jpg")
    (root / "truncated.jpg").write_bytes((CALIBRATION / "left03.jpg").read_bytes()[:20000])
    (root / "notes.txt").write_text("not a photo")
    (root / "empty.jpg").write_bytes(b"")
    (root / "nested").mkdir()
    (root / "nested" / "deep.jpg").write_bytes(tiny_jpeg(1))
    return root


def test_a_folder_of_good_corrupt_and_duplicate_files(tmp_path):
    photos = _mixed_folder(tmp_path / "in")
    out = tmp_path / "out"
    res = run("batch", photos, "--out", out, "--format", "json", "--workers", "2")
    assert res.returncode == 1, res.stderr
    assert "Traceback" not in res.stderr
    doc = summary(out)
    rows = doc["by_photo"]
    assert set(rows) == {"left01.jpg", "left02.jpg", "copy of left01.jpg", "truncated.jpg", "notes.txt", "empty.jpg"}
    reasons = {"truncated.jpg": "corrupt or truncated image", "notes.txt": "not an image", "empty.jpg": "empty file"}
    for name, reason in reasons.items():
        assert rows[name]["outcome"] == "failed" and reason in rows[name]["error"]
        assert f"forensics: error: {photos / name}: {rows[name]['error']}" in res.stderr
    assert len([ln for ln in res.stderr.splitlines() if ln.strip()]) == len(reasons)
    # "copy of left01.jpg" sorts first: it is analysed, left01 links to its folder.
    primary, dup = rows["copy of left01.jpg"], rows["left01.jpg"]
    assert primary["outcome"] == "analysed" and primary["verdict"] and primary["detectors"]["steady"]["status"] == "ok"
    assert dup["outcome"] == "duplicate" and dup["duplicate_of"] == str(photos / "copy of left01.jpg")
    assert os.readlink(out / "left01") == "copy of left01"
    assert dup["sha256"] == primary["sha256"] == sha256(CALIBRATION / "left01.jpg")
    kept = json.loads((out / "left01" / "findings.json").read_text())
    assert kept["evidence"]["name"] == "copy of left01.jpg"
    assert primary["log10_lr"] == dup["log10_lr"] == kept["verdict"]["log10_lr"]
    assert rows["left02.jpg"]["outcome"] == "analysed" and rows["left02.jpg"]["attempts"] == 1
    assert doc["counts"]["analysed"] == 2 and doc["counts"]["duplicate"] == 1 and doc["counts"]["failed"] == 3
    assert "2 local worker processes" in doc["run"]["workers"]
    csv_lines = (out / "summary.csv").read_text().splitlines()
    assert csv_lines[0].endswith("steady.status,steady.score") and len(csv_lines) == 7
    assert "batch summary" in res.stdout and not temp_files(out)

    deep = run("batch", photos, "--out", out, "--format", "json", "--recursive")
    rows = summary(out)["by_photo"]
    assert deep.returncode == 1 and rows["deep.jpg"]["outcome"] == "analysed"
    assert rows["left02.jpg"]["outcome"] == rows["copy of left01.jpg"]["outcome"] == "resumed"


def test_reports_are_resumed_shared_by_duplicates_and_redone_when_settings_change(tmp_path):
    photos = tmp_path / "in"
    photos.mkdir()
    (photos / "a.jpg").write_bytes(tiny_jpeg(3))
    (photos / "b.jpg").write_bytes(tiny_jpeg(3))
    out = tmp_path / "out"
    first = run("batch", photos, "--out", out, "--exhibit-id", "EX-1")
    assert first.returncode == 0, first.stderr
    names = {"findings.json", "report.html", "report.pdf", "manifest.json", "manifest.json.p7s", "signer.pem"}
    assert names <= {p.name for p in (out / "a").iterdir()}
    assert os.readlink(out / "b") == "a"
    for folder, photo in (("a", "a.jpg"), ("b", "b.jpg")):
        check = verify_bundle(out / folder, evidence=photos / photo)
        assert check.ok, check.problems
    stamp = (out / "a" / "report.pdf").stat().st_mtime_ns

    again = run("batch", photos, "--out", out, "--exhibit-id", "EX-1")
    assert again.returncode == 0, again.stderr
    rows = summary(out)["by_photo"]
    assert rows["a.jpg"]["outcome"] == "resumed" and rows["b.jpg"]["outcome"] == "duplicate"
    assert rows["a.jpg"]["time_s"] is not None  # carried over from the first summary
    assert (out / "a" / "report.pdf").stat().st_mtime_ns == stamp

    other = run("batch", photos, "--out", out, "--exhibit-id", "EX-2", "--format", "json,html")
    assert other.returncode == 0, other.stderr
    assert summary(out)["by_photo"]["a.jpg"]["outcome"] == "analysed"
    manifest = json.loads((out / "a" / "manifest.json").read_text())
    assert manifest["exhibit_id"] == "EX-2" and "report.pdf" not in {f["name"] for f in manifest["files"]}


def test_stems_clashing_across_folders_keep_their_folders_on_rerun(tmp_path):
    for sub, seed in (("a", 1), ("b", 2)):
        (tmp_path / sub).mkdir()
        (tmp_path / sub / "x.jpg").write_bytes(tiny_jpeg(seed))
    out = tmp_path / "out"
    assert run("batch", tmp_path / "a", tmp_path / "b", "--out", out, "--format", "json").returncode == 0
    suffixed = f"x-{sha256(tmp_path / 'b' / 'x.jpg')[:12]}"
    assert sorted(p.name for p in out.iterdir() if p.is_dir()) == ["x", suffixed]
    again = run("batch", tmp_path / "b", tmp_path / "a", "--out", out, "--format", "json")
    rows = summary(out)["by_photo"]
    assert again.returncode == 0 and {r["outcome"] for r in summary(out)["photos"]} == {"resumed"}
    assert {Path(r["output"]).name for r in summary(out)["photos"]} == {"x", suffixed}
    assert rows  # both photos have rows


def test_usage_errors_and_a_second_batch_on_the_same_folder(tmp_path):
    photo = tmp_path / "a.jpg"
    photo.write_bytes(tiny_jpeg(0))
    both = run("batch", photo, "--out", tmp_path / "o", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1")
    assert both.returncode == 2 and "Traceback" not in both.stderr
    bad = run("batch", photo, "--out", tmp_path / "o", "--param", "steady.nope=1")
    assert bad.returncode == 2
    (tmp_path / "o").mkdir()
    with OutputLock(tmp_path / "o"):  # as another batch would hold it
        held = run("batch", photo, "--out", tmp_path / "o", "--format", "json")
    assert held.returncode == 1
    assert held.stderr.strip() == f"forensics: error: batch: another `forensics batch` is writing into {tmp_path / 'o'}"


def _count_finished(out: Path) -> int:
    return len(list(out.glob("*/manifest.json.p7s")))


@pytest.mark.slow
def test_a_run_killed_midway_loses_nothing_finished_and_the_rerun_completes_it(tmp_path):
    photos = tmp_path / "in"
    photos.mkdir()
    for seed in range(6):
        (photos / f"p{seed}.jpg").write_bytes(tiny_jpeg(seed))
    out = tmp_path / "out"
    log = tmp_path / "workers.log"
    env = fixture_env(BATCH_TEST_LOG=str(log))
    args = ("batch", photos, "--out", out, "--format", "json,html", "--workers", "2", "--param", "steady.seconds=0.5")
    proc = popen(*args, env=env)
    deadline = time.monotonic() + 120
    while _count_finished(out) < 2 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert 2 <= _count_finished(out) < 6
    workers = {int(line.split()[1]) for line in log.read_text().splitlines()}
    deadline = time.monotonic() + 10
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not any(alive(pid) for pid in workers)  # the lifeline took the workers down with the command
    finished = {p.parent.name: p.stat().st_mtime_ns for p in out.glob("*/manifest.json.p7s")}
    assert finished and not (out / "summary.json").exists()
    visible = {p.name for p in out.iterdir() if p.is_dir() and not p.name.startswith(".")}
    assert visible == set(finished)  # no half bundle: unfinished ones are hidden staging folders
    # What a kill in the middle of a write leaves (write_atomic's temporary name), in an unfinished folder.
    unfinished = next(p.stem for p in sorted(photos.iterdir()) if p.stem not in finished)
    (out / unfinished).mkdir(exist_ok=True)
    (out / unfinished / ".report.html.k1ll3d_0.tmp").write_text("<html>half of a rep")

    rerun = run(*args, env=env)
    assert rerun.returncode == 0, rerun.stderr
    doc = summary(out)
    assert doc["counts"]["photos"] == 6 and doc["counts"]["failed"] == 0 and doc["counts"]["pending"] == 0
    for name, stamp in finished.items():
        assert doc["by_photo"][f"{name}.jpg"]["outcome"] == "resumed"
        assert (out / name / "manifest.json.p7s").stat().st_mtime_ns == stamp  # not redone
    assert doc["counts"]["analysed"] == 6 - len(finished)
    assert not temp_files(out)
    for row in doc["photos"]:
        check = verify_bundle(Path(row["output"]), evidence=Path(row["photo"]))
        assert check.ok, (row["photo"], check.problems)


def test_a_batch_killed_while_a_report_is_made_leaves_no_visible_half_bundle(tmp_path):
    photos = tmp_path / "in"
    photos.mkdir()
    (photos / "p.jpg").write_bytes(tiny_jpeg(0))
    out = tmp_path / "out"
    proc = popen("batch", photos, "--out", out, "--format", "json,html", "--workers", "1",
                 "--param", "steady.report_seconds=30", env=fixture_env())
    deadline = time.monotonic() + 60
    while not list(out.glob(".p.*.tmp/findings.json")) + list(out.glob("p/findings.json")):
        assert time.monotonic() < deadline and proc.poll() is None
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert not (out / "p").exists()  # the findings wait in a hidden staging folder until the bundle is whole

    rerun = run("batch", photos, "--out", out, "--format", "json,html", env=fixture_env())
    assert rerun.returncode == 0, rerun.stderr
    assert (out / "p" / "manifest.json.p7s").is_file() and not temp_files(out)


def test_a_worker_killed_mid_photo_is_retried_once_then_the_photo_fails(tmp_path):
    photos = tmp_path / "in"
    photos.mkdir()
    for seed, name in enumerate(("a.jpg", "kill_me.jpg", "b.jpg")):
        (photos / name).write_bytes(tiny_jpeg(seed))
    log = tmp_path / "attempts.log"
    res = run("batch", photos, "--out", tmp_path / "out", "--format", "json", "--workers", "2",
              env=fixture_env(BATCH_TEST_KILL="kill_me", BATCH_TEST_LOG=str(log)))
    assert res.returncode == 1
    rows = summary(tmp_path / "out")["by_photo"]
    assert rows["kill_me.jpg"]["outcome"] == "failed" and rows["kill_me.jpg"]["attempts"] == 2
    assert "died 2 times" in rows["kill_me.jpg"]["error"]
    assert rows["a.jpg"]["outcome"] == rows["b.jpg"]["outcome"] == "analysed"
    assert sum(line.startswith("kill_me.jpg") for line in log.read_text().splitlines()) == 2


def _start_cluster(tmp_path, env):
    scheduler_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([sys.executable, "-m", "dask", "scheduler", "--host", "127.0.0.1", "--port", "0",
                               "--no-dashboard", "--scheduler-file", str(scheduler_file)],
                              env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    deadline = time.monotonic() + 60
    while not scheduler_file.exists() and time.monotonic() < deadline:
        time.sleep(0.1)
    for _ in range(2):
        procs.append(subprocess.Popen([sys.executable, "-m", "dask", "worker", "--scheduler-file", str(scheduler_file),
                                       "--nthreads", "1", "--no-dashboard", "--host", "127.0.0.1"],
                                      env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    from distributed import Client

    with Client(scheduler_file=str(scheduler_file), timeout=60) as client:
        client.wait_for_workers(2, timeout=60)
        address = client.scheduler.address
    return address, procs


@pytest.mark.slow
def test_a_batch_on_a_dask_cluster_with_two_workers(tmp_path):
    photos = _mixed_folder(tmp_path / "in")
    (photos / "kill_me.jpg").write_bytes(tiny_jpeg(7))
    log = tmp_path / "attempts.log"
    # The workers see the same files, plugins and key folder (FORENSICS_HOME) as the command.
    env = fixture_env(BATCH_TEST_KILL="kill_me", BATCH_TEST_LOG=str(log),
                      DASK_DISTRIBUTED__SCHEDULER__ALLOWED_FAILURES="1",
                      DASK_DISTRIBUTED__SCHEDULER__WORKER_SATURATION="1.0")
    address, procs = _start_cluster(tmp_path, env)
    try:
        out = tmp_path / "out"
        res = run("batch", photos, "--out", out, "--format", "json,html", "--scheduler", address, env=env)
    finally:
        for proc in procs:
            proc.terminate()
        for proc in procs:
            try:
                proc.wait(30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
    assert res.returncode == 1, res.stderr
    doc = summary(out)
    rows = doc["by_photo"]
    assert doc["run"]["workers"].startswith(f"Dask cluster {address} (2 workers")
    assert rows["left02.jpg"]["outcome"] == rows["copy of left01.jpg"]["outcome"] == "analysed"
    assert rows["left01.jpg"]["outcome"] == "duplicate"
    assert "corrupt or truncated image" in rows["truncated.jpg"]["error"]
    assert rows["kill_me.jpg"]["outcome"] == "failed" and "died 2 times" in rows["kill_me.jpg"]["error"]
    assert sum(line.startswith("kill_me.jpg") for line in log.read_text().splitlines()) == 2
    pids = {int(line.rsplit(" ", 1)[1]) for line in log.read_text().splitlines()}
    assert len(pids) >= 2  # the work was spread over the workers (and their replacements)
    check = verify_bundle(out / "left02", evidence=photos / "left02.jpg")
    assert check.ok, check.problems
    assert not temp_files(out)
