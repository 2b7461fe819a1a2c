"""Hook implementations of the cfa plugin (entry point ``cfa``)."""
