"""Route a legacy script's SolveDynamic calls through the bridge (``lgt-bridge run``)."""
from contextlib import contextmanager


@contextmanager
def route_solve_dynamic(options):
    """While active, ``exu.SolveDynamic``, ``exudyn.solver.SolveDynamic`` and
    ``mbs.SolveDynamic`` run :func:`lgt_exudyn.SolveDynamic` with ``options``
    (method, group, chart, rtol, atol, progress). Yields the list of per-call statistics."""
    import exudyn
    import exudyn.solver

    from .solve import SolveDynamic, describe

    calls = []
    options = dict(options)
    options.setdefault("verbose", False)     # the routed call prints its own line below
    original = exudyn.solver.SolveDynamic

    def routed(mbs, simulationSettings=None, solverType=None, updateInitialValues=False,
               storeSolver=True, showHints=False, showCausingItems=True, autoAssemble=True):
        ok = SolveDynamic(mbs, simulationSettings, solverType, updateInitialValues, storeSolver,
                          showHints, showCausingItems, autoAssemble, **options)
        st = mbs.sys["lgtBridgeStats"]
        calls.append(st)
        print(f"lgt-bridge: SolveDynamic #{len(calls)} ran {describe(st)}; "
              f"{st['n_steps']} steps ({st['n_rejected']} rejected), {st['n_f']} f evaluations, "
              f"{st['wall_s']:.3f} s wall")
        return ok

    routed.__doc__ = original.__doc__
    targets = [(exudyn, "SolveDynamic"), (exudyn.solver, "SolveDynamic"), (exudyn.MainSystem, "SolveDynamic")]
    saved = [(obj, name, getattr(obj, name)) for obj, name in targets]
    for obj, name in targets:
        setattr(obj, name, routed)
    try:
        yield calls
    finally:
        for obj, name, fn in saved:
            setattr(obj, name, fn)
