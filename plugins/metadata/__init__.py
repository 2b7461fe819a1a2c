"""Metadata checks detector (entry point ``metadata``)."""
