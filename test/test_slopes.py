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

"""Weaving on a gentle hill walks on: no stuck event where nothing would touch."""
import functools
import os
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'bench'))

from bench_slopes import heightmap_hill, hill_starts, slopes, weave  # noqa: E402
from course_runs import judged  # noqa: E402
from digital_actor_planner.core.environment import Environment  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402


@functools.lru_cache(maxsize=None)
def hill():
    return Environment([heightmap_hill()])


def test_the_hill_is_gentle():
    face_slopes = slopes(heightmap_hill())
    assert 5.0 < np.median(face_slopes) < 7.0 and face_slopes.max() <= 10.0


@pytest.mark.parametrize('start', [hill_starts(8)[i] for i in (0, 1, 3, 6)])
def test_weaving_on_the_hill_never_stops(start):
    blocks = weave(hill(), start, 14.0)
    assert blocks is not None, 'a start the actor can stand on'
    reasons = sorted({b.reason for b in blocks if b.status == 'stuck'})
    assert not reasons, reasons
    _, frames, report = judged(blocks, hill())
    assert report.ok, report.failures()
    # It walked on, up and down the slope: about 0.5 m/s for 14 s, less the weave's arcs.
    assert np.hypot(*(frames[-1, :2] - frames[0, :2])) > 4.0
