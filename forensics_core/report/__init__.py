"""Report building blocks shared by the core and the plugins."""

from .images import display_image, figure_png
from .sections import Figure, ReportSection, Table

__all__ = ["Figure", "ReportSection", "Table", "display_image", "figure_png"]
