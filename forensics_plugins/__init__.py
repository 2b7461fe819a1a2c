"""Detector plugins bundled with forensics, installed as ``forensics_plugins``.

Each is found through the public ``forensics.plugins`` entry-point group, like
any third-party plugin; the core never imports them.
"""
