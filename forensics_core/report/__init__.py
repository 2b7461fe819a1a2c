"""Report building blocks shared by the core and the plugins."""

from .sections import Figure, ReportSection

__all__ = ["Figure", "ReportSection"]
