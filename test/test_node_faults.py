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
The planner node as a real process under faults.

actor_planner as a real process under faults: its planning process stopped past the planning
timeout or killed, a large scene loading, a wrong cmd_vel type, Ctrl-C while starting.

One node process serves the module (planning_timeout 3 s, so that the test need not wait the
default minute). CI-proof: rclpy only, localhost discovery, own ROS_DOMAIN_ID, and every wait
is for a condition, with bounds sized for a loaded 2-core machine.
"""
import math
import os
import signal
import struct
import subprocess
import time

import numpy as np
import pytest
from ros_harness import fresh_domain_id, NodeProcess, ros_env, wait_until_importing
from test_node_helpers import node_command, Probe, ROOT_X, ROOT_Y, scene

pytestmark = [pytest.mark.ros, pytest.mark.slow]

DOMAIN_ID = int(os.environ['ACTOR_NODE_TEST_DOMAIN']) + 5 if 'ACTOR_NODE_TEST_DOMAIN' in \
    os.environ else fresh_domain_id()
PLANNING_TIMEOUT = 3.0


@pytest.fixture(scope='module')
def actor(tmp_path_factory):
    log = tmp_path_factory.mktemp('actor_faults') / 'node.log'
    process = NodeProcess(node_command('-p', f'scene:={scene("flat")}',
                                       '-p', f'planning_timeout:={PLANNING_TIMEOUT}'),
                          ros_env(DOMAIN_ID), log_path=str(log))
    # Without the RViz topics: the large scene's environment markers would keep the probe
    # busy for seconds, deaf to joint_states.
    probe = Probe(DOMAIN_ID, rviz=False)
    try:
        assert probe.wait_for_stream(process, 300.0), \
            f'no joint_states or no ready planner:\n{process.output()}'
        yield process, probe
    finally:
        probe.close()
        code = process.stop()
        assert code == 0, f'node exit status {code} after SIGINT:\n{process.output()}'


def _values(probe, key):
    return probe.diagnostic_values().get(key)


def _planning_pid(probe) -> int:
    assert probe.spin_until(lambda: _values(probe, 'planning_process_pid'), 10.0)
    return int(_values(probe, 'planning_process_pid'))


def _replaced(probe) -> int:
    return int(_values(probe, 'planning_processes_replaced') or 0)


def _advance(probe, seconds: float = 4.0) -> float:
    """Drive forward for ``seconds``; return the distance the root moved (m)."""
    before = probe.latest()
    probe.drive(0.5, 0.0, seconds)
    after = probe.latest()
    return math.hypot(after[ROOT_X] - before[ROOT_X], after[ROOT_Y] - before[ROOT_Y])


def _parameter(probe, name: str, timeout: float = 30.0):
    """(value, seconds the node took to answer) of a get_parameters call."""
    from rcl_interfaces.srv import GetParameters
    client = probe.node.create_client(GetParameters, '/actor_planner/get_parameters')
    try:
        assert client.wait_for_service(timeout_sec=timeout)
        asked = time.monotonic()
        future = client.call_async(GetParameters.Request(names=[name]))
        assert probe.spin_until(future.done, timeout), 'get_parameters gave no answer'
        value = future.result().values[0]
        return value.string_value or value.double_value, time.monotonic() - asked
    finally:
        probe.node.destroy_client(client)


def test_a_planning_process_stopped_past_its_timeout_is_replaced_and_a_scene_change_walks(
        actor):
    """
    A planning process frozen past the timeout does not mix its late replies into later plans.

    The planning process is frozen (SIGSTOP) past the planning timeout while the actor walks, then
    let go, then the scene is set to another course: the actor walks there (the frozen process's
    late replies must not be taken for the answers to later requests).
    """
    process, probe = actor
    assert _advance(probe, 2.0) > 0.2
    replaced, pid = _replaced(probe), _planning_pid(probe)
    os.kill(pid, signal.SIGSTOP)
    try:
        probe.drive(0.5, 0.0, PLANNING_TIMEOUT + 1.0)
        assert probe.spin_until(lambda: _replaced(probe) > replaced, 60.0), \
            probe.diagnostic_values()
    finally:
        try:
            os.kill(pid, signal.SIGCONT)
        except ProcessLookupError:
            pass  # killed as given up on
    assert process.alive(), process.output()
    result = probe.set_scene(scene('stairs_up'), timeout=120.0)
    assert result.successful, result.reason
    assert probe.spin_until(lambda: _values(probe, 'scene') == scene('stairs_up'), 10.0)
    assert _advance(probe, 5.0) > 0.5, probe.diagnostic_values()
    assert _values(probe, 'state') in ('walking', 'stuck'), probe.diagnostic_values()
    # Back on the flat course for the tests below.
    assert probe.set_scene(scene('flat'), timeout=120.0).successful


def test_a_killed_planning_process_is_replaced_and_the_actor_goes_on_from_where_it_stood(
        actor):
    process, probe = actor
    probe.drive(0.5, 0.0, 3.0)
    replaced, pid = _replaced(probe), _planning_pid(probe)
    killed_at = probe.latest()
    os.kill(pid, signal.SIGKILL)
    probe.drive(0.5, 0.0, 1.0)
    assert probe.spin_until(lambda: _replaced(probe) > replaced, 60.0), \
        probe.diagnostic_values()
    assert int(_values(probe, 'planning_process_pid')) != pid
    # The new process plans from the stance held, not from the course's start.
    assert probe.spin_until(lambda: probe.planner_ready() and _values(probe, 'state') not in
                            ('recovering',), 120.0), probe.diagnostic_values()
    resumed = probe.latest()
    assert abs(resumed[ROOT_X] - killed_at[ROOT_X]) < 1.0, (resumed[ROOT_X], killed_at[ROOT_X])
    assert _advance(probe, 4.0) > 0.5, probe.diagnostic_values()
    assert process.alive()


def _large_scene(folder) -> str:
    """Write a floor of 400k triangles (binary STL) as a scene file: seconds to load."""
    n = 448
    xs = np.linspace(-5.0, 25.0, n)
    ys = np.linspace(-5.0, 5.0, n)
    grid = np.stack(np.meshgrid(xs, ys, indexing='ij'), axis=-1)
    a, b = grid[:-1, :-1].reshape(-1, 2), grid[1:, :-1].reshape(-1, 2)
    c, d = grid[1:, 1:].reshape(-1, 2), grid[:-1, 1:].reshape(-1, 2)
    triangles = np.concatenate([np.stack([a, b, c], 1), np.stack([a, c, d], 1)])
    corners = np.concatenate([triangles, np.zeros(triangles.shape[:2] + (1,))], axis=2)
    records = np.zeros(len(corners), dtype=[('normal', '<f4', 3), ('corners', '<f4', (3, 3)),
                                            ('attribute', '<u2')])
    records['normal'][:, 2] = 1.0
    records['corners'] = corners
    mesh = folder / 'large_floor.stl'
    with open(mesh, 'wb') as stream:
        stream.write(b'\0' * 80 + struct.pack('<I', len(records)) + records.tobytes())
    path = folder / 'large.yaml'
    path.write_text('meshes: [{file: large_floor.stl}]\nstart: [0, 0, 0]\n')
    return str(path)


def _set_parameter(probe, name: str, value: float) -> None:
    """Set the node's double parameter ``name``; assert it was taken."""
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    client = probe.node.create_client(SetParameters, '/actor_planner/set_parameters')
    try:
        assert client.wait_for_service(timeout_sec=30.0)
        future = client.call_async(SetParameters.Request(parameters=[Parameter(
            name=name, value=ParameterValue(type=ParameterType.PARAMETER_DOUBLE,
                                            double_value=float(value)))]))
        assert probe.spin_until(future.done, 30.0), f'set_parameters {name} gave no answer'
        assert future.result().results[0].successful, future.result().results[0].reason
    finally:
        probe.node.destroy_client(client)


def _stamps(probe, since: float, until: float) -> np.ndarray:
    """Header stamps (s, wall clock) of the joint_states received, those in [since, until]."""
    stamps = np.array([m.header.stamp.sec + 1e-9 * m.header.stamp.nanosec
                       for _, m in list(probe.joint_states)])
    return stamps[(stamps >= since) & (stamps <= until)]


def _walked_from(probe, since: float, start=(0.0, 0.0)) -> float:
    """How far (m) the root went from ``start`` after standing there, in frames since ``since``."""
    rows = [m.position for t, m in list(probe.joint_states) if t >= since]
    at_start = [i for i, q in enumerate(rows)
                if math.hypot(q[ROOT_X] - start[0], q[ROOT_Y] - start[1]) < 0.1]
    if not at_start:
        return 0.0
    return max(math.hypot(q[ROOT_X] - start[0], q[ROOT_Y] - start[1])
               for q in rows[at_start[0]:])


def test_while_a_large_scene_loads_the_node_answers_and_streams_and_a_bad_one_is_refused(
        actor, tmp_path):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import GetParameters, SetParameters
    process, probe = actor
    large = _large_scene(tmp_path)
    old = _parameter(probe, 'scene')[0]
    cmd_timeout = _parameter(probe, 'cmd_timeout')[0]
    # Still, and a command kept current all through the load: the only walk command is one
    # sent while the scene loads (a teleop key pressed meanwhile).
    probe.command = (0.0, 0.0)
    _set_parameter(probe, 'cmd_timeout', 600.0)
    probe.spin(1.0)
    probe.command = None
    probe.spin(0.5)
    setter = probe.node.create_client(SetParameters, '/actor_planner/set_parameters')
    # One client for every poll: a new one each time would wait for the service without
    # spinning, and the probe's joint_states queue would overflow meanwhile.
    getter = probe.node.create_client(GetParameters, '/actor_planner/get_parameters')
    try:
        assert setter.wait_for_service(timeout_sec=30.0)
        assert getter.wait_for_service(timeout_sec=30.0)
        began_wall = time.time()
        future = setter.call_async(SetParameters.Request(parameters=[Parameter(
            name='scene', value=ParameterValue(type=ParameterType.PARAMETER_STRING,
                                               string_value=large))]))
        began = time.monotonic()
        probe.command = (0.5, 0.0)
        answers, old_answers = 0, 0
        while not future.done() and time.monotonic() < began + 300.0:
            asked = getter.call_async(GetParameters.Request(names=['scene']))
            assert probe.spin_until(asked.done, 60.0), 'get_parameters gave no answer'
            answers += 1
            # The parameter takes the new scene only once it is loaded: an answer naming
            # the old one was given while the load was in progress.
            old_answers += asked.result().values[0].string_value == old
            probe.spin(0.05)
        probe.command = None
        loaded, loaded_wall = time.monotonic(), time.time()
        assert future.done(), 'the large scene did not load'
        assert future.result().results[0].successful, future.result().results[0].reason
        loading = loaded - began
        # More than one: the first may have been answered before the load began.
        assert old_answers >= 3, (old_answers, answers, loading)

        # The stream went on while the scene loaded: every 10 ms tick in the load's span has
        # its frame (a frame is stamped within its own tick, the stamps only increase).
        stamps = _stamps(probe, began_wall, loaded_wall)
        assert len(stamps) >= 2 and np.all(np.diff(stamps) > 0.0), stamps
        period = 0.01
        ticks = int(round((stamps[-1] - stamps[0]) / period)) + 1
        missing = ticks - len(stamps)
        assert missing <= 0.1 * ticks + 2, \
            f'{missing} of {ticks} ticks missing while the scene loaded ' \
            f'(longest gap {np.diff(stamps).max():.3f} s)'

        # The command sent during the load is the one the actor walks on once loaded.
        assert probe.spin_until(lambda: _walked_from(probe, loaded) > 0.3, 120.0), \
            (loading, probe.diagnostic_values())
    finally:
        probe.node.destroy_client(getter)
        probe.node.destroy_client(setter)
        probe.command = (0.0, 0.0)
        probe.spin(1.0)
        _set_parameter(probe, 'cmd_timeout', cmd_timeout)
    assert probe.spin_until(lambda: _values(probe, 'scene') == large, 10.0)
    assert _advance(probe, 5.0) > 0.3, (loading, probe.diagnostic_values(), process.output())

    # A directory, a scene naming a missing mesh, a degenerate mesh, NaN vertices, a file that
    # is not a mesh and one too large for the memory: each refused naming the file and the
    # reason; the old scene stays, and the parameter keeps naming it.
    broken = tmp_path / 'broken.yaml'
    broken.write_text('meshes: [{file: missing_mesh.stl}]\n')
    (tmp_path / 'line.obj').write_text('v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n')
    (tmp_path / 'nan.obj').write_text('v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n')
    (tmp_path / 'words.stl').write_text('a mesh this is not\n' * 40)
    with open(tmp_path / 'huge.stl', 'wb') as huge:
        huge.truncate(1 << 40)  # sparse: a terabyte that takes no disk
    bad_scenes = ((str(tmp_path), 'is a directory'), (str(broken), 'missing_mesh.stl'),
                  (str(tmp_path / 'line.obj'), 'line.obj: degenerate mesh'),
                  (str(tmp_path / 'nan.obj'), 'not finite'),
                  (str(tmp_path / 'words.stl'), 'words.stl'),
                  (str(tmp_path / 'huge.stl'), 'GB available'))
    for bad, words in bad_scenes:
        result = probe.set_scene(bad)
        assert not result.successful
        assert words in result.reason, result.reason
        assert _parameter(probe, 'scene')[0] == large
    assert _advance(probe, 2.0) > 0.1
    assert probe.set_scene(scene('flat'), timeout=120.0).successful


def test_a_twist_publisher_on_a_stamped_cmd_vel_is_named_with_the_parameter_to_set(actor):
    from geometry_msgs.msg import Twist
    process, probe = actor
    # Its own context (a DDS participant): one participant cannot have both types on a topic.
    context = probe.rclpy.Context()
    context.init(domain_id=DOMAIN_ID)
    other = probe.rclpy.create_node('old_teleop', context=context)
    publisher = other.create_publisher(Twist, 'cmd_vel', 10)
    try:
        assert probe.spin_until(lambda: 'cmd_vel_stamped' in
                                (_values(probe, 'cmd_vel_type_mismatch') or ''), 30.0), \
            probe.diagnostic_values()
        assert 'geometry_msgs/msg/Twist' in _values(probe, '_message')
        assert 'cmd_vel_stamped' in process.output()
    finally:
        other.destroy_publisher(publisher)
        other.destroy_node()
        context.try_shutdown()
    assert probe.spin_until(lambda: not _values(probe, 'cmd_vel_type_mismatch'), 30.0)


def test_ctrl_c_right_after_start_exits_cleanly(tmp_path):
    for delay in (0.0, 0.5, 3.0):
        node = subprocess.Popen(node_command('-p', f'scene:={scene("flat")}'),
                                env=ros_env(fresh_domain_id()), stdout=subprocess.PIPE,
                                stderr=subprocess.STDOUT, text=True, start_new_session=True)
        try:
            assert wait_until_importing(node, 120.0), 'the node never began its imports'
            time.sleep(delay)  # the point is the moment of the signal, not a wait for a state
            os.kill(node.pid, signal.SIGINT)
            output, _ = node.communicate(timeout=60)
        finally:
            if node.poll() is None:
                os.killpg(node.pid, signal.SIGKILL)
                node.wait()
        assert node.returncode == 0, (delay, node.returncode, output)
        assert 'Traceback' not in output, output


def test_a_directory_as_scene_is_told_as_one_at_start(tmp_path):
    node = subprocess.run(node_command('-p', f'scene:={tmp_path}'),
                          env=ros_env(fresh_domain_id()), stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, text=True, timeout=300)
    assert node.returncode == 2, node.stdout
    assert 'is a directory' in node.stdout, node.stdout


def test_ctrl_c_while_a_large_scene_loads_exits_cleanly(tmp_path):
    from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
    from rcl_interfaces.srv import SetParameters
    domain = fresh_domain_id()
    process = NodeProcess(node_command('-p', f'scene:={scene("flat")}'), ros_env(domain),
                          log_path=str(tmp_path / 'node.log'))
    probe = Probe(domain, rviz=False)
    try:
        assert probe.wait_for_stream(process, 300.0), process.output()
        client = probe.node.create_client(SetParameters, '/actor_planner/set_parameters')
        assert client.wait_for_service(timeout_sec=30.0)
        future = client.call_async(SetParameters.Request(parameters=[Parameter(
            name='scene', value=ParameterValue(type=ParameterType.PARAMETER_STRING,
                                               string_value=_large_scene(tmp_path)))]))
        probe.spin(1.0)  # the load has begun (it takes seconds)
        assert not future.done(), 'the large scene loaded too fast to interrupt'
        os.kill(process.pid, signal.SIGINT)
        code = process.proc.wait(timeout=60.0)
    finally:
        probe.close()
        process.stop()
    assert code == 0, process.output()
    assert 'Traceback' not in process.output() and 'planning failed' not in process.output(), \
        process.output()
