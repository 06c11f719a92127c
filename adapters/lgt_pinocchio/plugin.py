"""Entry point of the Pinocchio adapter (group ``lgt_bridge.adapters``)."""


class _PinocchioPlugin:
    name = "pinocchio"

    @staticmethod
    def accepts(obj):
        t = type(obj)
        return t.__name__ == "Model" and t.__module__.startswith("pinocchio")

    @staticmethod
    def wrap(obj, **options):
        from .model import PinocchioModel
        return PinocchioModel(obj, **options)

    @staticmethod
    def bench_scenes():
        """Example scenes with the Pinocchio user loops as native baselines, and the family
        ``pinocchio_robot:NAME`` (scenarios free, pd) of example-robot-data's free-flyer
        robots (:mod:`lgt_pinocchio.bench`; the loaders are imported only when one is named)."""
        from .bench import bench_scenes
        return bench_scenes()


PLUGIN = _PinocchioPlugin()
