"""The public entry points' docstrings are numpydoc: every parameter of the signature is
documented in a Parameters section (and nothing documented that the signature lacks), with
Returns where the function returns something, so the API reference renders them as tables."""
import inspect

import pytest

docscrape = pytest.importorskip("numpydoc.docscrape")

import lgt_bridge  # noqa: E402


def _entry_points():
    yield "lgt_bridge.simulate", lgt_bridge.simulate, True
    yield "lgt_bridge.wrap", lgt_bridge.wrap, True
    yield "lgt_bridge.Simulation", lgt_bridge.Simulation, False
    yield "lgt_bridge.Simulation.run", lgt_bridge.Simulation.run, True
    yield "lgt_bridge.Simulation.advance_to", lgt_bridge.Simulation.advance_to, False
    yield "lgt_bridge.Simulation.advance_to_many", lgt_bridge.Simulation.advance_to_many, True
    for mod, names in (("lgt_exudyn", ("ExudynModel", "SolveDynamic")), ("lgt_pinocchio", ("PinocchioModel",))):
        try:
            m = __import__(mod)
        except ImportError:              # the engine is not installed: its adapter is not public here
            continue
        for n in names:
            yield f"{mod}.{n}", getattr(m, n), n == "SolveDynamic"


def _documented(doc):
    names = []
    for p in doc["Parameters"]:
        names += [n.strip().lstrip("*") for n in p.name.split(",")]
    return names


@pytest.mark.parametrize("name, obj, returns", list(_entry_points()), ids=lambda v: v if isinstance(v, str) else "")
def test_public_docstrings_document_every_parameter(name, obj, returns):
    doc = docscrape.ClassDoc(obj) if inspect.isclass(obj) else docscrape.FunctionDoc(obj)
    sig = inspect.signature(obj.__init__ if inspect.isclass(obj) else obj)
    params = [p.name for p in sig.parameters.values() if p.name != "self"]
    documented = _documented(doc)
    assert documented, f"{name}: no Parameters section"
    assert sorted(set(params) - set(documented)) == [], f"{name}: parameters not documented"
    assert sorted(set(documented) - set(params)) == [], f"{name}: documented parameters it does not take"
    if returns:
        assert doc["Returns"], f"{name}: no Returns section"
    assert doc["Summary"], f"{name}: no one-line summary"


def test_the_result_documents_its_attributes():
    doc = docscrape.ClassDoc(lgt_bridge.SimulationResult)
    fields = set(lgt_bridge.SimulationResult.__dataclass_fields__)
    documented = {n.strip() for p in doc["Attributes"] for n in p.name.split(",")}
    assert fields == documented
