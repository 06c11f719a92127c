"""Work-precision sweeps: ``lgt-bridge bench SCENE``.

Every combination of method x group x chart x setting (tolerance for adaptive methods,
step for fixed-step ones) runs on a scene and is compared with a tight reference run;
output: a JSON of every run, a Markdown table and (with matplotlib) PNG plots.

- :mod:`.registry` — what can run: :class:`BenchScene`, :class:`SceneFamily`, the scenes
  (:data:`SCENES`, the adapters' ones, ``PREFIX:ARG``, ``file.py:function``) and their
  lookup; :func:`method_kind` (fixed step or adaptive) and :func:`check_options`;
- :mod:`.runner` — :func:`sweep`: the reference run, the process pool or Dask cluster,
  the serial timing pass;
- :mod:`.metrics` — errors against the reference, energy drift, wall time at an error,
  "auto" against the front;
- :mod:`.report` — :func:`write_report`: JSON, Markdown and the plots.
"""
from .metrics import best_at, end_errors, energy_drift, front_gaps, pose_error, pose_errors, wall_at_error
from .registry import (FIXED, SCENES, SCIPY, BenchScene, SceneFamily, all_scenes, check_options, get_scene,
                       load_scene, method_choices, method_kind, scenarios_of)
from .report import report_name, timing_text, write_report
from .runner import REFERENCE, WorkerDied, sweep

__all__ = ["FIXED", "REFERENCE", "SCENES", "SCIPY", "BenchScene", "SceneFamily", "WorkerDied", "all_scenes",
           "best_at", "check_options", "end_errors", "energy_drift", "front_gaps", "get_scene", "load_scene",
           "method_choices", "method_kind", "pose_error", "pose_errors", "report_name", "scenarios_of", "sweep",
           "timing_text", "wall_at_error", "write_report"]
