"""Plugin loading and hook calls with failure containment.

pluggy's own ``load_setuptools_entrypoints`` stops at the first plugin whose
import fails, and a hook call stops at the first implementation that raises,
discarding the others' results. Here each entry point is loaded on its own and
each implementation is called on its own, so one broken plugin is recorded as
failed and the rest carry on.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass
from importlib.metadata import EntryPoint, entry_points
from typing import Any

import numpy as np
import pluggy

from . import ENTRY_POINT_GROUP, hookspecs
from .containment import PluginFault, can_fork, one_line, run_forked
from .findings import DetectorFinding, DetectorSpec, PluginRecord, Status

ALLOW_ENV = "FORENSICS_PLUGINS"
DENY_ENV = "FORENSICS_DISABLE_PLUGINS"

_DETECTOR_NAME = re.compile(r"^[a-z][a-z0-9_]*$")


@dataclass(frozen=True)
class RegisteredDetector:
    spec: DetectorSpec
    plugin: str


@dataclass(frozen=True)
class HookOutcome:
    """What one plugin's implementation of a hook gave: a value or an error."""

    plugin: str
    value: Any = None
    error: BaseException | None = None


def _env_names(var: str) -> set[str] | None:
    raw = os.environ.get(var)
    if raw is None or not raw.strip():
        return None
    return {n.strip() for n in raw.split(",") if n.strip()}


class PluginHost:
    """The loaded plugins, how each one loaded, and the detectors they provide.

    Parameters
    ----------
    allow, deny : iterable of str, optional
        Plugin names to load exclusively / to leave out. Default: the
        comma-separated environment variables ``FORENSICS_PLUGINS`` and
        ``FORENSICS_DISABLE_PLUGINS``.
    """

    def __init__(self, allow: Iterable[str] | None = None, deny: Iterable[str] | None = None):
        self.pm = pluggy.PluginManager(hookspecs.PROJECT)
        self.pm.add_hookspecs(hookspecs)
        self.records: dict[str, PluginRecord] = {}
        self.detectors: dict[str, RegisteredDetector] = {}
        self.allow = set(allow) if allow is not None else _env_names(ALLOW_ENV)
        self.deny = set(deny) if deny is not None else (_env_names(DENY_ENV) or set())
        self._prepared: tuple[int, set[str]] = (0, set())
        from . import fusion

        self.add(fusion, "core.fusion", distribution="forensics", version=_core_version())

    @classmethod
    def from_entry_points(
        cls,
        group: str = ENTRY_POINT_GROUP,
        allow: Iterable[str] | None = None,
        deny: Iterable[str] | None = None,
    ) -> PluginHost:
        """Load every plugin advertised under ``group`` by the installed distributions."""
        host = cls(allow=allow, deny=deny)
        for ep in sorted(entry_points(group=group), key=lambda e: e.name):
            host.load_entry_point(ep)
        return host

    def _enabled(self, name: str) -> bool:
        return name not in self.deny and (self.allow is None or name in self.allow)

    def load_entry_point(self, ep: EntryPoint) -> PluginRecord:
        dist = getattr(ep, "dist", None)
        dist_name = dist.name if dist is not None else None
        dist_version = dist.version if dist is not None else None
        if not self._enabled(ep.name):
            return self._record(PluginRecord(ep.name, dist_name, dist_version, "disabled"))
        if ep.name in self.records:
            return self._record(
                PluginRecord(ep.name + f" ({dist_name})", dist_name, dist_version, "error",
                             error=f"plugin name {ep.name!r} is already taken by another distribution")
            )
        try:
            obj = ep.load()
        except (Exception, SystemExit) as exc:
            return self._record(PluginRecord(ep.name, dist_name, dist_version, "error", error=f"import failed: {one_line(exc)}"))
        return self.add(obj, ep.name, distribution=dist_name, version=dist_version)

    def add(self, plugin: object, name: str, distribution: str | None = None, version: str | None = None) -> PluginRecord:
        """Register one plugin object, validate it and collect its detectors.

        Any failure leaves the plugin unregistered and recorded with status
        ``error``; it never raises.
        """
        if not self._enabled(name):
            return self._record(PluginRecord(name, distribution, version, "disabled"))
        try:
            self.pm.register(plugin, name=name)
        except Exception as exc:
            return self._record(PluginRecord(name, distribution, version, "error", error=f"invalid hooks: {one_line(exc)}"))
        record = PluginRecord(name, distribution, version, "loaded", hooks=self._hook_names(plugin))
        unknown = [h for h in record.hooks if getattr(self.pm.hook, h).spec is None]
        if unknown:
            return self._fail(plugin, record, f"implements unknown hook(s) {', '.join(unknown)}")
        specs: list[DetectorSpec] = []
        for outcome in self.call_each("forensics_register_detectors", plugins=[name]):
            if outcome.error is not None:
                return self._fail(plugin, record, f"forensics_register_detectors raised {one_line(outcome.error)}")
            try:
                specs = self._check_specs(outcome.value)
            except ValueError as exc:
                return self._fail(plugin, record, str(exc))
        for spec in specs:
            self.detectors[spec.name] = RegisteredDetector(spec, name)
        record.detectors = [s.name for s in specs]
        return self._record(record)

    def _check_specs(self, value: Any) -> list[DetectorSpec]:
        if value is None:
            return []
        if not isinstance(value, (list, tuple)) or not all(isinstance(s, DetectorSpec) for s in value):
            raise ValueError("forensics_register_detectors must return a list of DetectorSpec")
        for spec in value:
            if not _DETECTOR_NAME.match(spec.name):
                raise ValueError(f"detector name {spec.name!r} must match {_DETECTOR_NAME.pattern}")
            if spec.name in self.detectors:
                raise ValueError(f"detector {spec.name!r} is already provided by plugin {self.detectors[spec.name].plugin!r}")
            if not isinstance(spec.version, str) or not spec.version:
                raise ValueError(f"detector {spec.name!r} has no version")
            if isinstance(spec.uses, str) or not all(isinstance(u, str) for u in spec.uses):
                raise ValueError(f"detector {spec.name!r}: uses must be a tuple of detector names")
        return list(value)

    def _fail(self, plugin: object, record: PluginRecord, reason: str) -> PluginRecord:
        self.pm.unregister(plugin)
        record.status, record.error, record.detectors = "error", reason, []
        return self._record(record)

    def _record(self, record: PluginRecord) -> PluginRecord:
        self.records[record.name] = record
        return record

    def _hook_names(self, plugin: object) -> list[str]:
        return sorted(h.name for h in self.pm.get_hookcallers(plugin) or [])

    def call_each(self, hook_name: str, plugins: Iterable[str] | None = None, *, contained_s: float | None = None,
                  **kwargs: Any) -> Iterator[HookOutcome]:
        """Call each plugin's implementation of ``hook_name`` on its own.

        Implementations are visited in pluggy's calling order (last registered
        first). An implementation that raises yields a :class:`HookOutcome`
        with the exception; the others still run. Hook wrappers are not called:
        every forensics hook is a plain call. With ``contained_s``, each call
        runs in a forked child (where the platform can fork) stopped after that
        many seconds, so a hang, an ``os._exit`` or a crash costs only that
        plugin's outcome; the value comes back pickled.
        """
        wanted = set(plugins) if plugins is not None else None
        hook = getattr(self.pm.hook, hook_name)
        for impl in reversed(hook.get_hookimpls()):
            if impl.hookwrapper or getattr(impl, "wrapper", False):
                continue
            if wanted is not None and impl.plugin_name not in wanted:
                continue
            args = [kwargs[arg] for arg in impl.argnames]
            if contained_s is not None and can_fork():
                outcome, _ = run_forked(lambda: impl.function(*args), contained_s)
                if outcome[0] == "error":
                    yield HookOutcome(impl.plugin_name, error=PluginFault(outcome[1]))
                else:
                    yield HookOutcome(impl.plugin_name, value=outcome[1])
                continue
            try:
                value = impl.function(*args)
            except Exception as exc:
                yield HookOutcome(impl.plugin_name, error=exc)
            else:
                yield HookOutcome(impl.plugin_name, value=value)

    def prepare(self, plugins: Iterable[str] | None = None) -> None:
        """Call the ``forensics_prepare`` of each plugin named (all by default) once for this host in this process.

        See the hook's documentation. The runner prepares a plugin just
        before its first detector starts, so that one plugin's imports
        overlap the detectors already running instead of delaying them all.
        """
        pid, done = self._prepared
        if pid != os.getpid():
            done = set()
            self._prepared = (os.getpid(), done)
        implemented = [impl.plugin_name for impl in self.pm.hook.forensics_prepare.get_hookimpls()]
        todo = [name for name in implemented if name not in done and (plugins is None or name in plugins)]
        if not todo:
            return
        done.update(todo)
        for _ in self.call_each("forensics_prepare", todo):
            pass

    def implementation(self, hook_name: str, plugin: str):
        """The function with which ``plugin`` implements ``hook_name``, or None."""
        for impl in getattr(self.pm.hook, hook_name).get_hookimpls():
            if impl.plugin_name == plugin:
                return lambda **kw: impl.function(*(kw[a] for a in impl.argnames))
        return None

    def plugin_records(self) -> list[PluginRecord]:
        return [self.records[n] for n in sorted(self.records)]


def _core_version() -> str:
    from . import __version__

    return __version__


def localise_map(host: PluginHost, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
    """The boolean ``shape`` map of the pixels ``finding`` flags, from its plugin's ``forensics_localize``.

    None when the plugin does not localise, fails, or answers with another shape.
    """
    impl = host.implementation("forensics_localize", finding.plugin)
    if impl is None or finding.status is Status.ERROR:
        return None
    try:
        pred = impl(finding=finding, shape=shape)
    except Exception:
        return None
    if pred is None:
        return None
    pred = np.asarray(pred, dtype=bool)
    return pred if pred.shape == tuple(shape) else None
