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

"""The readable expansion of §5.2's best-first search and its compiled twin plan alike."""
import os

from course_runs import scene, SCENES, simulate
from digital_actor_planner.cli import read_commands
from digital_actor_planner.core.actor import Actor, ActorConfig, run_commands
from digital_actor_planner.core.collision import BodyCollision
from digital_actor_planner.core.ct_roadmap import CTRoadmap
from digital_actor_planner.core.ct_space import CTSpace
from digital_actor_planner.core.environment import Environment
from digital_actor_planner.core.upper_body import UpperBodyConfig, UpperBodyPlanner
import numpy as np
import pytest
from scene_helpers import box, timed_body, walk

TRUNK = ('waist', 'torso', 'head', 'left_shoulder', 'right_shoulder')
LEGS = ('pelvis', 'left_hip', 'right_hip', 'left_thigh', 'right_thigh', 'left_shank',
        'right_shank', 'left_foot', 'right_foot')
PATTERNS = np.array([(0.0, 0.3), (0.0, 0.6), (0.0, 0.9), (0.4, 0.0), (-0.4, 0.0)])
#: The courses whose upper body leaves its motion pattern (test_upper_body_courses.py).
UPPER_BODY_COURSES = ['low_beam', 'table', 'pillars', 'uneven_beam']


def beam_space(skeleton, beam_bottom):
    """Return the waist's CT-space walking under a beam whose underside is ``beam_bottom`` m up."""
    meshes = [box([-2.5, -1.5, -0.1], [3.0, 1.5, 0.0]),
              box([0.3, -1.0, beam_bottom], [0.5, 1.0, beam_bottom + 0.2])]
    environment = Environment(meshes, resolution=0.05)
    times, frames = walk(skeleton, 220, swing_legs=False)
    body = timed_body(skeleton, environment, frames)
    return CTSpace('waist', body, times, frames[:, skeleton.branch('waist')], TRUNK, LEGS)


@pytest.mark.parametrize('prefer_lasting', [False, True])
def test_both_expansions_search_the_beam_node_for_node(skeleton, prefer_lasting):
    """
    Under beams, both expansions search node for node alike.

    Under beams low enough to bend for, and one too low to pass: the same result, states expanded,
    backtracks, nodes grown and configurations checked, from starts that bend, backtrack and grow
    (a start a hair off the pattern too, whose targets round to -0.0).
    """
    starts = [np.zeros(2), np.array([0.0, 0.9]), np.array([0.3, 0.2]), np.array([-0.4, 0.5]),
              np.array([-2e-4, 0.9]), np.array([-2e-4, 0.3])]
    expanded = backtracked = 0
    for beam_bottom in (1.60, 1.45, 0.9):
        space = beam_space(skeleton, beam_bottom)
        for seed, start in enumerate(starts):
            results = []
            for search in ('compiled', 'readable'):
                roadmap = CTRoadmap(PATTERNS, np.ones(2), radius=0.3, max_nodes=32,
                                    rng=np.random.default_rng(seed),
                                    prefer_lasting=prefer_lasting, search=search)
                before = space.checks
                result = roadmap.solve(space, space.objective[0] + start, check_budget=6000)
                results.append((result, space.checks - before, roadmap.nodes))
            (a, a_checks, a_nodes), (b, b_checks, b_nodes) = results
            case = (beam_bottom, seed)
            assert (b.ok, b.blocked_frame, b.nodes, b.backtracks, b.grown, b_checks) == (
                a.ok, a.blocked_frame, a.nodes, a.backtracks, a.grown, a_checks), case
            np.testing.assert_array_equal(b.path, a.path, err_msg=str(case))
            np.testing.assert_array_equal(b_nodes, a_nodes, err_msg=str(case))
            expanded += a.nodes
            backtracked += a.backtracks > 0
    assert expanded > 30 and backtracked >= 3, 'the searches did little more than follow'


def test_an_unknown_search_is_named():
    with pytest.raises(ValueError, match='search'):
        CTRoadmap(PATTERNS, np.ones(2), radius=0.3, max_nodes=32,
                  rng=np.random.default_rng(0), search='fast')
    with pytest.raises(ValueError, match='roadmap_search'):
        UpperBodyPlanner(None, None, UpperBodyConfig(roadmap_search='fast'))


def _walk(skeleton, name, roadmap_search):
    sc = scene(name)
    commands = read_commands(os.path.join(SCENES, name + '.csv'))
    config = ActorConfig()
    collision = BodyCollision(skeleton, sc.environment)
    upper = UpperBodyPlanner(skeleton, collision,
                             UpperBodyConfig(roadmap_search=roadmap_search),
                             rng=np.random.default_rng(0))
    actor = Actor(skeleton, sc.environment, config, start=sc.start, upper_body_planner=upper,
                  body_collision=collision)
    return run_commands(actor, [c.time for c in commands], [c.linear_x for c in commands],
                        [c.angular_z for c in commands])


@pytest.mark.slow
@pytest.mark.parametrize('name', UPPER_BODY_COURSES)
def test_every_upper_body_course_is_walked_alike_with_the_readable_expansion(skeleton, name):
    """
    The upper-body courses are walked alike with the readable expansion.

    The courses where the upper body must leave its pattern, planned with the readable expansion:
    the walk of the compiled one, frame for frame.
    """
    _, times, frames, blocks = simulate(name)
    readable = _walk(skeleton, name, 'readable')
    assert [b.status for b in readable] == [b.status for b in blocks], name
    np.testing.assert_array_equal(np.concatenate([b.times for b in readable]), times)
    np.testing.assert_array_equal(np.vstack([b.frames for b in readable]), frames)
