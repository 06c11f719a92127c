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
    """A :class:`~lgt_bridge.model.Model` for an engine's model, from the first adapter
    that accepts it.

    Parameters
    ----------
    obj : object
        An Exudyn ``MainSystem`` (assembled), a Pinocchio ``Model``, ... — or a
        :class:`~lgt_bridge.model.Model`, returned as is.
    **options
        Passed to the adapter's model (e.g. ``q0``, ``v0``, ``tau`` of
        :class:`lgt_pinocchio.PinocchioModel`).

    Returns
    -------
    lgt_bridge.model.Model
        e.g. an :class:`lgt_exudyn.ExudynModel` or :class:`lgt_pinocchio.PinocchioModel`.

    Raises
    ------
    lgt_bridge.InputError
        No installed adapter accepts ``obj`` (the message lists the adapters tried).
    """
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
