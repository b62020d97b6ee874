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
ROS 2 node ``actor_planner``: cmd_vel and a mesh scene in, a 22-DOF JointState stream out.

A thin adapter over :class:`digital_actor_planner.core.actor.Actor` and the ROS-free real time
of :mod:`digital_actor_planner.runtime` (STYLE: nodes only adapt). Planning never stalls the
stream:

* the core runs in a child process (``runtime.planning.PlanningProcess``): its NumPy and FCL
  calls hold the GIL for milliseconds at a time, which would delay a publishing thread in the
  same process;
* a planning thread asks it for the next block whenever less than the planning lead of
  committed frames is buffered ahead of playback (so about one step is buffered); actors that
  share a planning process share its planning thread (``runtime.scheduling.PlanningScheduler``),
  and an actor standing at rest (or stuck) with an unchanged command is not planned for at all;
* a publishing thread (``runtime.scheduling.StreamTicker``) ticks on a monotonic schedule at
  ``publish_rate`` and publishes the frame for "now", interpolated from the buffer; if planning
  is late it holds the last frame; ticks it slept over (the machine took its core away) are
  published late, not dropped;
* the executor's threads handle cmd_vel and parameter changes (a scene reload occupies one of
  them); a housekeeping thread publishes markers and diagnostics.

The stream starts at once, from a stand-in pose, while the planning process compiles the
core's kernels ("warming up"); a planning process that dies or stops answering is replaced and
the actor goes on from where it stands; blocks not yet begun are planned again when the
command changes (docs/planner_node_runtime.md).
"""
from __future__ import annotations

import array
import collections
import math
import os
import sys
import threading
import time
import traceback
from typing import Optional

# Ctrl-C while these load (a second or more on a busy machine) ends the node quietly, as
# it does once it runs.
try:
    from diagnostic_msgs.msg import DiagnosticArray
    from digital_actor_planner.nodes.diagnostics import planner_diagnostics
    from digital_actor_planner.nodes.hosting import CommandRouter, run_nodes, SharedThreads
    from digital_actor_planner.nodes.markers import block_markers, Housekeeper
    from digital_actor_planner.nodes.planner_params import parameter_declarations, \
        PlannerNodeConfig, read_node_config, RUNTIME_PARAMETERS, scene_file_error, \
        validate_node_config
    from digital_actor_planner.runtime.frame_buffer import CommandState, FrameBuffer
    from digital_actor_planner.runtime.planning import ConfigurationError, PlanningFailed, \
        PlanningLost, PlanningPool, PlanningProcess, PlanningStats, REPLAN_BLOCKS
    from digital_actor_planner.runtime.standing import stand_in_configuration
    from geometry_msgs.msg import Twist, TwistStamped
    from nav_msgs.msg import Path
    import numpy as np
    from rcl_interfaces.msg import SetParametersResult
    import rclpy
    from rclpy.callback_groups import ReentrantCallbackGroup
    from rclpy.event_handler import PublisherEventCallbacks, SubscriptionEventCallbacks
    from rclpy.exceptions import ParameterException, ParameterUninitializedException
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import JointState
    from std_msgs.msg import String
    from visualization_msgs.msg import MarkerArray
except KeyboardInterrupt:  # pragma: no cover - depends on when the signal lands
    # Not sys.exit: after an import cut short by the signal, the interpreter's exit would end
    # the process by SIGINT whatever status it was given.
    os._exit(0)

PAST_FOOTSTEPS = 40
# The planning lead grows to LEAD_SAFETY times the slowest of the last RECENT_BLOCKS response
# times (from a block falling due to its commit), up to MAX_LEAD s.
LEAD_SAFETY = 1.5
RECENT_BLOCKS = 10
MAX_LEAD = 2.0
# After a planning failure an actor is asked again after this long (s).
RETRY_AFTER = 0.1
# The stream blends from the pose it holds to a newly placed actor's first frame over this
# long (s): the stand-in pose of the start, or the stance held when a planning process failed.
BLEND_TIME = 0.5
# Blocks planned but not yet begun are planned again when the command changes this much
# (m/s, rad/s) or to a stop, instead of being played out: a released drag stills the actor
# at the end of the step in progress (docs/stopping.md).
REPLAN_LINEAR = 0.15
REPLAN_ANGULAR = 0.3
# A block starting sooner than this (s) after the frame on show is played as planned.
REPLAN_GUARD = 0.05
# The same for a stop: any block not yet begun is dropped. Should the stream reach the cut
# before the stop is planned, it holds the stance the step in progress landed in, which is
# where the actor stops anyway; a step played out instead would delay the stop by a step.
STOP_GUARD = 0.0
# Told to stop, the actor lands the step in progress sooner: the rest of it is played at up to
# this many times its planned speed, never a joint above its velocity limit (docs/stopping.md).
HURRY_MAX_RATE = 1.5
# Frames due within this long (s) after the frame on show keep their time when the step is
# hurried: the stream may be showing them while the buffer changes.
HURRY_GUARD = 0.02
# Planned blocks (per actor) that can be planned again; as many states kept to go back to.
# A planning process that fails this many times in a row while placing its actors is given
# up on: the node exits non-zero (a supervisor may start it again).
MAX_REPLACEMENTS = 3


class ActorPlannerNode(Node):
    """
    Stream the digital actor's whole-body motion as JointState, directed by cmd_vel.

    Parameters
    ----------
    node_name
        Name of the node.
    threads
        The process's :class:`SharedThreads`; None: this node's own.
    planners
        The process's :class:`~digital_actor_planner.runtime.planning.PlanningPool`; None: a
        planning process for this node alone.
    commands
        The process's :class:`CommandRouter` when it hosts several actors; None: the node
        subscribes to cmd_vel itself.
    **kwargs
        Passed to ``rclpy.node.Node`` (namespace, context, parameter overrides).

    """

    def __init__(self, node_name: str = 'actor_planner', threads: Optional[SharedThreads] = None,
                 planners: Optional[PlanningPool] = None,
                 commands: Optional[CommandRouter] = None, **kwargs):
        super().__init__(node_name, **kwargs)
        self._commands = commands
        self.config = self._declare_and_read()
        from digital_actor_planner.core.skeleton import Skeleton
        self.skeleton = Skeleton()
        # The actor is placed by the planning thread (its process may first compile the
        # core's kernels): the stream starts at once, from a stand-in pose.
        self.planner = PlanningProcess(self.config.actor_config_fields(),
                                       self.skeleton.urdf_path, self.config.scene,
                                       self.config.start_pose,
                                       worker=planners.worker() if planners else None)
        self.meshes = []
        self.scene_path = self.config.scene
        self.scene_error = ''
        self.cmd_timeout = self.config.cmd_timeout
        self.planning_lead = self.config.planning_lead
        self.period = 1.0 / self.config.publish_rate

        self.buffer = FrameBuffer(stand_in_configuration(self.skeleton, self.config.scene,
                                                         self.config.start_pose))
        self.actor_offset = 0.0  # buffer time of the current actor's clock zero
        self.command = CommandState()
        self.stats = PlanningStats(state='warming up',
                                   reason='the planning process is starting')
        # Exit status asked for by a fault the node cannot recover from (None: running).
        self.exit_code = None
        # Failed attempts in a row to place the actor in a (replaced) planning process.
        self._placement_failures = 0
        self._placed_once = False
        # A Twist publisher on cmd_vel while TwistStamped is expected, or the reverse.
        self.cmd_vel_mismatch = ''
        self._reload_lock = threading.Lock()
        self.playback_time = 0.0
        self.underruns = 0
        self.missed_frames = 0
        self.tick_times = collections.deque(maxlen=max(4, int(2 * self.config.publish_rate)))
        self.committed_footsteps = collections.deque(maxlen=PAST_FOOTSTEPS)
        self._latest_block = None
        self._markers_block = None
        self._pending_start = None
        self._pending_lock = threading.Lock()
        # Loading a scene and planning a block exclude each other: the new scene's start is
        # handed over before anything is planned on it, so no block planned on the new scene
        # reaches the old scene's buffer, and none is dropped as if planned on the old one.
        self._scene_lock = threading.Lock()
        self._stop = threading.Event()
        # The planning lead in force (s); the stream wakes the planner when less is buffered.
        self._lead = self.planning_lead
        # The block last planned repeats while the command stays this one (a hold at rest, or
        # stuck): no more blocks are planned and the stream holds the last frame.
        self._holding_for = None
        # The last block committed holds the actor still (at rest or stuck): the stream running
        # past it is not a buffer underrun, also while the first step after it is planned.
        self._at_rest = False
        # A scene is loading (or the new actor has not had its first block): the walk on the
        # old scene may run out meanwhile; holding then is not running dry either.
        self._reloading = True  # until the planner has placed the actor
        self._restarted = False
        self._retry_at = 0.0
        self._clock_zero = None
        # Seconds from each recent block falling due to its commit: its wait for the shared
        # planning thread plus its planning (the planning lead must cover both).
        self._responses = collections.deque(maxlen=RECENT_BLOCKS)
        self._due_since = None
        # (number, buffer start time s, command) of the blocks committed lately.
        self._blocks = collections.deque(maxlen=REPLAN_BLOCKS)
        self._hurried_block = None  # the step last hurried to a stop
        self.replanned_blocks = 0

        threads = threads or SharedThreads()
        self._scheduler = self.planner.scheduler
        self._housekeeper = threads.housekeeper
        self._make_interfaces()
        self.add_on_set_parameters_callback(self._on_set_parameters)
        # The planning thread below the stream's priority: it holds the GIL only briefly, and
        # below that priority it cannot be preempted by other programs while holding it.
        self._scheduler.attach(self, self.config.stream_priority - 1
                               if self.config.stream_priority > 1 else 0)
        self._housekeeper.attach(self)
        self.ticker = threads.ticker(self.period, self.config.stream_priority,
                                     self.get_logger().info)
        self.ticker.attach(self)
        self.get_logger().info(
            f'streaming {len(self.skeleton.joint_names)} joints at {self.config.publish_rate:g} '
            f'Hz, scene {self.scene_path}')

    @property
    def default_callback_group(self):
        """
        Reentrant callback group of the node's entities.

        The parameter services answer while a scene set loads in another executor thread
        (rclpy's default group would make them wait for it).
        """
        group = self.__dict__.get('_reentrant_group')
        if group is None:
            group = self.__dict__['_reentrant_group'] = ReentrantCallbackGroup()
        return group

    # -- configuration ----------------------------------------------------------------------
    def _declare_and_read(self) -> PlannerNodeConfig:
        for name, default, descriptor in parameter_declarations():
            if name not in RUNTIME_PARAMETERS:
                descriptor.read_only = True
            try:
                self.declare_parameter(name, default, descriptor)
            except ParameterException as error:
                raise ConfigurationError(name, str(error)) from error
        config = read_node_config(self._parameter_value)
        validate_node_config(config)
        return config

    def _parameter_value(self, name: str):
        try:
            return self.get_parameter(name).value
        except ParameterUninitializedException:
            return None

    def _make_interfaces(self) -> None:
        latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                             reliability=ReliabilityPolicy.RELIABLE)
        self.joint_state_msg = JointState()
        self.joint_state_msg.header.frame_id = self.config.frame_id
        self.joint_state_msg.name = list(self.skeleton.joint_names)
        # Half a second of history, so a reliable subscriber that is briefly busy loses nothing.
        # No QoS event handlers (rclpy adds two per publisher and subscription by default, for
        # its "incompatible QoS" warnings): the SingleThreadedExecutor matches every node's
        # handlers against every other's on each wake-up, so with 20 actors in one process the
        # cmd_vel traffic alone kept most of a core busy. The warnings could not fire anyway:
        # the latched publishers offer the strongest QoS, joint_states and diagnostics clash only
        # with a transient-local subscriber, and a best-effort cmd_vel subscription accepts every
        # publisher (a lost command is replaced by the next one, or by cmd_timeout).
        quiet = {'event_callbacks': PublisherEventCallbacks(use_default_callbacks=False)}
        self.joint_state_pub = self.create_publisher(JointState, 'joint_states', 50, **quiet)
        self.diagnostics_pub = self.create_publisher(DiagnosticArray, '/diagnostics', 10,
                                                     **quiet)
        self.markers_pub = self.create_publisher(MarkerArray, '~/markers', latched, **quiet)
        self.environment_pub = self.create_publisher(MarkerArray, '~/environment', latched,
                                                     **quiet)
        self.path_pub = self.create_publisher(Path, '~/path', latched, **quiet)
        if self.config.publish_robot_description:
            self.description_pub = self.create_publisher(String, 'robot_description', latched,
                                                         **quiet)
            with open(self.skeleton.urdf_path) as urdf:
                self.description_pub.publish(String(data=urdf.read()))
        commands = QoSProfile(depth=10, reliability=ReliabilityPolicy.BEST_EFFORT)
        quiet_sub = SubscriptionEventCallbacks(use_default_callbacks=False)
        # Hosted with other actors, the process's CommandRouter holds the subscription.
        owner, topic = self, 'cmd_vel'
        if self._commands is not None:
            owner, topic = self._commands.node, self.resolve_topic_name('cmd_vel')
        if self.config.cmd_vel_stamped:
            owner.create_subscription(TwistStamped, topic,
                                      lambda msg: self._on_cmd_vel(msg.twist), commands,
                                      event_callbacks=quiet_sub)
        else:
            owner.create_subscription(Twist, topic, self._on_cmd_vel, commands,
                                      event_callbacks=quiet_sub)
        # Diagnostics (1 Hz) and markers (5 Hz) come from the process's Housekeeper thread,
        # not executor timers: with a dozen actors in one process, rclpy's executor spent most
        # of a core waking up for their timers, at the stream's priority, starving the planning
        # processes.
        self._environment_due = None  # published by the Housekeeper once placed

    def _on_set_parameters(self, parameters) -> SetParametersResult:
        for parameter in parameters:
            if parameter.name == 'cmd_timeout':
                if not (math.isfinite(parameter.value) and parameter.value > 0.0):
                    return SetParametersResult(successful=False,
                                               reason=f'cmd_timeout {parameter.value!r}')
                self.cmd_timeout = float(parameter.value)
            elif parameter.name == 'scene':
                result = self._reload_scene(str(parameter.value))
                if not result.successful:
                    return result
        return SetParametersResult(successful=True)

    def _reload_scene(self, path: str) -> SetParametersResult:
        """
        Load ``path`` in the planning process and hand its start to the planning thread.

        Runs in one of the executor's threads (the others go on serving parameters and
        commands) while the stream holds the stance. The parameter takes the new value only
        once the scene is loaded; a scene that fails keeps the old one, with the reason.
        """
        problem = scene_file_error(path)
        if not problem and not self._placed_once:
            problem = 'the planner is still warming up (compiling its kernels); set it again ' \
                'once diagnostics no longer say "warming up"'
        if problem:
            return self._scene_refused(path, problem)
        with self._reload_lock:  # one reload at a time
            self._reloading = True
            with self._scene_lock:
                try:
                    configuration, meshes = self.planner.load_scene(path)
                except (ConfigurationError, PlanningFailed) as error:
                    self._reloading = False
                    return self._scene_refused(path, str(error))
                with self._pending_lock:
                    self._pending_start = (configuration, False)
                    self._environment_due = meshes
            self.meshes, self.scene_path, self.scene_error = meshes, path, ''
        self._scheduler.wake.set()
        self.get_logger().info(f'scene reloaded: {self.scene_path}')
        return SetParametersResult(successful=True)

    def _scene_refused(self, path: str, problem: str) -> SetParametersResult:
        problem = problem.replace("parameter 'scene': ", '')
        self.scene_error = f'{path}: {problem}' if path not in problem else problem
        self.get_logger().error(f'scene not reloaded, keeping {self.scene_path}: {problem}')
        return SetParametersResult(successful=False, reason=f'scene not loaded: {problem}')

    # -- planning (called by the worker's PlanningScheduler thread) -------------------------
    def planning_slack(self) -> Optional[float]:
        """
        Return the seconds until this actor's next block is due (<= 0: due now).

        Nothing is planned while the last block would only repeat: a hold at rest or a stuck
        hold, with the command unchanged since. A new scene's first block is due at once, as
        is placing the actor in a planning process that does not hold it (at the start, or
        after the process was replaced).

        Returns
        -------
        float or None
            s until due; None when there is nothing to plan.

        """
        if self._stop.is_set() or self.exit_code is not None:
            return None
        now = time.monotonic()
        if now < self._retry_at:
            return self._retry_at - now
        if self._pending_start is not None or not self.planner.placed:
            return -self._lead
        if self._holding_for is not None:
            if self.command.current(now, self.cmd_timeout) == self._holding_for:
                return None
            self._holding_for = None
        if self._replan_target(now) is not None or self._hurry_due(now):
            return -self._lead
        lead = self._lead = self.effective_lead()
        return self.buffer.end_time - self.playback_time - lead

    def plan_once(self) -> None:
        """
        Plan this actor's next block and commit it to the buffer.

        A new scene's first block is committed after the buffer restarts at the new start;
        the actor is placed first when its planning process does not hold it.
        """
        try:
            with self._scene_lock:
                if not self.planner.placed and not self._place():
                    return
                with self._pending_lock:
                    pending, self._pending_start = self._pending_start, None
                if pending is not None:
                    self._blocks.clear()
                    self._hurried_block = None
                    configuration, blend = pending
                    # A new actor: its clock starts at 0 from its start pose, right after
                    # the frame on show (a new scene) or after a blend from the pose held.
                    held = max(self.playback_time, self.buffer.end_time) + self.period
                    self.actor_offset = held + BLEND_TIME if blend else \
                        self.playback_time + self.period
                    self.buffer.restart(configuration, self.actor_offset,
                                        held if blend else None)
                    self.committed_footsteps.clear()
                    self._holding_for = None
                    self._restarted = True
                try:
                    if pending is None:
                        self._replan_tail()
                        if self._hurry_due(time.monotonic()):
                            self._hurry_to_stop()
                    self._plan_block()
                except Exception as error:  # noqa: B902 -- the thread serves every actor
                    # A fault in one block must not end the thread that plans for all the
                    # process's actors: this one holds its last frame and tries again.
                    self.stats.record('stuck', f'internal error: {error!r}', float('nan'))
                    self.get_logger().error(f'planning failed: {error!r}\n'
                                            f'{traceback.format_exc()}',
                                            throttle_duration_sec=2.0)
                    self._retry_at = time.monotonic() + RETRY_AFTER
        except Exception as error:  # noqa: B902 -- never a silently frozen actor
            self.fail(1, f'planning thread failed: {error!r}\n{traceback.format_exc()}')

    def _replan_target(self, now: float):
        """
        Return the first committed block not yet begun that the command has overtaken.

        That is a block planned for a command unlike the current one (a stop, or a change of
        REPLAN_LINEAR / REPLAN_ANGULAR); None if none.
        """
        linear, angular = self.command.current(now, self.cmd_timeout)
        stop = abs(linear) < 1e-3 and abs(angular) < 1e-3
        guard = STOP_GUARD if stop else REPLAN_GUARD
        for block in self._blocks:
            number, start, (old_linear, old_angular), _ = block
            if start <= self.playback_time + guard:
                continue
            if (stop and (abs(old_linear) >= 1e-3 or abs(old_angular) >= 1e-3)) or \
                    abs(linear - old_linear) >= REPLAN_LINEAR or \
                    abs(angular - old_angular) >= REPLAN_ANGULAR:
                return block
            return None
        return None

    def _replan_tail(self) -> None:
        """
        Drop the blocks not yet begun that the command has overtaken.

        The actor in its planning process goes back to the state before them (the next block
        replaces them).
        """
        target = self._replan_target(time.monotonic())
        if target is None:
            return
        number, start, _, _ = target
        # The stream holds the last frame kept (a double-support stance at a step's end) if
        # it gets there before the new block is planned.
        self.buffer.truncate(start)
        if not self.planner.replan_from(number):
            # That state is no longer kept: the actor goes on from the end of what it
            # planned, after a hold (its clock and the buffer's stay in step).
            self.get_logger().warning(f'block {number} could not be planned again')
            return
        self.replanned_blocks += sum(1 for block in self._blocks if block[0] >= number)
        while self._blocks and self._blocks[-1][0] >= number:
            self._blocks.pop()
        self._at_rest = False

    def _hurry_due(self, now: float) -> bool:
        """
        Tell whether the actor, told to stop, is in a walking step that can still land sooner.

        The step has begun, is the last block committed (what is planned next starts where it
        ends) and was not hurried yet.
        """
        linear, angular = self.command.current(now, self.cmd_timeout)
        if abs(linear) >= 1e-3 or abs(angular) >= 1e-3 or not self._blocks:
            return False
        number, start, _, status = self._blocks[-1]
        return status == 'walking' and number != self._hurried_block and \
            start <= self.playback_time

    def _hurry_to_stop(self) -> None:
        """
        Play the rest of the step in progress faster (``runtime.retiming``).

        The actor's clock moves on by the time saved, so that the block planned next follows on.
        """
        self._hurried_block = self._blocks[-1][0]
        self.actor_offset -= self.buffer.hurry(self.playback_time + HURRY_GUARD,
                                               self.skeleton.velocity_limit, HURRY_MAX_RATE)

    def _place(self) -> bool:
        """
        Place the actor in its planning process; True when placed.

        The first time on the configured scene and start; after the process was replaced,
        where the actor stood (the root of the last committed frame), blended over to.
        A bad scene or start ends the node with status 2 (a configuration error), a process
        that keeps failing with status 1.
        """
        first = not self._placed_once
        pose = None
        if not first:
            q = self.buffer.sample(self.buffer.end_time)[0]
            index = self.skeleton.index
            pose = (float(q[index['root_x']]), float(q[index['root_y']]),
                    float(q[index['root_yaw']]))
            self.stats.record('recovering', 'the planning process was replaced; placing the '
                              'actor where it stands', float('nan'))
            self.get_logger().warning(f'planning process replaced; placing the actor again at '
                                      f'({pose[0]:.3f}, {pose[1]:.3f}, yaw {pose[2]:.3f})')
        self._reloading = True
        try:
            configuration, meshes = self.planner.place(pose)
        except ConfigurationError as error:
            if first:
                self.fail(2, f'invalid configuration: {error}')
            else:
                self.fail(1, f'the actor cannot stand where it stood after the planning '
                          f'process was replaced: {error}')
            return False
        except PlanningFailed as error:
            if self._stop.is_set():
                return False
            self._placement_failures += 1
            if self._placement_failures >= MAX_REPLACEMENTS:
                self.fail(1, f'planning process failed {self._placement_failures} times in a '
                          f'row: {error}')
            else:
                self.get_logger().error(f'planning process failed while placing the actor, '
                                        f'trying a new one: {error}')
            return False
        self._placement_failures = 0
        self._placed_once = True
        with self._pending_lock:
            self._pending_start = (configuration, True)
            self._environment_due = meshes
        self.meshes = meshes
        if first:
            self.stats.record('idle', '', float('nan'))
            self.get_logger().info('planner ready')
        return True

    def fail(self, code: int, message: str) -> None:
        """
        End the node with exit status ``code``.

        An ERROR goes to /diagnostics and the log, then the context is shut down (``main``
        returns ``exit_code``).

        Parameters
        ----------
        code
            Exit status the process is to end with.
        message
            What went wrong; its first line is the diagnostics' reason.

        """
        if self.exit_code is not None or self._stop.is_set():
            return
        self.exit_code = code
        self.stats.state, self.stats.reason = 'error', message.splitlines()[0]
        self.get_logger().fatal(message)
        try:
            self._publish_diagnostics()
        except Exception:  # noqa: B902 -- shutting down anyway
            pass
        self.context.try_shutdown()

    def _plan_block(self) -> None:
        started = time.monotonic()
        command = self.command.current(started, self.cmd_timeout)
        try:
            warning, block, profile, number = self.planner.plan(
                *command, timeout=self.config.planning_timeout)
        except PlanningFailed as error:
            if self._stop.is_set():
                return  # shutting down: the planning process was told to finish
            if isinstance(error, PlanningLost):
                self.get_logger().error(f'planning failed: {error}')
                return  # placed again in the new process at the next turn
            self.stats.record('stuck', f'planner error: {error}', float('nan'))
            self.get_logger().error(f'planning failed: {error}', throttle_duration_sec=2.0)
            self._retry_at = time.monotonic() + RETRY_AFTER
            return
        if warning:
            self.get_logger().warning(warning, throttle_duration_sec=2.0)
        times = np.asarray(block.times) + self.actor_offset
        self.buffer.append(times, block.frames, block.velocities, self.playback_time)
        if len(times):
            self._blocks.append((number, float(times[0]), command, block.status))
        if self._restarted:  # the new actor's first block
            self._reloading = self._restarted = False
        self.stats.record(block.status, block.reason, block.planning_time)
        due, self._due_since = self._due_since, None
        self._responses.append(time.monotonic() - min(started, due or started))
        if block.status == 'walking' and len(block.footsteps):
            self.committed_footsteps.append(np.asarray(block.footsteps[0], dtype=float))
        self._at_rest = (block.status, block.reason) == ('idle', '') or block.status == 'stuck'
        if self._at_rest:
            self._holding_for = command
        self._latest_block = (block, profile)

    def effective_lead(self) -> float:
        """
        Return the buffered time (s) below which the next block is planned.

        At least ``planning_lead``, and more when recent blocks took long to plan or waited
        long for their turn in a shared planning process (a loaded machine), so that playback
        does not run dry while the next block is planned.
        """
        slowest = max(self._responses, default=0.0)
        return min(MAX_LEAD, max(self.planning_lead, LEAD_SAFETY * slowest))

    def publish_frame(self, now: float, late_ticks: int, instant: Optional[float],
                      stamp_ns: int) -> None:
        """
        Publish the frame for monotonic time ``instant`` at ``now`` (the stream ticker's call).

        Parameters
        ----------
        now
            Monotonic time (s) of publishing.
        late_ticks
            Ticks skipped before this one because the tick came too late to catch them up.
        instant
            Monotonic time (s) of the tick shown, for a frame published a period or more after
            its tick; None: ``now``.
        stamp_ns
            Wall-clock time (ns) of the instant shown; with ``use_sim_time`` the stamp is the
            ROS clock's time instead.

        """
        if self._stop.is_set():
            return
        self.missed_frames += late_ticks
        shown = now if instant is None else instant
        if self._clock_zero is None:
            self._clock_zero = shown
        play = max(0.0, shown - self._clock_zero)
        end = self.buffer.end_time
        if play > end:
            # Holding the last frame on purpose (at rest, or stuck), or while a new scene
            # loads, is not running dry.
            if play - end > self.period and not (self._at_rest or self._reloading):
                self.underruns += 1
            self._clock_zero = shown - end
            play = end
        self.playback_time = play
        if end - play <= self._lead and self._holding_for is None:
            if self._due_since is None:
                self._due_since = now
            self._scheduler.wake.set()
        q, v = self.buffer.sample(play)
        msg = self.joint_state_msg
        clock = self.get_clock()
        if clock.ros_time_is_active:  # use_sim_time: the stamp comes from /clock
            msg.header.stamp = clock.now().to_msg()
        else:  # ROS time is system time; this is about 10 us cheaper per frame
            msg.header.stamp.sec, msg.header.stamp.nanosec = divmod(stamp_ns, 1_000_000_000)
        # array('d') is taken by the message setters without a per-element type check.
        msg.position = array.array('d', q.tobytes())
        msg.velocity = array.array('d', v.tobytes())
        try:
            self.joint_state_pub.publish(msg)
        except Exception:  # noqa: B902 -- the context is shutting down
            if self._stop.is_set() or not rclpy.ok(context=self.context):
                return
            raise
        self.tick_times.append(now)

    def housekeeping(self, diagnostics: bool, housekeeper: 'Housekeeper') -> None:
        """
        Publish a new environment and new markers, and diagnostics (the Housekeeper's call).

        Parameters
        ----------
        diagnostics
            Whether diagnostics are due too.
        housekeeper
            The calling :class:`Housekeeper`, which keeps the serialized environments.

        """
        if self._stop.is_set():
            return
        try:
            with self._pending_lock:  # a reload may hand over newer meshes meanwhile
                meshes, self._environment_due = self._environment_due, None
            if meshes is not None:
                # Built in this thread, not in the executor's, which serves commands and the
                # reply to the scene change.
                self.environment_pub.publish(housekeeper.environment(meshes,
                                                                     self.config.frame_id))
            self._publish_markers()
            if diagnostics:
                self._check_cmd_vel_type()
                self._publish_diagnostics()
        except Exception as error:  # noqa: B902 -- the context is shutting down
            if self._stop.is_set() or not rclpy.ok(context=self.context):
                return
            self.get_logger().error(f'diagnostics/markers not published: {error!r}',
                                    throttle_duration_sec=2.0)

    def request_stop(self) -> None:
        """Tell the threads to finish (without waiting for them)."""
        self._stop.set()
        self._scheduler.wake.set()

    def stop(self) -> None:
        """Stop streaming and planning, and end the planning process."""
        self.request_stop()
        self.ticker.detach(self)
        self._housekeeper.detach(self)
        self._scheduler.detach(self)
        self.planner.close()

    # -- executor callbacks -----------------------------------------------------------------
    def _on_cmd_vel(self, twist: Twist) -> None:
        linear_x, angular_z = twist.linear.x, twist.angular.z
        if not (math.isfinite(linear_x) and math.isfinite(angular_z)):
            self.get_logger().warning(
                f'ignoring non-finite cmd_vel (linear.x={linear_x}, angular.z={angular_z})',
                throttle_duration_sec=2.0)
            return
        now = time.monotonic()
        was_moving = any(abs(c) >= 1e-3 for c in self.command.current(now, self.cmd_timeout))
        self.command.update(float(linear_x), float(angular_z), now)
        stop = abs(linear_x) < 1e-3 and abs(angular_z) < 1e-3
        if (self._holding_for is not None and (linear_x, angular_z) != self._holding_for) or \
                (stop and was_moving):
            self._scheduler.wake.set()  # a stop is planned at once (docs/stopping.md)

    def _check_cmd_vel_type(self) -> None:
        """
        Warn (log and diagnostics) about cmd_vel publishers of the other Twist type.

        The subscription never hears them, and nothing else would say so.
        """
        topic = self.resolve_topic_name('cmd_vel')
        expected = 'geometry_msgs/msg/TwistStamped' if self.config.cmd_vel_stamped else \
            'geometry_msgs/msg/Twist'
        others = sorted({info.topic_type for info in self.get_publishers_info_by_topic(topic)
                         if info.topic_type != expected})
        mismatch = ''
        if others:
            mismatch = (f'{topic} has a {", ".join(others)} publisher, ignored: this node '
                        f'takes {expected}; set cmd_vel_stamped:='
                        f'{"false" if self.config.cmd_vel_stamped else "true"} to follow it')
            if mismatch != self.cmd_vel_mismatch:
                self.get_logger().warning(mismatch)
        self.cmd_vel_mismatch = mismatch

    def _publish_diagnostics(self) -> None:
        array = planner_diagnostics(self)
        array.header.stamp = self.get_clock().now().to_msg()
        self.diagnostics_pub.publish(array)

    def _publish_markers(self) -> None:
        latest = self._latest_block
        if latest is None or latest is self._markers_block:
            return
        self._markers_block = latest
        markers, path = block_markers(*latest, list(self.committed_footsteps),
                                      self.config.frame_id,
                                      lambda: self.get_clock().now().to_msg())
        self.markers_pub.publish(markers)
        self.path_pub.publish(path)


def main(args=None) -> int:
    """
    Run the node(s) until interrupted.

    Parameters
    ----------
    args
        Command line (None: ``sys.argv``), ROS arguments included.

    Returns
    -------
    int
        Exit status: 0, 2 on a bad configuration, 1 on a fault the planner could not recover
        from.

    """
    try:
        return run_nodes(args, ActorPlannerNode)
    except KeyboardInterrupt:  # Ctrl-C while starting, before rclpy took it over
        rclpy.try_shutdown()
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(0)  # see the imports: a plain exit could end by SIGINT


if __name__ == '__main__':
    sys.exit(main())
