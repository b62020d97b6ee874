"""Drive a Protocol 2.0 X-series bus with dynamixel-sdk (the only module that imports it)."""
from __future__ import annotations

from typing import Dict, Iterable, Mapping, Tuple

import termios

import dynamixel_sdk as sdk
import serial

TORQUE_ENABLE = 64
HARDWARE_ERROR_STATUS = 70
GOAL_POSITION = 116
PRESENT_POSITION = 132
POSITION_BYTES = 4


class BusError(RuntimeError):
    """The serial port cannot be opened or failed (unplugged, vanished)."""


class ServoBus:
    """One serial port with X-series servos on it.

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
        self.packet = sdk.PacketHandler(2.0)
        self._read_position = None
        self._read_errors = None
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

    def open(self) -> None:
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
        group = sdk.GroupSyncWrite(port, self.packet, GOAL_POSITION, POSITION_BYTES)
        for servo_id, ticks in goals.items():
            group.addParam(servo_id, int(ticks).to_bytes(POSITION_BYTES, 'little', signed=True))
        result = self._guard(group.txPacket)
        if result != sdk.COMM_SUCCESS:
            raise BusError(f'{self.port_name}: sync write failed: '
                           f'{self.packet.getTxRxResult(result)}')

    def read_positions(self, ids: Iterable[int]) -> Dict[int, int]:
        """Read present positions (ticks) in one sync read; {} if any servo did not answer."""
        port = self._require()
        ids = tuple(ids)
        if not ids:
            return {}
        if self._read_position is None or ids != self._read_ids:
            self._read_position = sdk.GroupSyncRead(port, self.packet, PRESENT_POSITION,
                                                    POSITION_BYTES)
            for servo_id in ids:
                self._read_position.addParam(servo_id)
            self._read_ids = ids
        group = self._read_position
        self.last_result = self._guard(
            group.fastSyncRead if self.fast_sync_read else group.txRxPacket)
        if self.last_result != sdk.COMM_SUCCESS:
            return {}
        out = {}
        for servo_id in ids:
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
