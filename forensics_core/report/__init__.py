"""Report building blocks shared by the core and the plugins."""

from .images import display_image, figure_png
from .sections import Figure, ReportSection

__all__ = ["Figure", "ReportSection", "display_image", "figure_png"]
