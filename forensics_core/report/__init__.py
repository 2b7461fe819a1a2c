"""Report building blocks shared by the core and the plugins."""

from .images import display_image, figure_png
from .sections import Figure, ReportSection, Table
from .wording import lr_text

__all__ = ["Figure", "ReportSection", "Table", "display_image", "figure_png", "lr_text"]
