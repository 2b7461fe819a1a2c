"""The per-user configuration folder, which holds the examiner's key and the trust store."""

from __future__ import annotations

import os
from pathlib import Path

HOME_ENV = "FORENSICS_HOME"


def config_dir() -> Path:
    """``$FORENSICS_HOME``, else ``$XDG_CONFIG_HOME/forensics``, else ``~/.config/forensics``."""
    if os.environ.get(HOME_ENV):
        return Path(os.environ[HOME_ENV])
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "forensics"
