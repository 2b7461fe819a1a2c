"""The ``forensics`` command line.

A bad input is reported as one line on stderr and a non-zero exit status, never
a traceback (``FORENSICS_DEBUG=1`` shows tracebacks of internal errors). With
several photos, one bad photo does not stop the others.

Exit status: 0 every photo was analysed (whatever the verdict); 1 some photo
could not be taken in or written; 2 wrong usage; 3 internal error.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import click
from rich.console import Console
from rich.markup import escape
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn
from rich.table import Table

from . import ENTRY_POINT_GROUP, __version__
from .analysis import DEFAULT_TIMEOUT_S, ISOLATIONS, Options, analyze_evidence, resolve_params
from .evidence import DEFAULT_MAX_PIXELS, EvidenceError, load_evidence
from .output import output_dir_for, write_findings
from .plugins import PluginHost, one_line

FORMATS = ("json",)

err_console = Console(stderr=True, highlight=False)


def _fail_line(subject: str, reason: str) -> None:
    err_console.print(f"forensics: error: {subject}: {reason}", markup=False, soft_wrap=True)


def _parse_param(text: str) -> tuple[str, str, object]:
    """``detector.key=value``; the value is read as JSON when it parses, else as a string."""
    name, sep, raw = text.partition("=")
    detector, dot, key = name.partition(".")
    if not sep or not dot or not detector or not key:
        raise click.BadParameter(f"{text!r} is not of the form DETECTOR.KEY=VALUE", param_hint="--param")
    try:
        value = json.loads(raw)
    except json.JSONDecodeError:
        value = raw
    return detector, key, value


def _split_list(value: str | None) -> list[str] | None:
    if value is None:
        return None
    return [v.strip() for v in value.split(",") if v.strip()]


class ForensicsGroup(click.Group):
    """The command group, with plugins' commands added once plugins are loaded."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self._host: PluginHost | None = None

    @property
    def host(self) -> PluginHost:
        if self._host is None:
            self._host = PluginHost.from_entry_points()
            for outcome in self._host.call_each("forensics_register_commands", cli=self):
                if outcome.error is not None:
                    _fail_line(f"plugin {outcome.plugin}", f"could not add its commands: {one_line(outcome.error)}")
        return self._host

    def list_commands(self, ctx):
        self.host
        return super().list_commands(ctx)

    def get_command(self, ctx, name):
        if name not in self.commands:
            self.host
        return super().get_command(ctx, name)


@click.group(cls=ForensicsGroup, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, "--version", prog_name="forensics")
def cli() -> None:
    """Examine photos for splicing and record findings an examiner can defend.

    Detectors are plugins found through the entry-point group
    'forensics.plugins'; see `forensics plugins`.
    """


@cli.command()
@click.argument("photos", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output folder; each photo gets OUT/<photo stem>/.")
@click.option("--detectors", help="Comma-separated detector names (default: all installed).")
@click.option("--format", "formats", default="json", show_default=True,
              help=f"Comma-separated output formats: {', '.join(FORMATS)}.")
@click.option("--case-id", help="Case identifier carried into the findings.")
@click.option("--examiner", help="Examiner's name carried into the findings.")
@click.option("--param", "params", multiple=True, metavar="DETECTOR.KEY=VALUE",
              help="Override a detector parameter (repeatable); VALUE is read as JSON if it parses.")
@click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=DEFAULT_TIMEOUT_S, show_default=True,
              help="Time limit per detector, seconds.")
@click.option("--max-pixels", type=click.IntRange(min=1), default=DEFAULT_MAX_PIXELS, show_default=True,
              help="Refuse images with more pixels (decompression bombs).")
@click.option("--fusion", default="bonferroni", show_default=True, help="Fusion policy for the verdict.")
@click.option("--isolation", type=click.Choice(ISOLATIONS), default="process", show_default=True,
              help="Run each detector in a child process (killable at the time limit) or inline.")
@click.pass_context
def analyze(ctx, photos, out_dir, detectors, formats, case_id, examiner, params, timeout, max_pixels, fusion, isolation):
    """Analyse PHOTO... and write OUT/<photo stem>/findings.json for each.

    Exits 0 when every photo was analysed, whatever the verdict; 1 when some
    photo could not be taken in.
    """
    host: PluginHost = ctx.find_root().command.host
    wanted_formats = _split_list(formats) or []
    bad = sorted(set(wanted_formats) - set(FORMATS))
    if bad:
        raise click.BadParameter(f"unknown format(s) {', '.join(bad)}; available: {', '.join(FORMATS)}", param_hint="--format")
    detector_params: dict[str, dict[str, object]] = {}
    for text in params:
        det, key, value = _parse_param(text)
        detector_params.setdefault(det, {})[key] = value
    options = Options(detectors=_split_list(detectors), timeout_s=timeout, max_pixels=max_pixels, fusion=fusion,
                      isolation=isolation, detector_params=detector_params, case_id=case_id, examiner=examiner)
    try:
        resolve_params(host, options)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--param") from None
    for name in options.detectors or []:
        if name not in host.detectors:
            _fail_line(f"detector {name}", "not available; it is recorded as an error in the findings "
                                            f"(available: {', '.join(sorted(host.detectors)) or 'none'})")

    failures = 0
    used: set[str] = set()
    progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                        console=err_console, auto_refresh=False, transient=True, disable=len(photos) < 2)
    with progress:
        task = progress.add_task("analysing", total=len(photos))
        for photo in photos:
            progress.update(task, description=escape(f"analysing {photo.name}"))
            progress.refresh()
            try:
                evidence = load_evidence(photo, max_pixels=max_pixels)
                findings = analyze_evidence(evidence, host, options)
                target = output_dir_for(out_dir, photo, evidence.info.sha256, used)
                path = write_findings(findings, target)
            except EvidenceError as exc:
                failures += 1
                _fail_line(str(photo), str(exc))
            except OSError as exc:
                failures += 1
                _fail_line(str(photo), f"cannot write output: {exc.strerror or exc}")
            else:
                v = findings.verdict
                click.echo(f"{photo}: {v.label.value} -> {path}")
            progress.advance(task)
            progress.refresh()
    if failures:
        ctx.exit(1)


@cli.command("plugins")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.pass_context
def plugins_command(ctx, as_json):
    """List plugins: name, version, distribution, hooks, load status, error."""
    host: PluginHost = ctx.find_root().command.host
    records = host.plugin_records()
    if as_json:
        from dataclasses import asdict

        payload = {
            "entry_point_group": ENTRY_POINT_GROUP,
            "plugins": [asdict(r) for r in records],
            "detectors": [
                {"name": n, "plugin": d.plugin, "version": d.spec.version, "description": d.spec.description,
                 "references": list(d.spec.references), "default_params": dict(d.spec.default_params)}
                for n, d in sorted(host.detectors.items())
            ],
        }
        click.echo(json.dumps(payload, indent=2))
        return
    table = Table(title=f"plugins (entry-point group {ENTRY_POINT_GROUP})")
    for col in ("plugin", "distribution", "status", "detectors", "hooks", "error"):
        table.add_column(col)
    for r in records:
        dist = f"{r.distribution} {r.version}" if r.distribution else "-"
        cells = (r.name, dist, r.status, ", ".join(r.detectors) or "-",
                 ", ".join(h.removeprefix("forensics_") for h in r.hooks) or "-", r.error or "")
        table.add_row(*(escape(c) for c in cells))
    Console(highlight=False).print(table)


def main() -> None:
    """Entry point of the ``forensics`` script: no traceback reaches the user."""
    try:
        cli.main(standalone_mode=True)
    except SystemExit:
        raise
    except KeyboardInterrupt:
        _fail_line("interrupted", "stopped by the user")
        sys.exit(130)
    except Exception as exc:
        if os.environ.get("FORENSICS_DEBUG"):
            raise
        _fail_line("internal error", f"{one_line(exc)} (set FORENSICS_DEBUG=1 for the traceback)")
        sys.exit(3)
