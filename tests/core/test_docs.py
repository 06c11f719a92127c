"""The documentation site builds with warnings as errors and has its key pages and API entries.

The fast build of the site: Sphinx with ``-W --keep-going`` (a broken docstring or a dead
internal link fails), the gallery's examples not run (``-D plot_gallery=0``; the full build,
``python -m sphinx -W --keep-going -b html docs docs/_build/html``, runs them). ``docs/`` and
``examples/`` are copied into a temporary directory so the gallery's generated sources do not
land in the working tree; the sources documented are this checkout's (PYTHONPATH).
"""
import importlib
import importlib.util
import inspect
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

TOOLS = ("sphinx", "pydata_sphinx_theme", "numpydoc", "sphinx_gallery", "myst_parser",
         "sphinx-mathjax-offline", "matplotlib")


def _missing(names):
    return [n for n in names if importlib.util.find_spec(n) is None]


pytestmark = [
    pytest.mark.skipif(bool(_missing(TOOLS)),
                       reason=f"the documentation tools are not installed ({', '.join(_missing(TOOLS))}): "
                              "pip install -e '.[docs]'"),
    pytest.mark.skipif(bool(_missing(("exudyn", "pinocchio"))),
                       reason="the API reference documents lgt_exudyn and lgt_pinocchio, whose engines are "
                              f"not installed ({', '.join(_missing(('exudyn', 'pinocchio')))}): "
                              "pip install -e '.[all]'"),
]

PAGES = ["index", "getting_started", "theory", "performance", "architecture",
         "tutorials/index", "tutorials/exudyn", "tutorials/pinocchio", "tutorials/choosing",
         "tutorials/stiff", "tutorials/constraints", "tutorials/events", "paper_corrections",
         "auto_examples/index", "api/index"]

#: modules whose every public name must have an entry in the API reference
API_MODULES = ["lgt_bridge.lgt", "lgt_bridge.params", "lgt_bridge.charts", "lgt_bridge.charts.base",
               "lgt_bridge.groups.so3", "lgt_bridge.groups.se3", "lgt_bridge.groups.so3xr3",
               "lgt_bridge.groups.quaternion", "lgt_bridge.model", "lgt_bridge.integrators.registry",
               "lgt_bridge.validation", "lgt_bridge.scenes.catalogue", "lgt_bridge.scenes.system",
               "lgt_bridge.bench.runner", "lgt_bridge.bench.registry", "lgt_bridge.bench.metrics",
               "lgt_bridge.bench.report", "lgt_bridge.auto", "lgt_bridge.events", "lgt_pinocchio.baselines"]

#: entries named in the issue, and the top-level names
KEY_ENTRIES = ["lgt_bridge.simulate", "lgt_bridge.Simulation", "lgt_bridge.Simulation.run",
               "lgt_bridge.Simulation.advance_to", "lgt_bridge.SimulationResult", "lgt_bridge.wrap",
               "lgt_bridge.LGTError", "lgt_bridge.InputError", "lgt_bridge.ChartDomainError",
               "lgt_bridge.StepError", "lgt_bridge.errors.ModelError", "lgt_bridge.errors.ModelNote",
               "lgt_exudyn.SolveDynamic", "lgt_exudyn.ExudynModel", "lgt_pinocchio.PinocchioModel",
               "lgt_pinocchio.PinocchioModel.pin_state", "lgt_bridge.lgt.tau", "lgt_bridge.lgt.LGT",
               "module-lgt_bridge.charts", "module-lgt_bridge.charts.exp", "module-lgt_bridge.charts.cay",
               "module-lgt_bridge.charts.cay2", "lgt_bridge.charts.EXP", "lgt_bridge.charts.CAY",
               "lgt_bridge.charts.CAY2", "lgt_bridge.charts.base.Chart",
               "lgt_bridge.integrators.registry.METHODS", "lgt_bridge.groups.so3.exp",
               "lgt_bridge.scenes.catalogue.heavy_top", "lgt_bridge.bench.runner.sweep"]


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """Build the site (gallery not run) into a temporary directory; return its HTML folder."""
    tmp = tmp_path_factory.mktemp("docs")
    ignore = shutil.ignore_patterns("_build", "auto_examples", "sg_execution_times.rst", "__pycache__")
    shutil.copytree(ROOT / "docs", tmp / "docs", ignore=ignore)
    shutil.copytree(ROOT / "examples", tmp / "examples", ignore=ignore)
    env = dict(os.environ, CI="1", MPLBACKEND="Agg",
               PYTHONPATH=os.pathsep.join([str(ROOT), str(ROOT / "adapters"), os.environ.get("PYTHONPATH", "")]))
    html = tmp / "html"
    cmd = [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", "-D", "plot_gallery=0",
           "-d", str(tmp / "doctrees"), str(tmp / "docs"), str(html)]
    proc = subprocess.run(cmd, env=env, cwd=tmp, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, f"the documentation build failed:\n{proc.stderr[-6000:]}"
    return html


@pytest.fixture(scope="module")
def ids(site):
    """Every HTML id of the API reference pages."""
    found = set()
    for page in (site / "api").glob("*.html"):
        found.update(re.findall(r'\sid="([^"]+)"', page.read_text(encoding="utf-8")))
    return found


@pytest.mark.parametrize("page", PAGES)
def test_page_exists(site, page):
    text = (site / f"{page}.html").read_text(encoding="utf-8")
    assert "<h1>" in text or "<h1 " in text


def test_gallery_lists_every_example(site):
    text = (site / "auto_examples" / "index.html").read_text(encoding="utf-8")
    for example in sorted((ROOT / "examples").glob("*.py")):
        assert (site / "auto_examples" / f"{example.stem}.html").exists(), example.name
        assert f"{example.stem}.html" in text, example.name


def test_key_api_entries(ids):
    missing = [name for name in KEY_ENTRIES if name not in ids]
    assert not missing, f"no API entry for {missing}"


def _public_names(modname):
    mod = importlib.import_module(modname)
    if hasattr(mod, "__all__"):
        return list(mod.__all__)
    return [n for n, obj in vars(mod).items()
            if not n.startswith("_") and (inspect.isfunction(obj) or inspect.isclass(obj))
            and getattr(obj, "__module__", None) == modname]


@pytest.mark.parametrize("modname", API_MODULES)
def test_every_public_name_has_an_entry(ids, modname):
    defined_in = {}
    for name in _public_names(modname):
        obj = getattr(importlib.import_module(modname), name)
        home = getattr(obj, "__module__", None) if (inspect.isfunction(obj) or inspect.isclass(obj)) else None
        defined_in[name] = home or modname
    package = modname.split(".")[0]
    missing = [n for n, home in defined_in.items()
               if f"{modname}.{n}" not in ids and f"{home}.{n}" not in ids and f"module-{modname}.{n}" not in ids
               and not any(i.startswith(package) and i.endswith(f".{n}") for i in ids)]
    assert not missing, f"{modname}: no API entry for {missing} (document them, or give them a docstring)"


def test_math_renders_offline(site):
    theory = (site / "theory.html").read_text(encoding="utf-8")
    assert "_static/mathjax/tex-chtml.js" in theory and "cdn.jsdelivr" not in theory
    assert (site / "_static" / "mathjax" / "tex-chtml.js").exists()


def test_figures_are_included(site):
    text = (site / "tutorials" / "choosing.html").read_text(encoding="utf-8")
    for fig in sorted((ROOT / "docs" / "figures").glob("*.png")):
        assert fig.name in text, fig.name
        assert (site / "_images" / fig.name).exists(), fig.name
