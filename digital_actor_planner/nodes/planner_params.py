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

Every parameter is declared once with :func:`core.settings.setting`: the node's own ones as
fields of :class:`PlannerNodeConfig` here, the actor's ones in the core's configs (named in
:data:`ACTOR_PARAMETERS`). The ROS descriptors, the checks and the README's parameter table
(``scripts/parameter_table.py``) all come from those declarations. The node declares every
parameter with its descriptor, reads them into a :class:`PlannerNodeConfig` and calls
:func:`validate_node_config` once; a bad value makes the node exit non-zero with a message
naming the parameter (STYLE: Parameters).
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import os
import sys
from typing import Any, Callable, Dict, List, Optional, Tuple

from digital_actor_planner.core.settings import check_settings, ConfigError, \
    declared_settings, Setting, setting
# The error naming a bad parameter is the runtime's (ROS-free), shared with the planning process.
from digital_actor_planner.runtime.planning import ConfigurationError
from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.parameter import Parameter

PACKAGE_NAME = 'digital_actor_planner'
DEFAULT_SCENE = 'flat.yaml'

# Parameters that may change while the node runs; every other one is read-only.
RUNTIME_PARAMETERS = ('scene', 'cmd_timeout')

#: The actor's settings the node sets from parameters of the same names, declared in the core
#: (``FootstepConfig``, ``ActorConfig``); in the parameter list they follow ``publish_rate``.
ACTOR_PARAMETERS = ('window_steps', 'step_intervals', 'step_length_min', 'step_length_max',
                    'max_linear_speed', 'max_angular_speed', 'max_backward_speed',
                    'allow_backward')


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


@dataclass(frozen=True)
class PlannerNodeConfig:
    """
    Everything the node runs with, read once from its parameters.

    The fields are the node's own parameters, each declared once here; ``actor`` holds the
    values of :data:`ACTOR_PARAMETERS` by name, for ``ActorConfig.from_settings``.
    """

    scene: str = setting(
        '', doc='Scene YAML (meshes + start) or one mesh file; changing it reloads the '
        'environment (the old one is kept if the new one fails to load).',
        rule='a scene YAML or mesh file')
    start_pose: Optional[Tuple[float, float, float]] = setting(
        None, doc='Start pose [x, y, yaw]; unset or empty uses the scene start.',
        unit='m, m, rad', kind=tuple, optional=True, rule='empty or 3 finite numbers')
    publish_rate: float = setting(
        100.0, 1.0, 1000.0, 'Rate of joint_states; frames are interpolated from the planned '
        'blocks.', 'Hz')
    cmd_timeout: float = setting(
        0.5, 0.01, 3600.0, 'No cmd_vel for this long makes the actor come to a stop.', 's')
    frame_id: str = setting(
        'world', doc='header.frame_id of joint_states, markers and the path.',
        rule='non-empty')
    cmd_vel_stamped: bool = setting(
        True, doc='cmd_vel type: geometry_msgs/TwistStamped when true, geometry_msgs/Twist '
        'when false.')
    publish_robot_description: bool = setting(
        True, doc='Publish the URDF on robot_description (std_msgs/String, transient local).')
    planning_lead: float = setting(
        0.3, 0.02, 5.0, 'Plan the next block when less than this much committed motion is '
        'buffered ahead of playback; larger rides out planning hiccups, smaller reacts '
        'sooner.', 's')
    planning_timeout: float = setting(
        60.0, 0.1, 3600.0, 'A planning process that gives no answer for this long is replaced '
        'by a new one, and the actor goes on from where it stands.', 's')
    stream_priority: int = setting(
        10, 0, 99, 'SCHED_FIFO priority of the joint_states thread (1-99) for low jitter on a '
        'busy machine; 0 or no permission: normal scheduling.')
    actor: Dict[str, Any] = field(default_factory=dict)

    def __post_init__(self):
        """Check every parameter against its declaration, start_pose and frame_id too."""
        check_settings(self)
        if self.start_pose is not None:
            pose = tuple(self.start_pose)
            if len(pose) != 3:
                raise ConfigError('start_pose', pose, f'expected [x, y, yaw], got {list(pose)!r}')
            if not all(isinstance(v, (int, float)) and math.isfinite(v) for v in pose):
                raise ConfigError('start_pose', pose, f'not finite: {list(pose)!r}')
        if not self.frame_id.strip():
            raise ConfigError('frame_id', self.frame_id, 'frame_id must not be empty')

    def actor_config_fields(self) -> Dict[str, Any]:
        """Return the settings of the core ``ActorConfig`` these parameters set, by name."""
        return dict(self.actor)


def actor_parameter_settings() -> Dict[str, Setting]:
    """Return the core's declarations of :data:`ACTOR_PARAMETERS`, by name."""
    # Imported here: the node process loads the core only once it has chosen plain Python
    # over the compiled kernels (actor_planner._without_kernels).
    from digital_actor_planner.core.actor import ActorConfig
    from digital_actor_planner.core.footsteps import FootstepConfig
    from digital_actor_planner.core.gait import GaitConfig
    declared = {**declared_settings(FootstepConfig), **declared_settings(GaitConfig),
                **declared_settings(ActorConfig)}
    return {name: declared[name] for name in ACTOR_PARAMETERS}


def parameter_settings() -> List[Tuple[str, Setting]]:
    """
    Return ``(name, Setting)`` of every parameter the node declares, in declaration order.

    Returns
    -------
    list of (str, Setting)
        The node's own parameters with the actor's ones after ``publish_rate``.

    """
    own = list(declared_settings(PlannerNodeConfig).items())
    at = [name for name, _ in own].index('publish_rate') + 1
    return own[:at] + list(actor_parameter_settings().items()) + own[at:]


def _description(declaration: Setting) -> str:
    doc = declaration.doc
    if not declaration.unit:
        return doc
    return f'{doc[:-1]} ({declaration.unit}).' if doc.endswith('.') else \
        f'{doc} ({declaration.unit})'


def _constraints(declaration: Setting) -> str:
    """Return what the descriptor's range cannot say: open bounds, choices, a rule."""
    parts = []
    if declaration.low_open:
        parts.append(f'> {declaration.low:g}')
    if declaration.high_open:
        parts.append(f'< {declaration.high:g}')
    if declaration.choices:
        parts.append(declaration.describe_range())
    if declaration.rule:
        parts.append(declaration.rule)
    return '; '.join(parts)


def descriptor_of(name: str, declaration: Setting) -> ParameterDescriptor:
    """
    Return the ROS descriptor of a declared setting: description, range, read-only.

    The range is the declaration's (``low`` to ``high``); an open bound, the choices or a rule
    between parameters go to ``additional_constraints``.
    """
    descriptor = ParameterDescriptor(description=_description(declaration),
                                     read_only=name not in RUNTIME_PARAMETERS,
                                     additional_constraints=_constraints(declaration))
    bounded = declaration.low is not None and declaration.high is not None
    if bounded and declaration.kind is float:
        descriptor.floating_point_range = [FloatingPointRange(
            from_value=float(declaration.low), to_value=float(declaration.high), step=0.0)]
    elif bounded and declaration.kind is int:
        descriptor.integer_range = [IntegerRange(
            from_value=int(declaration.low), to_value=int(declaration.high), step=1)]
    return descriptor


def parameter_declarations() -> List[Tuple[str, Any, ParameterDescriptor]]:
    """
    Return ``(name, default, descriptor)`` for every parameter the node declares.

    Returns
    -------
    list of (str, value or Parameter.Type, ParameterDescriptor)
        ``start_pose`` is declared by type only (unset means the scene's start pose);
        ``scene`` defaults to the package's flat scene.

    """
    declarations = []
    for name, declaration in parameter_settings():
        default = declaration.default
        if name == 'scene':
            default = default_scene_path()
        elif name == 'start_pose':
            default = Parameter.Type.DOUBLE_ARRAY
        declarations.append((name, default, descriptor_of(name, declaration)))
    return declarations


def _typed(declaration: Setting, value: Any) -> Any:
    if value is None:
        return declaration.default
    if declaration.kind in (bool, int, float, str):
        return declaration.kind(value)
    return value


def read_node_config(get_value: Callable[[str], Any]) -> PlannerNodeConfig:
    """
    Build the frozen node config from ``get_value(name)`` (the declared parameter values).

    Parameters
    ----------
    get_value
        Returns the current value of a declared parameter (None when unset: its default).

    Returns
    -------
    PlannerNodeConfig
        Its own parameters checked; call :func:`validate_node_config` for the rest.

    Raises
    ------
    ConfigurationError
        A parameter outside its declared range, ``start_pose`` not empty or three numbers.

    """
    own = {}
    for name, declaration in declared_settings(PlannerNodeConfig).items():
        value = get_value(name)
        if name == 'start_pose':
            own[name] = None if value is None or len(value) == 0 else tuple(value)
        else:
            own[name] = _typed(declaration, value)
    actor = {name: _typed(declaration, get_value(name))
             for name, declaration in actor_parameter_settings().items()}
    try:
        return PlannerNodeConfig(actor=actor, **own)
    except ConfigError as error:
        raise ConfigurationError.of(error) from None


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
    Check the scene file and the actor's parameters with the core's own checks.

    Parameters
    ----------
    config
        The node configuration.

    Raises
    ------
    ConfigurationError
        Naming the first bad parameter and its value.

    """
    problem = scene_file_error(config.scene)
    if problem:
        raise ConfigurationError('scene', problem, config.scene)
    from digital_actor_planner.core.actor import ActorConfig
    try:
        ActorConfig.from_settings(**config.actor_config_fields())
    except ConfigError as error:
        raise ConfigurationError.of(error) from None
