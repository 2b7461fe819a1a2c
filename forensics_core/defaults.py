"""Defaults and choices of the command-line options, shared with the modules that apply them.

Nothing is imported here, so that ``forensics --help`` can show every
option's default without loading the analysis, the report or the signing code.
"""

#: Seconds a detector may run on one photo before it is stopped (``--timeout``).
DEFAULT_TIMEOUT_S = 300.0
#: How detectors are run: each in its own process, or in the command's (``--isolation``).
ISOLATIONS = ("process", "inline")
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
