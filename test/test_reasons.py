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

"""Stuck reasons a user understands: what stops the actor, with the number, in plain words."""
import re

from course_runs import simulate, skeleton
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.environment import Environment
import pytest
from scene_helpers import box


def stuck_reasons(blocks):
    return sorted({b.reason for b in blocks if b.status == 'stuck'})


def test_the_wall_is_a_rise_too_high_to_climb():
    reasons = stuck_reasons(simulate('wall')[3])
    assert len(reasons) == 1, reasons
    # The first words stay (the viewer and scripts read them); then why, with the numbers.
    reason = reasons[0]
    assert reason.startswith('no collision-free footstep window: ')
    rise = float(re.search(r'the next rise is ([0-9.]+) m', reason).group(1))
    assert rise == pytest.approx(2.0)  # the wall's height
    assert 'the legs climb at most 0.30 m' in reason


def test_the_pit_of_figure_8_has_a_rise_out_of_it_too_high_for_one_step():
    _, _, _, blocks = simulate('figure8_trap', window_steps=1, greedy_restart=False)
    reasons = stuck_reasons(blocks)
    assert reasons and all('the next rise is 0.33 m' in r for r in reasons), reasons


def test_the_beam_too_low_names_the_part_of_the_body_and_how_deep_it_would_go():
    reasons = stuck_reasons(simulate('beam_too_low')[3])
    assert reasons
    for reason in reasons:
        assert reason.startswith('upper body blocked: waist blocked at t=')
        match = re.search(r': the (torso|head) would be ([0-9]+) mm into an obstacle', reason)
        assert match and int(match.group(2)) > 0, reason


def test_a_floors_end_and_a_drop_are_told_apart():
    # A 3 m floor ending in open space, and one ending in a 0.5 m drop to a lower floor.
    for meshes, words in (([box([-1.0, -1.0, -0.1], [3.0, 1.0, 0.0])], 'the ground ends'),
                          ([box([-1.0, -1.0, -0.1], [3.0, 1.0, 0.0]),
                            box([3.0, -1.0, -0.6], [6.0, 1.0, -0.5])],
                           'the next drop is 0.50 m')):
        actor = Actor(skeleton(), Environment(meshes),
                      ActorConfig(plan_upper_body=False))
        blocks = run_commands(actor, [0.0, 8.0], [0.5, 0.0], [0.0, 0.0])
        reasons = stuck_reasons(blocks)
        assert reasons and all(words in r for r in reasons), reasons
        ahead = float(re.search(r'([0-9.]+) m ahead', reasons[0]).group(1))
        # Measured from the pelvis, which stopped short of the edge at x = 3 m.
        assert 0.0 < ahead < 1.5 and abs(blocks[-1].frames[-1, 0] + ahead - 3.0) < 0.3


def test_a_floors_end_behind_an_actor_walking_backward_is_told_with_its_distance():
    # A floor ending 1 m behind the start: stepping back, the actor stops short of its edge.
    actor = Actor(skeleton(), Environment([box([-1.0, -1.0, -0.1], [3.0, 1.0, 0.0])]),
                  ActorConfig(plan_upper_body=False))
    blocks = run_commands(actor, [0.0, 8.0], [-0.3, 0.0], [0.0, 0.0])
    reasons = stuck_reasons(blocks)
    assert reasons and all(r.startswith('no collision-free footstep window behind the actor: '
                                        'the ground ends ') for r in reasons), reasons
    behind = float(re.search(r'([0-9.]+) m behind', reasons[0]).group(1))
    # Measured from the pelvis, which stopped short of the edge at x = -1 m.
    assert 0.0 < behind < 1.5 and abs(blocks[-1].frames[-1, 0] - behind + 1.0) < 0.3
