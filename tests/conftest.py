"""Shared test set-up. The tests mirror the packages: ``core/`` (lgt_bridge), ``exudyn/``
(lgt_exudyn), ``pinocchio/`` (lgt_pinocchio); ``models/`` holds the models and
independent references the tests share (imported by name: it is put on sys.path here)."""
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

MODELS = Path(__file__).resolve().parent / "models"
if str(MODELS) not in sys.path:
    sys.path.insert(0, str(MODELS))

settings.register_profile("default", max_examples=60, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.load_profile("default")


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
