"""Route a legacy script's SolveDynamic calls through the bridge (``lgt-bridge run``)."""
from contextlib import contextmanager


@contextmanager
def route_solve_dynamic(options):
    """While active, ``exu.SolveDynamic``, ``exudyn.solver.SolveDynamic`` and
    ``mbs.SolveDynamic`` run :func:`lgt_exudyn.SolveDynamic` with ``options``
    (method, group, chart, rtol, atol, progress, events). Yields the list of per-call
    statistics; with events, each call also prints the crossings found."""
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
        for i, (fn, te) in enumerate(zip(options.get("events", ()), st.get("t_events", ()))):
            name = getattr(fn, "__name__", type(fn).__name__)
            times = ", ".join(f"{t:.9g}" for t in te) if len(te) else "none"
            print(f"lgt-bridge: SolveDynamic #{len(calls)} event {i} ({name}): {len(te)} crossing(s) "
                  f"at t = {times}")
        if st.get("end_jump") is not None:
            print(f"lgt-bridge: SolveDynamic #{len(calls)}: the accelerations jump by {st['end_jump']:.3g} at "
                  "endTime (a load switched there); the run ends at their left limit, the motion up to endTime")
        if "terminal event" in st["message"]:
            print(f"lgt-bridge: SolveDynamic #{len(calls)} ended at the {st['message']}")
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
