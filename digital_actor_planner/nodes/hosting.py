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
The process that hosts actor nodes: what they share, its command line and its spin loop.

The actors of one process share their stream tickers, one housekeeping thread and, when
there are several, one hidden node for their cmd_vel subscriptions (:class:`CommandRouter`).
:func:`run_nodes` builds the nodes, spins them and shuts everything down.
"""
from __future__ import annotations

import argparse
import gc
import os
import signal
import sys
import threading
from typing import Tuple

from digital_actor_planner.nodes.markers import Housekeeper
from digital_actor_planner.runtime.planning import ConfigurationError, PlanningPool, \
    usable_cores
from digital_actor_planner.runtime.scheduling import real_time, real_time_threads, \
    StreamTicker
import rclpy
from rclpy.exceptions import InvalidNamespaceException
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, \
    SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args
from rclpy.validate_namespace import validate_namespace

# The executor thread returns to Python at least this often (s), for the SIGTERM handler.
SIGNAL_CHECK = 0.5
# Executor threads of the node process (parameters, cmd_vel, scene reloads).
EXECUTOR_THREADS = 4


class SharedThreads:
    """
    The threads the actors of one process share.

    A stream ticker per (publish period, priority), and one housekeeper. Planning threads
    belong to the planning workers.
    """

    def __init__(self):
        self._tickers = {}
        self._lock = threading.Lock()
        self.housekeeper = Housekeeper()

    def ticker(self, period: float, priority: int, warn=None) -> StreamTicker:
        """
        Return the ticker for ``period`` s at ``priority`` (created on first use).

        Parameters
        ----------
        period
            Publish period, s.
        priority
            SCHED_FIFO priority of the stream thread (0: normal scheduling).
        warn
            Called with a message should the ticker not get real-time scheduling.

        Returns
        -------
        StreamTicker
            The same ticker for every actor asking with the same period and priority.

        """
        with self._lock:
            key = (float(period), int(priority))
            if key not in self._tickers:
                self._tickers[key] = StreamTicker(period, priority, warn)
            return self._tickers[key]


class CommandRouter:
    """
    The cmd_vel subscriptions of the actors hosted by one process.

    They live on one small hidden node spun by its own executor thread.

    Each subscription is made on the topic its actor resolves ``cmd_vel`` to (the actor's
    namespace and remappings). rclpy's SingleThreadedExecutor walks every entity of every node
    on each wake-up; 20 actors with their parameter services made that about 2.5 ms, so 20
    teleops at 10 Hz kept half a core busy. A command now wakes a node with only the
    subscriptions; the actors' executor wakes only for parameter and other services.
    """

    def __init__(self):
        # No global arguments: the topics are resolved by the actors already.
        self.node = Node(f'_actor_planner_commands_{os.getpid()}', use_global_arguments=False,
                         start_parameter_services=False)
        self._executor = SingleThreadedExecutor()
        self._executor.add_node(self.node)
        self._thread = None

    def start(self, priority: int) -> None:
        """
        Start delivering commands.

        Parameters
        ----------
        priority
            SCHED_FIFO priority of the delivering thread when > 0.

        """
        self._thread = threading.Thread(target=self._spin, args=(priority,),
                                        name='actor_commands', daemon=True)
        self._thread.start()

    def _spin(self, priority: int) -> None:
        if priority > 0:
            real_time(priority)
        try:
            self._executor.spin()
        except ExternalShutdownException:
            pass

    def stop(self) -> None:
        """Stop the thread and destroy the node."""
        self._executor.shutdown(timeout_sec=5.0)
        if self._thread is not None:
            self._thread.join(timeout=5.0)
        self.node.destroy_node()


def _command_line(argv) -> Tuple[list, int]:
    """
    Read the ``--actors NS [NS ...]`` and ``--planning-processes K`` options.

    Parameters
    ----------
    argv
        The non-ROS arguments, without the program name.

    Returns
    -------
    (list of str, int)
        The namespaces ([''] when absent) and the number of planning processes.

    Raises
    ------
    ConfigurationError
        An unknown argument or an invalid / repeated namespace.

    """
    parser = argparse.ArgumentParser(
        prog='actor_planner', description='Stream digital actors as JointState.',
        epilog='Several actors in one process share one DDS participant and one stream thread.')
    parser.add_argument('--actors', nargs='+', metavar='NS', default=[''],
                        help='host one actor per namespace in this process')
    parser.add_argument('--planning-processes', type=int, metavar='K', default=None,
                        help='planning processes shared by the actors (default: one per actor '
                        'up to the number of usable cores)')
    parsed, unknown = parser.parse_known_args(argv)
    if unknown:
        raise ConfigurationError('arguments', f'unknown arguments {unknown}')
    names = [ns.strip() for ns in parsed.actors]
    for ns in names:
        try:
            validate_namespace(ns if ns.startswith('/') else '/' + ns)
        except InvalidNamespaceException as error:
            raise ConfigurationError('actors', f'invalid namespace {ns!r}: '
                                     f'{str(error).splitlines()[0]}') from None
    if len(set(names)) != len(names):
        raise ConfigurationError('actors', f'repeated namespace in {names}')
    processes = parsed.planning_processes
    if processes is None:
        processes = min(len(names), usable_cores())
    return names, processes


def _terminated(signum, frame):
    raise KeyboardInterrupt(f'signal {signum}')


def spin_until_shutdown(executor, ok=rclpy.ok) -> None:
    """
    Spin ``executor`` until the context is shut down (``ok()`` false).

    Bounded waits, so that the SIGTERM handler (Python code, run by the main thread) gets its
    turn even when no message arrives. Ctrl-C shuts the context down from rclpy's signal
    handler, which can land between ``ok()`` and ``spin_once`` building its wait set (RCLError,
    a RuntimeError: "the given context is not valid"): that is the shutdown asked for, not a
    failure (the node exited with status 1 and a traceback, one CI run in many).

    Parameters
    ----------
    executor
        The executor of the actor nodes.
    ok
        Whether the context still runs (``rclpy.ok`` by default).

    """
    while ok():
        try:
            executor.spin_once(timeout_sec=SIGNAL_CHECK)
        except RuntimeError:
            if ok():
                raise


def _close_partial(nodes, commands, planners) -> None:
    """Shut down what :func:`main` built before it stopped starting."""
    for node in nodes:
        node.stop()
        node.destroy_node()
    if commands is not None:
        commands.stop()
    if planners is not None:
        planners.close()
    rclpy.try_shutdown()


def _without_kernels() -> None:
    """
    Load the core in this process as plain Python, not compiled.

    The node process runs no kernel (its planning processes do); compiling them here too
    took tens of seconds from an empty cache before the first frame.
    """
    if 'numba' not in sys.modules and 'digital_actor_planner.core.jit' not in sys.modules:
        sys.modules['numba'] = None


def run_nodes(args, node_type) -> int:
    """
    Run the actor nodes the command line asks for until the context is shut down.

    Parameters
    ----------
    args
        Command line (None: ``sys.argv``), ROS arguments included.
    node_type
        The actor node class, built once per namespace of ``--actors``.

    Returns
    -------
    int
        Exit status: 0, 2 on a bad configuration, or the highest ``exit_code`` of the nodes.

    """
    _without_kernels()
    # The executor and planning threads hold the GIL at times; a short switch interval bounds
    # how long the publishing thread waits for it after waking (the default 5 ms would be the
    # jitter).
    sys.setswitchinterval(0.0005)
    # SIGTERM (docker stop, systemd, ros2 launch after SIGINT) ends the node as Ctrl-C does.
    # rclpy's own SIGTERM handling left a node hosting 20 walking actors running for minutes.
    signal.signal(signal.SIGTERM, _terminated)
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.SIGINT)
    logger = rclpy.logging.get_logger('actor_planner')
    nodes, planners, commands = [], None, None
    try:
        namespaces, processes = _command_line(remove_ros_args(
            sys.argv if args is None else args)[1:])
        threads = SharedThreads()
        planners = PlanningPool(processes)
        commands = CommandRouter() if len(namespaces) > 1 else None
        for ns in namespaces:
            nodes.append(node_type(threads=threads, planners=planners, commands=commands,
                                   **({'namespace': ns} if ns else {})))
    # A parameter the node reads, or one its planning processes refuse: both name it.
    except ConfigurationError as error:
        logger.fatal(f'invalid configuration: {error}')
        _close_partial(nodes, commands, planners)
        return 2
    except (KeyboardInterrupt, ExternalShutdownException):
        _close_partial(nodes, commands, planners)
        return 0
    except RuntimeError:
        # Ctrl-C while a node was being built: rclpy's handler shut the context down under it.
        if rclpy.ok():
            raise
        _close_partial(nodes, commands, planners)
        return 0
    priority = nodes[0].config.stream_priority
    if priority > 2:
        # The executor thread as the planning threads, and the DDS threads below it.
        real_time_threads(priority - 1)
    if commands is not None:
        commands.start(priority - 1 if priority > 2 else 0)
    # Several threads: a scene reload (seconds for a large scene) occupies one of them while
    # the others answer parameter requests and cmd_vel (the node's callbacks are reentrant).
    executor = MultiThreadedExecutor(num_threads=EXECUTOR_THREADS)
    for node in nodes:
        executor.add_node(node)
    # Everything built so far (scene meshes for the markers, messages, modules) is moved out of
    # the garbage collector's reach, so its full collections, which run in whatever thread
    # allocates and hold the GIL, cannot delay a tick by milliseconds.
    gc.freeze()
    try:
        spin_until_shutdown(executor)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        for node in nodes:
            node.request_stop()
        if commands is not None:
            commands.stop()
        for node in nodes:
            node.stop()
        executor.shutdown(timeout_sec=5.0)
        for node in nodes:
            node.destroy_node()
        planners.close()
        rclpy.try_shutdown()
    codes = [node.exit_code for node in nodes if node.exit_code is not None]
    return max(codes, default=0)
