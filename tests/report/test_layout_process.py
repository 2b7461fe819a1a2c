"""The PDF laid out in a warm process of its own: the same PDF, refusals passed back, failures one line."""

import os
import signal

import pytest

from forensics_core.report import layout_process
from forensics_core.report.layout_process import LayoutError, LayoutProcess
from forensics_core.report.pdf import lay_out
from forensics_core.report.render import render_pdf
from report_helpers import hostile_jpeg, pdf_pages_text
from test_render import render


def test_the_layout_process_gives_the_pdf_laid_out_here_and_passes_refusals_back(tmp_path):
    report = render(hostile_jpeg(tmp_path / "p.jpg"), "section_fetches")
    here, refused_here = lay_out(report.html)
    process = LayoutProcess()
    try:
        (tmp_path / "there.pdf").write_bytes(render_pdf(report, process))
    finally:
        process.close()
    (tmp_path / "here.pdf").write_bytes(here)
    assert pdf_pages_text(tmp_path / "there.pdf") == pdf_pages_text(tmp_path / "here.pdf")
    assert sorted(report.refused_urls) == sorted(refused_here)
    assert "file:///etc/passwd" in report.refused_urls


def test_a_layout_process_that_died_is_one_line_and_the_next_report_gets_a_new_one():
    process = layout_process.started()
    assert layout_process.started() is process  # kept for the photos that follow
    os.kill(process._proc.pid, signal.SIGKILL)
    process._proc.join(10)
    with pytest.raises(LayoutError, match=r"^the PDF layout process ended \(exit code -9\)$"):
        process.lay_out("<p>x</p>")
    fresh = layout_process.started()
    assert fresh is not process and fresh.alive()
    pdf, refused = fresh.lay_out("<p>x</p>")
    assert pdf.startswith(b"%PDF") and refused == []


def test_a_layout_past_its_time_limit_is_given_up():
    process = LayoutProcess()
    with pytest.raises(LayoutError, match="took longer than 0.001 s"):
        process.lay_out("<p>x</p>" * 2000, timeout_s=0.001)
    assert not process.alive()


def test_where_no_layout_process_can_start_the_pdf_is_laid_out_here(monkeypatch):
    import multiprocessing

    monkeypatch.setattr(layout_process, "_shared", None)
    monkeypatch.setattr(multiprocessing.current_process(), "daemon", True)  # as a Dask worker's process is
    assert layout_process.started() is None
