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

"""Exact contact tests of convex shapes (GJK) against FCL's collision test."""
from digital_actor_planner.core import convex
import fcl
import numpy as np

NO_CORNERS = np.zeros((3, 3))


def _rotation(rng) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def _shape(rng):
    """Make a random box, cylinder or sphere near the origin: (kind, padded half extents, R, c)."""
    kind = int(rng.integers(0, 3))
    if kind == convex.BOX:
        half = rng.uniform(0.02, 0.3, 3)
    elif kind == convex.CYLINDER:
        half = np.array([rng.uniform(0.02, 0.1), rng.uniform(0.03, 0.25), 0.0])
    else:
        half = np.array([rng.uniform(0.02, 0.15), 0.0, 0.0])
    return kind, half, _rotation(rng), rng.uniform(-0.3, 0.3, 3)


def _fcl(kind, half, rotation, centre, corners=None):
    if kind == convex.TRIANGLE:
        model = fcl.BVHModel()
        model.beginModel(3, 1)
        model.addSubModel(corners, np.array([[0, 1, 2]]))
        model.endModel()
        return fcl.CollisionObject(model, fcl.Transform())
    geometry = (fcl.Box(*(2 * half)) if kind == convex.BOX
                else fcl.Cylinder(half[0], 2 * half[1]) if kind == convex.CYLINDER
                else fcl.Sphere(half[0]))
    return fcl.CollisionObject(geometry, fcl.Transform(rotation, centre))


def _pair(rng):
    """Two shapes, the second a triangle half the time (as the planner meets them)."""
    a = _shape(rng) + (NO_CORNERS,)
    if rng.random() < 0.5:
        corners = rng.uniform(-0.4, 0.4, (3, 3))
        b = (convex.TRIANGLE, np.zeros(3), np.eye(3), np.zeros(3), corners)
    else:
        b = _shape(rng) + (NO_CORNERS,)
    return a, b


def _fcl_touching(a, b) -> bool:
    return fcl.collide(_fcl(*a[:4]), _fcl(*b[:4], corners=b[4]), fcl.CollisionRequest(),
                       fcl.CollisionResult()) > 0


def test_the_exact_test_agrees_with_fcl_on_random_shapes():
    rng = np.random.default_rng(0)
    answers = []
    for _ in range(4000):
        a, b = _pair(rng)
        expected = _fcl_touching(a, b)
        assert convex.touching(*a, *b) == expected, (a, b)
        assert convex.touching(*b, *a) == expected, (a, b)  # either order
        answers.append(expected)
    assert 0.1 < np.mean(answers) < 0.5


def test_near_contact_the_answers_agree_beyond_ten_micrometres():
    # Slide one shape along a line through the point where FCL's answer changes: 10 um
    # before it they touch, 10 um after it they do not, for both tests.
    rng = np.random.default_rng(1)
    checked = 0
    while checked < 150:
        (kind, half, rotation, centre, corners), b = _pair(rng)
        if not _fcl_touching((kind, half, rotation, centre, corners), b):
            continue
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        inside, outside = 0.0, 2.0
        for _ in range(40):
            middle = (inside + outside) / 2
            moved = (kind, half, rotation, centre + middle * direction, corners)
            if _fcl_touching(moved, b):
                inside = middle
            else:
                outside = middle
        for offset, expected in ((inside - 1e-5, True), (outside + 1e-5, False)):
            moved = (kind, half, rotation, centre + offset * direction, corners)
            assert _fcl_touching(moved, b) == expected
            assert convex.touching(*moved, *b) == expected, (moved, b, offset)
        checked += 1


def test_support_points_are_the_farthest_points_of_each_shape():
    # The support point lies on the shape (within its half extents in its own frame) and no
    # sampled point of the shape reaches farther along the direction.
    rng = np.random.default_rng(2)
    for _ in range(200):
        kind, half, rotation, centre = _shape(rng)
        d = rng.normal(size=3)
        point = np.array(convex.support(kind, half, rotation, centre, NO_CORNERS, *d))
        local = rotation.T @ (point - centre)
        if kind == convex.BOX:
            samples = rng.uniform(-1, 1, (500, 3)) * half
            assert np.all(np.abs(local) <= half + 1e-12)
        elif kind == convex.CYLINDER:
            angle, radius = rng.uniform(0, 2 * np.pi, 500), half[0] * np.sqrt(rng.random(500))
            samples = np.stack([radius * np.cos(angle), radius * np.sin(angle),
                                rng.uniform(-half[1], half[1], 500)], axis=1)
            assert np.hypot(local[0], local[1]) <= half[0] + 1e-12
            assert abs(local[2]) <= half[1] + 1e-12
        else:
            samples = rng.normal(size=(500, 3))
            samples *= half[0] * rng.random((500, 1)) / np.linalg.norm(samples, axis=1)[:, None]
            assert np.linalg.norm(local) <= half[0] + 1e-12
        world = centre + samples @ rotation.T
        assert np.all(world @ d <= point @ d + 1e-12)
