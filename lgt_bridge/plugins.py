"""Engine adapters as plugins (entry-point group ``lgt_bridge.adapters``).

An adapter package registers an object with two functions:

    accepts(obj) -> bool          is ``obj`` something this adapter can wrap?
    wrap(obj, **options) -> Model

``lgt_bridge.wrap(obj)`` asks every registered adapter in turn. The core never
imports an engine: an adapter is loaded only when ``wrap`` needs it.
"""
from .errors import InputError
from .model import Model

GROUP = "lgt_bridge.adapters"


def adapters():
    """The registered adapter entry points, by name (scanned on call, not at import)."""
    from importlib.metadata import entry_points
    return {ep.name: ep for ep in entry_points(group=GROUP)}


def wrap(obj, **options):
    """A :class:`~lgt_bridge.model.Model` for ``obj`` (an Exudyn MainSystem, a Pinocchio
    model, ...) from the first adapter that accepts it; a Model is returned as is."""
    if isinstance(obj, Model):
        return obj
    tried = []
    for name, ep in sorted(adapters().items()):
        try:
            plugin = ep.load()
        except ImportError as exc:             # the engine of this adapter is not installed
            tried.append(f"{name} (not loadable: {exc})")
            continue
        if plugin.accepts(obj):
            return plugin.wrap(obj, **options)
        tried.append(name)
    raise InputError(f"no adapter accepts an object of type {type(obj).__module__}.{type(obj).__name__}; "
                     f"adapters tried: {tried or 'none installed'}. Install the engine extra "
                     "(pip install 'lgt-bridge[exudyn]' or '[pinocchio]') or pass a lgt_bridge Model.")
