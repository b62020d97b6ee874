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
The /diagnostics of the planner node: planning state, timing and the stream's health.

The node publishes :func:`planner_diagnostics` once a second from its housekeeping thread.
"""
from __future__ import annotations

import math
from typing import Tuple

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
import numpy as np


def stream_timing(tick_times, publish_rate: float) -> Tuple[float, float]:
    """
    Return the jitter p99 and the longest interval (ms) of the recent ticks.

    The jitter is the deviation of each interval between published frames from the
    period.

    Parameters
    ----------
    tick_times
        Monotonic times (s) the recent frames were published at, oldest first.
    publish_rate
        The stream's rate, Hz.

    Returns
    -------
    (float, float)
        Jitter p99 and longest interval, ms (NaN when unknown).

    """
    ticks = np.array(tick_times)
    if len(ticks) < 3:
        return float('nan'), float('nan')
    intervals = np.diff(ticks)
    jitter = np.abs(intervals - 1.0 / publish_rate)
    return 1e3 * float(np.percentile(jitter, 99)), 1e3 * float(intervals.max())


def publish_rate_measured(tick_times) -> float:
    """
    Return the joint_states rate (Hz) over the last second of ticks (NaN when unknown).

    Parameters
    ----------
    tick_times
        Monotonic times (s) the recent frames were published at, oldest first.

    Returns
    -------
    float
        Frames per second over the last second of ``tick_times``.

    """
    ticks = list(tick_times)
    if len(ticks) < 2:
        return float('nan')
    recent = [t for t in ticks if t >= ticks[-1] - 1.0]
    if len(recent) < 2 or recent[-1] <= recent[0]:
        return float('nan')
    return (len(recent) - 1) / (recent[-1] - recent[0])


def planner_diagnostics(node) -> DiagnosticArray:
    """
    Build the /diagnostics status of an actor planner node.

    Parameters
    ----------
    node
        The ``ActorPlannerNode``.

    Returns
    -------
    DiagnosticArray
        One status named after the node: OK, WARN (stuck, recovering, a scene error, a rate
        off by more than 5 %, a cmd_vel of the other type) or ERROR (the node is ending), with
        the planning and stream statistics as values; not stamped.

    """
    stats = node.stats
    p50, p99 = stats.percentiles()
    rate = publish_rate_measured(node.tick_times)
    jitter_p99, longest = stream_timing(node.tick_times, node.config.publish_rate)
    rate_ok = math.isfinite(rate) and abs(rate - node.config.publish_rate) <= \
        0.05 * node.config.publish_rate
    level = DiagnosticStatus.OK
    message = stats.state + (f': {stats.reason}' if stats.reason else '')
    if stats.state in ('stuck', 'recovering') or node.scene_error or not rate_ok or \
            node.cmd_vel_mismatch:
        level = DiagnosticStatus.WARN
    if node.exit_code is not None:
        level = DiagnosticStatus.ERROR
    if node.scene_error:
        message += f'; scene error: {node.scene_error}'
    if node.cmd_vel_mismatch:
        message += f'; {node.cmd_vel_mismatch}'
    if not rate_ok:
        message += f'; joint_states at {rate:.1f} Hz'
    values = {
        'state': stats.state,
        'reason': stats.reason,
        'steps': str(stats.steps),
        'blocks_planned': str(stats.blocks),
        'planning_time_last_ms': f'{1e3 * stats.last_planning_time:.3f}',
        'planning_time_p50_ms': f'{1e3 * p50:.3f}',
        'planning_time_p99_ms': f'{1e3 * p99:.3f}',
        'publish_rate_hz': f'{rate:.2f}',
        'publish_rate_target_hz': f'{node.config.publish_rate:g}',
        'stream_jitter_p99_ms': f'{jitter_p99:.3f}',
        'stream_longest_interval_ms': f'{longest:.2f}',
        'missed_frames': str(node.missed_frames),
        'stream_backup_ticks': str(node.ticker.backup_publishes),
        'stream_caught_up_ticks': str(node.ticker.caught_up),
        'stream_late_ticks': str(node.ticker.late_ticks),
        'stream_lateness_max_ms': f'{1e3 * node.ticker.max_lateness:.2f}',
        'buffer_underruns': str(node.underruns),
        'buffered_ahead_s': f'{node.buffer.end_time - node.playback_time:.3f}',
        'planning_lead_s': f'{node.effective_lead():.3f}',
        'scene': node.scene_path,
        'scene_error': node.scene_error,
        'cmd_vel_type_mismatch': node.cmd_vel_mismatch,
        'planning_process_pid': str(node.planner.worker.pid),
        'planning_processes_replaced': str(node.planner.worker.generation),
        'stale_replies_dropped': str(node.planner.worker.stale_replies),
        'blocks_planned_again': str(node.replanned_blocks),
    }
    status = DiagnosticStatus(
        level=level, name=f'{node.get_fully_qualified_name()}: actor planner',
        message=message, hardware_id=node.get_fully_qualified_name(),
        values=[KeyValue(key=k, value=v) for k, v in values.items()])
    return DiagnosticArray(status=[status])
