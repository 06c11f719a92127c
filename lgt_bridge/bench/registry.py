"""What the bench can run: its scenes and its methods.

A scene is a built-in name (see SCENES), ``PREFIX:ARG`` for a family of scenes an adapter
registers (:class:`SceneFamily`, e.g. ``pinocchio_robot:solo12``), or
``path/to/file.py:function`` where the function returns ``(model, t_end)``. A scene may
declare scenarios (variants such as free fall or PD control, ``--scenario NAME``); the
first is its default, and a scenario given to a scene without any is an error.

A method is one of the bridge's or ``scipy:<Name>``; :func:`method_kind` is the one place
that says what kind it is (steps dt or tolerances), for the bench and the CLI.
:func:`check_options` checks a sweep's options against both before anything runs.
"""
import importlib.util
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .. import scenes as _scenes
from ..errors import InputError
from ..charts import NAMES as CHART_NAMES
from ..integrators import registry as _methods
from ..lgt import GROUPS
from ..plugins import adapters


@dataclass
class BenchScene:
    """A bench scene: ``make() -> model``, the end time, and the engine's own solvers
    as baselines: ``natives[name] = (kind, settings, run)`` with kind "dt"/"tol"/"n"
    and ``run(setting) -> dict(q=final q in the model's coordinates, n_f, n_steps)``
    (n_f None where the solver does not expose its evaluations)."""

    make: Callable
    t_end: float
    natives: dict = field(default_factory=dict)
    about: str = ""
    #: scenario name -> the BenchScene of that variant (``--scenario NAME``), the first the
    #: default; empty: the scene has no scenarios
    scenarios: dict = field(default_factory=dict)


@dataclass
class SceneFamily:
    """Scenes named ``PREFIX:ARG``, registered under PREFIX: ``resolve(arg) -> BenchScene``
    (raising InputError for an ARG it does not know, cheaply: nothing is built). ``arg``
    names ARG in the help (e.g. "NAME"); ``scenarios``: scenario name -> one-line
    description, checked before ``resolve`` is called."""

    resolve: Callable
    about: str = ""
    arg: str = "ARG"
    scenarios: dict = field(default_factory=dict)


SCENES = {
    "heavy_top": BenchScene(lambda: _scenes.heavy_top(True), 0.1, about="heavy top, spherical joint"),
    "heavy_top_pivot": BenchScene(lambda: _scenes.heavy_top(False), 0.1, about="heavy top, frame at the pivot"),
    "free_body": BenchScene(lambda: _scenes.free_body((1.0, 2.0, 3.0), (0.01, 2.0, 0.01)), 10.0,
                            about="torque-free asymmetric body (Dzhanibekov flip)"),
    "chain": BenchScene(lambda: _scenes.chain(5), 1.0, about="5 links, spherical joints"),
    "top_and_free_bodies": BenchScene(lambda: _scenes.top_and_free_bodies(3), 0.5,
                                      about="jointed top + 3 free bodies"),
}


def all_scenes():
    """Built-in scenes plus those the installed adapters register (``bench_scenes()``
    on the plugin: the engines' example scenes with their native solvers)."""
    out = dict(SCENES)
    for name, ep in sorted(adapters().items()):
        try:
            plugin = ep.load()
        except ImportError:
            continue
        if hasattr(plugin, "bench_scenes"):
            try:
                out.update(plugin.bench_scenes())
            except ImportError:                 # the engine itself is not installed
                continue
    return out


def get_scene(spec, scenario=None):
    """The BenchScene of a name, of ``PREFIX:ARG`` (a :class:`SceneFamily`) or of
    'file.py:function' (which returns (model, t_end)); with ``scenario``, that variant of
    it (InputError when the scene has no scenarios or not this one; for a family checked
    before ARG is resolved). Without, a scene with scenarios gives its first (default)."""
    sc = _base_scene(spec, scenario)
    _check_scenario(spec, scenario, sc.scenarios)
    if sc.scenarios:
        return sc.scenarios[scenario if scenario is not None else next(iter(sc.scenarios))]
    return sc


def scenarios_of(spec):
    """The scenario names a scene declares (first: the default); () for none."""
    return tuple(_base_scene(spec).scenarios)


def _base_scene(spec, scenario=None):
    scenes = all_scenes()
    sc = scenes.get(spec)
    if isinstance(sc, SceneFamily):
        raise InputError(f"bench: {spec!r} is a family of scenes; name one as {spec}:{sc.arg} "
                         "(lgt-bridge bench --help describes it).")
    if sc is None and ":" in spec:
        prefix, arg = spec.split(":", 1)
        fam = scenes.get(prefix)
        if isinstance(fam, SceneFamily):
            _check_scenario(spec, scenario, fam.scenarios)
            sc = fam.resolve(arg)
        else:
            path, fn = spec.rsplit(":", 1)
            if Path(path).is_file():
                sc = BenchScene(lambda: _user_scene(path, fn, spec), None)
    if sc is None:
        names = [k + (f":{v.arg}" if isinstance(v, SceneFamily) else "") for k, v in sorted(scenes.items())]
        raise InputError(f"bench: unknown scene {spec!r}; use one of {names} or "
                         "'path/to/file.py:function' returning (model, t_end).")
    return sc


def _check_scenario(spec, scenario, scenarios):
    if scenario is None:
        return
    if not scenarios:
        raise InputError(f"bench --scenario {scenario}: scene {spec!r} has no scenarios; leave out "
                         "--scenario (lgt-bridge bench --help lists the scenes that have them).")
    if scenario not in scenarios:
        raise InputError(f"bench --scenario: unknown scenario {scenario!r} for scene {spec!r}; use one of "
                         f"{', '.join(scenarios)}.")


def _user_scene(path, fn, spec):
    s = importlib.util.spec_from_file_location("lgt_bench_user_scene", path)
    mod = importlib.util.module_from_spec(s)
    s.loader.exec_module(mod)
    if not hasattr(mod, fn):
        raise InputError(f"bench: {path} has no function {fn!r}; it must return (model, t_end).")
    out = getattr(mod, fn)()
    if not (isinstance(out, tuple) and len(out) == 2):
        raise InputError(f"bench: {spec} must return (model, t_end), got {type(out).__name__}.")
    return out


def load_scene(spec, scenario=None):
    """(model, t_end) from a scene name or 'file.py:function' (and a scenario of it)."""
    sc = get_scene(spec, scenario)
    out = sc.make()
    return out if sc.t_end is None else (out, sc.t_end)


# --- methods ------------------------------------------------------------------------------
SCIPY = _methods.SCIPY


def method_kind(name):
    """How a sweep drives method ``name``: "dt" when it takes fixed steps, "tol" when it is
    adaptive and takes rtol = atol (adaptive and scipy's macro-step methods), None when no
    method has this name (read from the method registry)."""
    try:
        return "dt" if _methods.get(name).fixed else "tol"
    except InputError:
        return None


method_choices = _methods.choices_text

#: the fixed-step methods (a sweep gives them --dts)
FIXED = tuple(_methods.by(steps="fixed"))


def check_options(spec, methods, groups, charts, tols, dts, scenario=None):
    """InputError on the first bad option, before anything runs (the scene and its
    scenario are looked up, not built)."""
    if not methods:
        raise InputError("bench: --methods is empty.")
    for m in methods:
        if method_kind(m) is None:
            raise InputError(f"bench: unknown method {m!r}; use {method_choices()}.")
    for opt, vals, ok in (("--groups", groups, (*GROUPS, "auto")), ("--charts", charts, (*CHART_NAMES, "auto"))):
        if not vals:
            raise InputError(f"bench: {opt} is empty.")
        for v in vals:
            if v not in ok:
                raise InputError(f"bench {opt}: unknown value {v!r}; use {', '.join(ok)}.")
    for opt, vals, needed in (("--tols", tols, any(method_kind(m) != "dt" for m in methods)),
                              ("--dts", dts, any(method_kind(m) == "dt" for m in methods))):
        if needed and not vals:
            raise InputError(f"bench: {opt} is empty but the methods need it.")
        for v in vals:
            if not (np.isfinite(v) and v > 0):
                raise InputError(f"bench {opt}: {v:g} must be a positive finite number.")
    get_scene(spec, scenario)
