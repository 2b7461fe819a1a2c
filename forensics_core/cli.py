"""The ``forensics`` command line.

A bad input is reported as one line on stderr and a non-zero exit status, never
a traceback (``FORENSICS_DEBUG=1`` shows tracebacks of internal errors). With
several photos, one bad photo does not stop the others.

Exit status: 0 every photo was analysed (whatever the verdict); 1 some photo
could not be taken in or written; 2 wrong usage; 3 internal error.
"""

from __future__ import annotations

import json
import logging
import os
import signal
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import click
from rich.console import Console
from rich.markup import escape

from . import ENTRY_POINT_GROUP, __version__, stopping
from .calibration.command import calibrate_command
from .containment import one_line
from .defaults import (
    DEFAULT_JOBS,
    DEFAULT_MAX_PIXELS,
    DEFAULT_TIMEOUT_S,
    ISOLATIONS,
    KEY_TYPES,
    PAPER_SIZES,
    PARALLEL_MAX_PIXELS,
    PASSWORD_ENV,
)
from .plugins import PluginHost
from .text import undecodable, visible
from .validation.command import validate_command

if TYPE_CHECKING:
    from .analysis import Options
    from .findings import Verdict
    from .pipeline import ReportSettings
    from .signing import ExaminerKey

# Modules that load numpy, Pillow, cryptography, Jinja2 or WeasyPrint are
# imported by the commands that use them, so that `--version`, `--help`,
# `plugins` and `verify` start in a fraction of a second.

FORMATS = ("json", "html", "pdf")
REPORT_FORMATS = ("html", "pdf")

err_console = Console(stderr=True, highlight=False, emoji=False)


def _strength_words(verdict: Verdict) -> str:
    """The fused likelihood ratio after the verdict's label on a photo's line, with its words when it supports a side.

    The label answers the triage rule; a copy found by a detector that states
    no p-value can leave it "consistent" while the likelihood ratio supports
    manipulation, so the line states both.
    """
    from .calibration.model import supports

    lr = verdict.likelihood_ratio
    if lr is None or lr.log10_lr is None:
        return ""
    words = f", {lr.verbal}" if supports(lr.log10_lr) else ""
    return f"; fused LR {10.0 ** lr.log10_lr:.3g}{words}"


def _fail_line(subject: str, reason: str) -> None:
    err_console.print(f"forensics: error: {visible(subject)}: {visible(reason)}", markup=False, soft_wrap=True)


class _Text(click.ParamType):
    """Words the user types that go into the findings, the report or a certificate.

    An argument typed in another encoding than the terminal's holds bytes
    that are not UTF-8, which none of those can hold: it is refused here, as
    a usage error, rather than failing once the photo has been analysed.
    Control and format characters (ESC, BEL, a bidirectional override
    U+202E that turns "Org\u202etxt.pdf" into "Orgfdp.txt" on the page) are
    kept as visible escapes, never as acting characters.
    """

    name = "text"

    def convert(self, value, param, ctx):
        if isinstance(value, str) and undecodable(value):
            self.fail(f"{visible(value)} holds bytes that are not UTF-8 text; type it in UTF-8", param, ctx)
        return visible(value) if isinstance(value, str) else value


TEXT = _Text()


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
            for failure in self._host.call("forensics_register_commands", cli=self).failures:
                _fail_line(f"plugin {failure.plugin}", f"could not add its commands: {one_line(failure.error)}")
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


def _password_from_env() -> bytes | None:
    value = os.environ.get(PASSWORD_ENV)
    return value.encode("utf-8") if value is not None else None


def _signing_key(key_path: Path | None, examiner: str | None, organisation: str | None) -> ExaminerKey:
    """The key that signs the reports: ``--key``, else the per-user key (made on first use).

    The password comes from the environment; without one a key that needs one
    is asked for on the terminal.
    """
    from .signing import SigningError, default_key, default_key_path, load_key

    password = _password_from_env()

    def load(pw: bytes | None) -> ExaminerKey:
        return load_key(key_path, pw) if key_path is not None else default_key(examiner, organisation, pw)

    try:
        try:
            key = load(password)
        except SigningError:
            if password is not None or not sys.stdin.isatty():
                raise
            key = load(click.prompt(f"password of {key_path or default_key_path()}", hide_input=True,
                                    err=True).encode("utf-8"))
    except SigningError as exc:
        raise click.BadParameter(str(exc), param_hint="--key") from None
    if key.created_now:
        click.echo(f"forensics: made a self-signed examiner key for trial use: {key.source} "
                   f"(SHA-256 {key.fingerprint}), trusted by `forensics verify` on this account; see "
                   "`forensics keys create` and --key")
    return key


def _run_options(command):
    """The options ``analyze`` and ``batch`` share: what to run, how, and how to report it."""
    options = [
        click.option("--detectors", type=TEXT, help="Comma-separated detector names (default: all installed)."),
        click.option("--format", "formats", default=",".join(FORMATS), show_default=True,
                     help=f"Comma-separated output formats: {', '.join(FORMATS)}. html and pdf also write the signed "
                          "manifest.json and manifest.json.p7s."),
        click.option("--case-id", type=TEXT, help="Case identifier carried into the findings."),
        click.option("--examiner", type=TEXT, help="Examiner's name carried into the findings."),
        click.option("--param", "params", type=TEXT, multiple=True, metavar="DETECTOR.KEY=VALUE",
                     help="Override a detector parameter (repeatable); VALUE is read as JSON if it parses."),
        click.option("--timeout", type=click.FloatRange(min=0, min_open=True), default=DEFAULT_TIMEOUT_S,
                     show_default=True, help="Time limit per detector, seconds."),
        click.option("--max-pixels", type=click.IntRange(min=1), default=DEFAULT_MAX_PIXELS, show_default=True,
                     help="Refuse images with more pixels (decompression bombs)."),
        click.option("--fusion", type=TEXT, default="bonferroni", show_default=True,
                     help="Fusion policy for the verdict."),
        click.option("--isolation", type=click.Choice(ISOLATIONS), default="process", show_default=True,
                     help="Run each detector in a child process (killable at the time limit) or inline."),
        click.option("--exhibit-id", type=TEXT, help="Exhibit identifier printed on every page of the report."),
        click.option("--organisation", type=TEXT,
                     help="Examiner's organisation for the signature block (default: the certificate's)."),
        click.option("--key", "key_path", type=click.Path(dir_okay=False, exists=True, path_type=Path),
                     help=f"Signing key, PKCS#12 (password from ${PASSWORD_ENV} or a prompt). Default: the per-user "
                          "self-signed key, made on first use."),
        click.option("--paper", type=click.Choice(sorted(PAPER_SIZES)), default="a4", show_default=True,
                     help="PDF paper size."),
        click.option("--tsa", "tsa_url", metavar="URL",
                     help="RFC 3161 time-stamping service for the signatures (default: none)."),
        click.option("--validation", "validation_path", type=click.Path(dir_okay=False, exists=True, path_type=Path),
                     help="validation.json whose error rates the report states (default: the record shipped with "
                          "this release)."),
        click.option("--calibration", "calibration_path", type=click.Path(dir_okay=False, exists=True, path_type=Path),
                     help="Likelihood-ratio calibrators (written by `forensics calibrate`) for the findings' LRs "
                          "(default: those shipped with this release, fitted on the real-photo corpus)."),
        click.option("--reference", "reference_path", type=click.Path(path_type=Path),
                     help="Folder of reference photos of the camera that allegedly took the photo(s): hashed, listed "
                          "in the findings and read only, for the detectors that compare with them (prnu)."),
    ]
    for option in reversed(options):
        command = option(command)
    return command


@dataclass(frozen=True)
class RunRequest:
    """What an ``analyze`` or ``batch`` run was asked for: the options of :func:`_run_options`, as given."""

    detectors: str | None
    formats: str
    case_id: str | None
    examiner: str | None
    params: tuple[str, ...]
    timeout: float
    max_pixels: int
    fusion: str
    isolation: str
    exhibit_id: str | None
    organisation: str | None
    key_path: Path | None
    paper: str
    tsa_url: str | None
    validation_path: Path | None
    calibration_path: Path | None
    reference_path: Path | None = None
    jobs: int = 1


def _prepare_run(host: PluginHost, request: RunRequest) -> tuple[Options, ReportSettings | None]:
    """Check the shared options, load the signing key and warn of unknown detectors.

    Raises ``click.BadParameter`` (exit status 2) for wrong usage.
    """
    from .analysis import Options
    from .calibration import CalibrationError
    from .calibration import load as load_calibration
    from .pipeline import ReportSettings
    from .reference import ReferenceError, references_for

    wanted_formats = _split_list(request.formats) or []
    bad = sorted(set(wanted_formats) - set(FORMATS))
    if bad:
        raise click.BadParameter(f"unknown format(s) {', '.join(bad)}; available: {', '.join(FORMATS)}", param_hint="--format")
    detector_params: dict[str, dict[str, object]] = {}
    for text in request.params:
        det, key, value = _parse_param(text)
        detector_params.setdefault(det, {})[key] = value
    if request.calibration_path is not None:
        try:
            load_calibration(request.calibration_path)
        except CalibrationError as exc:
            raise click.BadParameter(str(exc), param_hint="--calibration") from None
    reference = None
    if request.reference_path is not None:
        reference = str(request.reference_path.resolve())
        try:
            references_for(reference, request.max_pixels)
        except ReferenceError as exc:
            raise click.BadParameter(str(exc), param_hint="--reference") from None
    options = Options(detectors=_split_list(request.detectors), timeout_s=request.timeout,
                      max_pixels=request.max_pixels, fusion=request.fusion, isolation=request.isolation,
                      detector_params=detector_params, case_id=request.case_id, examiner=request.examiner,
                      calibration=str(request.calibration_path.resolve()) if request.calibration_path else None,
                      reference=reference, jobs=request.jobs)
    try:
        options = options.resolve(host)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--param") from None
    report_formats = tuple(f for f in REPORT_FORMATS if f in wanted_formats)
    report = None
    if report_formats:
        from .report.render import ReportOptions

        record = None
        if request.validation_path is not None:
            from .validation import read_record

            try:
                record = read_record(request.validation_path)
            except (OSError, ValueError) as exc:
                raise click.BadParameter(one_line(exc), param_hint="--validation") from None
        report = ReportSettings(_signing_key(request.key_path, request.examiner, request.organisation), report_formats,
                                ReportOptions(exhibit_id=request.exhibit_id, paper=request.paper, validation=record,
                                              validation_source=f"the validation record {request.validation_path}" if record else None,
                                              jobs=request.jobs),
                                request.organisation, request.tsa_url)
    for name in options.detectors or []:
        if name not in host.detectors:
            _fail_line(f"detector {name}", "not available; it is recorded as an error in the findings "
                                            f"(available: {', '.join(sorted(host.detectors)) or 'none'})")
    return options, report


@cli.command()
@click.argument("photos", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output folder; each photo gets OUT/<photo stem>/ (or <stem>-<SHA-256 prefix>/ when that holds "
                   "another photo's or other settings' outputs).")
@click.option("--force", is_flag=True, help="Replace, as a whole, a bundle this photo already has in OUT.")
@click.option("--jobs", type=click.IntRange(min=1), default=DEFAULT_JOBS, show_default=True,
              help="Detectors, and report sections, run at once, each in its own process (detectors one at a time "
                   f"on photos over {PARALLEL_MAX_PIXELS // 1_000_000} MP, and with --isolation inline). The findings "
                   "and the report are the same.")
@_run_options
@click.pass_context
def analyze(ctx, photos, out_dir, force, jobs, **run):
    """Analyse PHOTO... and write OUT/<photo stem>/findings.json for each,
    with the signed report (report.html, report.pdf, manifest.json and its
    signature) beside it.

    A folder holding another photo's outputs, or this photo's made with other
    settings, is never written: the photo gets OUT/<stem>-<SHA-256 prefix>/.
    When this photo's outputs with the same settings are already there they
    are kept as they are; --force replaces them.

    Exits 0 when every photo was analysed, whatever the verdict; 1 when some
    photo could not be taken in or its outputs could not be written.
    """
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

    from .evidence import EvidenceError
    from .output import place_outputs
    from .pipeline import ReportError, examine_photo, expected_files

    host: PluginHost = ctx.find_root().command.host
    options, report = _prepare_run(host, RunRequest(**run, jobs=jobs))

    failures = 0
    used: set[str] = set()
    files = expected_files(report)
    progress = Progress(TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeElapsedColumn(),
                        console=err_console, auto_refresh=False, transient=True, disable=len(photos) < 2)
    with progress:
        task = progress.add_task("analysing", total=len(photos))
        for photo in photos:
            stopping.check()
            progress.update(task, description=escape(f"analysing {visible(photo.name)}"))
            progress.refresh()
            try:
                done = examine_photo(photo, lambda ev, fi: place_outputs(out_dir, photo, fi, files, used, force),
                                     host, options, report)
            except EvidenceError as exc:
                failures += 1
                _fail_line(str(photo), str(exc))
            except OSError as exc:
                failures += 1
                _fail_line(str(photo), f"cannot write output: {exc.strerror or exc}")
            except ReportError as exc:
                failures += 1
                _fail_line(str(photo), f"cannot write the report: {exc}")
            except Exception as exc:  # a bug must cost this photo only, not the others
                if os.environ.get("FORENSICS_DEBUG"):
                    raise
                failures += 1
                _fail_line(str(photo), f"internal error: {one_line(exc)} (set FORENSICS_DEBUG=1 for the traceback)")
            else:
                used.add(done.folder.name)
                for url in done.refused_urls:
                    _fail_line(str(done.folder), f"the PDF renderer was refused {url[:100]!r} (only data: URLs are allowed)")
                if done.findings.evidence.changed_during_analysis:
                    failures += 1
                    _fail_line(str(photo), done.findings.evidence.changed_during_analysis)
                kept = " (kept: already analysed with these settings; --force replaces it)" if done.kept else ""
                click.echo(f"{visible(str(photo))}: {done.findings.verdict.label.value}"
                           f"{_strength_words(done.findings.verdict)}{kept} -> {visible(str(done.findings_path))}")
            progress.advance(task)
            progress.refresh()
    if failures:
        ctx.exit(1)


@cli.command("batch")
@click.argument("inputs", nargs=-1, required=True, metavar="INPUT...", type=click.Path(path_type=Path))
@click.option("--out", "out_dir", required=True, type=click.Path(file_okay=False, path_type=Path),
              help="Output folder; each photo gets OUT/<photo stem>/, plus OUT/summary.csv and OUT/summary.json.")
@click.option("--workers", type=click.IntRange(min=1),
              help="Local worker processes (default: the number of usable CPU cores).")
@click.option("--scheduler", metavar="tcp://HOST:PORT",
              help="Run on this Dask distributed cluster instead; its workers must see the inputs, OUT and the "
                   "signing key under the same paths.")
@click.option("--recursive", is_flag=True, help="Take photos from all descendants of folders, not only children.")
@click.option("--force", is_flag=True, help="Analyse again photos whose outputs are already finished.")
@_run_options
@click.pass_context
def batch_command(ctx, inputs, out_dir, workers, scheduler, recursive, force, **run):
    """Analyse every photo under INPUT... (files and folders) as `analyze`
    does, on local worker processes or a Dask cluster, with a progress bar and
    OUT/summary.csv and OUT/summary.json at the end.

    A rerun keeps photos whose outputs are finished (same bytes, same
    settings) and redoes the rest; photos with the same bytes are analysed
    once. Exits 0 when every photo was analysed, whatever the verdict; 1 when
    some failed.
    """
    from .batch import BatchError, BatchRequest, Settings, print_summary, run_batch

    if workers is not None and scheduler is not None:
        raise click.BadParameter("local workers and --scheduler exclude each other", param_hint="--workers")
    host: PluginHost = ctx.find_root().command.host
    options, report = _prepare_run(host, RunRequest(**run))
    settings = Settings(options)
    if report is not None:
        settings = Settings(options, report.formats, report.options, report.organisation, report.tsa_url,
                            key_path=str(Path(report.key.source).resolve()), key_fingerprint=report.key.fingerprint)
    request = BatchRequest(list(inputs), out_dir, settings, recursive=recursive, workers=workers, scheduler=scheduler,
                           force=force)
    try:
        result = run_batch(request, host, report.key if report else None, err_console, _fail_line)
    except BatchError as exc:
        _fail_line("batch", str(exc))
        ctx.exit(1)
    print_summary(result, Console(highlight=False, emoji=False))
    if result.failed:
        ctx.exit(1)


cli.add_command(validate_command)
cli.add_command(calibrate_command)


@cli.command("plugins")
@click.option("--json", "as_json", is_flag=True, help="Print JSON instead of a table.")
@click.pass_context
def plugins_command(ctx, as_json):
    """List plugins: name, version, distribution, hooks, load status, error."""
    from rich.table import Table

    host: PluginHost = ctx.find_root().command.host
    records = host.plugin_records()
    if as_json:
        from dataclasses import asdict

        payload = {
            "entry_point_group": ENTRY_POINT_GROUP,
            "plugins": [asdict(r) for r in records],
            "detectors": [
                {"name": n, "plugin": d.plugin, "version": d.spec.version, "description": d.spec.description,
                 "references": list(d.spec.references), "default_params": dict(d.spec.default_params),
                 "uses": list(d.spec.uses), "uses_reference": d.spec.uses_reference}
                for n, d in sorted(host.detectors.items())
            ],
        }
        click.echo(json.dumps(payload, indent=2))
        return
    table = Table(title=f"plugins (entry-point group {ENTRY_POINT_GROUP})")
    for col in ("plugin", "distribution", "status", "detectors", "hooks", "error"):
        # Fold rather than truncate: an error message must be shown whole.
        table.add_column(col, overflow="fold", no_wrap=col == "plugin", min_width=len(col))
    for r in records:
        dist = f"{r.distribution} {r.version}" if r.distribution else "-"
        cells = (r.name, dist, r.status, ", ".join(r.detectors) or "-",
                 ", ".join(h.removeprefix("forensics_") for h in r.hooks) or "-", r.error or "")
        table.add_row(*(escape(c) for c in cells))
    Console(highlight=False, emoji=False).print(table)


@cli.group("keys")
def keys_group() -> None:
    """Manage examiner signing keys."""


@keys_group.command("create")
@click.option("--name", type=TEXT, required=True, help="Examiner's name (the certificate's common name).")
@click.option("--org", "organisation", type=TEXT, required=True, help="Organisation (the certificate's O).")
@click.option("--out", "out_dir", type=click.Path(file_okay=False, path_type=Path),
              help="Folder for examiner.p12 and examiner.pem (default: the per-user configuration folder, "
                   "which makes it the default signing key).")
@click.option("--key-type", type=click.Choice(KEY_TYPES), default=KEY_TYPES[0], show_default=True)
def keys_create(name, organisation, out_dir, key_type):
    """Make a self-signed examiner certificate and PKCS#12, for trial use.

    The PKCS#12 is protected with the password in $FORENSICS_KEY_PASSWORD,
    else one asked for on the terminal (empty: none). A court will want a
    certificate issued by your organisation instead: use it with --key.
    """
    from . import trust as trust_store
    from .certificates import fingerprint
    from .home import config_dir
    from .signing import SigningError, create_self_signed, write_key_files
    from .trust import TrustError

    password = _password_from_env()
    if password is None and sys.stdin.isatty():
        password = click.prompt("password for the new key (empty: none)", hide_input=True,
                                confirmation_prompt=True, default="", show_default=False, err=True).encode("utf-8")
    folder = out_dir or config_dir()
    try:
        p12, cert = create_self_signed(name, organisation, key_type, password or None)
        p12_path, pem_path = write_key_files(folder, p12, cert)
        trusted = trust_store.trust_certificate(cert)
    except (SigningError, TrustError) as exc:
        _fail_line("keys create", str(exc))
        sys.exit(1)
    except OSError as exc:
        _fail_line("keys create", f"cannot write to {folder}: {exc.strerror or exc}")
        sys.exit(1)
    click.echo(f"key:         {p12_path}")
    click.echo(f"certificate: {pem_path}")
    click.echo(f"subject:     {cert.subject.rfc4514_string()} (self-signed, {key_type})")
    click.echo(f"SHA-256:     {fingerprint(cert)}")
    click.echo(f"trusted:     yes, in {trusted.path.parent} (your own key; `forensics verify` accepts its signatures)")


@keys_group.group("trust")
def trust_group() -> None:
    """The certificates whose signatures `verify` accepts (the trust store).

    A valid signature proves a bundle unchanged since signing, not who signed
    it: `verify` passes a bundle only when its signer chains to a certificate
    held here or given with --trust. Your own key is added when it is made.
    """


def _echo_trusted(entry, prefix: str = "") -> None:
    kind = "self-signed" if entry.self_signed else "issued"
    click.echo(f"{prefix}{entry.fingerprint}  {visible(entry.subject)}  ({kind}, valid to {entry.not_after})")


def _change_trust(command: str, done: str, change) -> None:
    """Run one change of the trust store; its certificates are echoed, a failure is one line and exit 1."""
    from .trust import TrustError

    try:
        entries = change()
    except TrustError as exc:
        _fail_line(command, str(exc))
        sys.exit(1)
    for entry in entries:
        _echo_trusted(entry, f"{done}: ")


@trust_group.command("add")
@click.argument("cert", type=click.Path(exists=True, dir_okay=False, path_type=Path))
def trust_add(cert):
    """Trust the certificate(s) in CERT (PEM or DER): a colleague's, or your organisation's CA."""
    from . import trust as trust_store
    from .certificates import fingerprint, outside_validity

    # Read once: the warnings are about the certificates trusted, even if the file changes meanwhile.
    certs: list = []

    def change():
        certs.extend(trust_store.read_certificates(cert))
        return [trust_store.trust_certificate(c) for c in certs]

    _change_trust("keys trust add", "trusted", change)
    for c in certs:
        problem = outside_validity(c)
        if problem:
            click.echo(f"warning: {fingerprint(c)} is {problem}; `verify` fails what it signed outside those dates",
                       err=True)


@trust_group.command("list")
def trust_list():
    """List the trusted certificates: SHA-256 fingerprint, subject, validity."""
    from . import trust as trust_store

    entries = trust_store.trusted()
    if not entries:
        click.echo(f"the trust store {trust_store.store_dir()} is empty")
    for entry in entries:
        _echo_trusted(entry)


@trust_group.command("remove")
@click.argument("which")
def trust_remove(which):
    """Stop trusting a certificate, named by its file or its SHA-256 fingerprint (8 hex digits at least)."""
    from . import trust as trust_store

    _change_trust("keys trust remove", "removed", lambda: trust_store.remove(which))


@cli.command("verify")
@click.argument("folder", type=click.Path(exists=True, file_okay=False, path_type=Path))
@click.option("--evidence", type=click.Path(exists=True, dir_okay=False, path_type=Path),
              help="The evidence photo; checked against the hashes the manifest records.")
@click.option("--trust", type=click.Path(exists=True, dir_okay=False, path_type=Path), multiple=True,
              help="Also trust this certificate (PEM or DER) for this run, besides the trust store's "
                   "(`forensics keys trust`). Repeatable.")
@click.option("--verbose", is_flag=True, help="Also print the signature libraries' own log messages.")
def verify_command(folder, evidence, trust, verbose):
    """Check a report folder: both signatures, every file's hash, the signer's trust, and the evidence.

    Exits 0 only when every check passes, the signer included: valid
    signatures by a certificate that does not chain to a trusted one (the
    trust store, or --trust) fail, since anyone can sign in any name. Prints
    one line per failed check on stderr and exits 1 if any failed.
    """
    from .verify import verify_bundle

    # pyHanko logs each failed path search with its traceback; the verdict
    # below already says what failed, in one line.
    captured = _CapturedLogs()
    root = logging.getLogger()
    previous, handlers = root.level, list(root.handlers)
    root.handlers = [captured]
    root.setLevel(logging.DEBUG if verbose else logging.WARNING)
    try:
        result = verify_bundle(folder, evidence=evidence, trust=trust)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--trust") from None
    finally:
        root.handlers = handlers
        root.setLevel(previous)
    if verbose:
        for record in captured.records:
            click.echo(f"log: {record.name}: {record.getMessage()}", err=True)
    for line in result.passed:
        click.echo(f"ok: {visible(line)}")
    for note in result.notes:
        click.echo(f"note: {visible(note)}")
    for problem in result.problems:
        _fail_line(problem.subject, problem.reason)
    if not result.ok:
        sys.exit(1)
    click.echo(f"verified: {visible(str(folder))}")


class _CapturedLogs(logging.Handler):
    """Keeps library log records for ``--verbose`` instead of letting them reach the terminal."""

    def __init__(self) -> None:
        super().__init__(logging.DEBUG)
        self.records: list[logging.LogRecord] = []

    def emit(self, record: logging.LogRecord) -> None:
        self.records.append(record)


def main() -> None:
    """Entry point of the ``forensics`` script: no traceback reaches the user.

    Click's own handling (``standalone_mode``) would end an interrupted run
    with "Aborted!" and status 1; a script must be able to tell it from a
    photo that failed.
    """
    stopping.install()
    try:
        code = cli.main(standalone_mode=False)
        stopping.check()
    except SystemExit:
        raise
    except click.ClickException as exc:
        exc.show()
        sys.exit(exc.exit_code)
    except stopping.Terminated:
        _fail_line("terminated", "stopped by SIGTERM")
        sys.exit(128 + signal.SIGTERM)
    except (click.Abort, KeyboardInterrupt) as exc:
        cause = exc if isinstance(exc, KeyboardInterrupt) else (exc.__cause__ or exc.__context__)
        if isinstance(cause, KeyboardInterrupt):
            _fail_line("interrupted", "stopped by the user")
            sys.exit(130)
        _fail_line("aborted", "no answer where the command asked for one")
        sys.exit(1)
    except Exception as exc:
        if os.environ.get("FORENSICS_DEBUG"):
            raise
        _fail_line("internal error", f"{one_line(exc)} (set FORENSICS_DEBUG=1 for the traceback)")
        sys.exit(3)
    sys.exit(code if isinstance(code, int) else 0)
