"""``forensics calibrate``: fit likelihood-ratio calibrators on validation records and print their cost."""

from __future__ import annotations

import sys
from pathlib import Path

import click
from rich.console import Console
from rich.table import Table

from ..atomic import write_atomic
from ..text import visible
from .model import CalibrationError

console = Console(stderr=True, highlight=False, emoji=False)


@click.command("calibrate")
@click.argument("records", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option("--out", "out_file", required=True, type=click.Path(dir_okay=False, path_type=Path),
              help="Calibration file to write (JSON), e.g. forensics_core/calibration/real.json.")
@click.option("--detectors", help="Comma-separated detector names (default: every detector in the records).")
@click.pass_context
def calibrate_command(ctx, records, out_file, detectors):
    """Fit each detector's LR calibrator and their fusion on validation RECORDS (validation.json of `validate`).

    Prints, per detector and fused, the photos used under each proposition,
    the ELUB bounds and the cross-validated Cllr and Cllr_min (folds grouped
    by scene). Needs NFI's lir (pip install lir).
    """
    from .fit import calibrate, calibrator_inputs

    names = [d.strip() for d in detectors.split(",") if d.strip()] if detectors else None
    try:
        result = calibrate(records, names, calibrator_inputs(ctx.find_root().command.host))
    except CalibrationError as exc:
        click.echo(f"forensics: error: {visible(str(exc))}", err=True)
        sys.exit(2)
    write_atomic(out_file, result.to_json().encode("utf-8"))
    table = Table(title=f"log10 LR calibrators: {result.data['n_hp']} Hp, {result.data['n_hd']} Hd photos, "
                        f"{result.data['cross_validation']}")
    for col in ("", "ran Hp / Hd", "declined Hp / Hd", "log10 LR = a + b x (4PL: module docstring)", "ELUB bounds",
                "Cllr", "Cllr_min"):
        table.add_column(col)
    for c in result.calibrators.values():
        table.add_row(c.detector, f"{c.n_hp} / {c.n_hd}", f"{c.n_declined_hp} / {c.n_declined_hd}",
                      f"{c.intercept:+.3f} {c.slope:+.3f} x" + (
                          f"; 4PL floor {c.floor:.3f}, ceiling {c.ceiling:.3f}" if c.floor or c.ceiling else ""),
                      f"{c.lower:+.2f} .. {c.upper:+.2f}",
                      f"{c.cllr:.3f}", f"{c.cllr_min:.3f}")
    f = result.fusion
    if f is not None:
        weights = ", ".join(f"{k} {v:+.2f}" for k, v in f.weights.items())
        table.add_row("fused", "", "", f"{f.intercept:+.3f}; {weights}", f"{f.lower:+.2f} .. {f.upper:+.2f}",
                      f"{f.cllr:.3f}", f"{f.cllr_min:.3f}")
    out = Console(highlight=False, emoji=False, width=160)
    out.print(table)
    parts = Table(title="cross-validated Cllr / Cllr_min per record and per set")
    for col in ("", "Hp / Hd", "fused", *result.data["fused"]):
        parts.add_column(col)
    for part, entry in result.data["costs"].items():
        parts.add_row(part, f"{entry['fused']['n_hp']} / {entry['fused']['n_hd']}",
                      *(f"{entry[n]['cllr']:.3f} / {entry[n]['cllr_min']:.3f}" for n in ("fused", *result.data["fused"])))
    out.print(parts)
    experimental = result.data["experimental"]
    if experimental:
        console.print(f"experimental, left out of the fusion (best AUC on a set of found photos below "
                      f"{result.data['min_fusion_auc']:g}): "
                      + ", ".join(f"{d} {auc:.2f}" for d, auc in experimental.items()))
    scored = sorted(c.detector for c in result.calibrators.values() if c.feature == "score")
    console.print(f"x = -log10 p (capped){'; x = score for ' + ', '.join(scored) if scored else ''}; "
                  f"calibration file: {out_file}")
