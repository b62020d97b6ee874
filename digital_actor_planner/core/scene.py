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
Scene files in, the start pose settled and checked with the actor.

Scene files in (a YAML list of meshes or one bare mesh file), the start pose settled and checked
with the actor.

The top floor of the core: it reads the files with :mod:`environment` and stands the actor of
:mod:`actor` at the start to check it, so neither of those needs to know about scene files.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import os
from typing import Optional, Sequence, Tuple

import numpy as np
import yaml

from .actor import Actor, ActorConfig
from .collision import BodyCollision
from .environment import Environment, finite_numbers, load_mesh, SceneError

__all__ = ['check_start', 'load_scene', 'Scene', 'SceneError']

SCENE_KEYS = ('meshes', 'start', 'description', 'expect')
MESH_KEYS = ('file', 'pose')
YAML_SUFFIXES = ('.yaml', '.yml')


@dataclass(frozen=True)
class Scene:
    """
    A loaded scene: the environment, the actor's start pose and the file's annotations.

    ``start`` is (x m, y m, yaw rad); ``source`` the scene file; ``mesh_files`` the mesh files
    read; ``expect`` the optional ``expect:`` mapping of the YAML (used by tests).
    """

    environment: 'Environment'
    start: Tuple[float, float, float]
    source: str
    mesh_files: Tuple[str, ...]
    description: str = ''
    expect: dict = field(default_factory=dict)


def _pose_matrix(pose: Sequence[float]) -> np.ndarray:
    """(4, 4) transform of [x, y, z, roll, pitch, yaw] (URDF fixed-axis convention)."""
    x, y, z, roll, pitch, yaw = pose
    cr, sr, cp, sp, cy, sy = (math.cos(roll), math.sin(roll), math.cos(pitch), math.sin(pitch),
                              math.cos(yaw), math.sin(yaw))
    transform = np.eye(4)
    transform[:3, :3] = [[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                         [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                         [-sp, cp * sr, cp * cr]]
    transform[:3, 3] = (x, y, z)
    return transform


def _read_yaml(path: str) -> dict:
    try:
        with open(path, 'r', encoding='utf-8') as stream:
            text = stream.read()
    except (OSError, UnicodeDecodeError) as error:
        raise SceneError(f'{path}: cannot read scene file: {error}') from error
    if not text.strip():
        raise SceneError(f'{path}: empty file')
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, 'problem_mark', None)
        where = f' line {mark.line + 1}, column {mark.column + 1}' if mark else ''
        problem = getattr(error, 'problem', None) or str(error)
        raise SceneError(f'{path}:{where} YAML syntax error: {problem}') from error
    if not isinstance(data, dict):
        raise SceneError(f'{path}: top level must be a mapping with a meshes: list, '
                         f'got {type(data).__name__}')
    unknown = sorted(set(map(str, data)) - set(SCENE_KEYS))
    if unknown:
        raise SceneError(f'{path}: unknown key(s) {unknown}; allowed: {list(SCENE_KEYS)}')
    return data


def load_scene(path: str, skeleton=None) -> Scene:
    """
    Load a scene: a YAML file listing meshes and the start pose, or one bare mesh file.

    YAML form::

        meshes:
          - {file: ground.stl}                          # relative to the YAML file
          - {file: box.obj, pose: [x, y, z, roll, pitch, yaw]}   # m, rad; optional
        start: [x, y, yaw]                              # optional, default [0, 0, 0]
        description: free text                          # optional
        expect: {...}                                   # optional, for tests

    Parameters
    ----------
    path
        Scene YAML (``.yaml``/``.yml``) or a mesh file (start at the origin).
    skeleton
        If given, :func:`check_start` verifies the actor can stand at the start.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        Naming the file and the field, line or value at fault.

    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise SceneError(f'{path}: no such scene file')
    if os.path.isdir(path):
        raise SceneError(f'{path}: is a directory, not a scene file')
    description, expect = '', {}
    start = (0.0, 0.0, 0.0)
    if path.lower().endswith(YAML_SUFFIXES):
        data = _read_yaml(path)
        entries = data.get('meshes')
        if not isinstance(entries, list) or not entries:
            raise SceneError(f'{path}: meshes must be a non-empty list, got {entries!r}')
        if 'start' in data:
            start = finite_numbers(data['start'], 3, 'start', path)
        if 'description' in data:
            if not isinstance(data['description'], str):
                raise SceneError(f'{path}: description must be a string, '
                                 f'got {data["description"]!r}')
            description = data['description']
        if 'expect' in data:
            if not isinstance(data['expect'], dict):
                raise SceneError(f'{path}: expect must be a mapping, got {data["expect"]!r}')
            expect = data['expect']
        base = os.path.dirname(os.path.abspath(path))
        meshes, names, files = [], [], []
        # One read of a file placed many times (a row of shelves).
        read = {}
        for i, entry in enumerate(entries):
            where = f'{path}: meshes[{i}]'
            if not isinstance(entry, dict):
                raise SceneError(f'{where} must be a mapping with file: (and pose:), '
                                 f'got {entry!r}')
            unknown = sorted(set(map(str, entry)) - set(MESH_KEYS))
            if unknown:
                raise SceneError(f'{where}: unknown key(s) {unknown}; allowed: {list(MESH_KEYS)}')
            if not isinstance(entry.get('file'), str) or not entry['file']:
                raise SceneError(f'{where}.file must be a file name, got {entry.get("file")!r}')
            mesh_path = os.path.normpath(os.path.join(base, entry['file']))
            if mesh_path not in read:
                read[mesh_path] = load_mesh(mesh_path)
            mesh = read[mesh_path]
            if 'pose' in entry:
                pose = finite_numbers(entry['pose'], 6, f'meshes[{i}].pose', path)
                mesh = mesh.copy()
                mesh.apply_transform(_pose_matrix(pose))
            meshes.append(mesh)
            names.append(f'{i}:{os.path.basename(mesh_path)}')
            files.append(mesh_path)
    else:
        meshes, names, files = [load_mesh(path)], [os.path.basename(path)], [path]
    try:
        environment = Environment(meshes, names)
    except ValueError as error:  # SceneError too: a message about the whole scene
        raise SceneError(f'{path}: {error}') from error
    except MemoryError as error:
        raise SceneError(f'{path}: the machine ran out of memory building its ground map '
                         f'and collision models') from error
    scene = Scene(environment=environment, start=start, source=path, mesh_files=tuple(files),
                  description=description, expect=expect)
    if skeleton is not None:
        try:
            check_start(environment, start, skeleton)
        except SceneError as error:
            raise SceneError(f'{path}: {error}') from error
    return scene


def check_start(environment: Environment, start, skeleton) -> None:
    """
    Check the actor can stand at a start pose.

    Places the configuration an :class:`actor.Actor` starts in there (each foot resting on the
    ground under it, at its own height and pitch, where it can; else both level on the lowest
    ground under them, as :func:`actor.start_configuration`) 2 mm up, so that a foot resting on a
    surface does not touch it, and tests it against the environment with
    :class:`collision.BodyCollision`. Where it cannot stand, the message says why and names
    the nearest start, within ``_SEARCH_RADII[-1]`` m and at the same heading, where it can.

    Raises
    ------
    SceneError
        No ground below the start, the ground under a foot too uneven or steep to rest on, or
        the standing actor inside an obstacle.

    """
    x, y, yaw = finite_numbers(list(start) if isinstance(start, (list, tuple, np.ndarray))
                               else start, 3, 'start', 'start pose')
    body = BodyCollision(skeleton, environment)
    problem = _start_problem(environment, (x, y, yaw), skeleton, body)
    if problem is None:
        return
    hint = _nearest_standable(environment, (x, y, yaw), skeleton, body)
    raise SceneError(f'start pose ({x:g}, {y:g}, yaw {yaw:g}) {problem}; {hint}')


# Rings searched for a standable start near one that is not, m, and starts tried per ring
# at the smallest radius (more on the wider rings, about one every 0.3 m of circumference).
_SEARCH_RADII = (0.25, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0)
_SEARCH_SPACING = 0.3
_LEG_LINKS = {f'{side}_{part}' for side in ('left', 'right')
              for part in ('thigh', 'shank', 'foot')}


def _start_problem(environment: Environment, start: Tuple[float, float, float], skeleton,
                   body: BodyCollision) -> Optional[str]:
    """
    Return why the actor cannot stand at ``start``, or None where it can.

    Why the actor cannot stand at ``start`` (a phrase after "start pose (x, y, yaw)"), or None
    where it can.
    """
    x, y, yaw = start
    try:
        actor = Actor(skeleton, environment, ActorConfig(plan_upper_body=False), start=start,
                      body_collision=body)
    except SceneError:
        return 'has no ground below it'
    q = actor.configuration
    q[skeleton.index['root_z']] += 0.002
    links = body.links_in_collision(q)
    if not links:
        return None
    uneven = _uneven_feet(environment, start, skeleton)
    # Feet that cannot rest are put level at the lowest ground: on a bank the uphill leg
    # is then in the ground.
    if uneven and set(links) <= _LEG_LINKS:
        return f'is not standable: {uneven}'
    return f'is inside an obstacle: links {links} collide'


def _uneven_feet(environment: Environment, start: Tuple[float, float, float],
                 skeleton) -> str:
    """
    Return what makes the ground under a foot at ``start`` unfit for a sole, or ''.

    What makes the ground under a foot at ``start`` unfit to rest a sole on (too uneven across the
    sole, or too steep along it, by the footstep planner's limits), or ''.
    """
    x, y, yaw = start
    leg = skeleton.leg
    limits = ActorConfig().footsteps
    c, s = math.cos(yaw), math.sin(yaw)
    lengths = np.array([-leg.heel, 0.5 * (leg.toe - leg.heel), leg.toe])
    for name, side in (('left', 1.0), ('right', -1.0)):
        across = np.array([-0.5, 0.0, 0.5]) * leg.foot_width + side * leg.hip_half_width
        local = np.stack(np.broadcast_arrays(lengths[:, None], across[None, :]), axis=-1)
        xy = local @ np.array([[c, s], [-s, c]]) + (x, y)
        ground = environment.lowest_ground(xy.reshape(-1, 2)).reshape(3, 3)
        if np.isnan(ground).any():
            return f'the {name} foot is partly over no ground'
        rise = float((ground.max(axis=1) - ground.min(axis=1)).max())
        if rise > limits.flatness_tolerance:
            return (f'the ground under the {name} foot rises {rise * 100:.1f} cm across the '
                    f'sole (a sole rests on ground level across within '
                    f'{limits.flatness_tolerance * 100:.1f} cm)')
        top = ground.max(axis=1)
        centred = lengths - lengths.mean()
        pitch = abs(math.atan(float(centred @ top / (centred @ centred))))
        if pitch > limits.max_foot_pitch:
            return (f'the ground under the {name} foot slopes {math.degrees(pitch):.0f} '
                    f'degrees along the sole (a sole rests on at most '
                    f'{math.degrees(limits.max_foot_pitch):.0f} degrees)')
    return ''


def _nearest_standable(environment: Environment, start: Tuple[float, float, float], skeleton,
                       body: BodyCollision) -> str:
    """
    Name the nearest start around ``start`` where the actor can stand, or say there is none.

    "the nearest standable start is [x, y, yaw]" for the nearest start on rings around ``start``
    (same heading) where the actor can stand, or that there is none near.
    """
    x, y, yaw = start
    for radius in _SEARCH_RADII:
        count = max(8, int(math.ceil(2 * math.pi * radius / _SEARCH_SPACING)))
        for angle in np.arange(count) * (2 * math.pi / count):
            candidate = (x + radius * math.cos(angle), y + radius * math.sin(angle), yaw)
            ground = environment.lowest_ground(np.array([candidate[:2]]))
            if np.isnan(ground[0]):
                continue
            if _start_problem(environment, candidate, skeleton, body) is None:
                return (f'the nearest standable start is [{candidate[0]:.2f}, '
                        f'{candidate[1]:.2f}, {yaw:g}]')
    return f'no standable start within {_SEARCH_RADII[-1]:g} m at this heading'
