"""Colour-filter-array demosaicing detector (entry point ``cfa``)."""
