"""Entry point of the Exudyn adapter (group ``lgt_bridge.adapters``)."""


class _ExudynPlugin:
    name = "exudyn"
    #: the solver calls ``lgt-bridge run`` routes through the bridge (see :meth:`patch`)
    routes = ("exu.SolveDynamic", "exudyn.solver.SolveDynamic", "mbs.SolveDynamic")

    @staticmethod
    def accepts(obj):
        t = type(obj)
        return t.__name__ == "MainSystem" and t.__module__.startswith("exudyn")

    @staticmethod
    def wrap(obj, **options):
        from .model import ExudynModel
        return ExudynModel(obj, **options)

    @staticmethod
    def bench_scenes():
        """Example scenes with Exudyn's own solvers as native baselines."""
        from .bench import bench_scenes
        return bench_scenes()

    @staticmethod
    def patch(options):
        """Context manager routing every exu.SolveDynamic / mbs.SolveDynamic to the bridge."""
        from .run import route_solve_dynamic
        return route_solve_dynamic(options)


PLUGIN = _ExudynPlugin()
