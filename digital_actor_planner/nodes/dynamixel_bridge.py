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
ROS 2 node ``dynamixel_bridge``: drive Dynamixel X-series servos from a JointState stream.

A thin adapter: parameters -> :class:`BridgeConfig`, messages -> :class:`BridgeController`,
feedback -> ``~/joint_states``, health -> ``/diagnostics``. Exit codes: 0 after a clean
shutdown, 2 for invalid configuration, 3 when required servos are missing at start-up, 4 when
torque could not be switched off on the way out (the servos named in the log may still hold).
"""
from __future__ import annotations

import os
import signal
import sys
import time
from typing import Dict, List, Optional

# Ctrl-C while the modules load (seconds on a busy machine): nothing is driven yet, so the
# bridge leaves quietly instead of with a traceback.
try:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from digital_actor_planner.core.skeleton import Skeleton
    from digital_actor_planner.dynamixel.config import (BridgeConfig, config_from_parameters,
                                                        ConfigError, servo_joint_names,
                                                        SUPPORTED_BAUD_RATES)
    from digital_actor_planner.dynamixel.controller import BridgeController, StartupError
    from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
    import rclpy
    from rclpy.exceptions import (InvalidParameterTypeException, InvalidParameterValueException,
                                  ParameterException)
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.parameter import Parameter
    from rclpy.signals import SignalHandlerOptions
    from sensor_msgs.msg import JointState
except KeyboardInterrupt:  # pragma: no cover - depends on when the signal lands
    # Not sys.exit: after an import cut short by the signal, the interpreter's exit would end
    # the process by SIGINT whatever status it was given.
    os._exit(0)

EXIT_BAD_CONFIG = 2
EXIT_MISSING_SERVOS = 3
EXIT_TORQUE_STILL_ON = 4


def _float_range(low: float, high: float) -> List[FloatingPointRange]:
    return [FloatingPointRange(from_value=low, to_value=high, step=0.0)]


def _int_range(low: int, high: int) -> List[IntegerRange]:
    return [IntegerRange(from_value=low, to_value=high, step=1)]


# name -> (default, description, extra descriptor fields)
_PARAMETERS = {
    'port': ('/dev/ttyUSB0', 'Serial device of the Dynamixel bus (U2D2, USB2Dynamixel).', {}),
    'baud_rate': (1_000_000, 'Bus bits per second; one of '
                  + ', '.join(str(b) for b in SUPPORTED_BAUD_RATES) + '.',
                  {'integer_range': _int_range(9600, 4_000_000)}),
    'control_rate': (100.0, 'Control cycles per second (one sync write + one sync read each).',
                     {'floating_point_range': _float_range(1.0, 1000.0)}),
    'joint_state_topic': ('joint_states', 'sensor_msgs/JointState input topic.', {}),
    'watchdog_timeout': (0.5, 'Seconds without valid input after which the servos hold.',
                         {'floating_point_range': _float_range(0.01, 60.0)}),
    'torque_off_on_shutdown': (True, 'Switch torque off on SIGINT/SIGTERM.', {}),
    'require_all_servos': (False, 'Exit at start-up if any configured servo does not answer.',
                           {}),
    'dry_run': (False, 'Open no port; log the goal ticks that would be sent.', {}),
    'reconnect_backoff_min': (0.2, 'First delay (s) before reopening a lost serial port.',
                              {'floating_point_range': _float_range(0.01, 60.0)}),
    'reconnect_backoff_max': (5.0, 'Longest delay (s) between reconnect attempts.',
                              {'floating_point_range': _float_range(0.01, 600.0)}),
    'fast_sync_read': (False, 'Read positions with Fast Sync Read (X-series firmware >= 45).',
                       {}),
    'health_check_period': (0.2, 'Seconds between Hardware Error Status reads.',
                            {'floating_point_range': _float_range(0.01, 60.0)}),
}

_SERVO_PARAMETERS = {
    'id': ('Dynamixel ID of the servo driving this joint.', Parameter.Type.INTEGER,
           {'integer_range': _int_range(0, 252)}),
    'offset': ('Servo angle (rad from the 2048-tick centre) at joint angle zero.',
               Parameter.Type.DOUBLE, {'floating_point_range': _float_range(-3.2, 3.2)}),
    'direction': ('+1 if the servo turns with the joint axis, -1 if against it.',
                  Parameter.Type.INTEGER, {'integer_range': _int_range(-1, 1)}),
    'min_position': ('Lower end of the safe range (rad), within the URDF limit.',
                     Parameter.Type.DOUBLE, {}),
    'max_position': ('Upper end of the safe range (rad), within the URDF limit.',
                     Parameter.Type.DOUBLE, {}),
    'max_speed': ('Fastest commanded joint speed (rad/s).', Parameter.Type.DOUBLE,
                  {'floating_point_range': _float_range(0.001, 100.0)}),
}


class DynamixelBridge(Node):
    """Subscribe joint states, drive the servos, publish feedback and diagnostics."""

    def __init__(self, skeleton: Optional[Skeleton] = None):
        super().__init__('dynamixel_bridge')
        self.skeleton = skeleton or Skeleton()
        self.config = self._read_config()
        if self.config.dry_run:
            bus, bus_error = None, RuntimeError
        else:
            try:
                from digital_actor_planner.dynamixel.bus import BusError, ServoBus
            except ImportError as error:
                raise ConfigError(
                    'dry_run: false drives a serial bus, which needs the module '
                    f'{error.name or error}, not installed (dynamixel_sdk: sudo apt install '
                    'ros-<distro>-dynamixel-sdk, or pip install -r requirements.txt); '
                    'dry_run:=true needs none') from None
            bus = ServoBus(self.config.port, self.config.baud_rate, self.config.fast_sync_read)
            bus_error = BusError
        self.controller = BridgeController(self.config, bus, log=self._log, bus_error=bus_error)
        self.controller.start(time.monotonic())
        self.feedback_publisher = self.create_publisher(JointState, '~/joint_states', 10)
        self.diagnostics_publisher = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.create_subscription(JointState, self.config.joint_state_topic, self._on_joint_state,
                                 10)
        self.create_timer(1.0 / self.config.control_rate, self._on_cycle)
        self.create_timer(0.5, self._publish_diagnostics)
        self._last_levels: Dict[str, int] = {}
        self._publish_diagnostics()

    def _log(self, level: str, message: str) -> None:
        if not self.context.ok():
            # After SIGINT/SIGTERM the ROS logger can no longer reach /rosout.
            print(f'[{level.upper()}] [dynamixel_bridge]: {message}', file=sys.stderr)
            return
        # rclpy ties one severity to each call site, hence three calls.
        logger = self.get_logger()
        if level == 'error':
            logger.error(message)
        elif level == 'warn':
            logger.warning(message)
        else:
            logger.info(message)

    def _declare(self, name, default, descriptor):
        try:
            return self.declare_parameter(name, default, descriptor).value
        except (InvalidParameterTypeException, InvalidParameterValueException,
                ParameterException) as error:
            raise ConfigError(f'{name}: {error}') from None

    def _read_config(self) -> BridgeConfig:
        values = {}
        for name, (default, description, extra) in _PARAMETERS.items():
            descriptor = ParameterDescriptor(description=description, read_only=True, **extra)
            values[name] = self._declare(name, default, descriptor)
        joints = self._declare(
            'servo_joints', list(servo_joint_names(self.skeleton)),
            ParameterDescriptor(description='Joints driven by servos (body joints of the URDF).',
                                read_only=True))
        values['servo_joints'] = list(joints)
        for joint in joints:
            for field_name, (description, kind, extra) in _SERVO_PARAMETERS.items():
                descriptor = ParameterDescriptor(description=description, read_only=True,
                                                 **extra)
                value = self._declare(f'servos.{joint}.{field_name}', kind, descriptor)
                if value is not None:
                    values[f'servos.{joint}.{field_name}'] = value
        return config_from_parameters(values, self.skeleton)

    def _on_joint_state(self, message: JointState) -> None:
        if len(message.position) != len(message.name):
            return
        self.controller.on_joint_state(message.name, message.position, time.monotonic())

    def _on_cycle(self) -> None:
        feedback = self.controller.cycle(time.monotonic())
        if feedback is not None and len(feedback.names):
            message = JointState()
            message.header.stamp = self.get_clock().now().to_msg()
            message.name = list(feedback.names)
            message.position = [float(p) for p in feedback.positions]
            self.feedback_publisher.publish(message)
        levels = {s.name: s.level for s in self.controller.health(time.monotonic())}
        if levels != self._last_levels:
            self._publish_diagnostics()

    def _publish_diagnostics(self) -> None:
        statuses = self.controller.health(time.monotonic())
        self._last_levels = {s.name: s.level for s in statuses}
        message = DiagnosticArray()
        message.header.stamp = self.get_clock().now().to_msg()
        for status in statuses:
            message.status.append(DiagnosticStatus(
                level=bytes([status.level]), name=status.name, message=status.message,
                hardware_id=status.hardware_id,
                values=[KeyValue(key=k, value=v) for k, v in status.values]))
        self.diagnostics_publisher.publish(message)


def main(args=None) -> int:
    """Run the bridge until SIGINT/SIGTERM; switch torque off on the way out."""
    # Own signal handling: the context must stay valid while torque is switched off, and a
    # signal must not tear it down in the middle of a control cycle.
    stop = []
    # Taken over before rclpy starts, so that no moment of the start-up ends in a traceback.
    previous = {sig: signal.signal(sig, lambda number, frame: stop.append(number))
                for sig in (signal.SIGINT, signal.SIGTERM)}
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    node = None
    code = 0
    try:
        if not stop:  # else asked to stop while rclpy started: nothing is driven yet
            node = DynamixelBridge()
            executor = SingleThreadedExecutor()
            executor.add_node(node)
        while not stop and rclpy.ok():
            executor.spin_once(timeout_sec=0.05)
    except ConfigError as error:
        print(f'dynamixel_bridge: invalid configuration: {error}', file=sys.stderr)
        code = EXIT_BAD_CONFIG
    except StartupError as error:
        print(f'dynamixel_bridge: {error}', file=sys.stderr)
        code = EXIT_MISSING_SERVOS
    finally:
        if node is not None:
            if not node.controller.shutdown() and code == 0:
                code = EXIT_TORQUE_STILL_ON
            node.destroy_node()
        rclpy.try_shutdown()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
    sys.exit(code)


if __name__ == '__main__':
    main()
