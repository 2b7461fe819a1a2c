"""Plugin loading and hook calls with failure containment.

pluggy's own ``load_setuptools_entrypoints`` stops at the first plugin whose
import fails, and a hook call stops at the first implementation that raises.
Here each entry point is loaded on its own, and a hook call that raises is
made again without the plugin whose implementation raised (found in the
traceback), so one broken plugin is recorded as failed and the rest carry on.

Detectors are the objects plugins register (:class:`~forensics_core.Detector`);
the core keeps them in :attr:`PluginHost.detectors` and calls their methods.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterable, Iterator
from dataclasses import dataclass, field
from importlib.metadata import EntryPoint, entry_points
from types import TracebackType
from typing import Any

import numpy as np
import pluggy

from . import ENTRY_POINT_GROUP, hookspecs
from .containment import PluginFault, can_fork, one_line, run_forked
from .detector import Detector, reads_prior
from .findings import DetectorFinding, DetectorSpec, PluginRecord, Status

ALLOW_ENV = "FORENSICS_PLUGINS"
DENY_ENV = "FORENSICS_DISABLE_PLUGINS"

_DETECTOR_NAME = re.compile(r"^[a-z][a-z0-9_]*$")
_REGISTER = "forensics_register_detectors"
_API_2 = "see the README, Writing a plugin"


@dataclass(frozen=True)
class RegisteredDetector:
    """A detector object as registered: its spec, the plugin that registered it, and the object."""

    spec: DetectorSpec
    plugin: str
    detector: Detector
    reads_prior: bool = False


@dataclass(frozen=True)
class HookOutcome:
    """What one plugin's implementation of a hook gave: a value or an error."""

    plugin: str
    value: Any = None
    error: BaseException | None = None


@dataclass(frozen=True)
class HookCall:
    """The result of a hook called through pluggy, and the implementations left out because they raised."""

    value: Any
    failures: list[HookOutcome] = field(default_factory=list)


def _env_names(var: str) -> set[str] | None:
    raw = os.environ.get(var)
    if raw is None or not raw.strip():
        return None
    return {n.strip() for n in raw.split(",") if n.strip()}


class PluginHost:
    """The loaded plugins, how each one loaded, and the detectors they registered.

    A plugin's ``forensics_register_detectors`` is called the first time
    :attr:`detectors` or :attr:`records` is read, so that commands which
    need no detector (``--help``) import no plugin's numerical code.

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
        self._records: dict[str, PluginRecord] = {}
        self._detectors: dict[str, RegisteredDetector] = {}
        self._unregistered: list[str] = []
        self._prepared: tuple[int, set[str]] = (0, set())
        self.allow = set(allow) if allow is not None else _env_names(ALLOW_ENV)
        self.deny = set(deny) if deny is not None else (_env_names(DENY_ENV) or set())
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

    @property
    def detectors(self) -> dict[str, RegisteredDetector]:
        """Every registered detector by name (registering the loaded plugins' detectors first)."""
        self._register_pending()
        return self._detectors

    @property
    def records(self) -> dict[str, PluginRecord]:
        """How each plugin loaded, by plugin name (its detectors registered first)."""
        self._register_pending()
        return self._records

    def _enabled(self, name: str) -> bool:
        return name not in self.deny and (self.allow is None or name in self.allow)

    def load_entry_point(self, ep: EntryPoint) -> PluginRecord:
        dist = getattr(ep, "dist", None)
        dist_name = dist.name if dist is not None else None
        dist_version = dist.version if dist is not None else None
        if not self._enabled(ep.name):
            return self._record(PluginRecord(ep.name, dist_name, dist_version, "disabled"))
        if ep.name in self._records:
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
        """Register one plugin object's hooks and check them; its detectors are registered when first needed.

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
        replaced = [h for h in record.hooks if h in hookspecs.REPLACED_HOOKS]
        if replaced:
            return self._fail(name, record, "written for plugin API 1: " + "; ".join(
                f"{h} is now {hookspecs.REPLACED_HOOKS[h]}" for h in replaced)
                + f" of a Detector registered by forensics_register_detectors(register) ({_API_2})")
        unknown = [h for h in record.hooks if getattr(self.pm.hook, h).spec is None]
        if unknown:
            return self._fail(name, record, f"implements unknown hook(s) {', '.join(unknown)}")
        if _REGISTER in record.hooks:
            self._unregistered.append(name)
        return self._record(record)

    def _register_pending(self) -> None:
        while self._unregistered:
            self._register(self._unregistered.pop(0))

    def _register(self, name: str) -> None:
        """Call ``name``'s ``forensics_register_detectors`` and keep its detectors, all or none."""
        record = self._records[name]
        found: list[Any] = []
        try:
            returned = self._only(name, _REGISTER)(register=found.append)
        except Exception as exc:
            self._fail(name, record, f"{_REGISTER} raised {one_line(exc)}")
            return
        try:
            if any(r is not None for r in returned):
                raise ValueError(f"{_REGISTER} returned a value: plugin API 2 registers Detector objects by calling "
                                 f"register(detector) for each instead ({_API_2})")
            taken = self._checked(found)
        except ValueError as exc:
            self._fail(name, record, str(exc))
            return
        for detector in taken:
            self._detectors[detector.spec.name] = RegisteredDetector(detector.spec, name, detector, reads_prior(detector))
        record.detectors = [d.spec.name for d in taken]

    def _checked(self, found: list[Any]) -> list[Detector]:
        names: set[str] = set()
        for detector in found:
            if not isinstance(detector, Detector):
                raise ValueError(f"register() takes a forensics_core.Detector, not {type(detector).__name__}")
            spec = getattr(detector, "spec", None)
            if not isinstance(spec, DetectorSpec):
                raise ValueError(f"{type(detector).__name__}.spec must be a DetectorSpec")
            if not _DETECTOR_NAME.match(spec.name):
                raise ValueError(f"detector name {spec.name!r} must match {_DETECTOR_NAME.pattern}")
            if spec.name in self._detectors or spec.name in names:
                owner = self._detectors[spec.name].plugin if spec.name in self._detectors else "this plugin"
                raise ValueError(f"detector {spec.name!r} is already provided by plugin {owner!r}")
            if not isinstance(spec.version, str) or not spec.version:
                raise ValueError(f"detector {spec.name!r} has no version")
            if isinstance(spec.uses, str) or not all(isinstance(u, str) for u in spec.uses):
                raise ValueError(f"detector {spec.name!r}: uses must be a tuple of detector names")
            names.add(spec.name)
        return found

    def _fail(self, name: str, record: PluginRecord, reason: str) -> PluginRecord:
        plugin = self.pm.get_plugin(name)
        if plugin is not None:
            self.pm.unregister(plugin)
        record.status, record.error, record.detectors = "error", reason, []
        return self._record(record)

    def _record(self, record: PluginRecord) -> PluginRecord:
        self._records[record.name] = record
        return record

    def _hook_names(self, plugin: object) -> list[str]:
        return sorted(h.name for h in self.pm.get_hookcallers(plugin) or [])

    def _only(self, name: str, hook_name: str):
        """pluggy's caller of ``hook_name`` restricted to plugin ``name``."""
        others = [p for n, p in self.pm.list_name_plugin() if n != name]
        return self.pm.subset_hook_caller(hook_name, remove_plugins=others)

    def call(self, hook_name: str, **kwargs: Any) -> HookCall:
        """Call ``hook_name`` through pluggy (``pm.hook``), leaving out each implementation that raises.

        pluggy's calling order and ``firstresult`` hold. When an
        implementation raises, the call is made again without that plugin,
        and the exception is kept in :attr:`HookCall.failures`; an
        implementation that ran before the raising one runs again.
        """
        failures: list[HookOutcome] = []
        left_out: list[object] = []
        while True:
            caller = (self.pm.subset_hook_caller(hook_name, remove_plugins=left_out) if left_out
                      else getattr(self.pm.hook, hook_name))
            try:
                return HookCall(caller(**kwargs), failures)
            except Exception as exc:
                culprit = _raised_in(caller.get_hookimpls(), exc.__traceback__)
                failures.append(HookOutcome(culprit.plugin_name if culprit else "unknown", error=exc))
                if culprit is None:
                    return HookCall(None, failures)
                left_out.append(culprit.plugin)

    def each(self, hook_name: str, *, contained_s: float | None = None, **kwargs: Any) -> Iterator[HookOutcome]:
        """Call each plugin's implementation of ``hook_name`` through pluggy on its own, for answers kept by plugin.

        Plugins are visited in pluggy's calling order (last registered
        first). An implementation that raises yields a :class:`HookOutcome`
        with the exception; the others still run. With ``contained_s``, each
        call runs in a forked child (where the platform can fork) stopped
        after that many seconds, so a hang, an ``os._exit`` or a crash costs
        only that plugin's outcome; the value comes back pickled.
        """
        for impl in reversed(getattr(self.pm.hook, hook_name).get_hookimpls()):
            caller = self._only(impl.plugin_name, hook_name)

            def first(caller=caller) -> Any:
                return next(iter(caller(**kwargs)), None)

            if contained_s is not None and can_fork():
                outcome, _ = run_forked(first, contained_s)
                if outcome[0] == "error":
                    yield HookOutcome(impl.plugin_name, error=PluginFault(outcome[1]))
                else:
                    yield HookOutcome(impl.plugin_name, value=outcome[1])
                continue
            try:
                value = first()
            except Exception as exc:
                yield HookOutcome(impl.plugin_name, error=exc)
            else:
                yield HookOutcome(impl.plugin_name, value=value)

    def prepare(self, name: str) -> None:
        """Call detector ``name``'s ``prepare`` once in this process (:meth:`forensics_core.Detector.prepare`).

        A failure is not raised here: the detector's own run, contained in
        its child, meets it again and records it as the detector's error.
        """
        pid, done = self._prepared
        if pid != os.getpid():
            done = set()
            self._prepared = (os.getpid(), done)
        if name in done or name not in self.detectors:
            return
        done.add(name)
        try:
            self.detectors[name].detector.prepare()
        except Exception:  # noqa: BLE001 (recorded by the detector's contained run)
            return

    def registered(self, finding: DetectorFinding) -> RegisteredDetector | None:
        """The detector object that made ``finding``, if the plugin that registered it is loaded here."""
        entry = self.detectors.get(finding.name)
        return entry if entry is not None and entry.plugin == finding.plugin else None

    def plugin_records(self) -> list[PluginRecord]:
        return [self.records[n] for n in sorted(self.records)]


def _raised_in(impls: list[pluggy.HookImpl], tb: TracebackType | None) -> pluggy.HookImpl | None:
    """The implementation among ``impls`` in whose frame the traceback ``tb`` passes first."""
    while tb is not None:
        frame = tb.tb_frame
        hits = [i for i in impls if getattr(i.function, "__code__", None) is frame.f_code]
        if len(hits) > 1:
            hits = [i for i in hits if getattr(i.function, "__self__", None) is frame.f_locals.get("self")]
        if hits:
            return hits[0]
        tb = tb.tb_next
    return None


def _core_version() -> str:
    from . import __version__

    return __version__


def localise_map(host: PluginHost, finding: DetectorFinding, shape: tuple[int, int]) -> np.ndarray | None:
    """The boolean ``shape`` map of the pixels ``finding`` flags, from its detector's ``localize``.

    None when the detector does not localise, fails, or answers with another shape.
    """
    entry = host.registered(finding)
    if entry is None or finding.status is Status.ERROR:
        return None
    try:
        pred = entry.detector.localize(finding, shape)
    except Exception:
        return None
    if pred is None:
        return None
    pred = np.asarray(pred, dtype=bool)
    return pred if pred.shape == tuple(shape) else None
