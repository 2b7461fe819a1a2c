"""Fixtures of the batch tests: a plugin host with the fixture plugins, in this process."""

from importlib.metadata import EntryPoint

import pytest

from batch_helpers import SITE
from forensics_core import ENTRY_POINT_GROUP
from forensics_core.batch import work
from forensics_core.plugins import PluginHost


@pytest.fixture
def steady_host(monkeypatch) -> PluginHost:
    """The ``steady`` and ``killer`` fixture plugins, loaded through real entry points.

    The site folder is on the path for this test only, so that the rest of
    the suite never sees the fixture distribution.
    """
    monkeypatch.syspath_prepend(str(SITE))
    monkeypatch.setattr(work, "_state", {})
    host = PluginHost(allow=None, deny=())
    for name in ("steady", "killer"):
        host.load_entry_point(EntryPoint(name, f"batch_fixture_plugins:{name}", ENTRY_POINT_GROUP))
    assert set(host.detectors) == {"steady"}
    return host
