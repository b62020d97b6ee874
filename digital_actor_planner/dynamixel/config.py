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

"""Bridge configuration: the servo table, its validation, and radians <-> X-series ticks."""
from __future__ import annotations

from dataclasses import dataclass
import math
from typing import Dict, Mapping, Optional, Sequence, Tuple

from digital_actor_planner.core.skeleton import ROOT_JOINTS, Skeleton
import numpy as np

#: X-series resolution: 4096 ticks per revolution, 2048 is the centre of the range.
TICKS_PER_REVOLUTION = 4096
CENTRE_TICKS = 2048
MAX_TICKS = TICKS_PER_REVOLUTION - 1
RADIANS_PER_TICK = 2.0 * math.pi / TICKS_PER_REVOLUTION
#: Baud rates both an X-series servo (Baud Rate register) and dynamixel-sdk's port support.
SUPPORTED_BAUD_RATES = (9600, 57600, 115200, 1_000_000, 2_000_000, 3_000_000, 4_000_000)
#: The parameters that describe one servo, under ``servos.<joint>.``.
SERVO_FIELDS = ('id', 'offset', 'direction', 'min_position', 'max_position', 'max_speed')


class ConfigError(ValueError):
    """The bridge configuration is invalid; the message names the bad item."""


@dataclass(frozen=True)
class ServoConfig:
    """
    One joint driven by one servo.

    ``offset`` is the servo angle (rad, from the 2048-tick centre) at joint angle zero;
    ``direction`` is +1 or -1; the safe range is in joint radians; ``max_speed`` in rad/s.
    """

    joint: str
    id: int  # noqa: A003 (the servo's Dynamixel ID, the name its e-Manual uses)
    offset: float = 0.0
    direction: int = 1
    min_position: float = -math.pi
    max_position: float = math.pi
    max_speed: float = 1.0

    def _raw_ticks(self, angle: float) -> float:
        return CENTRE_TICKS + (self.direction * angle + self.offset) / RADIANS_PER_TICK

    def to_ticks(self, angle: float) -> int:
        """
        Joint angle (rad) -> goal position ticks, kept within 0..4095.

        An angle inside the safe range gets the nearest tick that is also inside it: the ends
        of the range rarely fall on a tick, and rounding to the nearest one would put the
        servo up to half a tick past its limit. Outside the range (a servo still easing in
        from where it was switched on) the nearest tick is taken.
        """
        ticks = self._raw_ticks(angle)
        goal = round(ticks)
        low, high = sorted((self._raw_ticks(self.min_position),
                            self._raw_ticks(self.max_position)))
        # The tolerance keeps an end that lies on a tick (up to rounding error) usable.
        inner_low, inner_high = math.ceil(low - 1e-6), math.floor(high + 1e-6)
        if low <= ticks <= high and inner_low <= inner_high:
            goal = min(max(goal, inner_low), inner_high)
        return int(min(max(goal, 0), MAX_TICKS))

    def to_angle(self, ticks: int) -> float:
        """Present position ticks -> joint angle (rad)."""
        return self.direction * ((ticks - CENTRE_TICKS) * RADIANS_PER_TICK - self.offset)


@dataclass(frozen=True)
class BridgeConfig:
    """Everything the bridge needs; built from ROS parameters or a YAML file."""

    servos: Tuple[ServoConfig, ...]
    port: str = '/dev/ttyUSB0'
    baud_rate: int = 1_000_000
    control_rate: float = 100.0
    joint_state_topic: str = 'joint_states'
    watchdog_timeout: float = 0.5
    torque_off_on_shutdown: bool = True
    require_all_servos: bool = False
    dry_run: bool = False
    reconnect_backoff_min: float = 0.2
    reconnect_backoff_max: float = 5.0
    health_check_period: float = 0.2
    fast_sync_read: bool = False

    @property
    def joint_names(self) -> Tuple[str, ...]:
        return tuple(s.joint for s in self.servos)


def servo_joint_names(skeleton: Skeleton) -> Tuple[str, ...]:
    """Return the 18 body joints that can be servos (all but the root), in skeleton order."""
    return tuple(n for n in skeleton.joint_names if n not in ROOT_JOINTS)


def default_servo(skeleton: Skeleton, joint: str, servo_id: int) -> ServoConfig:
    """Make a servo for ``joint`` using the URDF position and velocity limits as its envelope."""
    i = skeleton.index[joint]
    return ServoConfig(joint=joint, id=servo_id, min_position=float(skeleton.lower[i]),
                       max_position=float(skeleton.upper[i]),
                       max_speed=float(skeleton.velocity_limit[i]))


def validate(config: BridgeConfig, skeleton: Skeleton) -> None:
    """Raise :class:`ConfigError` naming the first bad item of ``config``."""
    if not config.port:
        raise ConfigError('port: empty')
    if config.baud_rate not in SUPPORTED_BAUD_RATES:
        raise ConfigError(f'baud_rate: {config.baud_rate} unsupported; use one of '
                          f'{", ".join(str(b) for b in SUPPORTED_BAUD_RATES)}')
    for name in ('control_rate', 'watchdog_timeout', 'reconnect_backoff_min',
                 'reconnect_backoff_max', 'health_check_period'):
        value = getattr(config, name)
        if not (math.isfinite(value) and value > 0):
            raise ConfigError(f'{name}: {value} must be a positive number')
    if config.reconnect_backoff_max < config.reconnect_backoff_min:
        raise ConfigError(f'reconnect_backoff_max: {config.reconnect_backoff_max} is below '
                          f'reconnect_backoff_min {config.reconnect_backoff_min}')
    if not config.servos:
        raise ConfigError('servo_joints: no servos configured')
    allowed = servo_joint_names(skeleton)
    seen_joints: Dict[str, int] = {}
    seen_ids: Dict[int, str] = {}
    for servo in config.servos:
        where = f'servos.{servo.joint}'
        if servo.joint not in allowed:
            what = 'is a root joint, not a servo' if servo.joint in ROOT_JOINTS else (
                'is not a joint of the actor')
            raise ConfigError(f'{where}: unknown joint name {servo.joint!r} ({what}; '
                              f'joints: {", ".join(allowed)})')
        if servo.joint in seen_joints:
            raise ConfigError(f'{where}: joint {servo.joint!r} listed twice')
        seen_joints[servo.joint] = servo.id
        if not 0 <= servo.id <= 252:
            raise ConfigError(f'{where}.id: {servo.id} outside 0..252')
        if servo.id in seen_ids:
            raise ConfigError(f'{where}.id: duplicate servo ID {servo.id} (also used by '
                              f'{seen_ids[servo.id]})')
        seen_ids[servo.id] = servo.joint
        if servo.direction not in (1, -1):
            raise ConfigError(f'{where}.direction: {servo.direction} must be 1 or -1')
        for name in ('offset', 'min_position', 'max_position', 'max_speed'):
            if not math.isfinite(getattr(servo, name)):
                raise ConfigError(f'{where}.{name}: {getattr(servo, name)} is not finite')
        if not servo.max_speed > 0:
            raise ConfigError(f'{where}.max_speed: {servo.max_speed} must be positive')
        i = skeleton.index[servo.joint]
        lower, upper = float(skeleton.lower[i]), float(skeleton.upper[i])
        if not servo.min_position < servo.max_position:
            raise ConfigError(f'{where}: min_position {servo.min_position} is not below '
                              f'max_position {servo.max_position}')
        if servo.min_position < lower - 1e-9 or servo.max_position > upper + 1e-9:
            raise ConfigError(f'{where}: safe range [{servo.min_position}, '
                              f'{servo.max_position}] outside the URDF limits '
                              f'[{lower}, {upper}]')
        for end in (servo.min_position, servo.max_position):
            raw = CENTRE_TICKS + (servo.direction * end + servo.offset) / RADIANS_PER_TICK
            if not 0 <= raw <= MAX_TICKS:
                raise ConfigError(f'{where}: angle {end} rad with offset {servo.offset} maps '
                                  f'to {raw:.0f} ticks, outside 0..{MAX_TICKS}')


_SCALARS = {'port': str, 'baud_rate': int, 'control_rate': float, 'joint_state_topic': str,
            'watchdog_timeout': float, 'torque_off_on_shutdown': bool,
            'require_all_servos': bool, 'dry_run': bool, 'reconnect_backoff_min': float,
            'reconnect_backoff_max': float, 'health_check_period': float,
            'fast_sync_read': bool}


def config_from_parameters(parameters: Mapping[str, object], skeleton: Skeleton) -> BridgeConfig:
    """
    Build and validate a config from flat parameter names.

    Parameters
    ----------
    parameters : Mapping[str, object]
        ``port``, ``baud_rate``, ... and ``servo_joints`` (list of joint names) with
        ``servos.<joint>.<field>`` for each joint (fields in :data:`SERVO_FIELDS`); missing
        servo fields default to ID = position in the list + 1, zero offset, direction 1 and
        the URDF limits.
    skeleton
        Supplies the joint names and URDF limits.

    Returns
    -------
    BridgeConfig
        A validated configuration.

    """
    known = set(_SCALARS) | {'servo_joints'}
    for key in parameters:
        head, _, rest = key.partition('.')
        if key in known or (head == 'servos' and rest):
            continue
        raise ConfigError(f'{key}: unknown parameter')
    values = {}
    for name, kind in _SCALARS.items():
        if name in parameters:
            value = parameters[name]
            if kind is bool and not isinstance(value, bool):
                raise ConfigError(f'{name}: {value!r} is not true/false')
            try:
                values[name] = kind(value)
            except (TypeError, ValueError):
                raise ConfigError(f'{name}: {value!r} is not a {kind.__name__}') from None
    joints = parameters.get('servo_joints')
    if joints is None:
        joints = servo_joint_names(skeleton)
    if isinstance(joints, str) or not isinstance(joints, Sequence):
        raise ConfigError(f'servo_joints: {joints!r} is not a list of joint names')
    for key in parameters:
        head, _, rest = key.partition('.')
        if head == 'servos':
            joint, _, field_name = rest.partition('.')
            if joint not in joints:
                raise ConfigError(f'{key}: joint {joint!r} is not listed in servo_joints')
            if field_name not in SERVO_FIELDS:
                raise ConfigError(f'{key}: unknown servo field {field_name!r}')
    servos = []
    for number, joint in enumerate(joints):
        joint = str(joint)
        if joint in skeleton.index:
            base = default_servo(skeleton, joint, number + 1)
        else:
            base = ServoConfig(joint=joint, id=number + 1)
        fields = {}
        for field_name in SERVO_FIELDS:
            key = f'servos.{joint}.{field_name}'
            if key in parameters:
                kind = int if field_name in ('id', 'direction') else float
                raw = parameters[key]
                if isinstance(raw, bool) or (kind is int and isinstance(raw, float)
                                             and not raw.is_integer()):
                    raise ConfigError(f'{key}: {raw!r} is not an integer')
                try:
                    fields[field_name] = kind(raw)
                except (TypeError, ValueError):
                    raise ConfigError(f'{key}: {raw!r} is not a number') from None
        servos.append(ServoConfig(**{**base.__dict__, **fields}))
    config = BridgeConfig(servos=tuple(servos), **values)
    validate(config, skeleton)
    return config


def flatten_parameters(tree: Mapping[str, object], prefix: str = '') -> Dict[str, object]:
    """Flatten nested YAML mappings into dotted ROS parameter names."""
    flat: Dict[str, object] = {}
    for key, value in tree.items():
        name = f'{prefix}{key}'
        if isinstance(value, Mapping):
            flat.update(flatten_parameters(value, name + '.'))
        else:
            flat[name] = value
    return flat


def load_config(path: str, skeleton: Skeleton,
                node_name: str = 'dynamixel_bridge') -> BridgeConfig:
    """Read a ROS 2 parameter file (``<node>: ros__parameters: ...``) into a config."""
    import yaml
    try:
        with open(path) as stream:
            document = yaml.safe_load(stream) or {}
    except (OSError, yaml.YAMLError) as error:
        raise ConfigError(f'{path}: cannot read: {error}') from None
    section: Optional[Mapping] = None
    for key in (node_name, '/**', f'/{node_name}'):
        if isinstance(document.get(key), Mapping):
            section = document[key].get('ros__parameters')
            break
    if not isinstance(section, Mapping):
        raise ConfigError(f'{path}: no {node_name}: ros__parameters: section')
    return config_from_parameters(flatten_parameters(section), skeleton)


def angles_to_ticks(servos: Sequence[ServoConfig], angles: np.ndarray) -> np.ndarray:
    """Convert (n,) joint angles (rad) to (n,) int goal ticks for ``servos``."""
    return np.array([s.to_ticks(float(a)) for s, a in zip(servos, angles)], dtype=int)
