"""
A live node beside a CPU hog on every core still walks its obstacle course to the end.

The actor_planner process walks the course's command file, sent over DDS as a mouse teleop
would, while busy-looping processes take every CPU: a plan that takes longer may delay a step,
never stop the actor short of the course's end. The idle runs and every course are in
bench/bench_live_load.py.
"""
import math
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'bench'))

from bench_live_load import expectation, REACH_TOLERANCE, start_hogs, stop_hogs, \
    walk_live  # noqa: E402
import pytest  # noqa: E402
from ros_harness import fresh_domain_id  # noqa: E402
from test_node_helpers import scene  # noqa: E402

pytestmark = [pytest.mark.ros, pytest.mark.slow]

#: The README's headline course (the waist bends under the beam) and a climb.
COURSES = [c for c in ('low_beam', 'stairs_up') if os.path.exists(scene(c))]


@pytest.mark.parametrize('course', COURSES)
def test_course_walked_beside_a_cpu_hog_on_every_core_reaches_its_end(course, tmp_path):
    hogs = start_hogs(max(2, os.cpu_count() or 2))
    try:
        run = walk_live(course, fresh_domain_id(), str(tmp_path), 'loaded')
    finally:
        stop_hogs(hogs)
    assert not run['error'], f'{course}: {run["error"]}'
    goal = expectation(course)['reach_x'] - REACH_TOLERANCE
    assert math.isfinite(run['x']) and run['x'] >= goal, \
        f'{course} under load ended at x {run["x"]:.2f} m (goal {goal:.2f} m), ' \
        f'{run["state"]}: {run["reason"]}'
