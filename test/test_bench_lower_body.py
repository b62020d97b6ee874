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
The lower-body benchmark runs and gives what the README quotes from it.

The machine on the first line, and the footstep targets' verdict (``FootstepTargets``, printed
last): the default search's effort within the target of the exhaustive optimum's. Time ratios
depend on the machine: only a generous bound is asserted (one that a search judging most
configurations would break).
"""
import importlib.util
import os

import pytest

ROOT = os.path.join(os.path.dirname(os.path.abspath(__file__)), '..')
SCRIPT = os.path.join(ROOT, 'bench', 'bench_lower_body.py')


@pytest.fixture(scope='module')
def bench():
    spec = importlib.util.spec_from_file_location('bench_lower_body', SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope='module')
def stairs_run(bench):
    """Run the benchmark on the stairs up and the gap: (its printed lines, its verdict)."""
    import contextlib
    import io
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        targets = bench.main(['--courses', 'stairs_up', 'gap', '--walks', '1'])
    return printed.getvalue().strip().splitlines(), targets


def test_the_first_line_names_the_machine(stairs_run):
    first = stairs_run[0][0]
    assert first.startswith('load average '), first
    assert f'{os.cpu_count()} CPUs' in first, first


def test_the_footstep_targets_are_met_and_printed_last(stairs_run):
    lines, targets = stairs_run
    assert lines[-1] == targets.sentence()
    # The stairs up and the gap: 16 walking steps each, a window planned for every one.
    assert targets.windows == 32
    assert targets.effort_mean <= 1.05 and targets.effort_p95 <= 1.05 and targets.effort_met
    assert targets.time_met == (targets.time_p95 <= 0.05)
    # Generous: the search judges well under 2 % of the configurations on these windows.
    assert targets.time_p95 < 0.5 and targets.ours_ms / targets.exhaustive_ms < 0.3
