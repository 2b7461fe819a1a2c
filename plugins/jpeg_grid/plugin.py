"""Hook implementations of the jpeg_grid plugin (entry point ``jpeg_grid``)."""
