"""actor_planner with a bad configuration exits non-zero and names the parameter."""
import os
import subprocess

import pytest
from ros_harness import ros_env
from test_node_helpers import node_command, scene

pytestmark = [pytest.mark.ros]

DOMAIN_ID = int(os.environ.get('ACTOR_NODE_TEST_DOMAIN', '31')) + 2


def _broken_scene(folder):
    path = folder / 'broken.yaml'
    path.write_text('meshes: [{file: no_such_mesh.stl}]\n')
    return str(path)


CASES = [
    ('publish_rate', ['-p', 'publish_rate:=0.5']),
    ('publish_rate', ['-p', 'publish_rate:=fast']),
    ('window_steps', ['-p', 'window_steps:=0']),
    ('step_intervals', ['-p', 'step_intervals:=1']),
    ('step_length_min', ['-p', 'step_length_min:=0.9', '-p', 'step_length_max:=0.8']),
    ('max_linear_speed', ['-p', 'max_linear_speed:=-1.0']),
    ('cmd_timeout', ['-p', 'cmd_timeout:=0.0']),
    ('start_pose', ['-p', 'start_pose:=[1.0, 2.0]']),
    ('frame_id', ['-p', 'frame_id:=""']),
    ('scene', ['-p', 'scene:=/no/such/scene.yaml']),
    ('scene', 'broken'),
]


@pytest.mark.parametrize('parameter, arguments', CASES,
                         ids=[f'{name}-{i}' for i, (name, _) in enumerate(CASES)])
def test_bad_parameter_exits_non_zero_naming_it(parameter, arguments, tmp_path):
    if arguments == 'broken':
        arguments = ['-p', f'scene:={_broken_scene(tmp_path)}']
    result = subprocess.run(node_command(*arguments), env=ros_env(DOMAIN_ID),
                            capture_output=True, text=True, timeout=120)
    output = result.stdout + result.stderr
    assert result.returncode != 0, output
    assert parameter in output, output
    assert 'Traceback' not in output, output


def test_start_pose_without_ground_is_rejected(tmp_path):
    arguments = ['-p', f'scene:={scene("flat")}', '-p', 'start_pose:=[500.0, 500.0, 0.0]']
    result = subprocess.run(node_command(*arguments), env=ros_env(DOMAIN_ID),
                            capture_output=True, text=True, timeout=120)
    output = result.stdout + result.stderr
    assert result.returncode != 0, output
    assert 'start_pose' in output, output
