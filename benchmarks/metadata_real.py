"""How often each metadata check calls an authentic real photo "suspicious".

Usage: ``python benchmarks/metadata_real.py [CORPUS] [--no-lens] [--list] [--write]``

``CORPUS`` is the shared real-photo corpus (default ``../shared/data/real``
next to the repository); when it is absent the script says so and exits 0.
Every set folder below it with a ``truth.csv`` is read and each photo
labelled ``authentic`` is analysed through the public API
(``forensics_core.analyze``) with the metadata detector, and the lens
detector too when ``truth.csv`` names a camera (the lens check needs its
measurement; photos without EXIF cannot name a lens). Printed: per check,
how many photos it applied to (outcome consistent or suspicious), how many
it called suspicious, and the rates (suspicious / applicable, and
suspicious / photos as "of all"), for the camera originals (sets under
``authentic_buildings`` and ``authentic_charts`` except those marked as
processed) and for all authentic photos. ``--list`` adds every suspicious
outcome with its photo and sentence.

``--write`` stores the camera-original rates in
``forensics_plugins/metadata/real_rates.json``, which the report quotes next to each
check. The photos themselves are never copied: only counts, the set names
and the date.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from collections import Counter, defaultdict
from datetime import date
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
DEFAULT_CORPUS = REPO.parent / "shared" / "data" / "real"
RATES_FILE = REPO / "forensics_plugins" / "metadata" / "real_rates.json"
APPLICABLE = ("consistent", "suspicious")
# Sets whose photos were processed after capture (rotated): authentic scenes,
# but not camera originals, so they are reported apart.
PROCESSED_SETS = ("metadata-extractor-images_rotated",)
ORIGINAL_ROOTS = ("authentic_buildings", "authentic_charts")


def authentic_photos(corpus: Path) -> list[tuple[str, Path, str]]:
    """``(set name, photo path, camera named in truth.csv or "")`` for every authentic photo, sorted."""
    photos = []
    for truth in sorted(corpus.rglob("truth.csv")):
        name = truth.parent.relative_to(corpus).as_posix()
        with truth.open(newline="", encoding="utf-8") as fh:
            for row in csv.DictReader(fh):
                if row["label"] == "authentic":
                    photos.append((name, truth.parent / row["file"], row["camera"].strip()))
    return photos


def is_camera_original(set_name: str) -> bool:
    root, _, leaf = set_name.partition("/")
    return root in ORIGINAL_ROOTS and leaf not in PROCESSED_SETS


def run(photos: list[tuple[str, Path, str]], lens: bool) -> list[dict]:
    """The metadata checks' outcomes on each photo."""
    from forensics_core import analyze

    records = []
    for k, (set_name, path, camera) in enumerate(photos, 1):
        detectors = ["metadata", "lens_distortion"] if lens and camera else ["metadata"]
        findings = analyze(path, detectors=detectors, isolation="inline")
        meta = next(d for d in findings.detectors if d.name == "metadata")
        checks = meta.details.get("checks", [])
        records.append({"set": set_name, "file": path.name, "camera": camera, "original": is_camera_original(set_name),
                        "version": meta.version, "checks": checks})
        flagged = [c["id"] for c in checks if c["outcome"] == "suspicious"]
        print(f"[{k}/{len(photos)}] {set_name}/{path.name}: {', '.join(flagged) or 'nothing'} suspicious",
              file=sys.stderr)
    return records


def rates(records: list[dict]) -> dict[str, dict]:
    """Per check id: title, applicable and suspicious counts over ``records``."""
    table: dict[str, dict] = defaultdict(lambda: {"title": "", "photos": 0, "applicable": 0, "suspicious": 0})
    for rec in records:
        for c in rec["checks"]:
            row = table[c["id"]]
            row["title"] = c["title"]
            row["photos"] += 1
            row["applicable"] += c["outcome"] in APPLICABLE
            row["suspicious"] += c["outcome"] == "suspicious"
    return dict(table)


def print_table(label: str, records: list[dict]) -> None:
    print(f"\n{label}: {len(records)} photos")
    print(f"{'check':<32} {'applicable':>10} {'suspicious':>10} {'rate':>8} {'of all':>8}")
    for row in rates(records).values():
        rate = row["suspicious"] / row["applicable"] if row["applicable"] else 0.0
        print(f"{row['title']:<32} {row['applicable']:>10} {row['suspicious']:>10} {100 * rate:>7.1f}% "
              f"{100 * row['suspicious'] / row['photos']:>7.1f}%")


def write_rates(records: list[dict]) -> None:
    originals = [r for r in records if r["original"]]
    sets = Counter(r["set"] for r in originals)
    payload = {
        "measured": date.today().isoformat(),
        "detector_version": originals[0]["version"] if originals else None,
        "corpus": (f"{len(originals)} authentic camera originals (JPEG and MPO) of "
                   f"{len({r['camera'] for r in originals})} camera models, copied byte for byte from public GitHub "
                   f"snapshots: {', '.join(f'{s} ({n})' for s, n in sorted(sets.items()))}"),
        "n_photos": len(originals),
        "checks": {cid: {"applicable": row["applicable"], "suspicious": row["suspicious"]}
                   for cid, row in rates(originals).items()},
    }
    RATES_FILE.write_text(json.dumps(payload, indent=2) + "\n", encoding="utf-8")
    print(f"\nwrote {RATES_FILE.relative_to(REPO)}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("corpus", nargs="?", type=Path, default=DEFAULT_CORPUS)
    parser.add_argument("--no-lens", action="store_true", help="do not run the lens detector (lens check not applicable)")
    parser.add_argument("--list", action="store_true", help="list every suspicious outcome")
    parser.add_argument("--write", action="store_true", help=f"store the rates in {RATES_FILE.name}")
    parser.add_argument("--json", type=Path, help="also store every photo's outcomes here")
    args = parser.parse_args()
    if not args.corpus.is_dir():
        print(f"real-photo corpus {args.corpus} is absent; nothing measured")
        return 0
    records = run(authentic_photos(args.corpus), lens=not args.no_lens)
    if args.json:
        args.json.write_text(json.dumps(records, indent=1), encoding="utf-8")
    print_table("camera originals (authentic_buildings, authentic_charts; rotated set excluded)",
                [r for r in records if r["original"]])
    print_table("processed after capture (rotated set)", [r for r in records if r["set"].endswith(PROCESSED_SETS)])
    print_table("all authentic photos", records)
    if args.list:
        print("\nsuspicious outcomes:")
        for r in records:
            for c in r["checks"]:
                if c["outcome"] == "suspicious":
                    print(f"  {r['set']}/{r['file']} [{c['id']}]: {c['observation']}")
    if args.write:
        write_rates(records)
    return 0


if __name__ == "__main__":
    sys.exit(main())
