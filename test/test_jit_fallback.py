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
The kernels' fallback (core/jit.py): numba absent, present, or failing to compile.

A numba that is installed but cannot compile a kernel (a distribution's older release) must
not stop the planner: that kernel and those that call it run as Python, with one warning, and
the actor plans the same frames as with numba compiling everything, and as without numba.
"""
import json
import os
import subprocess
import sys
import warnings

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
COURSE = 'table'  # walks past the table flexing an arm: the CT-roadmap's kernels run

# Run in a child process: ``numba`` is ``absent`` (cannot be imported), ``failing`` (every
# kernel of core/ct_roadmap.py refused, as numba before 0.57 refused np.round on an array
# without ``out``) or ``present``; writes the frames and what the fallback reported.
CHILD = """
import json, sys, warnings
mode, out = sys.argv[1], sys.argv[2]
sys.path.insert(0, {here!r})
if mode == 'absent':
    sys.modules['numba'] = None
elif mode == 'failing':
    import numba
    from numba.core.errors import TypingError
    real = numba.njit

    def njit(*args, **kwargs):
        compile = real(*args, **kwargs)

        def decorate(function):
            if function.__module__.endswith('.ct_roadmap'):
                raise TypingError('No implementation of function round_ found for signature')
            return compile(function)
        return decorate
    numba.njit = njit
import numpy as np
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter('always')
    from digital_actor_planner.core import jit
    from course_runs import simulate
    frames = simulate({course!r})[2]
np.save(out + '.npy', frames)
kinds = [w.category.__name__ for w in caught]
messages = [str(w.message) for w in caught if w.category is getattr(jit, 'KernelCompileWarning',
                                                                     None)]
with open(out + '.json', 'w') as report:
    json.dump(dict(compiled=jit.COMPILED, failures=list(jit.compile_failures()),
                   kinds=kinds, messages=messages), report)
"""


def _plan(mode, tmp_path):
    out = str(tmp_path / mode)
    code = CHILD.format(here=HERE, course=COURSE)
    result = subprocess.run([sys.executable, '-c', code, mode, out], capture_output=True,
                            text=True, timeout=1500)
    assert result.returncode == 0, result.stderr[-4000:]
    with open(out + '.json') as report:
        return np.load(out + '.npy'), json.load(report)


@pytest.fixture(scope='module')
def compiled_frames(tmp_path_factory):
    pytest.importorskip('numba')
    frames, report = _plan('present', tmp_path_factory.mktemp('present'))
    assert report['compiled'] and report['failures'] == [], report
    assert 'KernelCompileWarning' not in report['kinds'], report
    assert frames.shape[0] > 300
    return frames


@pytest.mark.slow
def test_numba_failing_to_compile_plans_the_same_frames_with_one_warning(compiled_frames,
                                                                         tmp_path):
    frames, report = _plan('failing', tmp_path)
    assert report['compiled']
    failed = [name for name, _ in report['failures']]
    # Every refused kernel is Python now, with those that call one: more than one, one warning.
    assert len(failed) > 1 and all('ct_roadmap' in name for name in failed), failed
    assert report['kinds'].count('KernelCompileWarning') == 1, report['kinds']
    (message,) = report['messages']
    assert 'plain Python' in message and 'round_' in message and failed[0] in message
    np.testing.assert_array_equal(frames, compiled_frames)


@pytest.mark.slow
def test_without_numba_the_same_frames_and_no_warning(compiled_frames, tmp_path):
    frames, report = _plan('absent', tmp_path)
    assert not report['compiled'] and report['failures'] == []
    assert 'KernelCompileWarning' not in report['kinds']
    np.testing.assert_array_equal(frames, compiled_frames)


def test_a_kernel_numba_cannot_type_runs_as_python_with_one_warning(monkeypatch):
    pytest.importorskip('numba')
    from digital_actor_planner.core import jit
    monkeypatch.setattr(jit, '_FAILURES', [])

    def doubled(x):  # plain Python: compiled code cannot call it
        return 2.0 * x

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter('always')

        @jit.kernel('f8(f8)')
        def twice(x):
            return doubled(x)

        @jit.kernel('f8(f8)')
        def four_times(x):
            return twice(twice(x))

        @jit.kernel('f8(f8)')
        def plus_one(x):
            return x + 1.0

    assert [w.category for w in caught] == [jit.KernelCompileWarning]
    assert 'twice' in str(caught[0].message) and 'doubled' in str(caught[0].message)
    assert [name.rsplit('.', 1)[1] for name, _ in jit.compile_failures()] == [
        'twice', 'four_times']
    assert twice(1.5) == 3.0 and four_times(1.5) == 6.0 and twice.py_func is twice
    # A kernel that compiles still does.
    assert plus_one(1.0) == 2.0 and plus_one.py_func is not plus_one


def test_the_shipped_kernels_all_compile():
    """Where numba is installed at the pinned version, no kernel falls back."""
    pytest.importorskip('numba')
    import digital_actor_planner.core.actor  # noqa: F401
    import digital_actor_planner.core.upper_body  # noqa: F401
    from digital_actor_planner.core import jit
    assert jit.compile_failures() == ()


def test_a_numba_that_breaks_on_import_leaves_python_with_one_warning(tmp_path):
    # A numba built against another NumPy can fail on import with any error, not only
    # ImportError: the planner still imports, in plain Python, and says why once.
    broken = tmp_path / 'numba'
    broken.mkdir()
    (broken / '__init__.py').write_text(
        "raise AttributeError(\"module 'numpy' has no attribute 'long'\")\n")
    code = ('import warnings\n'
            'with warnings.catch_warnings(record=True) as caught:\n'
            '    warnings.simplefilter("always")\n'
            '    from digital_actor_planner.core import jit\n'
            'print(jit.COMPILED, [str(w.message) for w in caught\n'
            '                     if w.category is jit.KernelCompileWarning])\n')
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(tmp_path), os.path.dirname(HERE), os.environ.get('PYTHONPATH', '')]))
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                            env=env, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.startswith('False '), result.stdout
    assert result.stdout.count('could not be imported') == 1, result.stdout
    assert "has no attribute 'long'" in result.stdout and 'plain Python' in result.stdout
