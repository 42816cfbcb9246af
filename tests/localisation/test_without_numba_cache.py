"""The robot's planning (the README's "On a robot": the best viewpoint for the shipped
policy's proposal), and every module's import, where numba cannot write its on-disk cache:
a read-only install run by a user without a writable home. ``@njit(cache=True)`` refused
the import there ("RuntimeError: cannot cache function 'wrap_angle': no locator available",
seen as user nobody with HOME=/nonexistent); the kernels are compiled afresh instead and
plan the same views."""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap

import numpy as np

PLAN = """
import json
import numpy as np
from activevision.geometry import CameraConfig, FieldSpec, field_landmarks
from activevision.geometry.angles import wrap_angle
from activevision.localisation import DEFAULT_UKF, LocalisationConfig, best_viewpoint

landmarks = field_landmarks(FieldSpec())
camera = CameraConfig()
grid = LocalisationConfig.for_camera(camera).grid
plans = []
for pose, ball in (([-1.0, 0.5, 0.3], [0.5, -0.5]), ([2.0, -1.0, 2.5], [1.0, 1.5])):
    plan = best_viewpoint(
        np.array(pose), DEFAULT_UKF.initial_cov, np.array(ball), landmarks, camera, grid=grid
    )
    plans.append([float(plan.pan), float(plan.tilt), str(plan.status)])
print(json.dumps({"plans": plans, "wrapped": wrap_angle(np.array([4.0, -7.0])).tolist()}))
"""

NO_CACHE = """
from numba.core import caching
impl = getattr(caching, "CacheImpl", None) or caching._CacheImpl  # numba >= 0.61 / older
impl._locator_classes = []  # no place numba may write its cache
"""


def _run(script: str) -> dict:
    result = subprocess.run(
        [sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True, timeout=300
    )
    assert result.returncode == 0, result.stderr
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_planning_runs_where_numba_cannot_write_its_cache():
    without = _run(NO_CACHE + PLAN)
    assert without == _run(PLAN)
    np.testing.assert_allclose(without["wrapped"], [4.0 - 2 * np.pi, -7.0 + 2 * np.pi])


def test_every_module_imports_where_numba_cannot_write_its_cache():
    # the renderer's and the envs' kernels too: a service user's training or evaluation
    # stopped at the import as the robot's planning did
    imported = _run(
        NO_CACHE
        + """
import importlib, json, pkgutil
import activevision
packages = pkgutil.walk_packages(activevision.__path__, "activevision.")
names = [m.name for m in packages if not m.name.endswith("__main__")]  # those run the CLI
for name in names:
    importlib.import_module(name)
print(json.dumps({"modules": len(names)}))
"""
    )
    assert imported["modules"] > 100
