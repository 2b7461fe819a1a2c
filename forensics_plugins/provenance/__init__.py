"""C2PA Content Credentials (provenance): the manifest store read and validated, what it proves and what it does not.

Pipeline: :mod:`.credentials` (read the store, embedded or in a ``.c2pa``
sidecar, with c2pa-python, offline; validate signatures and the hard binding)
-> :mod:`.detector` (the finding) -> :mod:`.section` (the report).
"""
