"""Hook implementations of the metadata plugin (entry point ``metadata``)."""
