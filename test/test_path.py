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

"""Path prediction from a velocity command (§3.2)."""
from digital_actor_planner.core.path import predict_path
import numpy as np
import pytest


def test_straight_command_predicts_a_straight_line_along_the_heading():
    path = predict_path(1.0, 2.0, np.pi / 2, 0.8, 0.0, 3.0)
    poses = path.poses(np.array([0.0, 1.0, 3.0]))
    np.testing.assert_allclose(poses[:, 0], 1.0, atol=1e-12)
    np.testing.assert_allclose(poses[:, 1], [2.0, 3.0, 5.0], atol=1e-12)
    np.testing.assert_allclose(poses[:, 2], np.pi / 2)


def test_turning_command_predicts_an_arc_of_radius_v_over_w():
    path = predict_path(0.0, 0.0, 0.0, 1.0, 0.5, 10.0)
    assert path.curvature == pytest.approx(0.5)
    s = np.linspace(0, np.pi / 0.5, 20)  # half a circle of radius 2
    poses = path.poses(s)
    np.testing.assert_allclose(np.hypot(poses[:, 0], poses[:, 1] - 2.0), 2.0, atol=1e-12)
    assert poses[-1, 0] == pytest.approx(0.0, abs=1e-9)
    assert poses[-1, 1] == pytest.approx(4.0)
    assert poses[-1, 2] == pytest.approx(np.pi)


def test_pure_turn_walks_a_tight_circle_instead_of_an_infinite_curvature():
    path = predict_path(0.0, 0.0, 0.0, 0.0, 1.0, 2.0, min_turn_speed=0.25)
    assert path.curvature == pytest.approx(4.0)


def test_offset_tracks_and_projection():
    path = predict_path(0.0, 0.0, 0.0, 1.0, 0.2, 5.0)
    s = np.array([0.0, 1.0, 2.5])
    left = path.offset_points(s, 0.09)
    right = path.offset_points(s, -0.09)
    np.testing.assert_allclose(np.linalg.norm(left - right, axis=1), 0.18)
    for value, point in zip(s, path.poses(s)[:, :2]):
        assert path.project(point) == pytest.approx(value, abs=1e-9)


@pytest.mark.parametrize('args, word', [
    ((0, 0, 0, float('nan'), 0, 1), 'non-finite'),
    ((0, 0, 0, -0.5, 0, float('inf')), 'non-finite'),
    ((0, 0, 0, 0.5, 0, 0), 'length'),
])
def test_bad_input_is_named(args, word):
    with pytest.raises(ValueError, match=word):
        predict_path(*args)


@pytest.mark.parametrize('angular', [0.0, 0.7, -1.3])
def test_offset_points_for_many_tracks_at_once_match_one_track_at_a_time(angular):
    path = predict_path(0.3, -0.2, 0.4, 0.6, angular, 4.0)
    rng = np.random.default_rng(3)
    s = rng.uniform(-0.5, 4.5, 17)
    laterals = rng.uniform(-0.2, 0.2, 5)
    tracks = path.offset_points(s, laterals[:, None])
    assert tracks.shape == (5, 17, 2)
    poses = path.poses(s)
    for lateral, points in zip(laterals, tracks):
        expected = poses[:, :2] + lateral * np.column_stack([-np.sin(poses[:, 2]),
                                                             np.cos(poses[:, 2])])
        np.testing.assert_allclose(points, expected, atol=1e-12)
        np.testing.assert_allclose(path.offset_points(s, lateral), points, atol=1e-15)
    # One offset per point.
    per_point = path.offset_points(s[:5], laterals)
    for i in range(5):
        np.testing.assert_allclose(per_point[i], path.offset_points(s[i:i + 1], laterals[i])[0],
                                   atol=1e-15)


@pytest.mark.parametrize('angular', [0.0, 0.7])
def test_offset_poses_are_the_offset_points_with_the_heading(angular):
    path = predict_path(0.3, -0.2, 0.4, 0.8, angular, 3.0)
    s = np.array([0.1, 0.9, 2.2])
    lateral = np.array([0.1, -0.1, 0.0])
    poses = path.offset_poses(s, lateral)
    np.testing.assert_array_equal(poses[:, :2], path.offset_points(s, lateral))
    np.testing.assert_array_equal(poses[:, 2], path.poses(s)[:, 2])
