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
The bridge's control cycle without ROS: safety envelope in, one sync write/read per cycle out.

The node feeds it joint states and a clock; it drives a :class:`~.bus.ServoBus` (or nothing in
dry-run mode) and reports health as plain values that the node turns into diagnostics.
"""
from __future__ import annotations

from dataclasses import dataclass
import os
from typing import Callable, Dict, Iterable, List, Optional, Sequence, Tuple

from digital_actor_planner.dynamixel.config import BridgeConfig
from digital_actor_planner.dynamixel.safety import SafetyEnvelope
import numpy as np

OK, WARN, ERROR = 0, 1, 2
#: Torque Enable writes per servo at shutdown before it is reported as possibly still on.
SHUTDOWN_ATTEMPTS = 3
HARDWARE_ERROR_BITS = {0: 'input voltage', 2: 'overheating', 3: 'motor encoder',
                       4: 'electrical shock', 5: 'overload'}


def describe_hardware_error(bits: int) -> str:
    """Readable names of the Hardware Error Status bits that are set."""
    names = [name for bit, name in HARDWARE_ERROR_BITS.items() if bits & (1 << bit)]
    return ', '.join(names) if names else f'unknown bits 0x{bits:02x}'


class StartupError(RuntimeError):
    """Start-up cannot continue (servos missing while ``require_all_servos`` is set)."""


@dataclass(frozen=True)
class HealthStatus:
    """One diagnostics entry: ``level`` is OK (0), WARN (1) or ERROR (2)."""

    name: str
    level: int
    message: str
    hardware_id: str = ''
    values: Tuple[Tuple[str, str], ...] = ()


@dataclass(frozen=True)
class Feedback:
    """Measured joint positions: ``names`` (k,) and ``positions`` (k,) rad."""

    names: Tuple[str, ...]
    positions: np.ndarray


class BridgeController:
    """
    Safety envelope + bus driving + reconnection, one :meth:`cycle` per control period.

    Parameters
    ----------
    config
        A validated :class:`BridgeConfig`.
    bus
        An object with the :class:`~.bus.ServoBus` methods; ``None`` only in dry-run mode.
    log
        ``log(level, message)`` with level 'info', 'warn' or 'error'.
    bus_error
        The exception type the bus raises when the port fails.

    """

    def __init__(self, config: BridgeConfig, bus=None,
                 log: Optional[Callable[[str, str], None]] = None,
                 bus_error: type = RuntimeError):
        if bus is None and not config.dry_run:
            raise ValueError('bus: None is only allowed with dry_run')
        self.config = config
        self.bus = bus
        self.bus_error = bus_error
        self.log = log or (lambda level, message: None)
        self.servos = config.servos
        self.by_id = {s.id: s for s in self.servos}
        self.envelope = SafetyEnvelope(
            config.joint_names, [s.min_position for s in self.servos],
            [s.max_position for s in self.servos], [s.max_speed for s in self.servos],
            config.watchdog_timeout, max_step_time=max(2.0 / config.control_rate, 0.02))
        self.present: Tuple[int, ...] = ()
        self.missing: Tuple[int, ...] = ()
        self.faulted: Dict[int, int] = {}
        self.connected = False
        self.port_error = ''
        self.backoff = config.reconnect_backoff_min
        self.next_attempt = 0.0
        self.reconnects = 0
        self.read_failures = 0
        self.cycles = 0
        self.last_health_check = -np.inf
        self.next_missing_ping = 0.0
        self.last_feedback: Optional[Feedback] = None
        #: IDs that torque was switched on for and not (acknowledged) off since.
        self.torqued: set = set()
        self._last_dry_log = -np.inf
        self._last_dry_ticks: Optional[Tuple[int, ...]] = None

    # -- start-up and connection ---------------------------------------------------------
    def start(self, now: float) -> None:
        """Open the port and ping every servo; raise :class:`StartupError` if that is fatal."""
        self.envelope.reset(self.envelope.commanded, now)
        if self.config.dry_run:
            self.log('info', 'dry run: no serial port is opened; logging the goal ticks')
            return
        self._connect(now, first=True)

    def _names(self, ids: Iterable[int]) -> str:
        return ', '.join(f'{self.by_id[i].joint} (ID {i})' for i in ids)

    def _connect(self, now: float, first: bool = False) -> bool:
        try:
            self.bus.open()
            found = self.bus.ping(s.id for s in self.servos)
        except self.bus_error as error:
            self._lost(now, str(error))
            return False
        self.present = tuple(s.id for s in self.servos if s.id in found)
        self.missing = tuple(s.id for s in self.servos if s.id not in found)
        if self.missing:
            message = f'servos not answering ping: {self._names(self.missing)}'
            if first and self.config.require_all_servos:
                self.bus.close()
                raise StartupError(message + ' (require_all_servos is true)')
            self.log('warn', message)
        try:
            errors = self.bus.read_hardware_errors(self.present)
            for servo_id, bits in errors.items():
                if bits:
                    self._fault(servo_id, bits)
            ticks = self._present_positions()
            positions = self.envelope.commanded.copy()
            for i, servo in enumerate(self.servos):
                if servo.id in ticks:
                    positions[i] = servo.to_angle(ticks[servo.id])
            # Start from where the servos are, so that switching torque on moves nothing.
            self.envelope.reset(positions, now)
            self.bus.write_goals(self._goals(self.envelope.commanded))
            self._torque_on(self._active_ids())
        except self.bus_error as error:
            self._lost(now, str(error))
            return False
        if not first:
            self.reconnects += 1
            self.log('info', f'{self.config.port}: reconnected')
        self.connected = True
        self.port_error = ''
        self.backoff = self.config.reconnect_backoff_min
        self.read_failures = 0
        return True

    def _present_positions(self) -> Dict[int, int]:
        """
        Read the present positions (ticks) of the present servos; one not read is missing.

        Torque must not come on before a servo's position is known: its first goal would be
        the last commanded position, a jump to wherever that is. One lost reply fails a whole
        sync read, so after a failed one each servo is read alone, and a servo that still does
        not answer is left off (switched on later, once it is read, as a returning servo).
        """
        ticks = self.bus.read_positions(self.present)
        if len(ticks) == len(self.present):
            return ticks
        ticks = {}
        for servo_id in self.present:
            ticks.update(self.bus.read_positions((servo_id,)))
        unread = [i for i in self.present if i not in ticks]
        if unread:
            self.log('warn', f'present position not read: {self._names(unread)}; '
                     'torque stays off until it is')
            self.present = tuple(i for i in self.present if i in ticks)
            self.missing = tuple(s.id for s in self.servos if s.id not in self.present)
        return ticks

    def _lost(self, now: float, message: str) -> None:
        if self.connected or not self.port_error:
            self.log('error', f'serial port lost: {message}; reconnecting')
        self.bus.close()
        self.connected = False
        self.port_error = message
        self.next_attempt = now + self.backoff
        self.backoff = min(self.backoff * 2.0, self.config.reconnect_backoff_max)

    def _fault(self, servo_id: int, bits: int) -> None:
        if servo_id in self.faulted:
            return
        self.faulted[servo_id] = bits
        self.log('error', f'hardware error on {self._names([servo_id])}: '
                 f'{describe_hardware_error(bits)}; torque off')
        try:
            if self.bus.set_torque([servo_id], False).get(servo_id):
                self.torqued.discard(servo_id)
        except self.bus_error:
            pass

    def _active_ids(self) -> List[int]:
        return [i for i in self.present if i not in self.faulted]

    def _goals(self, commanded: np.ndarray) -> Dict[int, int]:
        active = set(self._active_ids())
        return {s.id: s.to_ticks(commanded[i]) for i, s in enumerate(self.servos)
                if s.id in active}

    # -- running ---------------------------------------------------------------------------
    def on_joint_state(self, names: Sequence[str], positions: Sequence[float],
                       now: float) -> List[str]:
        """Take one input message; return the names that were ignored."""
        return self.envelope.command(names, positions, now)

    def cycle(self, now: float) -> Optional[Feedback]:
        """
        Run one control cycle at time ``now`` (s); return the measured positions, if any.

        Order on the bus: sync read request, then (while the replies cross the wire) the
        safety envelope computes this cycle's goals, then the replies are taken and the goals
        go out in one sync write. The bridge's own computation therefore costs no bus time.
        """
        self.cycles += 1
        if self.config.dry_run:
            commanded = self.envelope.step(now)
            self._dry_run_log(commanded, now)
            self.last_feedback = Feedback(self.config.joint_names, commanded)
            return self.last_feedback
        held = False  # True: the envelope was just reset to where the servos are
        if not self.connected:
            if now < self.next_attempt or not self._connect(now):
                self.envelope.step(now)
                return None
            held = True
        if self.missing and now >= self.next_missing_ping:
            if not held:
                self.envelope.step(now)
            self._recover_missing(now)  # sets the envelope of returning servos to where they are
            held = True
        try:
            self.bus.request_positions(self.present)
            commanded = self.envelope.commanded.copy() if held else self.envelope.step(now)
            goals = self._goals(commanded)
            ticks = self.bus.collect_positions()
            self.bus.write_goals(goals)
            if now - self.last_health_check >= self.config.health_check_period:
                self.last_health_check = now
                for servo_id, bits in self.bus.read_hardware_errors(self.present).items():
                    if bits:
                        self._fault(servo_id, bits)
        except self.bus_error as error:
            self._lost(now, str(error))
            return None
        if self.present and not ticks:
            self.read_failures += 1
            if not os.path.exists(self.config.port):
                self._lost(now, f'{self.config.port}: device disappeared')
            elif self.read_failures >= 3:
                self._find_silent_servos(now)
            return None
        self.read_failures = 0
        names, positions = [], []
        for servo in self.servos:
            if servo.id in ticks:
                names.append(servo.joint)
                positions.append(servo.to_angle(ticks[servo.id]))
        self.last_feedback = Feedback(tuple(names), np.array(positions))
        return self.last_feedback

    def _find_silent_servos(self, now: float) -> None:
        """Ping the servos after repeated failed reads; drop the silent ones from the cycle."""
        try:
            found = self.bus.ping(self.present)
        except self.bus_error as error:
            self._lost(now, str(error))
            return
        silent = [i for i in self.present if i not in found]
        if silent:
            self.log('error', f'servos stopped answering: {self._names(silent)}')
            self.present = tuple(i for i in self.present if i in found)
            self.missing = tuple(s.id for s in self.servos if s.id not in self.present)
            self.read_failures = 0

    def _recover_missing(self, now: float) -> None:
        """Ping the missing servos now and then; bring back those that answer again."""
        self.next_missing_ping = now + self.config.reconnect_backoff_max
        try:
            found = self.bus.ping(self.missing, attempts=1)
            if not found:
                return
            ticks = self.bus.read_positions(tuple(found))
            if len(ticks) != len(found):
                return
            # Start from where it is (outside its range it eases in at its speed limit).
            back_at = [(i, servo.to_angle(ticks[servo.id]))
                       for i, servo in enumerate(self.servos) if servo.id in ticks]
            self.envelope.resume([i for i, _ in back_at], [a for _, a in back_at])
            self.present = tuple(s.id for s in self.servos
                                 if s.id in self.present or s.id in found)
            self.missing = tuple(s.id for s in self.servos if s.id not in self.present)
            back = [i for i in found if i not in self.faulted]
            self.bus.write_goals({i: g for i, g in self._goals(self.envelope.commanded).items()
                                  if i in back})
            self._torque_on(back)
            self.log('info', f'servos answering again: {self._names(found)}')
        except self.bus_error as error:
            self._lost(now, str(error))

    def _dry_run_log(self, commanded: np.ndarray, now: float) -> None:
        ticks = tuple(s.to_ticks(commanded[i]) for i, s in enumerate(self.servos))
        if ticks != self._last_dry_ticks and now - self._last_dry_log >= 0.5:
            self._last_dry_ticks = ticks
            self._last_dry_log = now
            self.log('info', 'dry run ticks: ' + ' '.join(
                f'{s.joint}[{s.id}]={t}' for s, t in zip(self.servos, ticks)))

    def _torque_on(self, ids: Sequence[int]) -> None:
        # Counted before the write: a servo may have switched on even if its reply was lost.
        self.torqued.update(ids)
        self.bus.set_torque(ids, True)

    def shutdown(self) -> bool:
        """
        Switch torque off (unless configured otherwise) and close the port.

        Returns
        -------
        bool
            False when servos may still hold torque that should have been switched off: the
            port is gone or they did not acknowledge. The log names them.

        """
        if self.bus is None:
            return True
        if not self.config.torque_off_on_shutdown or not self.torqued:
            self.bus.close()
            self.connected = False
            return True
        ids = [s.id for s in self.servos if s.id in self.torqued]
        problem = ''
        try:
            if not self.connected:
                self.bus.open()  # the port may be back; a servo keeps torque without it
            # A reply can be late on a busy host; asking again is harmless.
            for _ in range(SHUTDOWN_ATTEMPTS):
                done = self.bus.set_torque([i for i in ids if i in self.torqued], False)
                self.torqued.difference_update(i for i, ok in done.items() if ok)
                if not self.torqued:
                    break
            else:
                problem = f'no acknowledgement after {SHUTDOWN_ATTEMPTS} attempts'
        except self.bus_error as error:
            problem = str(error)
        self.bus.close()
        self.connected = False
        if problem:
            still = [i for i in ids if i in self.torqued]
            servos = f'{len(still)} servo' + ('s' if len(still) != 1 else '')
            self.log('error', f'TORQUE COULD NOT BE SWITCHED OFF ({problem}): '
                     f'{servos} may still hold torque: {self._names(still)}')
            return False
        self.log('info', 'torque off')
        return True

    # -- health ----------------------------------------------------------------------------
    def health(self, now: float) -> List[HealthStatus]:
        """Diagnostics entries: the bus first, then one per servo."""
        config = self.config
        watchdog = 'holding' if self.envelope.holding else 'following input'
        values = (('port', config.port), ('baud_rate', str(config.baud_rate)),
                  ('servos responding', f'{len(self.present)}/{len(self.servos)}'),
                  ('watchdog', watchdog), ('reconnects', str(self.reconnects)),
                  ('ignored inputs', ', '.join(f'{k}: {v}' for k, v in
                                               self.envelope.ignored.items())))
        if config.dry_run:
            bus = HealthStatus('dynamixel_bridge: bus', OK, 'dry run: no serial port',
                               config.port, values)
            return [bus]
        if not self.connected:
            wait = max(self.next_attempt - now, 0.0)
            bus = HealthStatus('dynamixel_bridge: bus', ERROR,
                               f'serial port unavailable: {self.port_error}; next reconnect '
                               f'attempt in {wait:.1f} s', config.port, values)
        elif self.missing or self.faulted:
            problems = []
            if self.missing:
                problems.append(f'missing servos: {self._names(self.missing)}')
            if self.faulted:
                problems.append(f'hardware errors: {self._names(self.faulted)}')
            bus = HealthStatus('dynamixel_bridge: bus', ERROR, '; '.join(problems),
                               config.port, values)
        elif self.read_failures:
            bus = HealthStatus('dynamixel_bridge: bus', WARN,
                               f'{self.read_failures} failed sync reads in a row',
                               config.port, values)
        else:
            bus = HealthStatus('dynamixel_bridge: bus', OK, f'connected; {watchdog}',
                               config.port, values)
        statuses = [bus]
        for servo in self.servos:
            name = f'dynamixel_bridge: {servo.joint}'
            hardware = f'dynamixel id {servo.id}'
            if servo.id in self.faulted:
                bits = self.faulted[servo.id]
                statuses.append(HealthStatus(
                    name, ERROR, f'hardware error: {describe_hardware_error(bits)}; torque off',
                    hardware, (('hardware_error_status', str(bits)),)))
            elif servo.id in self.missing:
                statuses.append(HealthStatus(name, ERROR, 'missing: no reply to ping',
                                             hardware))
            elif not self.connected:
                statuses.append(HealthStatus(name, ERROR, 'serial port unavailable', hardware))
            else:
                statuses.append(HealthStatus(name, OK, 'ok', hardware))
        return statuses
