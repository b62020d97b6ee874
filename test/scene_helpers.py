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

"""Small builders shared by the planner tests."""
import os

from digital_actor_planner.core.body_model import (
    BodyKinematics, BodyShapes, EnvironmentIndex, TimedBody)
from digital_actor_planner.core.scene import load_scene
from digital_actor_planner.core.upper_body import motion_patterns
import numpy as np
import trimesh
import yaml

RATE = 100.0


def box(lower, upper):
    """Make a closed box mesh spanning ``lower``..``upper`` ((3,) m each corner)."""
    lower, upper = np.asarray(lower, float), np.asarray(upper, float)
    mesh = trimesh.creation.box(extents=upper - lower)
    mesh.apply_translation((lower + upper) / 2)
    return mesh


def furniture_scene(rng):
    """
    Flat ground and a box beside the path at arm height, sometimes with a thing on it.

    The box is left or right of the x axis, its near side 0.17-0.32 m from it, its top
    0.65-1.05 m high, 0.4-2.0 m long from x = 1.5-2.5 m; in half of the scenes a 0.15 x 0.1 m
    box 0.1-0.3 m tall stands on it at the near edge. Returns (meshes, 'left' or 'right': the
    arm on the box's side).
    """
    side = 1.0 if rng.random() < 0.5 else -1.0
    near = rng.uniform(0.17, 0.32)
    top = rng.uniform(0.65, 1.05)
    x0, length, depth = rng.uniform(1.5, 2.5), rng.uniform(0.4, 2.0), rng.uniform(0.3, 0.8)
    low, high = sorted((side * near, side * (near + depth)))
    meshes = [box([-2.0, -2.0, -0.1], [12.0, 2.0, 0.0]), box([x0, low, 0.0],
                                                             [x0 + length, high, top])]
    if rng.random() < 0.5:
        height, edge = rng.uniform(0.1, 0.3), near + 0.03
        low, high = sorted((side * edge, side * (edge + 0.1)))
        x = x0 + rng.uniform(0.0, max(length - 0.2, 0.0))
        meshes.append(box([x, low, top], [x + 0.15, high, top + height]))
    return meshes, 'left' if side > 0 else 'right'


def pillars_moved_sideways(scenes, directory, centre, shift, skeleton=None):
    """
    Write the pillars course with its pillars moved sideways, and load it.

    The pillars course (``scenes``/pillars.yaml) with its two pillars ``centre`` m either side of a
    line ``shift`` m to the left of the actor's path (the course: 0.37 and 0), as a scene YAML
    written to ``directory``; returns the loaded Scene. The pillars stand at x = 3 m (radius 0.12
    m).
    """
    centre, shift = float(centre), float(shift)
    source = os.path.join(scenes, 'pillars.yaml')
    with open(source) as stream:
        data = yaml.safe_load(stream)
    for entry in data['meshes']:
        entry['file'] = os.path.join(scenes, entry['file'])
    data['meshes'][1]['pose'] = [3.0, centre + shift, 0.0, 0.0, 0.0, 0.0]
    data['meshes'][2]['pose'] = [3.0, -centre + shift, 0.0, 0.0, 0.0, 0.0]
    path = os.path.join(os.fspath(directory), f'pillars_{centre:.3f}_{shift:+.3f}.yaml')
    with open(path, 'w') as stream:
        yaml.safe_dump(data, stream)
    return load_scene(path, skeleton)


def walk(skeleton, k, x0=-1.0, speed=0.9, swing_legs=True):
    """
    Return the times and frames of a straight walk along +x.

    Times (k,) s and frames (k, 22) at RATE Hz: the pelvis along +x at ``speed`` m/s from ``x0``,
    root_z 0.92, the legs swinging (or straight), the upper body in its motion patterns.
    """
    times = np.arange(k) / RATE
    q = np.tile(skeleton.neutral(), (k, 1))
    q[:, skeleton.index['root_x']] = x0 + speed * times
    q[:, skeleton.index['root_z']] = 0.92
    if swing_legs:
        phase = 2 * np.pi * times / 1.2
        q[:, skeleton.index['left_hip_pitch']] = 0.3 * np.sin(phase)
        q[:, skeleton.index['right_hip_pitch']] = -0.3 * np.sin(phase)
    return times, motion_patterns(skeleton, q)


def timed_body(skeleton, environment, frames, padding=0.0):
    """Return the actor's body over ``frames`` in ``environment``, for CT-spaces."""
    return TimedBody(BodyKinematics(skeleton), BodyShapes(skeleton, padding),
                     EnvironmentIndex(environment.meshes, environment.objects), frames)
