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
Parameters of the ``actor_planner`` node: descriptors, the frozen node config, validation.

The node declares every parameter listed here with its descriptor, reads them into a
:class:`PlannerNodeConfig` and calls :func:`validate_node_config` once; a bad value makes the node
exit non-zero with a message naming the parameter (STYLE: Parameters).
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import os
import sys
from typing import Any, Callable, Dict, List, Optional, Tuple

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.parameter import Parameter

PACKAGE_NAME = 'digital_actor_planner'
DEFAULT_SCENE = 'flat.yaml'

# Parameters that may change while the node runs; every other one is read-only.
RUNTIME_PARAMETERS = ('scene', 'cmd_timeout')


class ConfigurationError(ValueError):
    """A parameter value the node cannot run with; ``parameter`` names it."""

    def __init__(self, parameter: str, message: str):
        super().__init__(f'parameter {parameter!r}: {message}')
        self.parameter = parameter


def default_scene_path() -> str:
    """
    Return the package's default scene (``config/scenes/flat.yaml``), installed or in source.

    Returns
    -------
    str
        The first existing candidate: the ament share directory, the source tree, then the
        Python prefix's share directory. When none exists the source-tree path is returned, so
        the error message names a real location.

    """
    candidates = []
    try:
        from ament_index_python.packages import get_package_share_directory, \
            PackageNotFoundError
        try:
            candidates.append(os.path.join(get_package_share_directory(PACKAGE_NAME),
                                           'config', 'scenes', DEFAULT_SCENE))
        except (PackageNotFoundError, OSError):  # OSError: AMENT_PREFIX_PATH unset
            pass
    except ImportError:
        pass
    here = os.path.dirname(os.path.abspath(__file__))
    source = os.path.normpath(os.path.join(here, '..', '..', 'config', 'scenes', DEFAULT_SCENE))
    candidates += [source, os.path.join(sys.prefix, 'share', PACKAGE_NAME, 'config', 'scenes',
                                        DEFAULT_SCENE)]
    # colcon install: <prefix>/lib/pythonX.Y/site-packages/<pkg>/nodes/planner_params.py
    prefix = here
    for _ in range(6):
        prefix = os.path.dirname(prefix)
        candidates.append(os.path.join(prefix, 'share', PACKAGE_NAME, 'config', 'scenes',
                                       DEFAULT_SCENE))
    for path in candidates:
        if os.path.isfile(path):
            return os.path.normpath(path)
    return source


def _float_range(low: float, high: float) -> List[FloatingPointRange]:
    return [FloatingPointRange(from_value=float(low), to_value=float(high), step=0.0)]


def _int_range(low: int, high: int) -> List[IntegerRange]:
    return [IntegerRange(from_value=int(low), to_value=int(high), step=1)]


def _descriptor(description: str, read_only: bool = True, floats=None,
                integers=None, constraints: str = '') -> ParameterDescriptor:
    descriptor = ParameterDescriptor(description=description, read_only=read_only,
                                     additional_constraints=constraints)
    if floats is not None:
        descriptor.floating_point_range = _float_range(*floats)
    if integers is not None:
        descriptor.integer_range = _int_range(*integers)
    return descriptor


def parameter_declarations() -> List[Tuple[str, Any, ParameterDescriptor]]:
    """
    Return ``(name, default, descriptor)`` for every parameter the node declares.

    Returns
    -------
    list of (str, value or Parameter.Type, ParameterDescriptor)
        ``start_pose`` is declared by type only (unset means the scene's start pose).

    """
    return [
        ('scene', default_scene_path(), _descriptor(
            'Scene YAML (meshes + start) or one mesh file; changing it reloads the environment '
            '(the old one is kept if the new one fails to load).', read_only=False)),
        ('start_pose', Parameter.Type.DOUBLE_ARRAY, _descriptor(
            'Start pose [x, y, yaw] (m, m, rad); unset or empty uses the scene start.',
            constraints='empty or 3 finite numbers')),
        ('publish_rate', 100.0, _descriptor(
            'Rate of joint_states (Hz); frames are interpolated from the planned blocks.',
            floats=(1.0, 1000.0))),
        ('window_steps', 3, _descriptor(
            'Footstep window length n (paper §4.2).', integers=(1, 10))),
        ('step_intervals', 13, _descriptor(
            'Step-length intervals m of the footstep planner (paper §4.2).',
            integers=(2, 100))),
        ('step_length_min', 0.15, _descriptor(
            'Shortest step s_min (m).', floats=(0.0, 2.0),
            constraints='step_length_min < step_length_max')),
        ('step_length_max', 0.8, _descriptor(
            'Longest step s_max (m).', floats=(0.01, 2.0),
            constraints='step_length_min < step_length_max')),
        ('max_linear_speed', 1.0, _descriptor(
            'Forward speed limit (m/s); commands beyond it are clamped. The default is the '
            'fastest the gait walks: above it the steps would slow down.', floats=(0.01, 3.0))),
        ('max_angular_speed', 1.0, _descriptor(
            'Turning speed limit (rad/s); commands beyond it are clamped.',
            floats=(0.01, 3.0))),
        ('max_backward_speed', 0.5, _descriptor(
            'Backward speed limit (m/s): a negative linear.x walks backward, clamped to '
            '-this.', floats=(0.01, 3.0), constraints='max_backward_speed <= max_linear_speed')),
        ('allow_backward', True, _descriptor(
            "Walk backward on a negative linear.x; false: the paper's actor, which walks "
            'forward only (a negative linear.x becomes 0).')),
        ('cmd_timeout', 0.5, _descriptor(
            'No cmd_vel for this long (s) makes the actor come to a stop.', read_only=False,
            floats=(0.01, 3600.0))),
        ('frame_id', 'world', _descriptor(
            'header.frame_id of joint_states, markers and the path.',
            constraints='non-empty')),
        ('cmd_vel_stamped', True, _descriptor(
            'cmd_vel type: geometry_msgs/TwistStamped when true, geometry_msgs/Twist when '
            'false.')),
        ('publish_robot_description', True, _descriptor(
            'Publish the URDF on robot_description (std_msgs/String, transient local).')),
        ('planning_lead', 0.3, _descriptor(
            'Plan the next block when less than this much committed motion (s) is buffered '
            'ahead of playback; larger rides out planning hiccups, smaller reacts sooner.',
            floats=(0.02, 5.0))),
        ('planning_timeout', 60.0, _descriptor(
            'A planning process that gives no answer for this long (s) is replaced by a new '
            'one, and the actor goes on from where it stands.', floats=(0.1, 3600.0))),
        ('stream_priority', 10, _descriptor(
            'SCHED_FIFO priority of the joint_states thread (1-99) for low jitter on a busy '
            'machine; 0 or no permission: normal scheduling.', integers=(0, 99))),
    ]


@dataclass(frozen=True)
class PlannerNodeConfig:
    """
    Everything the node runs with, read once from its parameters.

    ``start_pose`` is ``(x, y, yaw)`` in m, m, rad or None for the scene's own start;
    ``publish_rate`` in Hz; ``cmd_timeout`` and ``planning_lead`` in s.
    """

    scene: str
    start_pose: Optional[Tuple[float, float, float]]
    publish_rate: float
    window_steps: int
    step_intervals: int
    step_length_min: float
    step_length_max: float
    max_linear_speed: float
    max_angular_speed: float
    cmd_timeout: float
    frame_id: str
    cmd_vel_stamped: bool
    publish_robot_description: bool
    planning_lead: float = 0.3
    stream_priority: int = 0
    max_backward_speed: float = 0.5
    allow_backward: bool = True
    planning_timeout: float = 60.0

    def actor_config_fields(self) -> Dict[str, Any]:
        """Return the keyword arguments of the core ``ActorConfig`` these parameters set."""
        return {
            'window_steps': self.window_steps,
            'step_intervals': self.step_intervals,
            'step_length_min': self.step_length_min,
            'step_length_max': self.step_length_max,
            'max_linear_speed': self.max_linear_speed,
            'max_angular_speed': self.max_angular_speed,
            'max_backward_speed': self.max_backward_speed,
            'allow_backward': self.allow_backward,
        }


def _value_or(value: Any, default: Any) -> Any:
    return default if value is None else value


def read_node_config(get_value: Callable[[str], Any]) -> PlannerNodeConfig:
    """
    Build the frozen node config from ``get_value(name)`` (the declared parameter values).

    Parameters
    ----------
    get_value
        Returns the current value of a declared parameter (None when unset).

    Returns
    -------
    PlannerNodeConfig
        Not yet validated; call :func:`validate_node_config`.

    Raises
    ------
    ConfigurationError
        ``start_pose`` is not empty or three numbers.

    """
    start = get_value('start_pose')
    if start is None or len(start) == 0:
        start_pose = None
    elif len(start) != 3:
        raise ConfigurationError('start_pose', f'expected [x, y, yaw], got {list(start)!r}')
    else:
        start_pose = tuple(float(v) for v in start)
    return PlannerNodeConfig(
        scene=str(get_value('scene')),
        start_pose=start_pose,
        publish_rate=float(get_value('publish_rate')),
        window_steps=int(get_value('window_steps')),
        step_intervals=int(get_value('step_intervals')),
        step_length_min=float(get_value('step_length_min')),
        step_length_max=float(get_value('step_length_max')),
        max_linear_speed=float(get_value('max_linear_speed')),
        max_angular_speed=float(get_value('max_angular_speed')),
        cmd_timeout=float(get_value('cmd_timeout')),
        frame_id=str(get_value('frame_id')),
        cmd_vel_stamped=bool(get_value('cmd_vel_stamped')),
        publish_robot_description=bool(get_value('publish_robot_description')),
        planning_lead=float(get_value('planning_lead')),
        stream_priority=int(get_value('stream_priority')),
        # Unset: the declared defaults.
        max_backward_speed=float(_value_or(get_value('max_backward_speed'), 0.5)),
        allow_backward=bool(_value_or(get_value('allow_backward'), True)),
        planning_timeout=float(get_value('planning_timeout') or 60.0),
    )


def scene_file_error(path: str) -> str:
    """
    Return why ``path`` cannot be a scene file ('' when it may be one).

    Why ``path`` cannot be a scene file ('' when it may be one): the same words at start and for a
    change at run time.
    """
    if not path.strip():
        return 'must name a scene YAML or mesh file'
    if os.path.isdir(path):
        return f'{path}: is a directory, not a scene file'
    if not os.path.isfile(path):
        return f'{path}: no such scene file'
    return ''


def validate_node_config(config: PlannerNodeConfig) -> None:
    """
    Check the cross-field and file rules the descriptors cannot express.

    Parameters
    ----------
    config
        The node configuration.

    Raises
    ------
    ConfigurationError
        Naming the first bad parameter and its value.

    """
    if config.start_pose is not None and not all(math.isfinite(v) for v in config.start_pose):
        raise ConfigurationError('start_pose', f'not finite: {list(config.start_pose)!r}')
    for name in ('publish_rate', 'cmd_timeout', 'step_length_min', 'step_length_max',
                 'max_linear_speed', 'max_angular_speed', 'max_backward_speed',
                 'planning_lead'):
        value = getattr(config, name)
        if not math.isfinite(value) or value < 0.0:
            raise ConfigurationError(name, f'must be a finite non-negative number, got {value!r}')
    if not config.frame_id.strip():
        raise ConfigurationError('frame_id', 'must not be empty')
    if not config.scene.strip():
        raise ConfigurationError('scene', 'must name a scene YAML or mesh file')
    problem = scene_file_error(config.scene)
    if problem:
        raise ConfigurationError('scene', problem)
    if config.max_backward_speed > config.max_linear_speed:
        raise ConfigurationError(
            'max_backward_speed', f'{config.max_backward_speed} must not exceed '
            f'max_linear_speed {config.max_linear_speed}')
    if config.step_length_min >= config.step_length_max:
        raise ConfigurationError(
            'step_length_min', f'{config.step_length_min} must be below step_length_max '
            f'{config.step_length_max}')
