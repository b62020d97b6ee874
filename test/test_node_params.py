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

"""actor_planner with a bad configuration exits non-zero and names the parameter."""
import os
import subprocess

import pytest
from ros_harness import fresh_domain_id, ros_env
from test_node_helpers import node_command

pytestmark = [pytest.mark.ros]

# ACTOR_NODE_TEST_DOMAIN pins the domain (e.g. to a range of your own); by default each
# module takes a fresh one, so runs started side by side do not hear each other.
DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 2 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()


CASES = [
    ('publish_rate', ['-p', 'publish_rate:=0.5']),
    ('publish_rate', ['-p', 'publish_rate:=fast']),
    ('window_steps', ['-p', 'window_steps:=0']),
    ('step_intervals', ['-p', 'step_intervals:=0']),
    ('step_length_min', ['-p', 'step_length_min:=0.9', '-p', 'step_length_max:=0.8']),
    ('max_linear_speed', ['-p', 'max_linear_speed:=-1.0']),
    ('cmd_timeout', ['-p', 'cmd_timeout:=0.0']),
    ('start_pose', ['-p', 'start_pose:=[1.0, 2.0]']),
    ('frame_id', ['-p', 'frame_id:=""']),
    ('scene', ['-p', 'scene:=/no/such/scene.yaml']),
    ('scene', 'broken'),
    ('start_pose', ['-p', 'start_pose:=[500.0, 500.0, 0.0]']),  # no ground there
]

# Values past the declared range or a rule between parameters: exit status 2, naming the
# parameter and the value (the range the descriptor states is the one the core checks).
VALUE_CASES = [
    ('step_length_max', '1.5', ['-p', 'step_length_max:=1.5']),
    ('window_steps', '9', ['-p', 'window_steps:=9']),
    ('step_intervals', '61', ['-p', 'step_intervals:=61']),
    ('max_angular_speed', '0.0', ['-p', 'max_angular_speed:=0.0']),
    ('max_backward_speed', '1.5', ['-p', 'max_backward_speed:=1.5']),
]


@pytest.fixture(scope='module')
def runs(tmp_path_factory):
    """Start every bad configuration at once (node start-up is mostly imports) and collect."""
    folder = tmp_path_factory.mktemp('bad_parameters')
    broken = folder / 'broken.yaml'
    broken.write_text('meshes: [{file: no_such_mesh.stl}]\n')
    processes = []
    for _, arguments in CASES + [(name, arguments) for name, _, arguments in VALUE_CASES]:
        if arguments == 'broken':
            arguments = ['-p', f'scene:={broken}']
        processes.append(subprocess.Popen(node_command(*arguments), env=ros_env(DOMAIN_ID),
                                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                          text=True, start_new_session=True))
    results = []
    try:
        for process in processes:
            output, _ = process.communicate(timeout=300)
            results.append((process.returncode, output))
    finally:
        for process in processes:
            if process.poll() is None:
                process.kill()
                process.wait()
    return results


@pytest.mark.parametrize('case', range(len(CASES)),
                         ids=[f'{name}-{i}' for i, (name, _) in enumerate(CASES)])
def test_bad_parameter_exits_non_zero_naming_it(case, runs):
    parameter = CASES[case][0]
    returncode, output = runs[case]
    assert returncode != 0, output
    # The exit status too: under heavy load a run can exit non-zero with no output at all.
    assert f"parameter '{parameter}'" in output, (returncode, output)
    assert 'Traceback' not in output, output


@pytest.mark.parametrize('case', range(len(VALUE_CASES)),
                         ids=[f'{name}-{value}' for name, value, _ in VALUE_CASES])
def test_value_out_of_range_exits_2_naming_parameter_and_value(case, runs):
    parameter, value, _ = VALUE_CASES[case]
    returncode, output = runs[len(CASES) + case]
    assert returncode == 2, output
    message = next((line for line in output.splitlines() if 'invalid configuration' in line), '')
    assert f"parameter '{parameter}'" in message, output
    assert value in message.split(f"parameter '{parameter}'", 1)[1], output
    assert 'Traceback' not in output, output
