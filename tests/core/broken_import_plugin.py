"""A plugin module whose import fails, as a half-installed third-party plugin's might."""

raise ImportError("this plugin needs a library that is not installed")
