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

"""Drive a Protocol 2.0 X-series bus with dynamixel-sdk (the only module that imports it)."""
from __future__ import annotations

import termios
from typing import Dict, Iterable, Mapping, Tuple

import dynamixel_sdk as sdk
import serial

TORQUE_ENABLE = 64
HARDWARE_ERROR_STATUS = 70
GOAL_POSITION = 116
PRESENT_POSITION = 132
POSITION_BYTES = 4


def _crc16_table(poly: int = 0x8005) -> Tuple[int, ...]:
    table = []
    for byte in range(256):
        crc = byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ poly) if crc & 0x8000 else (crc << 1)
        table.append(crc & 0xFFFF)
    return tuple(table)


_CRC_TABLE = _crc16_table()
_STUFF_PATTERN = bytes((0xFF, 0xFF, 0xFD))
_STUFFED_PATTERN = bytes((0xFF, 0xFF, 0xFD, 0xFD))


class PacketHandler(sdk.Protocol2PacketHandler):
    """
    The SDK's Protocol 2.0 handler with its two per-byte hot spots made cheap.

    Every control cycle builds a sync write and checks the CRC of every status packet. The
    SDK's ``updateCRC`` rebuilds its 256-entry table on each call, ``addStuffing`` copies the
    packet into a 1 kB scratch list even when nothing needs stuffing and ``removeStuffing``
    walks every status packet byte by byte; together they were the larger part of the bridge's
    time on the critical path between two bus transfers. The
    results are byte-for-byte the SDK's (a test compares them on random and adversarial data).
    """

    def updateCRC(self, crc_accum, data_blk_ptr, data_blk_size):  # noqa: N802 (SDK's name)
        table = _CRC_TABLE
        crc = crc_accum
        for byte in data_blk_ptr[:data_blk_size]:
            crc = ((crc << 8) & 0xFFFF) ^ table[((crc >> 8) ^ byte) & 0xFF]
        return crc

    def addStuffing(self, packet):  # noqa: N802 (SDK's name)
        # Stuffing only ever applies to an FF FF FD inside instruction + parameters.
        if bytes(packet[4:]).find(_STUFF_PATTERN) < 0:
            return packet
        return super().addStuffing(packet)

    def removeStuffing(self, packet):  # noqa: N802 (SDK's name)
        # Only an FF FF FD FD inside a status packet is stuffed; most packets have none.
        if bytes(packet[4:]).find(_STUFFED_PATTERN) < 0:
            return packet
        return super().removeStuffing(packet)

    def readRx(self, port, dxl_id, length):  # noqa: N802 (SDK's name)
        """
        One servo's reply to a sync read: skip status packets that are not that reply.

        The SDK skips packets of other IDs but takes any packet of the right ID. On a busy
        machine a reply can come after its read timed out and the next read was sent; the
        SDK would then take, say, the first byte of a late present position for the Hardware
        Error Status (a false fault, or a real one missed). A reply to this read carries
        exactly ``length`` data bytes: instruction, error and CRC make up the other 4.
        """
        while True:
            packet, result = self.rxPacket(port, False)
            if result != sdk.COMM_SUCCESS:
                return [], result, 0
            data_length = sdk.DXL_MAKEWORD(packet[sdk.PKT_LENGTH_L],
                                           packet[sdk.PKT_LENGTH_H]) - 4
            if packet[sdk.PKT_ID] == dxl_id and data_length == length:
                start = sdk.PKT_PARAMETER0 + 1
                return list(packet[start:start + length]), result, packet[sdk.PKT_ERROR]


class BusError(RuntimeError):
    """The serial port cannot be opened or failed (unplugged, vanished)."""


class ServoBus:
    """
    One serial port with X-series servos on it.

    Parameters
    ----------
    port
        Serial device path.
    baud_rate
        Bits per second.
    fast_sync_read
        Read positions with Fast Sync Read (one status packet for all servos; X-series
        firmware 45 or newer) instead of Sync Read (one status packet per servo).

    """

    def __init__(self, port: str, baud_rate: int, fast_sync_read: bool = False):
        self.fast_sync_read = bool(fast_sync_read)
        self.port_name = port
        self.baud_rate = int(baud_rate)
        self.port = None
        self.packet = PacketHandler()
        self._read_position = None
        self._read_errors = None
        self._write_goal = None
        self._write_ids: Tuple[int, ...] = ()
        self._pending = False
        self._read_ids: Tuple[int, ...] = ()
        self._error_ids: Tuple[int, ...] = ()
        #: dynamixel-sdk result code of the last sync read.
        self.last_result = sdk.COMM_SUCCESS

    def _guard(self, call, *args):
        try:
            return call(*args)
        except (serial.SerialException, OSError, termios.error, TypeError) as error:
            # termios.error: flushing a hung-up tty; TypeError: pyserial on a closed descriptor
            raise BusError(f'{self.port_name}: {error}') from None

    def open(self) -> None:  # noqa: A003 (a port is opened and closed)
        """Open the port at the baud rate; raise :class:`BusError` if it cannot be opened."""
        self.close()
        port = sdk.PortHandler(self.port_name)
        port.baudrate = self.baud_rate
        ok = self._guard(port.openPort)
        if not ok:
            raise BusError(f'{self.port_name}: cannot open at {self.baud_rate} baud')
        self.port = port
        self._read_position = None
        self._read_errors = None
        self._write_goal = None
        self._pending = False

    def close(self) -> None:
        """Close the port if open (never raises)."""
        if self.port is not None and self.port.ser is not None:
            try:
                self.port.closePort()
            except (serial.SerialException, OSError, termios.error):
                pass
        self.port = None

    @property
    def is_open(self) -> bool:
        return self.port is not None

    def _require(self):
        if self.port is None:
            raise BusError(f'{self.port_name}: not open')
        return self.port

    def ping(self, ids: Iterable[int], attempts: int = 3) -> Dict[int, int]:
        """Ping each ID (up to ``attempts`` times); return {id: model} for those that answered."""
        port = self._require()
        found = {}
        for servo_id in ids:
            for _ in range(attempts):
                model, result, _ = self._guard(self.packet.ping, port, servo_id)
                if result == sdk.COMM_SUCCESS:
                    found[servo_id] = model
                    break
        return found

    def set_torque(self, ids: Iterable[int], enabled: bool) -> Dict[int, bool]:
        """Write Torque Enable to each ID; return {id: acknowledged}."""
        port = self._require()
        done = {}
        for servo_id in ids:
            result, _ = self._guard(self.packet.write1ByteTxRx, port, servo_id, TORQUE_ENABLE,
                                    1 if enabled else 0)
            done[servo_id] = result == sdk.COMM_SUCCESS
        return done

    def write_goals(self, goals: Mapping[int, int]) -> None:
        """Send all goal positions (ticks) in one sync write."""
        port = self._require()
        if not goals:
            return
        ids = tuple(goals)
        group = self._write_goal
        if group is None or ids != self._write_ids:
            # One group per set of IDs; later cycles only change its data.
            group = sdk.GroupSyncWrite(port, self.packet, GOAL_POSITION, POSITION_BYTES)
            for servo_id, ticks in goals.items():
                group.addParam(servo_id, int(ticks).to_bytes(POSITION_BYTES, 'little',
                                                             signed=True))
            self._write_goal, self._write_ids = group, ids
        else:
            for servo_id, ticks in goals.items():
                group.changeParam(servo_id, int(ticks).to_bytes(POSITION_BYTES, 'little',
                                                                signed=True))
        result = self._guard(group.txPacket)
        if result != sdk.COMM_SUCCESS:
            raise BusError(f'{self.port_name}: sync write failed: '
                           f'{self.packet.getTxRxResult(result)}')

    def read_positions(self, ids: Iterable[int]) -> Dict[int, int]:
        """Read present positions (ticks) in one sync read; {} if any servo did not answer."""
        if not self.request_positions(ids):
            return {}
        return self.collect_positions()

    def request_positions(self, ids: Iterable[int]) -> bool:
        """
        Send the sync read of present positions.

        The replies are taken by :meth:`collect_positions`. Work done in between overlaps the
        replies' wire time. Return False if there is nothing to read or the request could not be
        sent.
        """
        port = self._require()
        ids = tuple(ids)
        self._pending = False
        if not ids:
            return False
        if self._read_position is None or ids != self._read_ids:
            self._read_position = sdk.GroupSyncRead(port, self.packet, PRESENT_POSITION,
                                                    POSITION_BYTES)
            for servo_id in ids:
                self._read_position.addParam(servo_id)
            self._read_ids = ids
        group = self._read_position
        self.last_result = self._guard(
            group.fastSyncReadTxPacket if self.fast_sync_read else group.txPacket)
        self._pending = self.last_result == sdk.COMM_SUCCESS
        if not self._pending:
            port.is_using = False
        return self._pending

    def collect_positions(self) -> Dict[int, int]:
        """Receive the replies to :meth:`request_positions`; {} if any servo did not answer."""
        self._require()
        if not self._pending:
            return {}
        self._pending = False
        group = self._read_position
        self.last_result = self._guard(
            group.fastSyncReadRxPacket if self.fast_sync_read else group.rxPacket)
        if self.last_result != sdk.COMM_SUCCESS:
            return {}
        out = {}
        for servo_id in self._read_ids:
            try:
                raw = group.getData(servo_id, PRESENT_POSITION, POSITION_BYTES)
            except (IndexError, TypeError):
                # A late status packet of another length was taken for this servo's reply.
                self.last_result = sdk.COMM_RX_CORRUPT
                return {}
            out[servo_id] = raw - (1 << 32) if raw & (1 << 31) else raw
        return out

    def read_hardware_errors(self, ids: Iterable[int]) -> Dict[int, int]:
        """Read Hardware Error Status of each ID in one sync read; {} on failure."""
        port = self._require()
        ids = tuple(ids)
        if not ids:
            return {}
        if self._read_errors is None or ids != self._error_ids:
            self._read_errors = sdk.GroupSyncRead(port, self.packet, HARDWARE_ERROR_STATUS, 1)
            for servo_id in ids:
                self._read_errors.addParam(servo_id)
            self._error_ids = ids
        group = self._read_errors
        if self._guard(group.txRxPacket) != sdk.COMM_SUCCESS:
            return {}
        try:
            return {i: group.getData(i, HARDWARE_ERROR_STATUS, 1) for i in ids}
        except IndexError:
            return {}
