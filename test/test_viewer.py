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
Unit tests of the viewer helpers.

Unit tests of the viewer helpers: drag mapping, status line, diagnostics, courses, follow camera,
port.
"""
import glob
import math
import os
import socket
import subprocess
import sys

from diagnostic_msgs.msg import DiagnosticStatus, KeyValue
from digital_actor_planner.nodes.viewer_page import (along_view_plane, build_parser,
                                                     config_from_args, course_catalog,
                                                     drag_to_command, follow_target,
                                                     normalize_namespace, pad_pose,
                                                     parse_planner_diagnostics, pick_port,
                                                     shipped_scenes, smooth_step, status_text,
                                                     StreamMonitor, triangle_list_mesh, validate,
                                                     ViewerConfig)
import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_drag_up_walks_forward_and_left_turns_left():
    # Screen y grows downward: dragging up is a negative dy (mouse_teleop convention).
    lin, ang = drag_to_command((100, 300), (100, 250), span=100, max_linear_speed=0.8,
                               max_angular_speed=1.0)
    assert lin == pytest.approx(0.4) and ang == pytest.approx(0.0)
    lin, ang = drag_to_command((100, 300), (50, 300), span=100, max_linear_speed=0.8,
                               max_angular_speed=1.0)
    assert lin == pytest.approx(0.0) and ang == pytest.approx(0.5)
    lin, ang = drag_to_command((100, 300), (180, 360), span=100, max_linear_speed=0.8,
                               max_angular_speed=1.0)
    assert lin == pytest.approx(-0.6 * 0.8) and ang == pytest.approx(-0.8)


def test_drag_down_walks_backward_at_the_planners_backward_limit():
    # The whole lower half of the pad is used: a full downward drag is the backward limit, not
    # the forward one (which the planner would clamp).
    lin, _ = drag_to_command((100, 300), (100, 400), span=100, max_linear_speed=1.2,
                             max_angular_speed=1.0, max_backward_speed=0.5)
    assert lin == pytest.approx(-0.5)
    lin, _ = drag_to_command((100, 300), (100, 350), span=100, max_linear_speed=1.2,
                             max_angular_speed=1.0, max_backward_speed=0.5)
    assert lin == pytest.approx(-0.25)
    lin, _ = drag_to_command((100, 300), (100, 200), span=100, max_linear_speed=1.2,
                             max_angular_speed=1.0, max_backward_speed=0.5)
    assert lin == pytest.approx(1.2)
    # A forward-only planner (backward limit 0): a downward drag stands still.
    lin, _ = drag_to_command((100, 300), (100, 400), span=100, max_linear_speed=1.2,
                             max_angular_speed=1.0, max_backward_speed=0.0)
    assert lin == 0.0


def test_drag_is_clamped_to_the_maximum_speeds():
    lin, ang = drag_to_command((0, 0), (-1000, -1000), span=100, max_linear_speed=0.8,
                               max_angular_speed=1.2)
    assert (lin, ang) == (pytest.approx(0.8), pytest.approx(1.2))


@pytest.mark.parametrize('kwargs, word', [
    ({'span': 0.0}, 'span'),
    ({'span': float('nan')}, 'span'),
    ({'max_linear_speed': -1.0}, 'max_linear_speed'),
    ({'max_angular_speed': float('inf')}, 'max_angular_speed'),
    ({'max_backward_speed': -0.5}, 'max_backward_speed'),
])
def test_drag_bad_input_names_the_value(kwargs, word):
    args = {'span': 100.0, 'max_linear_speed': 0.8, 'max_angular_speed': 1.0}
    args.update(kwargs)
    with pytest.raises(ValueError, match=word):
        drag_to_command((0, 0), (0, -10), **args)


def _status(state, reason='', planning='2.500', hardware_id='/actor_planner', published='98.00'):
    values = [KeyValue(key='state', value=state), KeyValue(key='reason', value=reason),
              KeyValue(key='planning_time_p99_ms', value='9.000'),
              KeyValue(key='planning_time_last_ms', value=planning),
              KeyValue(key='publish_rate_hz', value=published)]
    return DiagnosticStatus(name=f'{hardware_id}: actor planner', hardware_id=hardware_id,
                            message=state, values=values)


def test_diagnostics_of_the_planner_in_the_namespace_are_picked():
    other = _status('walking', hardware_id='/other/actor_planner')
    mine = _status('stuck', 'no feasible footstep', hardware_id='/a/actor_planner')
    parsed = parse_planner_diagnostics([other, mine], '/a/actor_planner')
    assert parsed.state == 'stuck'
    assert parsed.reason == 'no feasible footstep'
    assert parsed.planning_time_ms == pytest.approx(2.5)
    assert parse_planner_diagnostics([other], '/a/actor_planner') is None


def test_status_line_waiting_walking_stuck_and_planner_gone():
    stream = StreamMonitor(window=1.0)
    assert status_text(0.0, stream, None, planner_present=False).startswith(
        'waiting for joint_states')
    for k in range(101):
        stream.add(10.0 + k * 0.01)
    walking = parse_planner_diagnostics([_status('walking')], '/actor_planner')
    text = status_text(11.0, stream, walking, planner_present=True)
    assert 'walking' in text and 'planning 2.5 ms' in text
    # What arrives here and what the planner sent, each labelled.
    assert 'received 100 Hz of 98 Hz published' in text
    stuck = parse_planner_diagnostics(
        [_status('stuck', 'no collision-free footstep window')], '/actor_planner')
    text = status_text(11.0, stream, stuck, planner_present=True)
    assert text.startswith('stuck: no room for the next steps ahead')
    assert 'turn on the spot (drag sideways) or step back (drag down)' in text
    assert 'collision-free' not in text
    gone = status_text(14.0, stream, stuck, planner_present=False)
    assert gone.startswith('planner stopped') and '3.0 s' in gone


@pytest.mark.parametrize('reason, words', [
    ('upper body blocked: waist blocked at t=0.19 s', 'upper body cannot get past'),
    ('the legs cannot take the step: the other foot could not follow (knee)',
     'legs cannot reach'),
    ('the legs would touch the environment: the left shank would be 3 mm into an obstacle',
     'would hit the obstacle'),
    ('something new', 'not possible here'),
])
def test_every_stuck_reason_comes_with_what_to_do(reason, words):
    stream = StreamMonitor(window=1.0)
    stream.add(0.0)
    stream.add(0.01)
    stuck = parse_planner_diagnostics([_status('stuck', reason)], '/actor_planner')
    text = status_text(0.02, stream, stuck, planner_present=True)
    assert words in text and 'turn on the spot' in text and 'step back' in text


def test_warming_up_is_said_and_what_it_means():
    stream = StreamMonitor(window=1.0)
    stream.add(0.0)
    stream.add(0.01)
    warming = parse_planner_diagnostics([_status('warming up', published='nan')],
                                        '/actor_planner')
    text = status_text(0.02, stream, warming, planner_present=True)
    assert text.startswith('warming up') and 'compiling' in text
    assert 'published' not in text, 'an unknown published rate is not shown as a number'
    silent = StreamMonitor(window=1.0)
    text = status_text(0.02, silent, warming, planner_present=True)
    assert text.startswith('warming up') and 'compiling' in text


def test_every_shipped_course_is_offered():
    scenes = shipped_scenes()
    on_disk = glob.glob(os.path.join(REPO, 'config', 'scenes', '*.yaml'))
    assert sorted(scenes) == sorted(os.path.splitext(os.path.basename(p))[0] for p in on_disk)
    assert all(os.path.isabs(p) and os.path.isfile(p) for p in scenes.values())
    assert 'wall' in scenes


def test_courses_show_their_descriptions_and_the_impassable_ones_are_marked():
    courses = course_catalog()
    assert sorted(courses) == sorted(shipped_scenes())
    for course in courses.values():
        assert course.description, f'{course.name} has no description'
        assert course.description.split()[0] in course.about()
    impassable = sorted(name for name, course in courses.items() if course.impassable)
    assert impassable == ['beam_too_low', 'wall']
    assert courses['wall'].label != 'wall' and 'impassable' in courses['wall'].label
    assert 'stop' in courses['wall'].about()
    assert courses['flat'].label == 'flat'


def test_a_course_file_that_cannot_be_read_is_still_offered(tmp_path):
    (tmp_path / 'broken.yaml').write_text('description: [unclosed\n')
    (tmp_path / 'plain.yaml').write_text('description: a plain course\nexpect: {stuck: true}\n')
    courses = course_catalog(str(tmp_path))
    assert courses['broken'].description == '' and 'No description' in courses['broken'].about()
    assert courses['plain'].impassable


def _screen_u(point, camera, look_at, fov, aspect):
    forward = np.asarray(look_at) - np.asarray(camera)
    forward /= np.linalg.norm(forward)
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    offset = np.asarray(point) - np.asarray(camera)
    return 0.5 + 0.5 * (offset @ right) / (offset @ forward) / (math.tan(fov / 2) * aspect)


def test_follow_camera_keeps_the_actor_left_of_the_panel():
    camera, look_at = np.array([-3.0, 3.0, 2.4]), np.array([0.0, 0.0, 0.9])
    fov, aspect = math.radians(50.0), 1.5
    actor = np.array([2.0, 0.3, 0.9])
    goal = follow_target(actor, camera, look_at, fov, aspect, screen_u=0.36)
    moved_camera = camera + (goal - look_at)
    assert _screen_u(actor, moved_camera, goal, fov, aspect) == pytest.approx(0.36, abs=1e-6)
    centred = follow_target(actor, camera, look_at, fov, aspect, screen_u=0.5)
    assert centred == pytest.approx(actor)


def test_during_a_drag_the_camera_keeps_its_distance_to_the_pad():
    # The pad (and viser's drag plane) faces the camera half a metre ahead of it.
    view = np.array([0.7, -0.6, -0.3])
    move = along_view_plane(np.array([0.4, 0.1, 0.0]), view)
    assert move @ view == pytest.approx(0.0, abs=1e-12)
    assert np.linalg.norm(move) > 0.1, 'the sideways part of the move is kept'


def test_follow_camera_glides_and_does_not_overshoot():
    current, target = np.zeros(3), np.array([1.0, 0.0, 0.0])
    path = []
    for _ in range(40):
        current = smooth_step(current, target, dt=0.05, time_constant=0.35)
        path.append(current[0])
    assert 0.0 < path[0] < 0.3, 'one render tick moves only part of the way'
    assert all(b >= a for a, b in zip(path, path[1:])) and path[-1] <= 1.0
    assert path[-1] > 0.99, 'two seconds later the camera is there'


def test_a_port_just_released_is_reused():
    # The side that closes first keeps the port in TIME_WAIT, as a stopped viewer does.
    with socket.socket() as server:
        server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        server.bind(('127.0.0.1', 0))
        server.listen(1)
        port = server.getsockname()[1]
        client = socket.create_connection(('127.0.0.1', port))
        accepted, _ = server.accept()
        accepted.close()
    client.close()
    assert pick_port('127.0.0.1', port) == port


def test_busy_port_moves_to_the_next_free_one():
    with socket.socket() as holder:
        holder.bind(('127.0.0.1', 0))
        holder.listen(1)
        busy = holder.getsockname()[1]
        chosen = pick_port('127.0.0.1', busy)
        assert chosen != busy and chosen > busy
    with pytest.raises(ValueError, match='70000'):
        pick_port('127.0.0.1', 70000)


def test_triangle_list_becomes_a_mesh_and_bad_lists_are_named():
    points = np.arange(18, dtype=float).reshape(6, 3)
    vertices, faces = triangle_list_mesh(points)
    assert vertices.shape == (6, 3) and faces.tolist() == [[0, 1, 2], [3, 4, 5]]
    with pytest.raises(ValueError, match=r'\(4, 3\)'):
        triangle_list_mesh(np.zeros((4, 3)))


def test_pad_sits_where_it_is_drawn_on_screen():
    # Camera at the origin looking along +x (OpenCV axes: z forward, y down, x right).
    rotation = np.array([[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]])
    w = math.sqrt(1.0 + np.trace(rotation)) / 2.0
    wxyz = np.array([w, (rotation[2, 1] - rotation[1, 2]) / (4 * w),
                     (rotation[0, 2] - rotation[2, 0]) / (4 * w),
                     (rotation[1, 0] - rotation[0, 1]) / (4 * w)])
    center = pad_pose(np.zeros(3), wxyz, fov=math.pi / 2, aspect=1.0, screen_uv=(0.5, 0.5),
                      depth=2.0)
    assert center == pytest.approx([2.0, 0.0, 0.0])
    lower_left = pad_pose(np.zeros(3), wxyz, fov=math.pi / 2, aspect=1.0,
                          screen_uv=(0.0, 1.0), depth=1.0)
    # Left of the view is +y (world), the bottom is -z.
    assert lower_left == pytest.approx([1.0, 1.0, -1.0])


def test_options_and_namespace_are_checked():
    config = config_from_args(build_parser().parse_args(['--port', '9000', '--twist']))
    assert config.port == 9000 and not config.cmd_vel_stamped
    assert config.host == '127.0.0.1'
    with pytest.raises(ValueError, match='render_rate'):
        validate(ViewerConfig(render_rate=0.0))
    with pytest.raises(ValueError, match='port'):
        validate(ViewerConfig(port=0))
    assert normalize_namespace('') == '/'
    assert normalize_namespace('actor1/') == '/actor1'
    with pytest.raises(ValueError, match='a-b'):
        normalize_namespace('a-b')


def test_the_page_logic_loads_without_ros_or_viser():
    # The demo and the warm-up use it before any node runs: they must not wait for rclpy and
    # viser to load, nor need them.
    code = ('import sys\n'
            "for name in ('rclpy', 'viser', 'diagnostic_msgs', 'geometry_msgs', 'nav_msgs',\n"
            "             'rcl_interfaces', 'sensor_msgs', 'std_msgs', 'visualization_msgs'):\n"
            '    sys.modules[name] = None\n'
            'import digital_actor_planner.demo\n'
            'import digital_actor_planner.nodes.viewer_page\n'
            'import digital_actor_planner.warmup\n')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
