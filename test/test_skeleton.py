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

"""The 22-DOF URDF and the skeleton read from it (paper §3.1, Figure 1)."""
import shutil
import subprocess

from digital_actor_planner.core.skeleton import (
    default_urdf_path, EXPECTED_JOINT_NAMES, Skeleton, UrdfError)
import numpy as np
import pytest


@pytest.fixture(scope='module')
def skeleton():
    return Skeleton()


def test_urdf_has_the_papers_22_joints_in_canonical_order(skeleton):
    assert skeleton.joint_names == EXPECTED_JOINT_NAMES
    assert len(skeleton.joint_names) == 22
    assert skeleton.joint_names[:4] == ('root_x', 'root_y', 'root_z', 'root_yaw')


def test_check_urdf_accepts_the_model():
    tool = shutil.which('check_urdf')
    assert tool, 'check_urdf (Debian liburdfdom-tools) is not installed; quickstart.sh installs it'
    result = subprocess.run([tool, default_urdf_path()], capture_output=True, text=True)
    assert result.returncode == 0, result.stdout + result.stderr
    assert 'Successfully Parsed XML' in result.stdout


def test_adult_proportions(skeleton):
    q = skeleton.neutral()
    q[skeleton.index['root_z']] = skeleton.leg.standing_height
    frames = skeleton.forward_kinematics(q)
    shapes = skeleton.shape_transforms(frames)
    tops, bottoms = [], []
    for shape, transform in zip(skeleton.collision_shapes, shapes):
        extent = {'sphere': lambda: shape.size[0], 'cylinder': lambda: shape.size[1] / 2,
                  'box': lambda: shape.size[2] / 2}[shape.kind]()
        tops.append(transform[2, 3] + extent)
        bottoms.append(transform[2, 3] - extent)
    assert min(bottoms) == pytest.approx(0.0, abs=1e-9)  # soles on z = 0
    assert 1.70 <= max(tops) <= 1.80
    assert 0.85 <= skeleton.leg.standing_height <= 0.95
    assert skeleton.leg.heel + skeleton.leg.toe == pytest.approx(0.25)


def test_limits_are_finite_and_realistic(skeleton):
    assert np.all(skeleton.lower < skeleton.upper)
    assert np.all(skeleton.velocity_limit > 0) and np.all(np.isfinite(skeleton.velocity_limit))
    body = [i for i, n in enumerate(skeleton.joint_names) if not n.startswith('root')]
    assert np.all(skeleton.upper[body] - skeleton.lower[body] < 2 * np.pi)
    assert np.all(skeleton.velocity_limit[body] <= 12.0)
    assert skeleton.within_limits(skeleton.neutral())[0]


def test_every_body_link_has_collision_geometry(skeleton):
    with_shapes = {s.link for s in skeleton.collision_shapes}
    body_links = [n for n in skeleton.link_names if n not in
                  ('world', 'root_x_link', 'root_y_link', 'root_z_link')]
    assert set(body_links) <= with_shapes


def test_forward_kinematics_signs_follow_the_documented_conventions(skeleton):
    q = skeleton.neutral()
    base = skeleton.forward_kinematics(q)
    foot = skeleton.link_index['left_foot']
    # hip pitch forward moves the ankle forward (+x)
    q1 = q.copy()
    q1[skeleton.index['left_hip_pitch']] = 0.5
    assert skeleton.forward_kinematics(q1)[foot, 0, 3] > base[foot, 0, 3] + 0.3
    # knee flexion moves the ankle backward and up
    q2 = q.copy()
    q2[skeleton.index['left_knee']] = 0.5
    moved = skeleton.forward_kinematics(q2)[foot, :3, 3]
    assert moved[0] < base[foot, 0, 3] and moved[2] > base[foot, 2, 3]
    # root yaw turns the whole body
    q3 = q.copy()
    q3[skeleton.index['root_yaw']] = np.pi / 2
    assert skeleton.forward_kinematics(
        q3)[foot, 0, 3] == pytest.approx(-skeleton.leg.hip_half_width)
    # waist pitch forward moves the head forward
    head = skeleton.link_index['head']
    q4 = q.copy()
    q4[skeleton.index['waist_pitch']] = 0.6
    assert skeleton.forward_kinematics(q4)[head, 0, 3] > 0.3


def test_batched_kinematics_matches_single(skeleton):
    rng = np.random.default_rng(3)
    qs = rng.uniform(np.maximum(skeleton.lower, -2), np.minimum(skeleton.upper, 2), size=(5, 22))
    batch = skeleton.forward_kinematics(qs)
    for q, frames in zip(qs, batch):
        np.testing.assert_allclose(skeleton.forward_kinematics(q), frames, atol=1e-12)


def test_broken_urdf_is_named(tmp_path):
    bad = tmp_path / 'bad.urdf'
    bad.write_text('<robot name="x"><link name="a"/></robot>')
    with pytest.raises(UrdfError, match='22 non-fixed joints'):
        Skeleton(str(bad))
    with pytest.raises(UrdfError, match='missing.urdf'):
        Skeleton(str(tmp_path / 'missing.urdf'))


def test_branches(skeleton):
    assert list(skeleton.branch('waist')) == [4, 5]
    assert len(skeleton.branch('left_arm')) == 4
    with pytest.raises(ValueError, match='tail'):
        skeleton.branch('tail')


def _reference_link_transforms(q_by_name):
    """Every link's world transform composed joint by joint straight from the URDF text."""
    import xml.etree.ElementTree as ElementTree

    def rpy_matrix(roll, pitch, yaw):
        cr, sr, cp, sp, cy, sy = (np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch),
                                  np.cos(yaw), np.sin(yaw))
        return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                         [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                         [-sp, cp * sr, cp * cr]])

    root = ElementTree.parse(default_urdf_path()).getroot()
    joints = {j.find('child').get('link'): j for j in root.findall('joint')}
    world = {}

    def transform(link):
        if link in world:
            return world[link]
        joint = joints.get(link)
        if joint is None:
            world[link] = np.eye(4)
            return world[link]
        origin = joint.find('origin')
        xyz = [float(v) for v in (origin.get('xyz', '0 0 0') if origin is not None
                                  else '0 0 0').split()]
        rpy = [float(v) for v in (origin.get('rpy', '0 0 0') if origin is not None
                                  else '0 0 0').split()]
        local = np.eye(4)
        local[:3, :3] = rpy_matrix(*rpy)
        local[:3, 3] = xyz
        motion = np.eye(4)
        axis_element = joint.find('axis')
        axis = np.array([float(v) for v in (axis_element.get('xyz') if axis_element is not None
                                            else '1 0 0').split()])
        value = q_by_name.get(joint.get('name'), 0.0)
        if joint.get('type') == 'prismatic':
            motion[:3, 3] = value * axis
        elif joint.get('type') in ('revolute', 'continuous'):
            skew = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]],
                             [-axis[1], axis[0], 0]])
            motion[:3, :3] = (np.eye(3) + np.sin(value) * skew
                              + (1 - np.cos(value)) * skew @ skew)
        world[link] = transform(joint.find('parent').get('link')) @ local @ motion
        return world[link]

    return transform


def test_forward_kinematics_matches_the_urdf_composed_joint_by_joint(skeleton):
    rng = np.random.default_rng(11)
    qs = rng.uniform(np.maximum(skeleton.lower, -2), np.minimum(skeleton.upper, 2), size=(4, 22))
    batch = skeleton.forward_kinematics(qs)
    legs = ['left_foot', 'right_shank', 'left_forearm']
    partial = skeleton.forward_kinematics(qs, links=legs)
    for q, frames, some in zip(qs, batch, partial):
        reference = _reference_link_transforms(dict(zip(skeleton.joint_names, q)))
        for link, index in skeleton.link_index.items():
            np.testing.assert_allclose(frames[index], reference(link), atol=1e-12,
                                       err_msg=link)
        for link in legs:
            np.testing.assert_allclose(some[skeleton.link_index[link]], reference(link),
                                       atol=1e-12, err_msg=link)


def test_shape_transforms_at_matches_the_full_kinematics(skeleton):
    rng = np.random.default_rng(3)
    frames = skeleton.neutral() + rng.normal(0.0, 0.3, (7, len(skeleton.joint_names)))
    for shapes in ((0, 2, 5), tuple(range(len(skeleton.collision_shapes)))):
        expected = skeleton.shape_transforms(skeleton.forward_kinematics(frames), shapes=shapes)
        np.testing.assert_allclose(skeleton.shape_transforms_at(frames, shapes), expected,
                                   atol=1e-12)
    with pytest.raises(ValueError, match='shape'):
        skeleton.shape_transforms_at(frames[0], (0,))
