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
A Dynamixel X-series bus emulator written from the ROBOTIS Protocol 2.0 packet specification.

It serves a pseudo-terminal (``os.openpty``) so that a program under test opens it exactly as it
would open a USB serial adapter. Packet format (Protocol 2.0): header ``FF FF FD``, reserved
``00``, ID, length (2 bytes, little endian: instruction + parameters + CRC), instruction,
parameters, CRC-16 (polynomial 0x8005, over everything before the CRC). Any ``FF FF FD`` inside
the instruction/parameters is sent as ``FF FF FD FD`` (byte stuffing). A servo answers with a
status packet (instruction 0x55) that carries an error byte; bit 7 (Alert) is set while the servo
has a hardware error.

The emulator keeps a stable symlink (``port_path``) to the current pty slave, like a udev
``/dev/serial/by-id`` link, so that a test can make the port vanish and come back.
"""
from __future__ import annotations

from collections import deque
import os
import select
import struct
import threading
import time
import tty
from typing import Deque, Dict, Iterable, List, Optional, Tuple

HEADER = b'\xff\xff\xfd\x00'
BROADCAST_ID = 0xFE
STATUS = 0x55

PING, READ, WRITE, REG_WRITE, ACTION = 0x01, 0x02, 0x03, 0x04, 0x05
FACTORY_RESET, REBOOT = 0x06, 0x08
SYNC_READ, SYNC_WRITE, BULK_READ, BULK_WRITE = 0x82, 0x83, 0x92, 0x93
FAST_SYNC_READ = 0x8A

# Status packet error byte (bits 0..6 = error number, bit 7 = hardware alert).
ERR_RESULT_FAIL, ERR_INSTRUCTION, ERR_CRC, ERR_DATA_RANGE, ERR_DATA_LENGTH = 1, 2, 3, 4, 5
ERR_DATA_LIMIT, ERR_ACCESS = 6, 7
ALERT = 0x80

# X-series control table (XM430-W350 layout): address -> (size, writable, eeprom).
MODEL_NUMBER, FIRMWARE_VERSION, ID, BAUD_RATE, RETURN_DELAY_TIME = 0, 6, 7, 8, 9
TORQUE_ENABLE, LED, HARDWARE_ERROR_STATUS = 64, 65, 70
GOAL_POSITION, MOVING, PRESENT_POSITION = 116, 122, 132
CONTROL_TABLE = {
    0: (2, False, True), 2: (4, False, True), 6: (1, False, True), 7: (1, True, True),
    8: (1, True, True), 9: (1, True, True), 10: (1, True, True), 11: (1, True, True),
    12: (1, True, True), 13: (1, True, True), 20: (4, True, True), 24: (4, True, True),
    31: (1, True, True), 32: (2, True, True), 34: (2, True, True), 36: (2, True, True),
    38: (2, True, True), 44: (4, True, True), 48: (4, True, True), 52: (4, True, True),
    63: (1, True, True),
    64: (1, True, False), 65: (1, True, False), 68: (1, True, False), 69: (1, True, False),
    70: (1, False, False), 76: (2, True, False), 78: (2, True, False), 80: (2, True, False),
    82: (2, True, False), 84: (2, True, False), 88: (2, True, False), 90: (2, True, False),
    98: (1, True, False), 100: (2, True, False), 102: (2, True, False), 104: (4, True, False),
    108: (4, True, False), 112: (4, True, False), 116: (4, True, False),
    120: (2, False, False), 122: (1, False, False), 123: (1, False, False),
    124: (2, False, False), 126: (2, False, False), 128: (4, False, False),
    132: (4, False, False), 136: (4, False, False), 140: (4, False, False),
    144: (2, False, False), 146: (1, False, False),
}
CONTROL_TABLE_SIZE = 147
# Baud Rate register value -> bits per second (X-series).
BAUD_RATES = {0: 9600, 1: 57600, 2: 115200, 3: 1_000_000, 4: 2_000_000, 5: 3_000_000,
              6: 4_000_000, 7: 4_500_000}
X_MODEL_NUMBER = 1020  # XM430-W350


def _crc_table() -> Tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x8005) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc_table()


def crc16(data: bytes) -> int:
    """CRC-16 of Protocol 2.0: polynomial 0x8005, initial value 0, no reflection."""
    crc = 0
    for byte in data:
        crc = ((crc << 8) & 0xFFFF) ^ _CRC_TABLE[((crc >> 8) ^ byte) & 0xFF]
    return crc


def stuff(payload: bytes) -> bytes:
    """Insert 0xFD after every FF FF FD in the instruction/parameter field."""
    out = bytearray()
    for byte in payload:
        out.append(byte)
        if byte == 0xFD and out[-3:] == b'\xff\xff\xfd':
            out.append(0xFD)
    return bytes(out)


def unstuff(payload: bytes) -> bytes:
    """Remove the 0xFD that byte stuffing inserted after each FF FF FD."""
    out = bytearray()
    i = 0
    while i < len(payload):
        out.append(payload[i])
        if out[-3:] == b'\xff\xff\xfd' and i + 1 < len(payload) and payload[i + 1] == 0xFD:
            i += 1
        i += 1
    return bytes(out)


def build_packet(packet_id: int, instruction: int, params: bytes = b'') -> bytes:
    """Build a complete Protocol 2.0 packet (stuffing and CRC included)."""
    body = stuff(bytes([instruction]) + bytes(params))
    head = HEADER + bytes([packet_id]) + struct.pack('<H', len(body) + 2)
    packet = head + body
    return packet + struct.pack('<H', crc16(packet))


def build_status(packet_id: int, error: int, params: bytes = b'') -> bytes:
    """Build a status packet: instruction 0x55, error byte, then the parameters."""
    return build_packet(packet_id, STATUS, bytes([error]) + bytes(params))


def parse_packet(buffer: bytes) -> Tuple[Optional[Tuple[int, int, bytes]], int, bool]:
    """
    Find one packet at the start of ``buffer``.

    Returns
    -------
    tuple
        ``(packet or None, bytes consumed, crc_ok)``; packet is ``(id, instruction, params)``
        with the stuffing removed. Consumed is 0 when more bytes are needed.

    """
    start = buffer.find(HEADER[:3])
    while start >= 0 and start + 3 < len(buffer) and buffer[start + 3] != 0x00:
        start = buffer.find(HEADER[:3], start + 1)
    if start < 0:
        keep = 2 if buffer.endswith(b'\xff\xff') else (1 if buffer.endswith(b'\xff') else 0)
        return None, len(buffer) - keep, True
    if len(buffer) < start + 7:
        return None, start, True
    length = struct.unpack_from('<H', buffer, start + 5)[0]
    end = start + 7 + length
    if length < 3:
        return None, start + 3, True
    if len(buffer) < end:
        return None, start, True
    raw = buffer[start:end]
    crc_ok = crc16(raw[:-2]) == struct.unpack_from('<H', raw, len(raw) - 2)[0]
    body = unstuff(raw[7:-2])
    return (raw[4], body[0], body[1:]), end, crc_ok


class Servo:
    """One X-series servo: its control table and a simple position response."""

    def __init__(self, servo_id: int, position: int = 2048, speed: float = 4000.0):
        self.table = bytearray(CONTROL_TABLE_SIZE)
        self._set(MODEL_NUMBER, X_MODEL_NUMBER)
        self._set(FIRMWARE_VERSION, 48)
        self._set(ID, servo_id)
        self._set(BAUD_RATE, 3)
        self._set(RETURN_DELAY_TIME, 250)
        self._set(48, 4095)  # max position limit
        self._set(52, 0)     # min position limit
        self._set(GOAL_POSITION, position)
        self._set(PRESENT_POSITION, position)
        #: Ticks per second the emulated horn moves toward the goal while torque is on.
        self.speed = float(speed)
        #: True after an injected error that shut the servo down (torque locked off).
        self.shutdown = False
        self._position = float(position)
        self._stamp = time.monotonic()
        #: Every (time, goal ticks) the servo accepted, for tests that check rate limits.
        self.goal_history: List[Tuple[float, int]] = []

    def _set(self, address: int, value: int) -> None:
        size = CONTROL_TABLE[address][0]
        self.table[address:address + size] = int(value).to_bytes(
            size, 'little', signed=size == 4)

    def get(self, address: int) -> int:
        """Register value (signed for 4-byte registers)."""
        self.update()
        size = CONTROL_TABLE[address][0]
        return int.from_bytes(self.table[address:address + size], 'little', signed=size == 4)

    @property
    def servo_id(self) -> int:
        return self.table[ID]

    def update(self) -> None:
        """Advance the present position toward the goal while torque is enabled."""
        now = time.monotonic()
        dt, self._stamp = now - self._stamp, now
        if self.table[TORQUE_ENABLE]:
            goal = int.from_bytes(self.table[GOAL_POSITION:GOAL_POSITION + 4], 'little',
                                  signed=True)
            step = self.speed * dt
            delta = goal - self._position
            self._position = goal if abs(delta) <= step else self._position + step * (
                1 if delta > 0 else -1)
        moving = int(round(self._position)) != int.from_bytes(
            self.table[GOAL_POSITION:GOAL_POSITION + 4], 'little', signed=True)
        self.table[MOVING] = 1 if (moving and self.table[TORQUE_ENABLE]) else 0
        self._set(PRESENT_POSITION, int(round(self._position)))

    def place(self, ticks: int) -> None:
        """Put the horn at ``ticks`` (goal and present position), as if moved by hand."""
        self.update()
        self._position = float(ticks)
        self._set(GOAL_POSITION, ticks)
        self._set(PRESENT_POSITION, ticks)

    def error_byte(self) -> int:
        return ALERT if self.table[HARDWARE_ERROR_STATUS] else 0

    def read(self, address: int, length: int) -> Tuple[int, bytes]:
        """Return (error, data) for a READ of ``length`` bytes at ``address``."""
        if length == 0 or address + length > CONTROL_TABLE_SIZE:
            return ERR_DATA_RANGE | self.error_byte(), b''
        self.update()
        return self.error_byte(), bytes(self.table[address:address + length])

    def check_write(self, address: int, data: bytes) -> int:
        """Return the error number a WRITE would get (0 when it is allowed)."""
        end = address + len(data)
        if not data or end > CONTROL_TABLE_SIZE:
            return ERR_DATA_RANGE
        for item, (size, writable, eeprom) in CONTROL_TABLE.items():
            if item < end and address < item + size:
                if not writable:
                    return ERR_ACCESS
                if eeprom and self.table[TORQUE_ENABLE]:
                    return ERR_ACCESS  # EEPROM is locked while torque is on
                if item < address or item + size > end:
                    return ERR_DATA_LENGTH  # must write whole registers
        if address <= GOAL_POSITION < end:
            goal = int.from_bytes(data[GOAL_POSITION - address:GOAL_POSITION - address + 4],
                                  'little', signed=True)
            if not (self.get(52) <= goal <= self.get(48)):
                return ERR_DATA_LIMIT
        return 0

    def write(self, address: int, data: bytes) -> int:
        """Apply a WRITE; return the status error byte."""
        error = self.check_write(address, data)
        if error:
            return error | self.error_byte()
        self.update()
        if (address <= TORQUE_ENABLE < address + len(data) and self.table[HARDWARE_ERROR_STATUS]
                and self.shutdown and data[TORQUE_ENABLE - address]):
            return ERR_RESULT_FAIL | self.error_byte()
        self.table[address:address + len(data)] = data
        if address <= GOAL_POSITION < address + len(data):
            self.goal_history.append((time.monotonic(), self.get(GOAL_POSITION)))
        return self.error_byte()


class DynamixelEmulator:
    """
    A bus of emulated X-series servos behind a pseudo-terminal.

    Parameters
    ----------
    ids
        Servo IDs present on the bus.
    link_path
        Stable symlink the program under test opens as its port.
    baud_rate
        Bits per second used to model wire time (10 bits per byte).
    wire_time
        When true, instruction and status packets take their transmission time (plus each
        servo's Return Delay Time) before a reply is released.
    speed
        Ticks per second each servo's horn moves toward its goal.

    """

    def __init__(self, ids: Iterable[int], link_path: str, baud_rate: int = 1_000_000,
                 wire_time: bool = False, speed: float = 4000.0, realtime: bool = False):
        #: Serve from a SCHED_FIFO thread (when permitted): hardware is never descheduled,
        #: and on a loaded machine a late emulator would be charged to the host.
        self.realtime = bool(realtime)
        self.servos: Dict[int, Servo] = {i: Servo(i, speed=speed) for i in ids}
        self.link_path = link_path
        self.baud_rate = int(baud_rate)
        self.wire_time = bool(wire_time)
        self.lock = threading.RLock()
        #: Counts by instruction code, bytes received / sent, and CRC failures.
        self.instruction_counts: Dict[int, int] = {}
        self.bytes_in = 0
        self.bytes_out = 0
        self.crc_errors = 0
        self.wire_busy_s = 0.0
        #: The last raw instruction packets received (as sent on the wire, stuffing included).
        self.received: Deque[bytes] = deque(maxlen=64)
        self._master = self._slave = -1
        self._stop = threading.Event()
        self._thread: Optional[threading.Thread] = None
        self._wire_free = 0.0
        #: Seconds by which the replies to the next sync reads are held back (see
        #: :meth:`delay_sync_read_replies`), and how many sync reads that still applies to.
        self._late_by = 0.0
        self._late_count = 0

    # -- lifecycle -------------------------------------------------------------------------
    @property
    def port_path(self) -> str:
        return self.link_path

    def start(self) -> 'DynamixelEmulator':
        """Open a fresh pty, point the link at it and serve it in a thread."""
        self._master, self._slave = os.openpty()
        tty.setraw(self._slave)
        tmp = self.link_path + '.tmp'
        if os.path.lexists(tmp):
            os.unlink(tmp)
        os.symlink(os.ttyname(self._slave), tmp)
        os.replace(tmp, self.link_path)
        self._stop.clear()
        self._thread = threading.Thread(target=self._serve, name='dynamixel-emulator',
                                        daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        """Unplug: stop serving, close the pty and remove the link."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        for fd in (self._master, self._slave):
            if fd >= 0:
                try:
                    os.close(fd)
                except OSError:
                    pass
        self._master = self._slave = -1
        if os.path.lexists(self.link_path):
            os.unlink(self.link_path)

    def __enter__(self) -> 'DynamixelEmulator':
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()

    # -- test hooks ------------------------------------------------------------------------
    def register(self, servo_id: int, address: int) -> int:
        """Read a register of one servo (what a test checks)."""
        with self.lock:
            return self.servos[servo_id].get(address)

    def set_register(self, servo_id: int, address: int, value: int) -> None:
        """Set a register directly (bypassing access rules), e.g. Return Delay Time."""
        with self.lock:
            self.servos[servo_id]._set(address, value)

    def inject_hardware_error(self, servo_id: int, bits: int, shutdown: bool = False) -> None:
        """
        Raise Hardware Error Status bits.

        Raise Hardware Error Status bits (bit 0 voltage, 2 overheating, 3 encoder, 4 electrical
        shock, 5 overload).

        With ``shutdown`` the servo also drops torque and refuses to re-enable it, as a real
        X-series servo does for the bits selected in its Shutdown register.
        """
        with self.lock:
            servo = self.servos[servo_id]
            servo.update()
            servo.table[HARDWARE_ERROR_STATUS] = bits & 0xFF
            servo.shutdown = shutdown
            if shutdown:
                servo.table[TORQUE_ENABLE] = 0

    def place(self, servo_id: int, ticks: int) -> None:
        """Put a servo's horn at ``ticks`` (goal and present position), as if moved by hand."""
        with self.lock:
            self.servos[servo_id].place(ticks)

    def delay_sync_read_replies(self, seconds: float, count: int = 1) -> None:
        """Answer the next ``count`` sync reads ``seconds`` late (after the reader gave up)."""
        with self.lock:
            self._late_by, self._late_count = float(seconds), int(count)

    def disconnect_servo(self, servo_id: int) -> Servo:
        """Take one servo off the bus (a broken cable): it stops answering."""
        with self.lock:
            return self.servos.pop(servo_id)

    def connect_servo(self, servo: Servo) -> None:
        """Put a servo (back) on the bus."""
        with self.lock:
            self.servos[servo.servo_id] = servo

    def goal_history(self, servo_id: int) -> List[Tuple[float, int]]:
        with self.lock:
            return list(self.servos[servo_id].goal_history)

    # -- serving ---------------------------------------------------------------------------
    def _byte_time(self, count: int) -> float:
        return count * 10.0 / self.baud_rate

    def _serve(self) -> None:
        _tight_timer_slack()
        if self.realtime:
            try:
                os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(10))
            except (AttributeError, PermissionError, OSError):
                pass
        buffer = b''
        while not self._stop.is_set():
            ready, _, _ = select.select([self._master], [], [], 0.05)
            if not ready:
                continue
            try:
                chunk = os.read(self._master, 4096)
            except OSError:
                continue
            received_at = time.monotonic()
            buffer += chunk
            while True:
                packet, consumed, crc_ok = parse_packet(buffer)
                if packet is None:
                    buffer = buffer[consumed:]
                    break
                raw_length = consumed
                raw = bytes(buffer[:consumed])
                self.received.append(raw[raw.find(HEADER):])
                buffer = buffer[consumed:]
                with self.lock:
                    self.bytes_in += raw_length
                    if not crc_ok:
                        self.crc_errors += 1
                        replies = self._crc_failure(packet)
                    else:
                        replies = self._handle(*packet)
                    late_by = 0.0
                    if crc_ok and packet[1] == SYNC_READ and self._late_count > 0:
                        self._late_count -= 1
                        late_by = self._late_by
                if late_by:
                    # A stalled bus or host: nothing else is served meanwhile either.
                    time.sleep(late_by)
                self._transmit(received_at, raw_length, replies)

    def _transmit(self, received_at: float, instruction_bytes: int,
                  replies: List[Tuple[int, bytes]]) -> None:
        """Send status packets, each after its modelled wire time when enabled."""
        if not self.wire_time:
            for _, reply in replies:
                self._write(reply)
            return
        # The instruction occupies the wire first, then each reply (after its return delay).
        t = max(received_at, self._wire_free) + self._byte_time(instruction_bytes)
        busy = self._byte_time(instruction_bytes)
        for delay, reply in replies:
            t += delay + self._byte_time(len(reply))
            busy += delay + self._byte_time(len(reply))
            _wait_until(t)
            self._write(reply)
        _wait_until(t)
        self._wire_free = t
        self.wire_busy_s += busy

    def _write(self, data: bytes) -> None:
        try:
            os.write(self._master, data)
            self.bytes_out += len(data)
        except OSError:
            pass

    def _delay(self, servo: Servo) -> float:
        return servo.table[RETURN_DELAY_TIME] * 2e-6

    def _crc_failure(self, packet) -> List[Tuple[int, bytes]]:
        servo = self.servos.get(packet[0])
        if servo is None:
            return []
        return [(self._delay(servo), build_status(servo.servo_id, ERR_CRC | servo.error_byte()))]

    def _handle(self, packet_id: int, instruction: int, params: bytes):
        self.instruction_counts[instruction] = self.instruction_counts.get(instruction, 0) + 1
        if instruction == SYNC_WRITE:
            self._sync_write(params)
            return []
        if instruction == SYNC_READ:
            return self._sync_read(params)
        if instruction == FAST_SYNC_READ:
            return self._fast_sync_read(params)
        if instruction == BULK_WRITE:
            self._bulk_write(params)
            return []
        if instruction == BULK_READ:
            return self._bulk_read(params)
        targets = (list(self.servos.values()) if packet_id == BROADCAST_ID
                   else [self.servos[packet_id]] if packet_id in self.servos else [])
        replies = []
        for servo in targets:
            status = self._single(servo, instruction, params)
            if status is not None and (packet_id != BROADCAST_ID or instruction == PING):
                replies.append((self._delay(servo), build_status(servo.servo_id, *status)))
        return replies

    def _single(self, servo: Servo, instruction: int, params: bytes):
        if instruction == PING:
            return (servo.error_byte(), struct.pack('<HB', servo.get(MODEL_NUMBER),
                                                    servo.get(FIRMWARE_VERSION)))
        if instruction == READ:
            if len(params) != 4:
                return (ERR_DATA_LENGTH | servo.error_byte(),)
            address, length = struct.unpack('<HH', params)
            return servo.read(address, length)
        if instruction == WRITE:
            if len(params) < 3:
                return (ERR_DATA_LENGTH | servo.error_byte(),)
            address = struct.unpack_from('<H', params)[0]
            return (servo.write(address, params[2:]),)
        if instruction == REBOOT:
            servo.table[TORQUE_ENABLE] = 0
            servo.table[HARDWARE_ERROR_STATUS] = 0
            servo.shutdown = False
            return (0,)
        return (ERR_INSTRUCTION | servo.error_byte(),)

    def _sync_write(self, params: bytes) -> None:
        if len(params) < 4:
            return
        address, length = struct.unpack_from('<HH', params)
        for offset in range(4, len(params) - length, length + 1):
            servo = self.servos.get(params[offset])
            if servo is not None:
                servo.write(address, params[offset + 1:offset + 1 + length])

    def _sync_read(self, params: bytes):
        if len(params) < 5:
            return []
        address, length = struct.unpack_from('<HH', params)
        replies = []
        for servo_id in params[4:]:
            servo = self.servos.get(servo_id)
            if servo is not None:
                error, data = servo.read(address, length)
                replies.append((self._delay(servo), build_status(servo_id, error, data)))
        return replies

    def _fast_sync_read(self, params: bytes):
        """
        One status packet (ID 0xFE) that the servos fill in turn: ERR ID DATA CRC each.

        Each servo's CRC covers the packet up to its own block, so the last one is the CRC of
        the whole packet. Replies are returned per servo so that wire time is modelled.
        """
        if len(params) < 5:
            return []
        address, length = struct.unpack_from('<HH', params)
        servos = [self.servos[i] for i in params[4:] if i in self.servos]
        if not servos:
            return []
        packet = bytearray(HEADER + bytes([BROADCAST_ID]) + struct.pack(
            '<H', 1 + len(servos) * (length + 4)) + bytes([STATUS]))
        replies = []
        start = 0
        for servo in servos:
            error, data = servo.read(address, length)
            if len(data) != length:
                break
            packet += bytes([error, servo.servo_id]) + data
            packet += struct.pack('<H', crc16(bytes(packet)))
            replies.append((self._delay(servo), bytes(packet[start:])))
            start = len(packet)
        return replies

    def _bulk_write(self, params: bytes) -> None:
        offset = 0
        while offset + 5 <= len(params):
            servo_id = params[offset]
            address, length = struct.unpack_from('<HH', params, offset + 1)
            servo = self.servos.get(servo_id)
            if servo is not None:
                servo.write(address, params[offset + 5:offset + 5 + length])
            offset += 5 + length

    def _bulk_read(self, params: bytes):
        replies = []
        for offset in range(0, len(params) - 4, 5):
            servo_id = params[offset]
            address, length = struct.unpack_from('<HH', params, offset + 1)
            servo = self.servos.get(servo_id)
            if servo is not None:
                error, data = servo.read(address, length)
                replies.append((self._delay(servo), build_status(servo_id, error, data)))
        return replies


#: The last stretch before a release deadline is waited for by spinning, not sleeping.
_SPIN_S = 60e-6


def _tight_timer_slack() -> None:
    """Ask Linux for 1 us timer slack on this thread (default 50 us); no-op elsewhere."""
    try:
        import ctypes
        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(29, 1000, 0, 0, 0)  # PR_SET_TIMERSLACK, in nanoseconds
    except (OSError, AttributeError):
        pass


def _wait_until(deadline: float) -> None:
    """
    Wait until ``deadline`` (monotonic s), to within a few microseconds.

    Sleeps until shortly before the deadline, then spins: a real servo answers on time, and a
    plain sleep overshoots by the kernel's timer slack (50 us by default) plus wake-up latency,
    which would be charged to the bridge as if the bus were slower. Deadlines are absolute, so
    nothing accumulates over the status packets of a cycle.
    """
    remaining = deadline - time.monotonic()
    if remaining > _SPIN_S:
        time.sleep(remaining - _SPIN_S)
    while time.monotonic() < deadline:
        pass
