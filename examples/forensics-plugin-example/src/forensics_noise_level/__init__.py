"""Example forensics plugin: the photo's sensor noise level, globally and per block."""
