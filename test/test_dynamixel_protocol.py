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
The emulator and dynamixel-sdk against the e-Manual's Protocol 2.0 example packets.

The golden packets are the examples of the ROBOTIS e-Manual "DYNAMIXEL Protocol 2.0" page
(instruction and status packets, CRC bytes included).
"""
import os
import select
import time
from typing import Optional

import dynamixel_emulator as emu
import dynamixel_sdk as sdk
import pytest

GOLDEN = {
    'ping': bytes.fromhex('FF FF FD 00 01 03 00 01 19 4E'),
    'ping status': bytes.fromhex('FF FF FD 00 01 07 00 55 00 06 04 26 65 5D'),
    'read': bytes.fromhex('FF FF FD 00 01 07 00 02 84 00 04 00 1D 15'),
    'read status': bytes.fromhex('FF FF FD 00 01 08 00 55 00 A6 00 00 00 8C C0'),
    'write': bytes.fromhex('FF FF FD 00 01 09 00 03 74 00 00 02 00 00 CA 89'),
    'write status': bytes.fromhex('FF FF FD 00 01 04 00 55 00 A1 0C'),
    'sync read': bytes.fromhex('FF FF FD 00 FE 09 00 82 84 00 04 00 01 02 CE FA'),
    'sync read status 2': bytes.fromhex('FF FF FD 00 02 08 00 55 00 1F 08 00 00 BA BE'),
    'sync write': bytes.fromhex(
        'FF FF FD 00 FE 11 00 83 74 00 04 00 01 96 00 00 00 02 AA 00 00 00 82 87'),
}


def test_emulator_encodes_the_golden_packets():
    assert emu.build_packet(1, emu.PING) == GOLDEN['ping']
    assert emu.build_status(1, 0, bytes([0x06, 0x04, 0x26])) == GOLDEN['ping status']
    assert emu.build_packet(1, emu.READ, bytes([0x84, 0, 4, 0])) == GOLDEN['read']
    assert emu.build_status(1, 0, (166).to_bytes(4, 'little')) == GOLDEN['read status']
    assert emu.build_packet(1, emu.WRITE, bytes([0x74, 0]) + (512).to_bytes(4, 'little')) \
        == GOLDEN['write']
    assert emu.build_status(1, 0) == GOLDEN['write status']
    assert emu.build_packet(0xFE, emu.SYNC_READ, bytes([0x84, 0, 4, 0, 1, 2])) \
        == GOLDEN['sync read']
    assert emu.build_status(2, 0, (2079).to_bytes(4, 'little')) == GOLDEN['sync read status 2']
    params = bytes([0x74, 0, 4, 0, 1]) + (150).to_bytes(4, 'little') + bytes([2]) + (
        170).to_bytes(4, 'little')
    assert emu.build_packet(0xFE, emu.SYNC_WRITE, params) == GOLDEN['sync write']


def test_emulator_decodes_the_golden_packets():
    for key in ('ping', 'read', 'write', 'sync read', 'sync write'):
        packet, consumed, crc_ok = emu.parse_packet(b'\x00\x13' + GOLDEN[key] + b'\xff')
        assert crc_ok and consumed == len(GOLDEN[key]) + 2, key
    packet, _, _ = emu.parse_packet(GOLDEN['sync write'])
    assert packet == (0xFE, emu.SYNC_WRITE, GOLDEN['sync write'][8:-2])


def test_byte_stuffing_round_trip():
    payload = bytes([0x03, 0xFF, 0xFF, 0xFD, 0x01, 0xFF, 0xFF, 0xFD])
    stuffed = emu.stuff(payload)
    assert stuffed == bytes([0x03, 0xFF, 0xFF, 0xFD, 0xFD, 0x01, 0xFF, 0xFF, 0xFD, 0xFD])
    assert emu.unstuff(stuffed) == payload


@pytest.fixture
def bus(tmp_path):
    with emu.DynamixelEmulator([1, 2], str(tmp_path / 'ttyDXL')) as emulator:
        emulator.set_register(1, emu.MODEL_NUMBER, 1030)
        emulator.set_register(1, emu.FIRMWARE_VERSION, 0x26)
        emulator.set_register(1, emu.PRESENT_POSITION, 166)
        emulator.servos[1]._position = 166
        emulator.set_register(2, emu.PRESENT_POSITION, 2079)
        emulator.servos[2]._position = 2079
        fd = os.open(emulator.port_path, os.O_RDWR | os.O_NOCTTY)
        try:
            yield emulator, fd
        finally:
            os.close(fd)


def _exchange(fd, request: bytes, expect: int, timeout: float = 2.0) -> bytes:
    os.write(fd, request)
    reply = b''
    deadline = time.monotonic() + timeout
    while len(reply) < expect and time.monotonic() < deadline:
        ready, _, _ = select.select([fd], [], [], 0.05)
        if ready:
            reply += os.read(fd, 256)
    return reply


def _until(condition, timeout: float = 10.0) -> bool:
    """Whether ``condition()`` holds within ``timeout`` seconds (the emulator is a thread)."""
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


def test_emulated_servo_answers_golden_instructions_with_golden_status(bus):
    emulator, fd = bus
    assert _exchange(fd, GOLDEN['ping'], 14) == GOLDEN['ping status']
    assert _exchange(fd, GOLDEN['read'], 15) == GOLDEN['read status']
    assert _exchange(fd, GOLDEN['sync read'], 30) == GOLDEN['read status'] + GOLDEN[
        'sync read status 2']
    assert _exchange(fd, GOLDEN['write'], 11) == GOLDEN['write status']
    assert emulator.register(1, emu.GOAL_POSITION) == 512
    os.write(fd, GOLDEN['sync write'])
    assert _until(lambda: (emulator.register(1, emu.GOAL_POSITION),
                           emulator.register(2, emu.GOAL_POSITION)) == (150, 170))
    # No status for sync write: the servo answers in order, so the ping's status comes first.
    assert _exchange(fd, GOLDEN['ping'], 14) == GOLDEN['ping status']


def test_corrupt_crc_gets_a_crc_error_status(bus):
    emulator, fd = bus
    corrupt = GOLDEN['write'][:-1] + bytes([GOLDEN['write'][-1] ^ 0x01])
    reply = _exchange(fd, corrupt, 11)
    assert reply == emu.build_status(1, emu.ERR_CRC)
    assert emulator.register(1, emu.GOAL_POSITION) != 512


def test_sdk_sends_the_golden_instruction_bytes(bus):
    emulator, _ = bus
    port = sdk.PortHandler(emulator.port_path)
    assert port.openPort()
    try:
        packet = sdk.PacketHandler(2.0)
        model, result, error = _answered(packet.ping, port, 1, result_at=1)
        assert (model, result, error) == (1030, sdk.COMM_SUCCESS, 0)
        assert emulator.received[-1] == GOLDEN['ping']
        value, result, _ = _answered(packet.read4ByteTxRx, port, 1, 132, result_at=1)
        assert (value, result) == (166, sdk.COMM_SUCCESS)
        assert emulator.received[-1] == GOLDEN['read']
        # Writing the same goal again is harmless, so a timed-out write may be repeated.
        assert _answered(packet.write4ByteTxRx, port, 1, 116, 512, result_at=0)[0] \
            == sdk.COMM_SUCCESS
        assert emulator.received[-1] == GOLDEN['write']
        group = sdk.GroupSyncWrite(port, packet, 116, 4)
        group.addParam(1, (150).to_bytes(4, 'little'))
        group.addParam(2, (170).to_bytes(4, 'little'))
        assert group.txPacket() == sdk.COMM_SUCCESS
        assert _until(lambda: emulator.register(2, emu.GOAL_POSITION) == 170)
        assert emulator.received[-1] == GOLDEN['sync write']
        reader = sdk.GroupSyncRead(port, packet, 132, 4)
        reader.addParam(1)
        reader.addParam(2)
        assert _answered(reader.txRxPacket) == sdk.COMM_SUCCESS
        assert emulator.received[-1] == GOLDEN['sync read']
    finally:
        port.closePort()


def test_stuffed_parameters_cross_the_wire_intact(bus):
    # dynamixel-sdk 4.1.0 (Python) does not stuff what it transmits (addStuffing rebinds its
    # list), so this sends a correctly stuffed packet by hand. The bridge's own packets never
    # contain FF FF FD: goal ticks <= 4095 and IDs <= 252.
    emulator, fd = bus
    value = bytes([0xFF, 0xFF, 0xFD, 0x00])  # Homing Offset (EEPROM, torque is off)
    request = emu.build_packet(1, emu.WRITE, bytes([20, 0]) + value)
    assert b'\xff\xff\xfd\xfd' in request
    assert _exchange(fd, request, 11) == emu.build_status(1, 0)
    assert emulator.servos[1].table[20:24] == value
    reply = _exchange(fd, emu.build_packet(1, emu.READ, bytes([20, 0, 4, 0])), 16)
    assert reply == emu.build_status(1, 0, value)
    assert b'\xff\xff\xfd\xfd' in reply


def _answered(call, *args, result_at: Optional[int] = None):
    """
    Repeat ``call(*args)`` until the reply arrives in time.

    The SDK waits about 35 ms for it, and a loaded machine can keep the emulator thread from
    answering that fast. Only a timed-out exchange is repeated; any answer that came back is
    returned as it is. ``result_at`` is where the result code sits in the returned tuple, or
    None when the call returns the code alone.
    """
    deadline = time.monotonic() + 20.0
    while True:
        reply = call(*args)
        result = reply if result_at is None else reply[result_at]
        if result != sdk.COMM_RX_TIMEOUT or time.monotonic() > deadline:
            return reply


def _positions(servo_bus, ids) -> dict:
    """
    Read positions, again while the answer comes back empty (for 20 s at most).

    An empty answer is a read that timed out, as it can on a loaded machine; reading again
    changes nothing on the servos.
    """
    deadline = time.monotonic() + 20.0
    while not (positions := servo_bus.read_positions(ids)) and time.monotonic() < deadline:
        pass
    return positions


def test_status_reports_access_errors_and_hardware_alert(bus):
    emulator, _ = bus
    port = sdk.PortHandler(emulator.port_path)
    assert port.openPort()
    try:
        packet = sdk.PacketHandler(2.0)
        assert _answered(packet.write4ByteTxRx, port, 1, 132, 5, result_at=1)[1] \
            == emu.ERR_ACCESS  # read-only
        assert _answered(packet.write1ByteTxRx, port, 1, 64, 1, result_at=0) == (
            sdk.COMM_SUCCESS, 0)
        assert _answered(packet.write1ByteTxRx, port, 1, 7, 9, result_at=0)[1] \
            == emu.ERR_ACCESS  # EEPROM locked
        emulator.inject_hardware_error(1, 0x20)
        assert _answered(packet.ping, port, 1, result_at=1)[2] & emu.ALERT
        value, result, error = _answered(packet.read1ByteTxRx, port, 1, 70, result_at=1)
        assert (value, result) == (0x20, sdk.COMM_SUCCESS) and error & emu.ALERT
        assert packet.ping(port, 3)[1] == sdk.COMM_RX_TIMEOUT  # nobody has ID 3
    finally:
        port.closePort()


def test_a_late_reply_is_not_taken_for_the_next_read(bus):
    """
    A present position answered after its read gave up is not read as Hardware Error Status.

    Position 2080 is 0x0820: its first byte is the overload bit. The SDK alone would take it
    for servo 1's hardware error (a false fault that switches the servo off).
    """
    from digital_actor_planner.dynamixel.bus import PacketHandler
    emulator, _ = bus
    late = emu.build_status(1, 0, (2080).to_bytes(4, 'little'))
    reply = emu.build_status(1, 0, bytes([0]))
    port = sdk.PortHandler(emulator.port_path)
    assert port.openPort()
    try:
        for handler, expected in ((sdk.PacketHandler(2.0), [0x20]), (PacketHandler(), [0])):
            port.clearPort()
            emulator._write(late + reply)  # as the wire delivers them
            port.setPacketTimeoutMillis(5000)
            data, result, _ = handler.readRx(port, 1, 1)
            assert (data, result) == (expected, sdk.COMM_SUCCESS)
    finally:
        port.closePort()


def test_servo_bus_reports_no_false_fault_after_a_late_position_reply(bus):
    """End to end: the sync read of positions answered late, then the hardware error read."""
    from digital_actor_planner.dynamixel.bus import ServoBus
    emulator, _ = bus
    emulator.place(1, 2080)  # first byte 0x20: the overload bit
    servo_bus = ServoBus(emulator.port_path, 9600)
    servo_bus.open()
    try:
        for _ in range(5):
            # held past the read's timeout (about 55 ms at 9600 baud), into the next read's
            emulator.delay_sync_read_replies(0.08)
            servo_bus.read_positions([1, 2])
            errors = servo_bus.read_hardware_errors([1, 2])
            assert errors.get(1, 0) == 0, errors
        emulator.delay_sync_read_replies(0.0, count=0)
        deadline = time.monotonic() + 20.0  # a read that times out on a busy machine is {}
        while not (errors := servo_bus.read_hardware_errors([1, 2])) and (
                time.monotonic() < deadline):
            pass
        assert errors == {1: 0, 2: 0}
    finally:
        servo_bus.close()


def test_fast_sync_read_returns_every_servo_in_one_status_packet(bus):
    emulator, _ = bus
    port = sdk.PortHandler(emulator.port_path)
    assert port.openPort()
    try:
        reader = sdk.GroupSyncRead(port, sdk.PacketHandler(2.0), 132, 4)
        reader.addParam(1)
        reader.addParam(2)
        assert _answered(reader.fastSyncRead) == sdk.COMM_SUCCESS
        assert emulator.received[-1][7] == emu.FAST_SYNC_READ
        assert (reader.getData(1, 132, 4), reader.getData(2, 132, 4)) == (166, 2079)
    finally:
        port.closePort()


def test_bridge_packet_handler_matches_the_sdk_byte_for_byte():
    import random
    from digital_actor_planner.dynamixel.bus import PacketHandler
    ours, theirs = PacketHandler(), sdk.PacketHandler(2.0)
    rng = random.Random(7)
    for size in (0, 1, 2, 15, 104, 300):
        for _ in range(20):
            data = [rng.randrange(256) for _ in range(size)]
            start = rng.randrange(1 << 16)
            assert ours.updateCRC(start, data, size) == theirs.updateCRC(start, data, size)
            assert ours.updateCRC(0, data + [1, 2], size) == theirs.updateCRC(0, data, size)
    # Stuffing: packets without FF FF FD come back unchanged; with it, the SDK's answer.
    plain = list(emu.build_packet(1, emu.WRITE, bytes([116, 0, 1, 2, 3, 4])))
    assert ours.addStuffing(list(plain)) == theirs.addStuffing(list(plain)) == plain
    for params in ([116, 0, 0xFF, 0xFF, 0xFD, 0], [0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFD]):
        packet = [0xFF, 0xFF, 0xFD, 0, 1, len(params) + 3, 0, emu.WRITE] + params + [0, 0]
        assert ours.addStuffing(list(packet)) == theirs.addStuffing(list(packet))
    for body in ([0x55, 0, 1, 2, 3], [0x55, 0, 0xFF, 0xFF, 0xFD, 0xFD, 7],
                 [0x55, 0xFF, 0xFF, 0xFD, 0xFD, 0xFF, 0xFF, 0xFD, 0xFD]):
        status = [0xFF, 0xFF, 0xFD, 0, 1, len(body) + 2, 0] + body + [0x12, 0x34]
        assert ours.removeStuffing(list(status)) == theirs.removeStuffing(list(status))


def test_servo_bus_sends_the_golden_sync_write_and_reuses_its_group(bus):
    from digital_actor_planner.dynamixel.bus import ServoBus
    emulator, _ = bus
    servo_bus = ServoBus(emulator.port_path, 57600)
    servo_bus.open()
    try:
        servo_bus.write_goals({1: 150, 2: 170})
        assert _until(lambda: emulator.register(2, emu.GOAL_POSITION) == 170)
        assert emulator.received[-1] == GOLDEN['sync write']
        assert _positions(servo_bus, [1, 2]) == {1: 166, 2: 2079}
        group = servo_bus._write_goal
        servo_bus.write_goals({1: 300, 2: 4000})
        # The servos answer in order: once the read is answered, the write has been applied.
        assert _positions(servo_bus, [1, 2])
        assert servo_bus._write_goal is group
        assert (emulator.register(1, emu.GOAL_POSITION),
                emulator.register(2, emu.GOAL_POSITION)) == (300, 4000)
        servo_bus.write_goals({2: 77})  # another set of IDs: a new group
        assert _positions(servo_bus, [1, 2])
        assert servo_bus._write_goal is not group
        assert emulator.register(2, emu.GOAL_POSITION) == 77
        assert emulator.register(1, emu.GOAL_POSITION) == 300
    finally:
        servo_bus.close()


def test_servo_bus_request_then_collect_positions(bus):
    from digital_actor_planner.dynamixel.bus import ServoBus
    emulator, _ = bus
    servo_bus = ServoBus(emulator.port_path, 57600)
    servo_bus.open()
    try:
        assert servo_bus.collect_positions() == {}  # nothing requested
        assert servo_bus.request_positions([1, 2])
        time.sleep(0.01)  # work done here overlaps the replies
        deadline = time.monotonic() + 20.0  # a collect that times out on a busy machine is {}
        while not (positions := servo_bus.collect_positions()) and time.monotonic() < deadline:
            assert servo_bus.request_positions([1, 2])
        assert positions == {1: 166, 2: 2079}
        assert servo_bus.collect_positions() == {}  # each request is answered once
        assert not servo_bus.request_positions([])
        assert servo_bus.request_positions([1, 9])  # ID 9 does not exist: no full answer
        assert servo_bus.collect_positions() == {}
        assert _positions(servo_bus, [2]) == {2: 2079}
    finally:
        servo_bus.close()
