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
A planning worker's replies matched to their requests, and planning faults that end the node.

ROS-free. The worker's child is a stand-in process (spawned like the real one, on the real
pipe) that answers at once, late, or twice; the worker's own request, timeout and replacement
code is what runs.
"""
import threading
import time

from digital_actor_planner.runtime.planning import PlanningLost, PlanningWorker
from digital_actor_planner.runtime.scheduling import PlanningScheduler
import pytest


def _stand_in_child(connection) -> None:
    """
    Answer ``(number, kind, ...)`` requests as a planning process would, on ``connection``.

    ``('echo', tag)``: ``('done', tag)`` at once. ``('sleep', seconds, tag)``: the same after
    ``seconds`` (a slow plan). ``('twice', tag)``: two replies to the one request, the second
    of which is left in the pipe for the next request to find. ``(number, 'stop')`` ends it.
    """
    while True:
        try:
            number, kind, *request = connection.recv()
        except (EOFError, OSError):
            return
        if kind == 'echo':
            connection.send((number, 'done', request[0]))
        elif kind == 'sleep':
            time.sleep(request[0])
            connection.send((number, 'done', request[1]))
        elif kind == 'twice':
            connection.send((number, 'done', request[0]))
            connection.send((number, 'done', request[0]))
        else:
            return


class StandInWorker(PlanningWorker):
    """A :class:`PlanningWorker` whose child process is :func:`_stand_in_child`."""

    child_main = staticmethod(_stand_in_child)


@pytest.fixture
def worker():
    worker = StandInWorker()
    try:
        yield worker
    finally:
        worker.close()


def test_a_reply_left_for_an_earlier_request_is_dropped_and_the_next_gets_its_own(worker):
    # Spawning the child takes a while on a loaded machine: generous timeouts throughout.
    assert worker.request(('twice', 'first'), 120.0) == ('done', 'first')
    # The first request's second reply is in the pipe ahead of this one's.
    assert worker.request(('echo', 'second'), 60.0) == ('done', 'second')
    assert worker.stale_replies == 1
    assert worker.request(('echo', 'third'), 60.0) == ('done', 'third')
    assert worker.stale_replies == 1
    assert worker.generation == 0


def test_a_child_answering_after_the_timeout_is_replaced_and_its_late_reply_never_arrives(
        worker):
    assert worker.request(('echo', 'warm'), 120.0) == ('done', 'warm')
    slow = worker.pid
    started = time.monotonic()
    with pytest.raises(PlanningLost, match='no answer'):
        worker.request(('sleep', 3.0, 'late'), 0.5)
    assert worker.generation == 1
    assert worker.pid != slow
    # Past the moment the slow child would have answered, had it not been killed: the next
    # request is answered by the new child, with its own reply, and nothing stale is seen.
    time.sleep(max(0.0, started + 4.0 - time.monotonic()))
    assert worker.request(('echo', 'after'), 120.0) == ('done', 'after')
    assert worker.request(('echo', 'again'), 60.0) == ('done', 'again')
    assert worker.stale_replies == 0
    assert worker.generation == 1


class _FaultyNode:
    """A node the scheduler plans for whose ``plan_once`` raises; ``fail`` calls recorded."""

    def __init__(self, faulty: bool):
        self.faulty = faulty
        self.failures = []
        self.failed = threading.Event()
        self.planned = 0

    def planning_slack(self):
        # The faulty node is due; the healthy one has nothing to plan (but shares the thread).
        return -0.1 if self.faulty and not self.failures else None

    def plan_once(self):
        self.planned += 1
        raise RuntimeError('a fault in plan_once')

    def fail(self, code, message):
        self.failures.append((code, message))
        self.failed.set()


def test_a_fault_escaping_plan_once_ends_every_node_of_the_planning_thread_with_status_1():
    scheduler = PlanningScheduler()
    healthy, faulty = _FaultyNode(False), _FaultyNode(True)
    scheduler.attach(healthy, 0)
    scheduler.attach(faulty, 0)
    try:
        assert faulty.failed.wait(30.0) and healthy.failed.wait(30.0)
        for node in (healthy, faulty):
            assert [code for code, _ in node.failures] == [1]
            assert 'a fault in plan_once' in node.failures[0][1]
        assert faulty.planned == 1
        # The thread has ended: nobody is planned for any more (not a silently frozen actor).
        scheduler._thread.join(timeout=10.0)
        assert not scheduler._thread.is_alive()
    finally:
        scheduler.detach(faulty)
        scheduler.detach(healthy)
