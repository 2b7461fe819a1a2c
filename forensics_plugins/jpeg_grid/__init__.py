"""JPEG block-grid detector (entry point ``jpeg_grid``)."""
