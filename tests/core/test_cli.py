"""The command line as a user meets it: real processes, real files."""

import errno
import hashlib
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image
from test_evidence import bad_inputs, png_header_only

FORENSICS = [sys.executable, "-m", "forensics_core"]


def run(*args, env=None, cwd=None):
    full_env = {**os.environ, **(env or {})}
    return subprocess.run([*FORENSICS, *map(str, args)], capture_output=True, text=True, env=full_env, cwd=cwd, timeout=300)


def test_version_and_help():
    out = run("--version")
    assert out.returncode == 0 and "forensics, version" in out.stdout
    for cmd in ([], ["analyze"], ["plugins"]):
        res = run(*cmd, "--help")
        assert res.returncode == 0 and "Usage:" in res.stdout


def test_analyze_writes_findings_and_leaves_the_evidence_untouched(photo, tmp_path, validate):
    before = hashlib.sha256(photo.read_bytes()).hexdigest()
    mtime = photo.stat().st_mtime_ns
    out = run("analyze", photo, "--out", tmp_path / "out", "--case-id", "C-1", "--examiner", "A. Examiner")
    assert out.returncode == 0, out.stderr
    findings = json.loads((tmp_path / "out" / "left01" / "findings.json").read_text())
    validate(findings)
    lr = findings["verdict"]["likelihood_ratio"]
    assert f": {findings['verdict']['label']}; fused LR {10.0 ** lr['log10_lr']:.3g}" in out.stdout
    assert findings["evidence"]["sha256"] == before
    assert findings["parameters"]["case_id"] == "C-1"
    assert hashlib.sha256(photo.read_bytes()).hexdigest() == before
    assert photo.stat().st_mtime_ns == mtime
    assert not list(tmp_path.glob("out/left01/*.tmp"))


def test_bad_inputs_get_one_line_each_and_do_not_stop_the_good_one(tmp_path, data_dir, photo):
    reasons = bad_inputs(tmp_path, data_dir)
    paths = [tmp_path / n for n in reasons]
    out = run("analyze", *paths, photo, "--out", tmp_path / "out")
    assert out.returncode == 1
    assert "Traceback" not in out.stderr
    lines = [ln for ln in out.stderr.splitlines() if ln.strip()]
    assert len(lines) == len(reasons), out.stderr
    for line, (name, reason) in zip(lines, reasons.items()):
        assert line.startswith("forensics: error: ") and name in line and reason in line
    assert (tmp_path / "out" / "left01" / "findings.json").exists()


def test_same_stem_twice_gets_distinct_folders(tmp_path, data_dir):
    a, b = tmp_path / "a", tmp_path / "b"
    a.mkdir(), b.mkdir()
    (a / "x.jpg").write_bytes((data_dir / "calibration" / "left01.jpg").read_bytes())
    (b / "x.jpg").write_bytes((data_dir / "calibration" / "left02.jpg").read_bytes())
    out = run("analyze", a / "x.jpg", b / "x.jpg", "--out", tmp_path / "out", "--detectors", "none_at_all")
    assert out.returncode == 0, out.stderr
    assert len(list((tmp_path / "out").glob("x*/findings.json"))) == 2


def test_a_link_that_loops_is_named_as_batch_names_it_not_as_missing(tmp_path):
    (tmp_path / "a.jpg").symlink_to("b.jpg")
    (tmp_path / "b.jpg").symlink_to("a.jpg")
    line = f"forensics: error: {tmp_path / 'a.jpg'}: cannot read: {os.strerror(errno.ELOOP)}"
    analysed = run("analyze", tmp_path / "a.jpg", "--out", tmp_path / "out", "--format", "json")
    assert analysed.returncode == 1 and analysed.stderr.splitlines() == [line]
    batch = run("batch", tmp_path / "a.jpg", "--out", tmp_path / "batch", "--format", "json")
    assert batch.returncode == 1 and batch.stderr.strip().splitlines() == [line]


def test_usage_errors_exit_2_without_traceback(photo, tmp_path):
    for args in (["--format", "docx"], ["--param", "lens_distortion.no_such=1"], ["--param", "garbled"]):
        out = run("analyze", photo, "--out", tmp_path, *args)
        assert out.returncode == 2, (args, out.stderr)
        assert "Traceback" not in out.stderr


def test_unknown_detector_warns_and_is_recorded(photo, tmp_path):
    out = run("analyze", photo, "--out", tmp_path, "--detectors", "nope")
    assert out.returncode == 0
    assert "detector nope: not available" in out.stderr
    doc = json.loads((tmp_path / "left01" / "findings.json").read_text())
    assert doc["detectors"][0]["status"] == "error"


def test_internal_errors_are_one_line(tmp_path, photo):
    out_file = tmp_path / "occupied"
    out_file.write_text("a file where the output folder should be")
    out = run("analyze", photo, "--out", out_file / "sub")
    assert out.returncode != 0
    assert "Traceback" not in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1


def test_a_one_pixel_photo_and_a_float_tiff_with_nan_are_inconclusive_in_silence(tmp_path):
    tiny, nan = tmp_path / "one.png", tmp_path / "nan.tif"
    Image.fromarray(np.zeros((1, 1), np.uint8)).save(tiny)
    grid = np.random.default_rng(0).random((64, 64)).astype(np.float32)
    grid[10:20, 10:20] = np.nan
    Image.fromarray(grid, mode="F").save(nan)
    out = run("analyze", tiny, nan, "--out", tmp_path / "out", "--format", "json")
    assert out.returncode == 0, out.stderr
    assert out.stderr.strip() == "", out.stderr
    for stem in ("one", "nan"):
        findings = json.loads((tmp_path / "out" / stem / "findings.json").read_text())
        status = {d["name"]: d["status"] for d in findings["detectors"]}
        assert status["lens_distortion"] == "inconclusive" and "error" not in status.values(), status
    note = json.loads((tmp_path / "out" / "nan" / "findings.json").read_text())["evidence"]["decoder_note"]
    assert "100 sample(s)" in note and "read them as 0" in note


def test_control_and_bidirectional_characters_in_names_are_shown_escaped(tmp_path, data_dir):
    hostile = tmp_path / "photo\x1b[31m\u202egpj\nx.jpg"
    hostile.write_bytes((data_dir / "exif" / "Canon_40D.jpg").read_bytes())
    out = run("analyze", hostile, "--out", tmp_path / "out", "--format", "html", "--detectors", "metadata")
    assert out.returncode == 0, out.stderr
    assert "\x1b" not in out.stdout + out.stderr and "\u202e" not in out.stdout
    (line,) = [x for x in out.stdout.splitlines() if "photo" in x]
    assert "photo\\x1b[31m\\u202egpj\\x0ax.jpg" in line
    (report,) = (tmp_path / "out").rglob("report.html")
    html = report.read_text(encoding="utf-8")
    assert "\u202e" not in html and "\\u202egpj" in html
    missing = run("analyze", tmp_path / "gone\x1b[2J.jpg", "--out", tmp_path / "out2")
    assert missing.returncode != 0 and "\x1b" not in missing.stderr and "gone\\x1b[2J.jpg" in missing.stderr


def test_control_and_bidirectional_characters_in_case_fields_are_shown_escaped(tmp_path, data_dir):
    # "Org\u202etxt.pdf" rendered as "Orgfdp.txt" in the report's header and metadata.
    out = run("analyze", data_dir / "exif" / "Canon_40D.jpg", "--out", tmp_path / "out", "--format", "html",
              "--detectors", "metadata", "--examiner", "Ada\x07\u202eExaminer", "--organisation", "Org\u202etxt.pdf",
              "--case-id", "C\x1b[2J-1", "--exhibit-id", "E\u2066-2")
    assert out.returncode == 0, out.stderr
    (report,) = (tmp_path / "out").rglob("report.html")
    html = report.read_text(encoding="utf-8")
    for raw in ("\u202e", "\x07", "\x1b", "\u2066"):
        assert raw not in html, repr(raw)
    assert "Org\\u202etxt.pdf" in html and "C\\x1b[2J-1" in html and "Ada\\x07\\u202eExaminer" in html
    (findings,) = (tmp_path / "out").rglob("findings.json")
    assert "\u202e" not in findings.read_text(encoding="utf-8")


def test_a_name_that_is_not_utf8_is_examined_reported_verified_and_listed(tmp_path, data_dir, validate):
    # A Latin-1 name from an archive made on another system: a valid file name
    # here, but its bytes are not text that JSON, HTML or PDF can hold.
    folder = tmp_path / "in"
    folder.mkdir()
    photo = folder / os.fsdecode(b"caf\xe9.jpg")
    photo.write_bytes((data_dir / "exif" / "Canon_40D.jpg").read_bytes())
    out = run("analyze", photo, "--out", tmp_path / "out", "--format", "json,html,pdf", "--detectors", "metadata")
    assert out.returncode == 0, out.stderr
    assert "caf\\xe9.jpg: " in out.stdout
    (bundle,) = (tmp_path / "out").iterdir()
    findings = validate(json.loads((bundle / "findings.json").read_text(encoding="utf-8")))
    assert findings["evidence"]["name"] == "caf\\xe9.jpg"
    assert findings["evidence"]["path"].endswith("/in/caf\\xe9.jpg")
    assert "/in/caf\\xe9.jpg&#39;" in (bundle / "report.html").read_text(encoding="utf-8")
    verified = run("verify", bundle, "--evidence", photo)
    assert verified.returncode == 0, verified.stderr
    assert "evidence: caf\\xe9.jpg matches" in verified.stdout
    results = tmp_path / os.fsdecode(b"r\xe9sultats")
    batch = run("batch", folder, "--out", results, "--format", "json", "--detectors", "metadata")
    assert batch.returncode == 0, batch.stderr
    summary = json.loads((results / "summary.json").read_text(encoding="utf-8"))
    assert summary["run"]["out_dir"].endswith("/r\\xe9sultats")
    (row,) = summary["photos"]
    assert row["outcome"] == "analysed" and row["photo"].endswith("/in/caf\\xe9.jpg")


def test_words_typed_in_another_encoding_are_a_usage_error_before_any_analysis(photo, tmp_path):
    for option in ("--case-id", "--examiner", "--exhibit-id"):
        out = run("analyze", photo, "--out", tmp_path / "out", option, os.fsdecode(b"Jos\xe9"))
        assert out.returncode == 2 and "Traceback" not in out.stderr
        assert f"Invalid value for '{option}': Jos\\xe9 holds bytes that are not UTF-8 text" in out.stderr
    assert not (tmp_path / "out").exists()


def _children(pid: int) -> list[int]:
    """The running processes forked by ``pid`` that run this project's code (zombies left out)."""
    found = []
    for entry in filter(str.isdigit, os.listdir("/proc")):
        try:
            stat = Path(f"/proc/{entry}/stat").read_text()
            command = Path(f"/proc/{entry}/cmdline").read_bytes()
        except (FileNotFoundError, ProcessLookupError):
            continue
        state, ppid = stat.rsplit(")", 1)[1].split()[:2]
        if int(ppid) == pid and state != "Z" and b"forensics_core" in command:
            found.append(int(entry))
    return found


def test_sigterm_and_ctrl_c_stop_a_run_in_one_line_and_leave_no_detector_running(photo, tmp_path):
    # SIGTERM (a scheduler, timeout, docker stop) used to end the command at
    # once, its detector children left running; Ctrl-C ended as "Aborted!", 1.
    for sig, status, words in ((signal.SIGTERM, 143, "forensics: error: terminated: stopped by SIGTERM"),
                               (signal.SIGINT, 130, "forensics: error: interrupted: stopped by the user")):
        out = tmp_path / sig.name
        # Ctrl-C as in a terminal's foreground: a shell starts background jobs
        # (as CI may run this suite) with SIGINT ignored, and so does the command.
        proc = subprocess.Popen([*FORENSICS, "analyze", str(photo), "--out", str(out), "--format", "json"],
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        deadline = time.monotonic() + 60
        while not _children(proc.pid):
            assert proc.poll() is None and time.monotonic() < deadline, "no detector child started"
            time.sleep(0.02)
        started = _children(proc.pid)
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=60)
        # CPython ends a process by SIGINT when a KeyboardInterrupt was raised
        # inside exec() (a plugin's import), whatever status it exits with.
        assert proc.returncode in ((status, -signal.SIGINT) if sig == signal.SIGINT else (status,)), stderr
        assert stderr.strip().splitlines() == [words] and stdout == ""
        assert not set(started) & set(_children(1))
        assert not list(out.rglob("manifest.json"))


def test_sigterm_sent_again_while_stopping_prints_no_traceback(photo, tmp_path):
    # Three SIGTERMs 10 ms apart printed a Python traceback in 5 of 8 tries.
    for attempt in range(4):
        proc = subprocess.Popen([*FORENSICS, "analyze", str(photo), "--out", str(tmp_path / str(attempt)),
                                 "--format", "json"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 60
        while not _children(proc.pid):
            assert proc.poll() is None and time.monotonic() < deadline, "no detector child started"
            time.sleep(0.02)
        for _ in range(3):
            proc.send_signal(signal.SIGTERM)
            time.sleep(0.01)
        _, stderr = proc.communicate(timeout=60)
        assert proc.returncode == 143, stderr
        assert stderr.strip().splitlines() == ["forensics: error: terminated: stopped by SIGTERM"], stderr


def test_names_and_fingerprints_are_printed_verbatim_not_as_emoji(tmp_path):
    # Rich would print ":cd:" as an emoji: a SHA-256 fingerprint holds ":CD:" one time in ten.
    missing = run("analyze", tmp_path / "gone:cd:smile:.jpg", "--out", tmp_path / "out")
    assert missing.returncode != 0 and "gone:cd:smile:.jpg" in missing.stderr


def test_analyze_never_writes_into_another_photos_or_other_settings_bundle(tmp_path, data_dir):
    a, b = tmp_path / "A" / "photo.jpg", tmp_path / "B" / "photo.jpg"
    for path, source in ((a, "Canon_40D.jpg"), (b, "87_OSError.jpg")):
        path.parent.mkdir()
        path.write_bytes((data_dir / "exif" / source).read_bytes())
    out = tmp_path / "out"
    base = ["--out", out, "--detectors", "metadata"]
    assert run("analyze", a, *base).returncode == 0
    first = {p.name: p.read_bytes() for p in (out / "photo").iterdir()}
    assert run("analyze", b, *base).returncode == 0
    sha_b = hashlib.sha256(b.read_bytes()).hexdigest()
    assert (out / f"photo-{sha_b[:12]}" / "manifest.json").exists()
    assert {p.name: p.read_bytes() for p in (out / "photo").iterdir()} == first, "A's bundle was touched"
    again = run("analyze", a, *base, "--format", "json")
    assert again.returncode == 0 and "kept" in again.stdout
    assert {p.name: p.read_bytes() for p in (out / "photo").iterdir()} == first, "a signed bundle was rewritten"
    other = run("analyze", a, *base, "--param", "metadata.datetime_tolerance_s=5")
    sha_a = hashlib.sha256(a.read_bytes()).hexdigest()
    assert other.returncode == 0 and f"photo-{sha_a[:12]}" in other.stdout
    forced = run("analyze", a, *base, "--force")
    assert forced.returncode == 0 and "kept" not in forced.stdout
    assert (out / "photo" / "findings.json").read_bytes() != first["findings.json"]
    assert run("verify", out / "photo", "--evidence", a).returncode == 0
    assert not [p for p in out.iterdir() if p.name.startswith(".")], "staging folders left behind"


def test_two_runs_of_one_photo_started_together_keep_one_whole_bundle(tmp_path, data_dir):
    # Both runs used to take the empty <stem> folder: the second wrote over
    # the first's finished bundle, file by file, and could leave a mixture.
    from forensics_core.signing import default_key

    default_key()  # made here once, so that the two runs race for the output folder only
    photo = tmp_path / "photo.jpg"
    photo.write_bytes((data_dir / "exif" / "Canon_40D.jpg").read_bytes())
    for attempt in range(3):
        out = tmp_path / f"out{attempt}"
        command = [*FORENSICS, "analyze", str(photo), "--out", str(out), "--detectors", "metadata", "--format", "html"]
        runs = [subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
        results = [(proc.communicate(timeout=300), proc.returncode) for proc in runs]
        assert all(status == 0 for _, status in results), [stderr for (_, stderr), _ in results]
        lines = sorted((stdout for (stdout, _), _ in results), key=lambda line: "(kept:" in line)
        assert "(kept:" not in lines[0] and "(kept: already analysed with these settings" in lines[1], lines
        assert {line.rsplit(" -> ", 1)[1].strip() for line in lines} == {str(out / "photo" / "findings.json")}
        assert os.listdir(out) == ["photo"], "a second bundle or a staging folder was left"
        verified = run("verify", out / "photo", "--evidence", photo)
        assert verified.returncode == 0, verified.stdout + verified.stderr


def test_a_run_killed_while_writing_leaves_the_folder_free_for_the_next(tmp_path, data_dir):
    photo = tmp_path / "photo.jpg"
    photo.write_bytes((data_dir / "exif" / "Canon_40D.jpg").read_bytes())
    out = tmp_path / "out"
    args = ["analyze", photo, "--out", out, "--detectors", "metadata", "--format", "html,pdf", "--jobs", "1"]
    proc = subprocess.Popen([*FORENSICS, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not list(out.glob(".photo.*.tmp")):
        assert proc.poll() is None and time.monotonic() < deadline, "the bundle was never seen being made"
        time.sleep(0.005)
    proc.kill()
    proc.communicate(timeout=60)
    assert not (out / "photo").exists(), "a bundle was published by a killed run"
    again = run(*args)
    assert again.returncode == 0 and "kept" not in again.stdout, again.stderr
    assert run("verify", out / "photo", "--evidence", photo).returncode == 0


def test_one_changed_byte_in_the_exif_header_is_an_observation_and_stops_nothing(tmp_path, data_dir):
    good = data_dir / "exif" / "Canon_40D.jpg"
    data = bytearray(good.read_bytes())
    data[data.find(b"Exif\x00\x00") + 6] = 0x94  # the TIFF byte order mark
    bad = tmp_path / "bad.jpg"
    bad.write_bytes(bytes(data))
    out = run("analyze", bad, good, "--out", tmp_path / "out", "--format", "json")
    assert out.returncode == 0, out.stderr
    assert "internal error" not in out.stderr and len(out.stdout.strip().splitlines()) == 2
    findings = json.loads((tmp_path / "out" / "bad" / "findings.json").read_text())
    assert findings["evidence"]["exif"]["unreadable"].startswith("EXIF unreadable: not a TIFF file")
    checks = {c["id"]: c for d in findings["detectors"] if d["name"] == "metadata" for c in d["details"]["checks"]}
    assert checks["exif_present"]["outcome"] == "note" and "EXIF unreadable" in checks["exif_present"]["observation"]


def test_photos_between_pillows_bomb_warning_and_our_limit_give_one_line_and_no_warning(tmp_path):
    """108 MP and 144 MP are above Pillow's DecompressionBombWarning level (89 MP) and below --max-pixels."""
    for name, (w, h) in {"p108.png": (12000, 9000), "p144.png": (13856, 10392)}.items():
        (tmp_path / name).write_bytes(png_header_only(w, h))
    out = run("analyze", tmp_path / "p108.png", tmp_path / "p144.png", "--out", tmp_path / "o", "--format", "json")
    assert out.returncode == 1
    lines = out.stderr.strip().splitlines()
    assert len(lines) == 2 and all(line.startswith("forensics: error: ") for line in lines), out.stderr
    assert "Warning" not in out.stderr


def test_a_photos_line_names_the_side_the_likelihood_ratio_supports():
    from forensics_core.calibration.model import verbal
    from forensics_core.cli import _strength_words
    from forensics_core.findings import LikelihoodRatio, Verdict, VerdictLabel

    verdict = Verdict(VerdictLabel.CONSISTENT, 1.0, "e", "bonferroni")
    assert _strength_words(verdict) == ""
    for log10_lr, words in ((1.48, "; fused LR 30.2, moderate support for Hp (manipulation)"),
                            (-0.19, "; fused LR 0.646")):
        verdict.likelihood_ratio = LikelihoodRatio("h", "d", log10_lr, verbal(log10_lr))
        assert _strength_words(verdict) == words
