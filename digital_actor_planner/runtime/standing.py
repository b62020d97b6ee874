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
The pose the node streams before its planning process is ready.

The planning process compiles the core's kernels when it starts from an empty cache (a minute
or more on a loaded machine). The node streams from its first second meanwhile: the neutral
standing configuration at the scene's start, on the lowest upward-facing surface under the
pelvis. Once the planner has placed the actor properly (feet on the ground under them, arms
in their pattern) the stream blends over to that configuration.
"""
from __future__ import annotations

import math
import os
from typing import Optional, Sequence, Tuple

import numpy as np
import yaml

#: Scenes larger than this (bytes of mesh files) are not read for the stand-in pose: the
#: stream must start at once, and the planner places the actor soon after anyway.
MAX_SCENE_BYTES = 5_000_000


def scene_start(scene_path: str) -> Tuple[float, float, float]:
    """
    Return the start pose ``(x m, y m, yaw rad)`` a scene file names ((0, 0, 0) if none).

    Raises
    ------
    ValueError
        The scene YAML cannot be read or its ``start`` is not three finite numbers.

    """
    if not scene_path.lower().endswith(('.yaml', '.yml')):
        return 0.0, 0.0, 0.0
    with open(scene_path) as stream:
        try:
            data = yaml.safe_load(stream)
        except yaml.YAMLError as error:
            raise ValueError(f'{scene_path}: {error}') from error
    start = data.get('start', (0.0, 0.0, 0.0)) if isinstance(data, dict) else None
    try:
        x, y, yaw = (float(v) for v in start)
    except (TypeError, ValueError):
        raise ValueError(f'{scene_path}: start must be [x, y, yaw], got {start!r}') from None
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise ValueError(f'{scene_path}: start not finite: {start!r}')
    return x, y, yaw


def _stl_triangles(path: str) -> np.ndarray:
    """(f, 3, 3) triangle corners of an STL file (binary or ASCII), m."""
    with open(path, 'rb') as stream:
        data = stream.read()
    if len(data) >= 84:
        count = int.from_bytes(data[80:84], 'little')
        if len(data) == 84 + 50 * count:
            records = np.frombuffer(data, dtype=np.dtype([('normal', '<f4', 3),
                                                          ('corners', '<f4', (3, 3)),
                                                          ('attribute', '<u2')]),
                                    count=count, offset=84)
            return records['corners'].astype(float)
    words = data.decode('ascii', errors='replace').split()
    values = [float(v) for i, word in enumerate(words) if word == 'vertex'
              for v in words[i + 1:i + 4]]
    return np.array(values, dtype=float).reshape(-1, 3, 3)


def _scene_meshes(scene_path: str) -> list:
    """
    Return the (f, 3, 3) triangle arrays of a scene's STL meshes, m; [] when too large.

    (f, 3, 3) triangle arrays (m, world frame) of a scene's STL meshes (the formats read here
    without a mesh library, whose import alone takes seconds); [] when too large.
    """
    if scene_path.lower().endswith(('.yaml', '.yml')):
        with open(scene_path) as stream:
            data = yaml.safe_load(stream)
        base = os.path.dirname(os.path.abspath(scene_path))
        entries = [(os.path.join(base, str(entry['file'])), entry.get('pose'))
                   for entry in data.get('meshes', ())]
    else:
        entries = [(scene_path, None)]
    entries = [(path, pose) for path, pose in entries if path.lower().endswith('.stl')]
    if sum(os.path.getsize(path) for path, _ in entries) > MAX_SCENE_BYTES:
        return []
    triangles = []
    for path, pose in entries:
        corners = _stl_triangles(path).reshape(-1, 3)
        if pose is not None:
            corners = corners @ _rotation(*(float(v) for v in pose[3:])).T + \
                np.array([float(v) for v in pose[:3]])
        triangles.append(corners.reshape(-1, 3, 3))
    return triangles


def _rotation(roll: float, pitch: float, yaw: float) -> np.ndarray:
    """
    Return the (3, 3) rotation of URDF fixed axes roll, pitch, yaw (rad).

    (3, 3) rotation of URDF fixed axes (roll about x, then pitch about y, then yaw about z), as the
    scene format defines a mesh's pose.
    """
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch),
                              math.sin(pitch), math.cos(yaw), math.sin(yaw))
    about_x = np.array([[1.0, 0.0, 0.0], [0.0, cr, -sr], [0.0, sr, cr]])
    about_y = np.array([[cp, 0.0, sp], [0.0, 1.0, 0.0], [-sp, 0.0, cp]])
    about_z = np.array([[cy, -sy, 0.0], [sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return about_z @ about_y @ about_x


def lowest_surface(triangles: Sequence[np.ndarray], x: float, y: float) -> Optional[float]:
    """
    Height (m) of the lowest upward-facing triangle over the point (x, y); None if none.

    Parameters
    ----------
    triangles
        (f, 3, 3) arrays of triangle corners, m.
    x, y
        The point, m.

    """
    lowest = None
    for corners in triangles:
        a, b, c = corners[:, 0], corners[:, 1], corners[:, 2]
        normal_z = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - \
            (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
        up = normal_z > 1e-12
        if not np.any(up):
            continue
        a, b, c, area = a[up], b[up], c[up], normal_z[up]
        # Barycentric coordinates of (x, y) in each triangle's projection on the ground.
        u = ((b[:, 0] - x) * (c[:, 1] - y) - (b[:, 1] - y) * (c[:, 0] - x)) / area
        v = ((c[:, 0] - x) * (a[:, 1] - y) - (c[:, 1] - y) * (a[:, 0] - x)) / area
        w = 1.0 - u - v
        inside = (u >= -1e-9) & (v >= -1e-9) & (w >= -1e-9)
        if np.any(inside):
            z = (u * a[:, 2] + v * b[:, 2] + w * c[:, 2])[inside]
            lowest = float(z.min()) if lowest is None else min(lowest, float(z.min()))
    return lowest


def stand_in_configuration(skeleton, scene_path: str,
                           start_pose: Optional[Tuple[float, float, float]]) -> np.ndarray:
    """
    Return the neutral standing configuration at the start, on the ground under the pelvis.

    Parameters
    ----------
    skeleton
        The actor model (:class:`digital_actor_planner.core.skeleton.Skeleton`).
    scene_path
        Scene YAML or mesh file.
    start_pose
        ``(x m, y m, yaw rad)``, or None for the scene's start.

    Returns
    -------
    numpy.ndarray
        (22,) float64, rad or m. On a scene that cannot be read here (the planner reports
        why), or one too large to read at once, the actor stands at height 0.

    """
    q = skeleton.neutral()
    try:
        x, y, yaw = start_pose if start_pose is not None else scene_start(scene_path)
        ground = lowest_surface(_scene_meshes(scene_path), x, y)
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        x = y = yaw = 0.0
        ground = None
    q[skeleton.index['root_x']], q[skeleton.index['root_y']] = x, y
    q[skeleton.index['root_yaw']] = yaw
    q[skeleton.index['root_z']] = (ground or 0.0) + skeleton.leg.standing_height + 0.002
    return q
