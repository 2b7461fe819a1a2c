"""Plugin hosts built from test fixture plugins (imported by tests as ``plugin_hosts``).

Kept out of conftest.py: several test folders have a conftest of their own,
and ``from conftest import ...`` would find whichever was loaded last.
"""

from importlib.metadata import EntryPoint

from forensics_core import ENTRY_POINT_GROUP
from forensics_core.plugins import PluginHost


def fixture_host(*names: str, module: str = "fixture_plugins") -> PluginHost:
    """A host with the named fixture plugins, loaded through real entry points."""
    host = PluginHost(allow=None, deny=())
    for name in names:
        host.load_entry_point(EntryPoint(name, f"{module}:{name}", ENTRY_POINT_GROUP))
    return host
