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
Probe for the actor_planner process tests, and tests of the node's ROS-free pieces.

The probe is an rclpy node in the test process, in its own context and ROS_DOMAIN_ID, that
sends cmd_vel like a mouse teleop (a steady 20 Hz stream) and records joint_states,
/diagnostics and robot_description.
"""
import collections
import math
import os
import sys
import threading
import time

from digital_actor_planner.core.skeleton import Skeleton
import numpy as np
import pytest

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(REPO, 'config', 'scenes')
JOINT_NAMES = tuple(Skeleton().joint_names)
ROOT_X, ROOT_Y, ROOT_YAW = (JOINT_NAMES.index(n) for n in ('root_x', 'root_y', 'root_yaw'))


def scene(name: str) -> str:
    """Path of a shipped course, ``name`` without .yaml."""
    return os.path.join(SCENES, name + '.yaml')


def node_command(*ros_args: str, executable: str = None) -> list:
    """
    Command line that starts actor_planner, with ros args.

    The venv's console script by default; ``executable`` or the environment variable
    ``ACTOR_PLANNER_EXECUTABLE`` (e.g. a colcon install's ``lib/digital_actor_planner/
    actor_planner``) override it.
    """
    script = executable or os.environ.get('ACTOR_PLANNER_EXECUTABLE') or \
        os.path.join(sys.prefix, 'bin', 'actor_planner')
    base = [script] if os.path.exists(script) else \
        [sys.executable, '-m', 'digital_actor_planner.nodes.actor_planner']
    return base + ['--ros-args', *ros_args]


class Probe:
    """A test-side rclpy node that talks to one actor_planner (optionally namespaced)."""

    def __init__(self, domain_id: int, namespace: str = '', stamped: bool = True,
                 rviz: bool = True):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy, QoSProfile
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Twist, TwistStamped
        from nav_msgs.msg import Path
        from sensor_msgs.msg import JointState
        from visualization_msgs.msg import MarkerArray
        from std_msgs.msg import String

        os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
        self.rclpy = rclpy
        self.context = rclpy.Context()
        self.context.init(domain_id=domain_id)
        self.node = rclpy.create_node(f'probe_{os.getpid()}', namespace=namespace or '/',
                                      context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        # The latest frames (a long run keeps only the newest); ``received`` counts them all,
        # so a count compared across a long run keeps growing.
        self.joint_states = collections.deque(maxlen=20000)
        self.received = 0
        self.diagnostics = collections.deque(maxlen=100)
        self.descriptions = []
        self.stamped = stamped
        self._types = (TwistStamped, Twist)
        self.node.create_subscription(JointState, 'joint_states', self._on_joint_state, 100)
        self.node.create_subscription(DiagnosticArray, '/diagnostics',
                                      lambda msg: self.diagnostics.append(msg),
                                      10)
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(String, 'robot_description',
                                      lambda msg: self.descriptions.append(msg),
                                      latched)
        self.cmd_pub = self.node.create_publisher(TwistStamped if stamped else Twist,
                                                  'cmd_vel', 10)
        # The RViz topics of the node named actor_planner in this namespace: latest of each
        # (when ``rviz``: a large environment takes the probe ~1 s to take in).
        self.rviz = {}
        for topic, kind in (('environment', MarkerArray), ('markers', MarkerArray),
                            ('path', Path)) if rviz else ():
            self.node.create_subscription(
                kind, f'actor_planner/{topic}',
                lambda msg, topic=topic: self.rviz.__setitem__(topic, msg), latched)
        self.command = None
        self.node.create_timer(0.05, self._send_command)
        self._lock = threading.Lock()

    def _on_joint_state(self, msg) -> None:
        self.joint_states.append((time.monotonic(), msg))
        self.received += 1

    def _send_command(self) -> None:
        if self.command is None:
            return
        linear_x, angular_z = self.command
        TwistStamped, Twist = self._types
        if self.stamped:
            msg = TwistStamped()
            msg.header.stamp = self.node.get_clock().now().to_msg()
            twist = msg.twist
        else:
            msg = twist = Twist()
        twist.linear.x, twist.angular.z = float(linear_x), float(angular_z)
        self.cmd_pub.publish(msg)

    def spin(self, seconds: float) -> None:
        """Process callbacks for ``seconds``."""
        deadline = time.monotonic() + seconds
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=min(0.02, max(0.0, deadline - time.monotonic())))

    def spin_until(self, predicate, timeout: float) -> bool:
        """Process callbacks until ``predicate()`` holds or ``timeout`` s pass."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.executor.spin_once(timeout_sec=0.02)
            if predicate():
                return True
        return bool(predicate())

    def wait_for_stream(self, process=None, timeout: float = 30.0, ready: bool = True) -> bool:
        """
        Wait until the actor streams and sees our publisher, and optionally until it is ready.

        Wait until the actor's joint_states arrive and it sees our cmd_vel publisher, and
        (``ready``) until its planner has placed the actor (diagnostics no longer say "warming
        up").

        Gives up early when ``process`` (a NodeProcess) exits.
        """
        def done():
            return len(self.joint_states) > 5 and self.cmd_pub.get_subscription_count() > 0 \
                and (not ready or self.planner_ready())

        self.spin_until(lambda: done() or (process is not None and not process.alive()),
                        timeout)
        return done()

    def planner_ready(self) -> bool:
        """Whether the latest diagnostics say the planner is past warming up."""
        state = self.diagnostic_values().get('state')
        return state is not None and state != 'warming up'

    def stamps_after(self, stamp_ns: int) -> list:
        """Distinct header stamps (ns, ascending) of the frames kept stamped after ``stamp_ns``."""
        stamps = set()
        for _, msg in reversed(self.joint_states):
            stamp = msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec
            if stamp <= stamp_ns:
                break
            stamps.add(stamp)
        return sorted(stamps)

    def latest(self) -> np.ndarray:
        """Return the latest received configuration (22,)."""
        return np.array(self.joint_states[-1][1].position)

    def positions_since(self, since: float) -> tuple:
        """Receipt times (k,) and configurations (k, 22) received after monotonic ``since``."""
        rows = [(t, m.position) for t, m in list(self.joint_states) if t >= since]
        return np.array([r[0] for r in rows]), np.array([r[1] for r in rows])

    def drive(self, linear_x: float, angular_z: float, seconds: float) -> float:
        """Send a command stream for ``seconds``; return the monotonic time it started."""
        started = time.monotonic()
        self.command = (linear_x, angular_z)
        self._send_command()
        self.spin(seconds)
        return started

    def wait_until_still(self, timeout: float, still_for: float = 1.0,
                         tolerance: float = 2e-3) -> float:
        """
        Spin until the root stays within ``tolerance`` m/rad for ``still_for`` s.

        Returns
        -------
        float
            Monotonic receipt time of the first frame of the still period (inf on timeout).

        """
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self.spin(0.1)
            times, frames = self.positions_since(time.monotonic() - still_for - 0.2)
            if len(times) < 2 or times[-1] - times[0] < still_for:
                continue
            root = frames[:, [ROOT_X, ROOT_Y, ROOT_YAW]]
            moving = np.nonzero(np.any(np.abs(root - root[-1]) > tolerance, axis=1))[0]
            first_still = 0 if len(moving) == 0 else moving[-1] + 1
            if times[-1] - times[first_still] >= still_for:
                return float(times[first_still])
        return math.inf

    def diagnostic_values(self) -> dict:
        """Key/values of the latest actor planner diagnostic status (empty when none)."""
        for array in reversed(self.diagnostics):
            for status in array.status:
                if 'actor planner' in status.name:
                    values = {kv.key: kv.value for kv in status.values}
                    values['_level'] = int.from_bytes(status.level, 'little') \
                        if isinstance(status.level, bytes) else int(status.level)
                    values['_message'] = status.message
                    values['_name'] = status.name
                    return values
        return {}

    def set_scene(self, path: str, node: str = '/actor_planner', timeout: float = 120.0):
        """
        Set ``node``'s ``scene`` parameter; return the SetParametersResult.

        Raises AssertionError when the service does not appear or answer within ``timeout`` s.
        """
        from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
        from rcl_interfaces.srv import SetParameters
        client = self.node.create_client(SetParameters, f'{node}/set_parameters')
        try:
            assert client.wait_for_service(timeout_sec=timeout), f'{node}/set_parameters'
            request = SetParameters.Request(parameters=[Parameter(
                name='scene', value=ParameterValue(type=ParameterType.PARAMETER_STRING,
                                                   string_value=path))])
            future = client.call_async(request)
            assert self.spin_until(future.done, timeout), f'{node}/set_parameters timed out'
            return future.result().results[0]
        finally:
            self.node.destroy_client(client)

    def close(self) -> None:
        """Destroy the probe node and its context."""
        self.executor.shutdown()
        self.node.destroy_node()
        self.context.try_shutdown()


# -- tests of the node's ROS-free pieces -------------------------------------------------------
def test_frame_buffer_interpolates_and_holds_the_last_frame():
    from digital_actor_planner.runtime.frame_buffer import FrameBuffer
    q0 = np.zeros(22)
    buffer = FrameBuffer(q0)
    times = np.array([0.01, 0.02])
    frames = np.zeros((2, 22))
    frames[:, ROOT_X] = [0.1, 0.2]
    velocities = np.full((2, 22), 10.0)
    buffer.append(times, frames, velocities, now=0.0)
    q, v = buffer.sample(0.015)
    assert q[ROOT_X] == pytest.approx(0.15)
    assert v[ROOT_X] == pytest.approx(10.0)
    q, v = buffer.sample(5.0)
    assert q[ROOT_X] == pytest.approx(0.2)
    assert np.all(v == 0.0)
    with pytest.raises(ValueError, match='0.0100'):
        buffer.append(times, frames, velocities, now=0.0)


def test_frame_buffer_restart_jumps_to_the_new_configuration():
    from digital_actor_planner.runtime.frame_buffer import FrameBuffer
    buffer = FrameBuffer(np.zeros(22))
    frames = np.zeros((10, 22))
    frames[:, ROOT_X] = np.arange(10)
    buffer.append(0.1 * np.arange(1, 11), frames, np.zeros((10, 22)), now=0.0)
    fresh = np.full(22, 7.0)
    buffer.restart(fresh, 0.35)
    assert buffer.end_time == pytest.approx(0.35)
    assert buffer.sample(0.35)[0][ROOT_X] == 7.0
    assert buffer.sample(0.2)[0][ROOT_X] == pytest.approx(1.0)


def test_frame_buffer_restart_blends_from_the_pose_held_and_refuses_a_wrong_shape():
    from digital_actor_planner.runtime.frame_buffer import FrameBuffer
    buffer = FrameBuffer(np.zeros(22))
    frames = np.zeros((10, 22))
    frames[:, ROOT_X] = np.arange(10)
    buffer.append(0.1 * np.arange(1, 11), frames, np.zeros((10, 22)), now=0.0)
    fresh = np.full(22, 7.0)
    buffer.restart(fresh, 1.5, blend_from=1.0)
    assert buffer.sample(0.5)[0][ROOT_X] == pytest.approx(4.0)  # kept as it was
    assert buffer.sample(1.0)[0][ROOT_X] == pytest.approx(9.0)  # held at the last frame
    halfway, speed = buffer.sample(1.25)
    assert halfway[ROOT_X] == pytest.approx(8.0)
    assert -4.0 <= speed[ROOT_X] < 0.0  # towards the new pose, at most (7 - 9) m over 0.5 s
    assert np.array_equal(buffer.sample(2.0)[0], fresh)
    with pytest.raises(ValueError, match=r'\(1, 22\)'):
        buffer.restart(fresh[None, :], 3.0)


def test_frame_buffer_truncate_drops_the_motion_not_yet_begun():
    from digital_actor_planner.runtime.frame_buffer import FrameBuffer
    buffer = FrameBuffer(np.zeros(22))
    frames = np.zeros((10, 22))
    frames[:, ROOT_X] = np.arange(1, 11)
    buffer.append(0.1 * np.arange(1, 11), frames, np.zeros((10, 22)), now=0.0)
    buffer.truncate(0.55)
    assert buffer.end_time == pytest.approx(0.5)
    assert buffer.sample(2.0)[0][ROOT_X] == pytest.approx(5.0)
    buffer.truncate(-1.0)
    assert buffer.end_time == 0.0  # the first frame stays


def _binary_stl(path, z: float) -> None:
    """Write a 20 m x 20 m square at height ``z`` (m), two triangles, binary STL."""
    import struct
    corners = np.array([[[-10, -10, z], [10, -10, z], [10, 10, z]],
                        [[-10, -10, z], [10, 10, z], [-10, 10, z]]], dtype='<f4')
    records = b''.join(struct.pack('<3f', 0, 0, 1) + c.tobytes() + b'\0\0' for c in corners)
    path.write_bytes(b'\0' * 80 + struct.pack('<I', 2) + records)


def test_the_stand_in_pose_stands_on_the_scene_start(tmp_path):
    """
    The pose streamed while the planner warms up stands on the scene's start.

    The pose streamed while the planner warms up: the scene's start pose, on the lowest surface
    under it (a platform posed up in the YAML), or on height 0 where the mesh cannot be read
    without a mesh library.
    """
    from digital_actor_planner.runtime.standing import stand_in_configuration
    skeleton = Skeleton()
    _binary_stl(tmp_path / 'platform.stl', 0.1)
    (tmp_path / 'raised.yaml').write_text(
        'meshes: [{file: platform.stl, pose: [0, 0, 0.4, 0, 0, 0]}]\nstart: [1.5, -2.0, 0.7]\n')
    q = stand_in_configuration(skeleton, str(tmp_path / 'raised.yaml'), None)
    index = skeleton.index
    assert (q[index['root_x']], q[index['root_y']], q[index['root_yaw']]) == (1.5, -2.0, 0.7)
    assert q[index['root_z']] == pytest.approx(0.5 + skeleton.leg.standing_height + 0.002,
                                               abs=1e-6)
    q = stand_in_configuration(skeleton, str(tmp_path / 'raised.yaml'), (30.0, 0.0, 0.0))
    assert q[index['root_z']] == pytest.approx(skeleton.leg.standing_height + 0.002)
    assert q[index['root_x']] == 30.0  # off the platform: height 0
    q = stand_in_configuration(skeleton, scene('stairs_down'), None)  # a .glb ground
    assert np.all(np.isfinite(q))


def test_command_times_out_to_zero():
    from digital_actor_planner.runtime.frame_buffer import CommandState
    command = CommandState()
    assert command.current(0.0, 0.5) == (0.0, 0.0)
    command.update(0.4, -0.2, now=10.0)
    assert command.current(10.3, 0.5) == (0.4, -0.2)
    assert command.current(10.6, 0.5) == (0.0, 0.0)


def test_validation_names_the_bad_parameter():
    from digital_actor_planner.nodes.planner_params import ConfigurationError, \
        default_scene_path, read_node_config, validate_node_config
    values = {'scene': default_scene_path(), 'start_pose': None, 'publish_rate': 100.0,
              'window_steps': 3, 'step_intervals': 13, 'step_length_min': 0.15,
              'step_length_max': 0.8, 'max_linear_speed': 1.2, 'max_angular_speed': 1.0,
              'cmd_timeout': 0.5, 'frame_id': 'world', 'cmd_vel_stamped': True,
              'publish_robot_description': True, 'planning_lead': 0.3, 'stream_priority': 0}
    validate_node_config(read_node_config(values.get))
    for name, bad in (('step_length_min', 0.9), ('scene', '/no/such/scene.yaml'),
                      ('frame_id', ' '), ('start_pose', [0.0, float('nan'), 0.0]),
                      ('planning_lead', float('inf')),
                      ('start_pose', [1.0, 2.0])):
        with pytest.raises(ConfigurationError, match=name) as caught:
            validate_node_config(read_node_config(dict(values, **{name: bad}).get))
        assert caught.value.parameter == name


def test_planning_worker_scene_cache_shares_and_forgets_scenes():
    """
    Actors of one worker share a loaded scene; a scene no actor uses is dropped.

    Actors of one worker on the same scene file share the loaded scene; a scene no actor uses any
    more is dropped.
    """
    import gc

    from digital_actor_planner.core.actor import ActorConfig
    from digital_actor_planner.runtime.planning import SceneCache
    cache, skeleton = SceneCache(), Skeleton()
    a, scene_a = cache.build(skeleton, ActorConfig(), scene('flat'), None)
    b, scene_b = cache.build(skeleton, ActorConfig(), scene('flat'), None)
    assert scene_b is scene_a and b is not a
    assert b.environment is a.environment
    del a, b, scene_a, scene_b
    gc.collect()
    _, fresh = cache.build(skeleton, ActorConfig(), scene('flat'), None)
    assert len(cache._scenes) == 1
    _, other = cache.build(skeleton, ActorConfig(), scene('stairs_up'), None)
    del fresh
    gc.collect()
    assert list(cache._scenes.values()) == [other]


class _ScheduledActor:
    """
    Stand-in for an ActorPlannerNode that logs its plans.

    Stands in for an ActorPlannerNode: due at ``due[name]`` (monotonic s; None: resting), and logs
    its plans.
    """

    def __init__(self, name, due, log):
        self.name, self.due, self.log = name, due, log

    def planning_slack(self):
        due = self.due.get(self.name)
        return None if due is None else due - time.monotonic()

    def plan_once(self):
        self.log.append((self.name, time.monotonic()))
        self.due[self.name] = None


def test_environment_markers_are_built_once_per_scene_and_sent_serialized(monkeypatch):
    """
    The environment markers are built once per scene and sent serialized.

    The environment is drawn as TRIANGLE_LISTs of exactly the scene's triangles (up to the budget),
    serialized once for every actor on the same scene content.
    """
    from rclpy.serialization import deserialize_message
    from visualization_msgs.msg import Marker, MarkerArray
    from digital_actor_planner.nodes import markers
    rng = np.random.default_rng(3)
    ground = (rng.normal(size=(10, 3)), rng.integers(0, 10, size=(12, 3)))
    box = (rng.normal(size=(8, 3)), rng.integers(0, 8, size=(6, 3)))
    array = deserialize_message(markers.environment_markers([ground, box], 'map'),
                                MarkerArray)
    assert array.markers[0].action == Marker.DELETEALL
    drawn = [m for m in array.markers if m.type == Marker.TRIANGLE_LIST]
    assert [m.id for m in drawn] == [0, 1]
    assert {m.header.frame_id for m in array.markers} == {'map'}
    for marker, (vertices, faces) in zip(drawn, (ground, box)):
        points = np.array([[p.x, p.y, p.z] for p in marker.points])
        assert np.array_equal(points, vertices[faces].reshape(-1, 3))
    # Points written into a serialized template: the same message as rclpy's own conversion.
    monkeypatch.setattr(markers, '_spliced', lambda *args: None)
    assert deserialize_message(markers.environment_markers([ground, box], 'map'),
                               MarkerArray) == array
    monkeypatch.undo()

    monkeypatch.setattr(markers, 'MAX_MARKER_TRIANGLES', 15)
    array = deserialize_message(markers.environment_markers([ground, box], 'map'),
                                MarkerArray)
    assert [len(m.points) for m in array.markers[1:]] == [36, 9]

    housekeeper = markers.Housekeeper()
    first = housekeeper.environment([ground, box], 'world')
    again = housekeeper.environment([(ground[0].copy(), ground[1].copy()), box], 'world')
    assert again is first  # another actor on the same scene: not built again
    moved = (ground[0] + [0.0, 0.0, 0.1], ground[1])
    assert housekeeper.environment([moved, box], 'world') != first
    assert housekeeper.environment([ground, box], 'map') != first


class _TickRecorder:
    """
    Stand-in for an actor node attached to a StreamTicker that records its frames.

    Stands in for an actor node attached to a StreamTicker: records, per frame, the time it was
    published, the ticks skipped before it, its own instant (None: "now"), its tick and the
    publishing thread; and each tick's stamp (ns).
    """

    def __init__(self, ticker):
        self.ticker = ticker
        self.frames = []
        self.stamps = {}

    def publish_frame(self, now, skipped, instant, stamp_ns):
        ticker = self.ticker
        # A frame without its own instant is the newest tick (set under the ticker's lock
        # before the actors are called); a caught-up one is known by its instant.
        tick = ticker._published if instant is None else \
            round((instant - ticker._start) / ticker.period)
        self.frames.append((now, skipped, instant, tick, threading.current_thread().name))
        self.stamps[tick] = stamp_ns

    def record(self, frames: int) -> list:
        """Attach to the ticker until ``frames`` frames are published (10 s at most)."""
        self.ticker.attach(self)
        try:
            deadline = time.monotonic() + 10.0
            while len(self.frames) < frames and time.monotonic() < deadline:
                time.sleep(0.05)
        finally:
            self.ticker.detach(self)
        return self.frames


def test_stream_backup_thread_publishes_the_ticks_a_stalled_stream_thread_misses():
    """
    The backup thread publishes the ticks a stalled stream thread misses, each once.

    The publishing thread stalls for six periods (as on a core the hypervisor took away); the
    backup thread on the other core publishes those ticks, each tick once. A thread may wake
    late on a loaded machine: the stall falls on the first tick the publishing thread reaches
    from ``stalled`` on, and a backup waking late publishes several ticks in one go.
    """
    if len(os.sched_getaffinity(0)) < 2:
        pytest.skip('the backup thread needs a second core')
    from digital_actor_planner.runtime.scheduling import StreamTicker
    period, stalled = 0.05, 20

    class Stalling(StreamTicker):
        stalled_at = None

        def _publish(self, tick, now, backup):
            if tick >= stalled and not backup and Stalling.stalled_at is None:
                Stalling.stalled_at = tick
                time.sleep(6.2 * period)  # woke up for its tick, then lost the core
            super()._publish(tick, now, backup)

    ticker = Stalling(period, priority=1)
    frames = _TickRecorder(ticker).record(stalled + 20)
    stalled = Stalling.stalled_at
    assert stalled is not None, 'the publishing thread never stalled'
    ticks = [tick for _, _, _, tick, _ in frames]
    assert ticks == sorted(set(ticks)), 'a tick was published twice or out of order'
    by_backup = [tick for _, _, _, tick, name in frames if name == 'joint_state_backup']
    assert stalled in by_backup, by_backup
    assert 1 <= ticker.backup_publishes <= len(by_backup)
    # Nothing skipped around the stall: the backup kept the stream going.
    around = [skipped for _, skipped, _, tick, _ in frames if stalled - 2 <= tick <= stalled + 8]
    assert len(around) == 11 and not any(around), frames


def test_stream_catches_up_the_ticks_a_stall_of_every_thread_slept_over():
    """
    A thread waking late publishes every tick it slept over: no frame is lost.

    With no thread to take over (one core, or both stalled), a thread waking 4.5 periods late
    publishes every tick it slept over at once, each showing its own instant, then the current one:
    no frame is lost. A stall longer than ``CATCH_UP`` ticks skips the oldest ones. A sleep may
    last longer than asked on a loaded machine, so the stalls leave ``CATCH_UP`` room either way;
    and a thread may wake late for a tick, so each stall falls on the first tick it reaches from
    ``stalled`` (``long_stall``) on.
    """
    from digital_actor_planner.runtime.scheduling import StreamTicker
    period, stalled, long_stall, catch_up = 0.05, 10, 30, 10

    class Stalling(StreamTicker):
        CATCH_UP = catch_up
        stalled_at = {}  # the tick each stall fell on, by its length in periods

        def _publish(self, tick, now, backup):
            for at, periods in ((stalled, 4.5), (long_stall, 15.5)):
                if tick >= at and periods not in Stalling.stalled_at:
                    Stalling.stalled_at[periods] = tick
                    time.sleep(periods * period)
                    now = time.monotonic()
                    break
            super()._publish(tick, now, backup)

    ticker = Stalling(period, priority=0)
    frames = _TickRecorder(ticker).record(long_stall + 30)
    assert set(Stalling.stalled_at) == {4.5, 15.5}, Stalling.stalled_at
    stalled, long_stall = Stalling.stalled_at[4.5], Stalling.stalled_at[15.5]
    ticks = [tick for _, _, _, tick, _ in frames]
    assert ticks == sorted(set(ticks)), 'a tick published twice or out of order'
    # The first stall: the stalled tick and the 3 after it slept over, all published, each
    # showing its instant.
    assert ticks[:long_stall + 1] == list(range(long_stall + 1)), ticks
    for now, _, instant, tick, _ in frames:
        if stalled <= tick < stalled + 4:
            assert instant == pytest.approx(ticker._start + tick * period)
            assert now - instant >= period  # published late, not lost
    burst = [now for now, _, _, tick, _ in frames if stalled + 1 <= tick <= stalled + 4]
    assert max(burst) - min(burst) < 0.5 * period  # caught up at once
    # The long stall: at least 15.5 periods late with CATCH_UP 10, so the oldest ticks after the
    # stalled one (at least 4) are skipped, counted once, and the CATCH_UP before the current
    # tick are published together with it.
    missing = sorted(set(range(ticks[-1] + 1)) - set(ticks))
    assert len(missing) >= 4, missing
    assert missing == list(range(long_stall + 1, long_stall + 1 + len(missing))), missing
    assert sum(skipped for _, skipped, _, _, _ in frames) == len(missing)
    resumed = long_stall + 1 + len(missing)
    second_burst = [now for now, _, _, tick, _ in frames if resumed <= tick <= resumed + catch_up]
    assert len(second_burst) == catch_up + 1
    assert max(second_burst) - min(second_burst) < 0.5 * period
    assert ticker.caught_up >= 3 + catch_up
    assert ticker.late_ticks >= 3 + catch_up and ticker.max_lateness >= 15 * period


def test_stream_stamps_stay_on_the_tick_grid_when_a_catch_up_burst_is_interrupted():
    """
    Stamps stay on the tick grid when a catch-up burst is interrupted.

    Every thread stalls for 4.5 periods; the thread catching up then loses its core again for 1.5
    periods in the middle of the burst (the hypervisor, or the planner holding the GIL). Each frame
    is stamped with the instant it shows, not the moment it got out: the caught-up frames stay one
    period apart, and the stamps only increase. A thread may wake late for a tick on a loaded
    machine, so the stall falls on the first tick it reaches from ``stalled`` on.
    """
    from digital_actor_planner.runtime.scheduling import StreamTicker
    period, stalled = 0.05, 10

    class Stalling(StreamTicker):
        stalled_at = None

        def _publish(self, tick, now, backup):
            if tick >= stalled and Stalling.stalled_at is None:
                Stalling.stalled_at = tick
                time.sleep(4.5 * period)
                now = time.monotonic()
            super()._publish(tick, now, backup)

    class Preempted(_TickRecorder):

        def publish_frame(self, now, skipped, instant, stamp_ns):
            super().publish_frame(now, skipped, instant, stamp_ns)
            if Stalling.stalled_at is not None and \
                    self.frames[-1][3] == Stalling.stalled_at + 1:  # the burst's first frame
                time.sleep(1.5 * period)

    recorder = Preempted(Stalling(period, priority=0))
    frames = recorder.record(stalled + 20)
    stalled = Stalling.stalled_at
    assert stalled is not None, 'the thread never stalled'
    ticks = [tick for _, _, _, tick, _ in frames]
    assert ticks == sorted(set(ticks)) and ticks[:stalled + 8] == list(range(stalled + 8)), ticks
    stamps = 1e-9 * np.array([recorder.stamps[tick] for tick in ticks])
    intervals = np.diff(stamps)
    assert np.all(intervals > 0.0), intervals
    burst = intervals[stalled:stalled + 3]  # the stalled tick and 3 after, at their own instants
    assert np.allclose(burst, period, atol=2e-6), burst
    # On the wall clock: a stamp is within a period of the tick's instant mapped to it.
    wall = time.time() - time.monotonic()
    instants = recorder.ticker._start + period * np.array(ticks)
    assert np.abs(stamps - (instants + wall)).max() < period, stamps - instants - wall


def test_planning_scheduler_plans_the_most_urgent_actor_first_and_skips_resting_ones(
        monkeypatch):
    """
    The planning thread plans the most urgent due actor first, and skips resting ones.

    It sleeps until the next actor falls due, and a wake-up (a new command) plans a resting
    actor at once. The rescan is put far off so that a plan well before it shows the thread
    was woken, by its own timeout or by ``wake``; the bounds leave room for a loaded machine.
    """
    from digital_actor_planner.runtime import scheduling
    monkeypatch.setattr(scheduling, 'IDLE_RESCAN', 30.0)
    scheduler = scheduling.PlanningScheduler()
    log, due = [], {}
    actors = [_ScheduledActor(name, due, log) for name in ('late', 'later', 'resting', 'soon')]
    try:
        for actor in actors:
            scheduler.attach(actor, 0)
        # Overdue by 0.1 s, by 0.3 s, resting, and due in 0.15 s (one update: the planning
        # thread sees all four or none).
        now = time.monotonic()
        due.update({'late': now - 0.1, 'later': now - 0.3, 'soon': now + 0.15})
        scheduler.wake.set()
        deadline = time.monotonic() + 20.0
        while len(log) < 3 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert [name for name, _ in log] == ['later', 'late', 'soon']
        assert log[2][1] >= now + 0.14, 'planned before it was due'
        assert log[2][1] < now + 15.0, 'not woken when it fell due'
        # A resting actor whose command changes is woken at once, not at the next rescan.
        time.sleep(0.05)
        due['resting'] = time.monotonic() - 0.01
        woken = time.monotonic()
        scheduler.wake.set()
        while len(log) < 4 and time.monotonic() < woken + 20.0:
            time.sleep(0.002)
        assert [name for name, _ in log][3:] == ['resting']
        assert log[3][1] - woken < 15.0, 'not woken by the wake-up'
    finally:
        for actor in actors:
            scheduler.detach(actor)
    assert not scheduler._thread.is_alive(), 'the planning thread outlived its last actor'


@pytest.mark.ros
def test_a_scene_reload_racing_a_plan_neither_breaks_the_buffer_nor_drops_the_first_block(
        monkeypatch):
    """
    The executor thread loads a new scene while the planning thread wants the next block.

    The worker serves one request at a time, so the plan runs on the new scene as soon as the
    load is done. If the planning thread got in before the executor thread handed the new
    start over (a preemption on a busy machine), the new scene's first block went into the old
    scene's buffer: a ValueError there, which ended the planning thread for good, and later a
    jump past the lost block. Loading and planning now exclude each other.
    """
    import rclpy
    from rclpy.parameter import Parameter
    from ros_harness import fresh_domain_id, ros_env
    from digital_actor_planner.nodes import actor_planner
    from digital_actor_planner.nodes.actor_planner import ActorPlannerNode
    # A retry far off: the slack after a fault shows the retry was set, however long the
    # loaded machine takes to ask for it.
    monkeypatch.setattr(actor_planner, 'RETRY_AFTER', 30.0)
    for key, value in ros_env(fresh_domain_id()).items():
        monkeypatch.setenv(key, value)
    context = rclpy.Context()
    rclpy.init(context=context, domain_id=int(os.environ['ROS_DOMAIN_ID']))
    node = ActorPlannerNode(context=context, parameter_overrides=[
        Parameter('scene', value=scene('flat')), Parameter('cmd_timeout', value=60.0)])
    try:
        node._scheduler.detach(node)  # this test is the planning thread
        node.command.update(0.6, 0.0, time.monotonic())
        for _ in range(3):
            assert node.planning_slack() is not None
            node.plan_once()
        assert node.buffer.end_time > 1.0

        real_load = node.planner.load_scene
        loaded, go_on, started = threading.Event(), threading.Event(), {}

        def load_then_stall(path, timeout=300.0):
            result = real_load(path, timeout)  # the worker holds the new scene from here on
            started['q'] = result[0]
            loaded.set()
            go_on.wait(10.0)  # the executor thread is preempted before it hands it over
            return result

        node.planner.load_scene = load_then_stall
        replies, errors = [], []
        reload = threading.Thread(target=lambda: replies.append(node._on_set_parameters(
            [Parameter('scene', value=scene('stairs_up'))])))

        def plan():
            try:
                node.planning_slack()
                node.plan_once()
            except Exception as error:  # noqa: B902 -- reported by the assertion below
                errors.append(error)

        planning = threading.Thread(target=plan)
        reload.start()
        assert loaded.wait(120.0), 'the new scene did not load'
        planning.start()
        planning.join(1.0)  # it either plans now (on which scene?) or waits for the hand-over
        go_on.set()
        reload.join(60.0)
        planning.join(60.0)
        assert not errors, f'the planning thread failed: {errors!r}'
        assert replies and replies[0].successful
        for _ in range(2):
            assert node.planning_slack() is not None
            node.plan_once()

        # The buffer from the restart on: the new start, then the new actor's blocks with no
        # frame missing in between (a lost first block shows as a jump to the second one).
        times, frames, _ = node.buffer._data
        after = times >= node.actor_offset - 1e-9
        assert np.array_equal(frames[after][0], started['q'])
        assert times[after][-1] - node.actor_offset > 1.0
        gaps = np.diff(times[after])
        assert gaps.max() < 1.5 / node.config.publish_rate, f'a gap of {gaps.max():.3f} s'
        speed = np.abs(np.diff(frames[after], axis=0)) / gaps[:, None]
        limit = node.skeleton.velocity_limit
        assert np.all(speed[:, 4:] <= 1.05 * limit[4:]), 'the motion jumps'

        # A fault while planning leaves this actor holding; the planning thread goes on.
        def fault(*args, **kwargs):
            raise RuntimeError('fault')

        real_plan, end = node.planner.plan, node.buffer.end_time
        node.planner.plan = fault
        node.plan_once()
        assert 0.0 < node.planning_slack() <= 30.0, 'no retry set after the fault'
        # Diagnostics say why; the committed motion is kept.
        assert node.stats.state == 'stuck'
        assert node.stats.reason == "internal error: RuntimeError('fault')"
        assert node.buffer.end_time == end
        # Once planning works again the actor goes on from where it was.
        node.planner.plan = real_plan
        node.plan_once()
        assert node.stats.state == 'walking', node.stats.reason
        assert node.buffer.end_time > end
    finally:
        node.stop()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


class _Executor:
    """
    Stand-in for spin_once that fails as rclpy does when the context is gone.

    spin_once stand-in: on call ``fail_on`` sets the context's validity to ``valid_after`` and
    fails as rclpy does when the context is gone while it builds its wait set.
    """

    def __init__(self, context, fail_on, valid_after):
        self.context, self.fail_on, self.valid_after, self.calls = context, fail_on, valid_after, 0

    def spin_once(self, timeout_sec=None):
        self.calls += 1
        if self.calls == self.fail_on:
            self.context['ok'] = self.valid_after
            raise RuntimeError('failed to initialize wait set: the given context is not valid')


@pytest.mark.parametrize('shut_down', [True, False])
def test_spin_ends_quietly_when_ctrl_c_shuts_the_context_down_mid_spin(shut_down):
    """
    Spinning ends quietly when Ctrl-C shuts the context down mid-spin.

    Ctrl-C shuts the context down from rclpy's signal handler; landing between the loop's ok()
    check and spin_once building its wait set, spin_once raises RCLError (a RuntimeError). That is
    the shutdown asked for: the node returns (it exited 1 with a traceback). The same error with
    the context still valid is a real failure and is raised.
    """
    from digital_actor_planner.nodes.hosting import spin_until_shutdown
    context = {'ok': True}
    executor = _Executor(context, fail_on=3, valid_after=not shut_down)
    if shut_down:
        spin_until_shutdown(executor, ok=lambda: context['ok'])
        assert executor.calls == 3
    else:
        with pytest.raises(RuntimeError, match='context is not valid'):
            spin_until_shutdown(executor, ok=lambda: context['ok'])
