"""Defaults and choices of the command-line options, shared with the modules that apply them.

Nothing heavy is imported here, so that ``forensics --help`` can show every
option's default without loading the analysis, the report or the signing code.
"""

import os

#: Seconds a detector may run on one photo before it is stopped (``--timeout``).
DEFAULT_TIMEOUT_S = 300.0
#: How detectors are run: each in its own process, or in the command's (``--isolation``).
ISOLATIONS = ("process", "inline")
_CORES = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
#: Detectors run at once on one photo by ``forensics analyze`` (``--jobs``): one per core the
#: process may use, at most four, since each one running adds its own working memory.
DEFAULT_JOBS = max(1, min(_CORES, 4))
#: Above this many pixels detectors run one at a time whatever ``--jobs`` says: each holds
#: several float copies of the photo. Two at once took the peak from 696 to 798 MB on 12 MP
#: (``benchmarks/memory.py --jobs``); one at a time keeps a 100 MP photo within 2.5 GB.
PARALLEL_MAX_PIXELS = 24_000_000
#: Largest photo taken in, in pixels (``--max-pixels``), against decompression bombs.
DEFAULT_MAX_PIXELS = 150_000_000
#: Paper sizes of the PDF report (``--paper``), as CSS names them.
PAPER_SIZES = {"a4": "A4", "letter": "letter"}
#: Environment variable holding the signing key's password.
PASSWORD_ENV = "FORENSICS_KEY_PASSWORD"
#: Key types ``forensics keys create`` makes; the first is the default.
KEY_TYPES = ("ecdsa-p256", "rsa-3072")
#: Seed and size of the built-in synthetic validation suite (``forensics validate synthetic``).
DEFAULT_SEED = 2026
DEFAULT_COUNT = 20
#: The real-photo corpus (``forensics validate lens-splices|innocent-processing --corpus``): research use only,
#: never in the repository.
DEFAULT_REAL_CORPUS = "../shared/data/real"
