# Copyright 2026 digital_actor_planner developers
#
# Licensed under the Apache License, Version 2.0 (the "License");
# you may not use this file except in compliance with the License.
# You may obtain a copy of the License at
#
#     http://www.apache.org/licenses/LICENSE-2.0
#
# Unless required by applicable law or agreed to in writing, software
# distributed under the License is distributed on an "AS IS" BASIS,
# WITHOUT WARRANTIES OR CONDITIONS OF ANY KIND, either express or implied.
# See the License for the specific language governing permissions and
# limitations under the License.

"""
The compiled kernels (core/jit.py): compiled where numba is, and the same plans without it.

An installation without numba runs every kernel as plain Python: the actor then walks the same
frames, only slower. What each kernel computes is tested through the public functions that call
it, against an independent reference or what a user notices, in the tests of its stage:
the footholds and the window search against the readable search and the exhaustive optimum
(test_footsteps.py, test_footstep_window.py); the kinematics against the URDF composed joint
by joint (test_skeleton.py); the ground map against the meshes' geometry (test_environment.py);
the 3D check and the CT-space's contact tests against FCL (test_collision.py,
test_ct_space.py); the leg's inverse kinematics against the forward kinematics and the steps'
promises (test_gait.py); the predicted path against its circle (test_path.py, and below); the
motion patterns (test_upper_body.py). Here: the compilation itself, numba's dispatch, and
footholds and path points on ground and arcs whose answers are known.
"""
import importlib
import os
import pkgutil
import subprocess
import sys

from digital_actor_planner import core as core_package
from digital_actor_planner.core import footstep_search
from digital_actor_planner.core.footsteps import FootstepConfig, FootstepPlanner, GroundProfile
from digital_actor_planner.core.jit import COMPILED, direct
from digital_actor_planner.core.path import PredictedPath
from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest


def _kernels():
    """Every kernel of the core (what ``jit.kernel`` made: it keeps ``py_func``), by name."""
    found = {}
    for info in pkgutil.iter_modules(core_package.__path__):
        module = importlib.import_module(f'{core_package.__name__}.{info.name}')
        for name, value in vars(module).items():
            if callable(value) and hasattr(value, 'py_func') and value.__module__ == \
                    module.__name__:
                found[f'{info.name}.{name}'] = value
    return found


def test_numba_is_installed_and_the_kernels_are_compiled():
    """
    The kernels are compiled: numba is installed.

    requirements.txt pins numba: without it every kernel runs as Python, many times slower, and the
    planning-time numbers in the README would not hold.
    """
    assert COMPILED
    kernels = _kernels()
    # The stages that run compiled: the footstep search, the ground map, the gait, the 3D
    # check, the CT-space and the roadmap's search.
    stages = {name.split('.')[0] for name in kernels}
    assert {'footstep_search', 'environment', 'gait', 'collision', 'ct_space',
            'ct_roadmap'} <= stages
    for name, kernel in kernels.items():
        assert kernel.py_func is not kernel, name


def test_a_kernel_called_without_numbas_dispatch_answers_alike():
    """
    A kernel called without numba's dispatch answers alike.

    ``jit.direct``: the footstep search as the planner calls it (its compiled code, not numba's
    dispatcher) answers exactly what the dispatcher's call answers; a plain function, or a kernel
    of more than one signature, is handed back as it is.
    """
    from digital_actor_planner.core import footsteps
    assert footsteps.window_search is not footstep_search.window_search
    assert footsteps.window_search is direct(footstep_search.window_search)
    planner = FootstepPlanner(FootstepConfig(), Skeleton().leg)
    s = -0.3 + 0.02 * np.arange(200)
    height = np.vstack([np.where(s > 0.6, 0.12, 0.0)] * 2)
    profile = GroundProfile(s0=-0.3, ds=0.02, height=height, low=height.copy(),
                            headroom=np.full_like(height, np.inf),
                            obstacle=np.full_like(height, np.nan))
    none_banned = np.zeros(14, dtype=bool)
    none_banned.setflags(write=False)
    arguments = (6 * 14 + 6) * 14 + 6, none_banned, none_banned, True, \
        planner.search_profile(profile, 1, 0.0, 0.0, -0.1, 0.0, 0.5, 0.5)
    through, direct_answer = (footstep_search.window_search(*arguments),
                              footsteps.window_search(*arguments))
    assert through[0] >= 0 and through[0] == direct_answer[0]
    np.testing.assert_array_equal(through[1], direct_answer[1])
    assert through[2:] == direct_answer[2:]

    def plain(x):
        return x
    assert direct(plain) is plain


def test_footholds_on_ground_whose_answers_are_known():
    """
    Footholds on flat ground, on a step, against its riser, over a hole and under a low ceiling.

    ``FootstepPlanner.footholds`` (the judging kernel): a sole on level ground rests on it, one
    whose toes would go into a riser is refused, one on the step rests on its top, one over a
    hole or under too low a ceiling is refused; both foot tracks alike.
    """
    leg = Skeleton().leg
    planner = FootstepPlanner(FootstepConfig(), leg)
    s = -0.3 + 0.02 * np.arange(200)
    track = np.where(s > 0.6, 0.12, 0.0)
    track[(s > 1.5) & (s < 1.7)] = np.nan
    height = np.vstack([track, track])
    headroom = np.full_like(height, np.inf)
    headroom[:, (s > 2.2) & (s < 2.5)] = 0.5
    profile = GroundProfile(s0=-0.3, ds=0.02, height=height, low=height.copy(),
                            headroom=headroom, obstacle=np.full_like(height, np.nan))
    ankles = np.array([0.2, 0.5, 1.0, 1.6, 2.35])
    for side in (0, 1):
        ok, sole, pitch = planner.footholds(profile, side, ankles)
        assert ok.tolist() == [True, False, True, False, False]
        np.testing.assert_allclose(sole[ok], [0.0, 0.12], atol=1e-9)
        np.testing.assert_allclose(pitch[ok], 0.0, atol=1e-9)
        assert np.isnan(sole[~ok]).all()


@pytest.mark.parametrize('curvature', [0.0, 0.8, -2.5])
def test_points_beside_a_path_lie_on_its_offset_circle(curvature):
    """
    Points beside a predicted path lie on the circle (or line) at that offset from it.

    ``PredictedPath.offset_points`` and ``offset_poses`` (the arc kernel): a point ``lateral``
    m to the left of an arc of curvature c lies on the circle of radius 1/c - lateral about the
    arc's centre, at the arc's heading; on a straight path, on the parallel line.
    """
    rng = np.random.default_rng(15)
    x0, y0, heading = 0.4, -1.2, 0.7
    path = PredictedPath(x0, y0, heading, curvature, 2.0)
    s = rng.uniform(-0.5, 2.5, 40)
    for lateral in (0.0, 0.09, -0.1):
        poses = path.offset_poses(s, lateral)
        np.testing.assert_allclose(poses[:, 2], heading + curvature * s, atol=1e-12)
        np.testing.assert_allclose(path.offset_points(s, lateral), poses[:, :2], atol=1e-12)
        left = np.array([-np.sin(heading), np.cos(heading)])
        if curvature == 0.0:
            along = np.array([np.cos(heading), np.sin(heading)])
            expected = np.array([x0, y0]) + s[:, None] * along + lateral * left
            np.testing.assert_allclose(poses[:, :2], expected, atol=1e-12)
        else:
            centre = np.array([x0, y0]) + left / curvature
            radius = np.hypot(*(poses[:, :2] - centre).T)
            np.testing.assert_allclose(radius, abs(1.0 / curvature - lateral), atol=1e-12)


def test_without_numba_the_actor_walks_the_same_frames(tmp_path):
    """
    Without numba the actor walks the same frames.

    The kernels' fallback: in a process where numba cannot be imported every kernel runs as Python,
    and the actor climbs the stairs (lower body) and passes the table, flexing an arm (whole body),
    with the same frames to the last bit.
    """
    from course_runs import simulate
    courses = (('stairs_up', False), ('table', True))
    code = '\n'.join([
        'import sys',
        'sys.modules["numba"] = None',
        f'sys.path.insert(0, {os.path.dirname(os.path.abspath(__file__))!r})',
        'import numpy as np',
        'from digital_actor_planner.core import jit',
        'assert not jit.COMPILED',
        'from course_runs import simulate',
        f'for i, (name, upper) in enumerate({courses!r}):',
        '    np.save(f"{sys.argv[1]}/{i}.npy", simulate(name, upper_body=upper)[2])'])
    subprocess.run([sys.executable, '-c', code, str(tmp_path)], check=True, timeout=300)
    for i, (name, upper) in enumerate(courses):
        frames = simulate(name, upper_body=upper)[2]
        assert frames.shape[0] > 300
        np.testing.assert_array_equal(np.load(tmp_path / f'{i}.npy'), frames, err_msg=name)


def test_a_kernel_compiles_without_a_cache_when_numba_can_cache_it_nowhere(monkeypatch):
    """
    A kernel compiles without a cache when numba can cache it nowhere.

    numba refuses ``cache=True`` when neither the package nor the user's cache directory is
    writable: the kernel is then compiled for the process alone, not an import error.
    """
    from digital_actor_planner.core import jit
    real = jit.numba.njit

    def no_cache(*args, **kwargs):
        if kwargs.get('cache'):
            raise RuntimeError('cannot cache function: no locator available')
        return real(*args, **kwargs)

    monkeypatch.setattr(jit.numba, 'njit', no_cache)

    @jit.kernel('f8(f8[::1])')
    def total(values):
        out = 0.0
        for value in values:
            out += value
        return out

    assert total(np.arange(4.0)) == 6.0
    assert total.py_func is not total


def test_an_inline_kernel_is_compiled_into_the_kernels_that_call_it():
    """
    An inline kernel is compiled into the kernels that call it.

    ``kernel(..., inline=True)``: numba compiles it into its callers (no call between them); the
    same answers compiled and as Python.
    """
    from digital_actor_planner.core import jit

    @jit.kernel('f8(f8, f8)', inline=True)
    def weighted_square(weight, x):
        return weight * x * x

    @jit.kernel('f8(f8[::1])')
    def total(values):
        out = 0.0
        for value in values:
            out += weighted_square(0.5, value)
        return out

    assert total(np.arange(4.0)) == total.py_func(np.arange(4.0)) == 7.0
    assert weighted_square(2.0, 3.0) == 18.0
    if COMPILED:
        assert weighted_square.targetoptions['inline'] == 'always'
        assert total.targetoptions['inline'] == 'never'
