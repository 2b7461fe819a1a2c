"""The provenance detector on the C2PA public test files: no credentials the SDK calls Invalid are called valid.

Usage: ``python benchmarks/c2pa_public_files.py [DIR]``

``DIR`` is a clone of https://github.com/c2pa-org/public-testfiles (CC BY-SA
4.0; read from where it is, never copied into this repository), by default
``../shared/c2pa-public-testfiles``; a bare git directory is read with ``git
show``. Every JPEG under ``image/jpeg`` (not the extracted ``manifests/``)
is read twice: by ``c2pa.Reader`` for the SDK's own validation state, and by
the detector (``analyse`` with its ``DEFAULT_PARAMS``, offline, no trust
list). Each row prints the SDK's state, the finding's status and score and
the start of its sentence; the script exits 1 when a file the SDK calls
``Invalid`` is described as "Valid Content Credentials", 0 otherwise, and
says so and exits 0 when the folder is absent.
"""

from __future__ import annotations

import io
import subprocess
import sys
import tempfile
from pathlib import Path

DEFAULT = Path(__file__).resolve().parents[1].parent / "shared" / "c2pa-public-testfiles"


def _files(root: Path) -> list[tuple[str, bytes]]:
    """(name, bytes) of every JPEG of the set, from a work tree or a bare git directory."""
    if (root / "image" / "jpeg").is_dir():
        return [(p.name, p.read_bytes()) for p in sorted((root / "image" / "jpeg").glob("*.jp*g"))]
    names = subprocess.run(["git", "-C", str(root), "ls-tree", "--name-only", "HEAD", "image/jpeg/"],
                           capture_output=True, text=True, check=True).stdout.split()
    return [(Path(n).name, subprocess.run(["git", "-C", str(root), "show", f"HEAD:{n}"], capture_output=True,
                                          check=True).stdout)
            for n in sorted(names) if n.lower().endswith((".jpg", ".jpeg"))]


def main() -> int:
    root = Path(sys.argv[1]) if len(sys.argv) > 1 else DEFAULT
    if not root.exists():
        print(f"the C2PA public test files are absent ({root}): nothing checked")
        return 0
    import c2pa

    from forensics_core import load_evidence
    from forensics_plugins.provenance.detector import Provenance
    from forensics_plugins.provenance.spec import DEFAULT_PARAMS

    wrong = 0
    with tempfile.TemporaryDirectory() as tmp:
        for name, data in _files(root):
            reader = c2pa.Reader.try_create("image/jpeg", io.BytesIO(data), None)
            state = "none"
            if reader is not None:
                with reader:
                    state = str(reader.get_validation_state())
            path = Path(tmp) / name
            path.write_bytes(data)
            finding = Provenance().analyze(load_evidence(path), DEFAULT_PARAMS)
            bad = state == "Invalid" and "Valid Content Credentials" in finding.summary
            wrong += bad
            print(f"{'WRONG' if bad else '     '} {name:42s} SDK {state:8s} -> {finding.status.value:12s} "
                  f"score {finding.score}  {finding.summary[:110]}")
    print(f"{wrong} file(s) the SDK calls Invalid described as valid")
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
