"""The environment: meshes in, an FCL BVH and walkable-ground queries out.

The paper (§3.2, §4.2) asks the lower-body planner for the ground profile under the predicted
path and for collision tests of the legs against obstacles. The environment is any set of
triangle meshes in the world frame (z up, metres); the ground is simply one of them. This module
loads them, keeps an FCL broad-phase manager for exact collision tests (used by
:mod:`collision`), and answers "where can a foot stand" with a layered height map built once at
construction, so that planners query it with vectorised NumPy lookups.
"""
from __future__ import annotations

from dataclasses import dataclass, field
import math
import os
from typing import Optional, Sequence, Tuple

import fcl
import numpy as np
import trimesh
import yaml

from .jit import float_array, kernel

SCENE_KEYS = ('meshes', 'start', 'description', 'expect')
MESH_KEYS = ('file', 'pose')
YAML_SUFFIXES = ('.yaml', '.yml')

# Free intervals thinner than this are numerical artefacts of coincident faces (a box resting
# exactly on the floor), not room to stand in, m.
_MIN_INTERVAL = 1e-3
# Surfaces this close in height at one grid node are the same surface hit twice (a node on an
# edge shared by two triangles), m.
_SAME_SURFACE = 1e-7
# Tolerance of "at or below z_ref", m.
_Z_TOLERANCE = 1e-6
# Candidate (node, triangle) pairs rasterised at once; bounds the memory of construction.
_RASTER_CHUNK = 2_000_000
# Dilations of the top map, cells (see Environment.top_height_near).
_TOP_RADII = (1, 2, 4, 8, 16, 32)


@kernel('Tuple((f8[::1], f8[::1]))(f8[:, :], f8[::1], f8, f8, f8, f8, f8, i8, f8[::1], '
        'f8[::1], i8)')
def _ground_heights(xy, z_ref, x0, y0, inverse, last_x, last_y, row_cells, ground, ceiling,
                    layers):
    """:meth:`Environment.ground_height` of each point in one pass (see there): the grid
    cell holding it (``row_cells`` cells a row, node indices up to ``last_x``, ``last_y``),
    the highest of its ``layers`` grounds at or below ``z_ref`` and the ceiling over that."""
    count = xy.shape[0]
    height = np.full(count, np.nan)
    clearance = np.full(count, np.nan)
    for n in range(count):
        z = z_ref[n]
        gx, gy = (xy[n, 0] - x0) * inverse, (xy[n, 1] - y0) * inverse
        # On the grid when clamping leaves the point where it is (NaN is not).
        if not (0.0 <= gx <= last_x and 0.0 <= gy <= last_y and abs(z) < np.inf):
            continue
        cell = int(min(gy, last_y - 1.0)) * row_cells + int(min(gx, last_x - 1.0))
        if layers == 1:
            index = cell
            if not ground[index] <= z + _Z_TOLERANCE:
                continue
        else:
            level = -1
            for layer in range(layers):
                if ground[cell * layers + layer] <= z + _Z_TOLERANCE:
                    level += 1
            if level < 0:
                continue
            index = cell * layers + level
        if z > ceiling[index]:
            continue
        height[n] = ground[index]
        clearance[n] = ceiling[index] - ground[index]
    return height, clearance


@kernel('f8(f8[::1], i8, i8, i8, f8, f8, f8, f8, f8, f8)')
def _top_near(pyramid, cells, nx, ny, x0, y0, inverse, x, y, half):
    """:meth:`Environment.top_height_near` of one square: the smallest dilation of the top map
    that covers ``half`` (m) read at the cell holding (x, y) (clamped onto the grid); +inf
    where no dilation is wide enough or the centre is NaN."""
    need = np.ceil(half * inverse + 1e-6)
    fx, fy = (x - x0) * inverse, (y - y0) * inverse
    if not need <= _TOP_RADII[-1] or fx != fx or fy != fy:
        return np.inf
    level = 0
    while _TOP_RADII[level] < need:
        level += 1
    column = min(max(np.floor(fx), 0.0), nx - 1)
    row = min(max(np.floor(fy), 0.0), ny - 1)
    return pyramid[level * cells + int(row) * nx + int(column)]


@kernel('f8[::1](f8[::1], i8, i8, i8, f8, f8, f8, f8[:, :], f8[::1])')
def _tops_near(pyramid, cells, nx, ny, x0, y0, inverse, xy, half):
    """:func:`_top_near` of each (N, 2) centre and (N,) half width."""
    out = np.empty(xy.shape[0])
    for i in range(xy.shape[0]):
        out[i] = _top_near(pyramid, cells, nx, ny, x0, y0, inverse, xy[i, 0], xy[i, 1],
                           half[i])
    return out


def _compact(grounds: np.ndarray, ceilings: np.ndarray):
    """Sort each row's intervals by ground (empty ones last) and drop all-empty columns."""
    order = np.argsort(grounds, axis=1, kind='stable')
    grounds = np.take_along_axis(grounds, order, axis=1)
    ceilings = np.take_along_axis(ceilings, order, axis=1)
    used = max(1, int(np.isfinite(grounds).sum(axis=1).max()) if len(grounds) else 1)
    return grounds[:, :used], ceilings[:, :used]


def _intersect(ground_a, ceiling_a, ground_b, ceiling_b):
    """Intersect two rows-of-disjoint-intervals sets: (M, Ka), (M, Kb) -> (M, K)."""
    shape = (len(ground_a), ground_a.shape[1] * ground_b.shape[1])
    ground = np.maximum(ground_a[:, :, None], ground_b[:, None, :]).reshape(shape)
    ceiling = np.minimum(ceiling_a[:, :, None], ceiling_b[:, None, :]).reshape(shape)
    empty = ~((ground < np.inf) & (ceiling >= ground))
    ground[empty] = np.inf
    ceiling[empty] = np.inf
    return _compact(ground, ceiling)


class SceneError(ValueError):
    """A scene file cannot be used: names the file and the field, line or value at fault."""


@dataclass(frozen=True)
class Scene:
    """A loaded scene: the environment, the actor's start pose and the file's annotations.

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


def _finite_numbers(value, count: int, what: str, source: str) -> Tuple[float, ...]:
    """Check that ``value`` is a list of ``count`` finite numbers, else raise SceneError."""
    ok = isinstance(value, (list, tuple)) and len(value) == count and all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        for v in value)
    if not ok:
        raise SceneError(f'{source}: {what} must be a list of {count} finite numbers, '
                         f'got {value!r}')
    return tuple(float(v) for v in value)


def load_mesh(path: str) -> trimesh.Trimesh:
    """Read one mesh file (STL, OBJ, PLY, GLB/GLTF, DAE) as world-frame triangles.

    Multi-geometry files (a GLB scene) are flattened with their node transforms.

    Raises
    ------
    SceneError
        Missing, unreadable, empty or non-mesh file; NaN/inf vertices; no triangles.

    """
    if not os.path.isfile(path):
        raise SceneError(f'{path}: no such mesh file')
    try:
        size = os.path.getsize(path)
        with open(path, 'rb'):
            pass
    except OSError as error:
        raise SceneError(f'{path}: cannot read mesh file: {error}') from error
    if size == 0:
        raise SceneError(f'{path}: empty file')
    try:
        loaded = trimesh.load(path, force='scene', process=False)
        geometry = [g for g in loaded.dump(concatenate=False)] if loaded.geometry else []
    except Exception as error:  # trimesh's loaders raise many exception types
        raise SceneError(f'{path}: not a readable mesh: {error}') from error
    meshes = [g for g in geometry if isinstance(g, trimesh.Trimesh)]
    if not meshes:
        raise SceneError(f'{path}: contains no triangle mesh')
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
    _check_mesh(mesh, path)
    return mesh


def _check_mesh(mesh, what: str) -> None:
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f'{what}: expected a trimesh.Trimesh, got {type(mesh).__name__}')
    if len(mesh.faces) == 0:
        raise SceneError(f'{what}: mesh has zero triangles')
    vertices = np.asarray(mesh.vertices, dtype=float)
    if not np.all(np.isfinite(vertices)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(vertices), axis=1))[0])
        raise SceneError(f'{what}: vertex {bad} is not finite: {vertices[bad].tolist()}')


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
    """Load a scene: a YAML file listing meshes and the start pose, or one bare mesh file.

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
            start = _finite_numbers(data['start'], 3, 'start', path)
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
            mesh = load_mesh(mesh_path)
            if 'pose' in entry:
                pose = _finite_numbers(entry['pose'], 6, f'meshes[{i}].pose', path)
                mesh = mesh.copy()
                mesh.apply_transform(_pose_matrix(pose))
            meshes.append(mesh)
            names.append(f'{i}:{os.path.basename(mesh_path)}')
            files.append(mesh_path)
    else:
        meshes, names, files = [load_mesh(path)], [os.path.basename(path)], [path]
    try:
        environment = Environment(meshes, names)
    except SceneError:
        raise
    except ValueError as error:
        raise SceneError(f'{path}: {error}') from error
    scene = Scene(environment=environment, start=start, source=path, mesh_files=tuple(files),
                  description=description, expect=expect)
    if skeleton is not None:
        try:
            check_start(environment, start, skeleton)
        except SceneError as error:
            raise SceneError(f'{path}: {error}') from error
    return scene


def start_configuration(environment: 'Environment', start, skeleton) -> np.ndarray:
    """Place the actor's neutral standing configuration at a start pose.

    The actor stands on the lowest walkable surface under its soles and pelvis, so a start in
    a wall, under a table or under a beam puts it at floor level (where it collides) rather
    than on top: ``root_z`` = that ground + ``skeleton.leg.standing_height`` + 2 mm.

    Parameters
    ----------
    environment
        The world.
    start
        (x m, y m, yaw rad).
    skeleton
        The actor model.

    Returns
    -------
    numpy.ndarray
        (22,) float64 configuration, rad or m.

    Raises
    ------
    SceneError
        ``start`` is not 3 finite numbers, or there is no ground below it.

    """
    x, y, yaw = _finite_numbers(list(start) if isinstance(start, (list, tuple, np.ndarray))
                                else start, 3, 'start', 'start pose')
    q = skeleton.neutral().copy()
    q[skeleton.index['root_x']], q[skeleton.index['root_y']] = x, y
    q[skeleton.index['root_yaw']] = yaw
    leg = skeleton.leg
    # Sole corners of both feet and the pelvis, in the pelvis frame (§4: feet under the hips).
    points = np.array([[0.0, 0.0]] + [[dx, side * leg.hip_half_width + dy]
                                      for side in (1.0, -1.0)
                                      for dx in (-leg.heel, leg.toe)
                                      for dy in (-leg.foot_width / 2, leg.foot_width / 2)])
    c, s = math.cos(yaw), math.sin(yaw)
    xy = points @ np.array([[c, s], [-s, c]]) + (x, y)
    ground = environment.lowest_ground(xy)
    if np.all(np.isnan(ground)):
        raise SceneError(f'no ground below the start pose ({x:g}, {y:g}, yaw {yaw:g})')
    q[skeleton.index['root_z']] = float(np.nanmin(ground)) + leg.standing_height + 0.002
    return q


def check_start(environment: 'Environment', start, skeleton) -> None:
    """Check the actor can stand at a start pose.

    Places the configuration an :class:`actor.Actor` starts in there (each foot resting on the
    ground under it where it can, else both level on the lowest ground under them, as
    :func:`start_configuration`) 2 mm up, so that a foot resting on a surface does not touch
    it, and tests it against the environment with :class:`collision.BodyCollision`.

    Raises
    ------
    SceneError
        No ground below the start, or the standing actor would be inside an obstacle.

    """
    from .actor import Actor, ActorConfig
    from .collision import BodyCollision

    body = BodyCollision(skeleton, environment)
    actor = Actor(skeleton, environment, ActorConfig(plan_upper_body=False), start=start,
                  body_collision=body)
    q = actor.configuration
    q[skeleton.index['root_z']] += 0.002
    links = body.links_in_collision(q)
    if links:
        x, y, yaw = (float(v) for v in start)
        raise SceneError(f'start pose ({x:g}, {y:g}, yaw {yaw:g}) is inside an obstacle: '
                         f'links {links} collide')


class Environment:
    """Triangle meshes in the world frame with an FCL BVH and a layered walkable-ground map.

    Parameters
    ----------
    meshes
        World-frame triangle meshes (z up, m). Closed meshes are solids; an open upward-facing
        surface (a height-field terrain) counts as solid below it.
    names
        One name per mesh (for messages); default ``mesh0``, ``mesh1``, ...
    resolution
        Grid spacing of the ground map, m.

    Attributes
    ----------
    meshes, names
        As given (tuples).
    bounds
        (2, 3) world axis-aligned bounds of all meshes, m.
    manager
        ``fcl.DynamicAABBTreeCollisionManager`` over one ``fcl.BVHModel`` per mesh.
    objects
        The FCL collision objects, in mesh order.

    Notes
    -----
    Queries: :meth:`ground_height` (highest walkable surface at or below a height, and the room
    above it) and :meth:`lowest_ground`; exact tests go through :class:`collision.BodyCollision`.
    Construction rasterises every triangle on a ``resolution`` grid (about 1 s for a 20 m x 6 m
    course at 2 cm); memory is two floats per grid cell and layer.

    """

    def __init__(self, meshes: Sequence[trimesh.Trimesh], names: Optional[Sequence[str]] = None,
                 resolution: float = 0.02):
        meshes = tuple(meshes)
        if not meshes:
            raise ValueError('environment needs at least one mesh, got none')
        if names is None:
            names = tuple(f'mesh{i}' for i in range(len(meshes)))
        names = tuple(str(n) for n in names)
        if len(names) != len(meshes):
            raise ValueError(f'{len(names)} names given for {len(meshes)} meshes')
        for i, (mesh, name) in enumerate(zip(meshes, names)):
            _check_mesh(mesh, f'mesh {i} ({name})')
        if not (isinstance(resolution, (int, float)) and math.isfinite(resolution)
                and resolution > 0):
            raise ValueError(f'resolution must be a positive number of metres, got {resolution!r}')
        self.meshes = meshes
        self.names = names
        self.resolution = float(resolution)
        self.bounds = np.array([np.min([m.bounds[0] for m in meshes], axis=0),
                                np.max([m.bounds[1] for m in meshes], axis=0)])
        self.objects = []
        self._models = []
        for mesh in meshes:
            model = fcl.BVHModel()
            vertices = np.asarray(mesh.vertices, dtype=float)
            faces = np.asarray(mesh.faces, dtype=np.int64)
            model.beginModel(len(vertices), len(faces))
            model.addSubModel(vertices, faces)
            model.endModel()
            self._models.append(model)
            self.objects.append(fcl.CollisionObject(model, fcl.Transform()))
        self.manager = fcl.DynamicAABBTreeCollisionManager()
        self.manager.registerObjects(self.objects)
        self.manager.setup()
        self._object_index = {id(m): i for i, m in enumerate(self._models)}
        self._vertices = [np.asarray(m.vertices, dtype=float) for m in meshes]
        self._faces = [np.asarray(m.faces, dtype=np.int64) for m in meshes]
        self._build_ground_map()
        self._tops = self._build_top_map()
        self._build_top_pyramid()

    def mesh_of(self, geometry) -> int:
        """Index of the mesh whose FCL geometry is ``geometry`` (from a contact), or -1."""
        return self._object_index.get(id(geometry), -1)

    def triangle(self, mesh_index: int, triangle_index: int) -> np.ndarray:
        """(3, 3) world vertices of one triangle of one mesh, m."""
        return self._vertices[mesh_index][self._faces[mesh_index][triangle_index]]

    # -- the layered ground map ----------------------------------------------------------
    def _build_ground_map(self) -> None:
        """Rasterise every triangle on the grid nodes: a vertical ray per node, all hits.

        Walking down each ray from the sky with a depth counter (+1 entering a solid at an
        upward face, -1 leaving at a downward face) gives the free intervals [ground, ceiling)
        a foot can stand in.
        """
        res = self.resolution
        lo, hi = self.bounds[0, :2], self.bounds[1, :2]
        counts = np.maximum(np.ceil((hi - lo) / res).astype(int) + 1, 2)
        self._origin = lo.copy()
        self._inverse_resolution = 1.0 / res
        self._shape = (int(counts[1]), int(counts[0]))  # (ny, nx)
        # The last node's x and y index (nx - 1, ny - 1), for _cells.
        self._grid_last = np.array([self._shape[1] - 1, self._shape[0] - 1], dtype=float)
        nx, ny = int(counts[0]), int(counts[1])
        parts = []
        for mesh, vertices, faces in zip(self.meshes, self._vertices, self._faces):
            # A closed mesh wound inside out (negative volume) would read as free space inside
            # and solid outside: flip its faces for the depth count.
            if mesh.is_watertight and mesh.volume < 0:
                faces = faces[:, ::-1]
            parts.append(vertices[faces])
        triangles = np.concatenate(parts)
        nodes, heights, signs = self._rasterise(triangles, nx, ny)

        order = np.lexsort((-heights, nodes))
        nodes, heights, signs = nodes[order], heights[order], signs[order]
        if len(nodes):
            repeat = np.zeros(len(nodes), dtype=bool)
            repeat[1:] = ((nodes[1:] == nodes[:-1]) & (signs[1:] == signs[:-1])
                          & (heights[:-1] - heights[1:] < _SAME_SURFACE))
            nodes, heights, signs = nodes[~repeat], heights[~repeat], signs[~repeat]
        unique, first, per_node = np.unique(nodes, return_index=True, return_counts=True)
        depth_max = int(per_node.max()) if len(per_node) else 1
        rank = np.arange(len(nodes)) - np.repeat(first, per_node)
        row = np.repeat(np.arange(len(unique)), per_node)
        hit_z = np.full((len(unique), depth_max), -np.inf)
        hit_sign = np.zeros((len(unique), depth_max), dtype=np.int8)
        hit_z[row, rank] = heights
        hit_sign[row, rank] = signs

        grounds = np.full((len(unique), depth_max), np.inf)
        ceilings = np.full((len(unique), depth_max), np.inf)
        depth = np.zeros(len(unique), dtype=np.int32)
        ceiling = np.full(len(unique), np.inf)
        for j in range(depth_max):
            z, s = hit_z[:, j], hit_sign[:, j]
            up, down = s > 0, s < 0
            starts = up & (depth == 0)
            grounds[starts, j] = z[starts]
            ceilings[starts, j] = ceiling[starts]
            depth += up
            depth = np.where(down, np.maximum(depth - 1, 0), depth)
            leaves = down & (depth == 0)
            ceiling[leaves] = z[leaves]
        with np.errstate(invalid='ignore'):
            thin = ~(ceilings - grounds >= _MIN_INTERVAL)
        grounds[thin] = np.inf
        ceilings[thin] = np.inf
        grounds, ceilings = _compact(grounds, ceilings)
        node_ground = np.full((nx * ny, grounds.shape[1]), np.inf)
        node_ceiling = np.full((nx * ny, grounds.shape[1]), np.inf)
        node_ground[unique] = grounds
        node_ceiling[unique] = ceilings
        node_ground = node_ground.reshape(ny, nx, -1)
        node_ceiling = node_ceiling.reshape(ny, nx, -1)
        # Conservative over each cell: a height z is free in the cell when it is free at all four
        # corners, so the cell's free intervals are the intersection of the corners' intervals.
        # Most cells have four identical corners (open floor): only intersect the others.
        layers = node_ground.shape[-1]
        corners = [(slice(None, -1), slice(None, -1)), (slice(None, -1), slice(1, None)),
                   (slice(1, None), slice(None, -1)), (slice(1, None), slice(1, None))]
        grounds = [node_ground[c].reshape(-1, layers) for c in corners]
        ceilings = [node_ceiling[c].reshape(-1, layers) for c in corners]
        uniform = np.ones(len(grounds[0]), dtype=bool)
        for g, c in zip(grounds[1:], ceilings[1:]):
            uniform &= np.all((g == grounds[0]) & (c == ceilings[0]), axis=1)
        mixed = np.flatnonzero(~uniform)
        cell_ground, cell_ceiling = grounds[0][mixed], ceilings[0][mixed]
        for g, c in zip(grounds[1:], ceilings[1:]):
            cell_ground, cell_ceiling = _intersect(cell_ground, cell_ceiling, g[mixed], c[mixed])
        width = max(1, int(np.isfinite(grounds[0][uniform]).sum(axis=1).max(initial=0)),
                    cell_ground.shape[1])
        all_ground = np.full((len(uniform), width), np.inf)
        all_ceiling = np.full((len(uniform), width), np.inf)
        all_ground[uniform, :layers] = grounds[0][uniform][:, :width]
        all_ceiling[uniform, :layers] = ceilings[0][uniform][:, :width]
        all_ground[mixed, :cell_ground.shape[1]] = cell_ground
        all_ceiling[mixed, :cell_ground.shape[1]] = cell_ceiling
        cell_ground, cell_ceiling = all_ground, all_ceiling
        self._layers = cell_ground.shape[-1]
        self._ground = np.ascontiguousarray(cell_ground.reshape(-1, self._layers))
        self._ceiling = np.ascontiguousarray(cell_ceiling.reshape(-1, self._layers))
        self._ground_flat = self._ground.ravel()
        self._ceiling_flat = self._ceiling.ravel()

    def _rasterise(self, triangles: np.ndarray, nx: int, ny: int):
        """Heights and facing of every non-vertical triangle at the grid nodes it covers.

        Returns (node index, height m, +1 upward / -1 downward facing) of each hit.
        """
        res, (x0, y0) = self.resolution, self._origin
        edge1 = triangles[:, 1] - triangles[:, 0]
        edge2 = triangles[:, 2] - triangles[:, 0]
        normal = np.cross(edge1, edge2)
        norm = np.linalg.norm(normal, axis=1)
        steep = np.abs(normal[:, 2]) <= 1e-9 * np.maximum(norm, 1e-300)
        triangles = triangles[~steep]
        normal_z = normal[~steep, 2]
        low = triangles[:, :, :2].min(axis=1)
        high = triangles[:, :, :2].max(axis=1)
        ix0 = np.clip(np.ceil((low[:, 0] - x0) / res - 1e-9), 0, nx - 1).astype(np.int64)
        ix1 = np.clip(np.floor((high[:, 0] - x0) / res + 1e-9), -1, nx - 1).astype(np.int64)
        iy0 = np.clip(np.ceil((low[:, 1] - y0) / res - 1e-9), 0, ny - 1).astype(np.int64)
        iy1 = np.clip(np.floor((high[:, 1] - y0) / res + 1e-9), -1, ny - 1).astype(np.int64)
        rows = np.maximum(iy1 - iy0 + 1, 0) * (ix1 >= ix0)
        # Barycentric weights and height are affine in the node indices relative to each
        # triangle's first covered node: w = a * i + b * j + c. Precompute a, b, c per triangle.
        det = normal_z
        ox = x0 + ix0 * res - triangles[:, 0, 0]
        oy = y0 + iy0 * res - triangles[:, 0, 1]
        e1x, e1y = edge1[~steep, 0], edge1[~steep, 1]
        e2x, e2y = edge2[~steep, 0], edge2[~steep, 1]
        dz1, dz2 = edge1[~steep, 2], edge2[~steep, 2]
        coefficients = np.empty((len(triangles), 9))
        coefficients[:, 0] = res * e2y / det
        coefficients[:, 1] = -res * e2x / det
        coefficients[:, 2] = (ox * e2y - e2x * oy) / det
        coefficients[:, 3] = -res * e1y / det
        coefficients[:, 4] = res * e1x / det
        coefficients[:, 5] = (e1x * oy - ox * e1y) / det
        coefficients[:, 6:9] = (coefficients[:, 0:3] * dz1[:, None]
                                + coefficients[:, 3:6] * dz2[:, None])
        coefficients[:, 8] += triangles[:, 0, 2]
        first_node = iy0 * nx + ix0
        sign = np.where(det > 0, 1, -1).astype(np.int8)
        # Scan line by grid row: each (triangle, row) pair covers the nodes between the
        # triangle's edges on that row, so slivers cost their area, not their bounding box.
        estimate = np.abs(det) / 2 / res ** 2 + 2 * rows
        out_nodes, out_z, out_sign = [], [], []
        cumulative = np.cumsum(estimate)
        start = 0
        eps = 1e-9
        while start < len(triangles):
            limit = (cumulative[start - 1] if start else 0.0) + _RASTER_CHUNK
            stop = max(start + 1, int(np.searchsorted(cumulative, limit, side='right')))
            sel = np.arange(start, stop)
            start = stop
            n = rows[sel]
            pairs = int(n.sum())
            if pairs == 0:
                continue
            tri = np.repeat(sel, n)
            j = np.arange(pairs) - np.repeat(np.cumsum(n) - n, n)
            y = y0 + (iy0[tri] + j) * res
            t = triangles[tri]
            left = np.full(pairs, np.inf)
            right = np.full(pairs, -np.inf)
            for a_, b_ in ((0, 1), (1, 2), (2, 0)):
                ya, yb = t[:, a_, 1], t[:, b_, 1]
                xa, xb = t[:, a_, 0], t[:, b_, 0]
                span = yb - ya
                with np.errstate(divide='ignore', invalid='ignore'):
                    u = (y - ya) / span
                crosses = (span != 0) & (u >= -1e-9) & (u <= 1 + 1e-9)
                x = np.where(crosses, xa + np.clip(u, 0.0, 1.0) * (xb - xa), np.nan)
                left = np.fmin(left, x)
                right = np.fmax(right, x)
            first = np.maximum(np.ceil((left - x0) / res - 1e-7), ix0[tri])
            last = np.minimum(np.floor((right - x0) / res + 1e-7), ix1[tri])
            ok = np.isfinite(first) & np.isfinite(last) & (last >= first)
            tri, j = tri[ok], j[ok]
            first = first[ok].astype(np.int64) - ix0[tri]
            width = last[ok].astype(np.int64) - ix0[tri] - first + 1
            total = int(width.sum())
            if total == 0:
                continue
            owner = np.repeat(np.arange(len(tri)), width)
            i = first[owner] + np.arange(total) - np.repeat(np.cumsum(width) - width, width)
            tri, j = tri[owner], j[owner]
            c = coefficients[tri]
            w1 = c[:, 0] * i + c[:, 1] * j + c[:, 2]
            w2 = c[:, 3] * i + c[:, 4] * j + c[:, 5]
            inside = (w1 >= -eps) & (w2 >= -eps) & (w1 + w2 <= 1 + eps)
            z = c[:, 6] * i + c[:, 7] * j + c[:, 8]
            out_nodes.append((first_node[tri] + j * nx + i)[inside])
            out_z.append(z[inside])
            out_sign.append(sign[tri[inside]])
        if not out_nodes:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int8)
        return np.concatenate(out_nodes), np.concatenate(out_z), np.concatenate(out_sign)

    def _build_top_map(self) -> np.ndarray:
        """Upper bound of every triangle's height over each ground-map cell, (ny - 1, nx - 1) m.

        A cell gets, from each triangle whose xy bounding box touches it, the lower of the
        triangle's highest vertex and the highest point of the triangle's plane over the cell
        (a plane's maximum over a rectangle is at a corner). Every point of every mesh, and of
        the solid below a surface, therefore lies at or below its cell's value; -inf where no
        triangle reaches.
        """
        res, (x0, y0) = self.resolution, self._origin
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
        tops = np.full(nx * ny, -np.inf)
        triangles = np.concatenate([v[f] for v, f in zip(self._vertices, self._faces)])
        low = triangles[:, :, :2].min(axis=1)
        high = triangles[:, :, :2].max(axis=1)
        z_max = triangles[:, :, 2].max(axis=1)
        normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
        # Gradient of the triangle's plane; steep (near-vertical) ones only bound by z_max.
        tilted = np.abs(normal[:, 2]) > 1e-6 * np.linalg.norm(normal, axis=1)
        with np.errstate(divide='ignore', invalid='ignore'):
            slope_x = np.where(tilted, -normal[:, 0] / normal[:, 2], 0.0)
            slope_y = np.where(tilted, -normal[:, 1] / normal[:, 2], 0.0)
        ix0 = np.clip(np.floor((low[:, 0] - x0) / res - 1e-9), 0, nx - 1).astype(np.int64)
        ix1 = np.clip(np.floor((high[:, 0] - x0) / res + 1e-9), 0, nx - 1).astype(np.int64)
        iy0 = np.clip(np.floor((low[:, 1] - y0) / res - 1e-9), 0, ny - 1).astype(np.int64)
        iy1 = np.clip(np.floor((high[:, 1] - y0) / res + 1e-9), 0, ny - 1).astype(np.int64)
        columns, rows = ix1 - ix0 + 1, iy1 - iy0 + 1
        # Relative to each triangle's first cell: the plane's maximum over cell (i, j) is
        # base + step_x * i + step_y * j (a little above it for the rounding of the sums).
        base = (triangles[:, 0, 2] + slope_x * (x0 + ix0 * res - triangles[:, 0, 0])
                + slope_y * (y0 + iy0 * res - triangles[:, 0, 1])
                + res * (np.maximum(slope_x, 0.0) + np.maximum(slope_y, 0.0)) + 1e-6)
        step_x, step_y = slope_x * res, slope_y * res
        base = np.where(tilted, base, z_max)
        step_x = np.where(tilted, step_x, 0.0)
        step_y = np.where(tilted, step_y, 0.0)
        tops2d = tops.reshape(ny, nx)
        # Large triangles (a floor, a wall) one by one as blocks of cells; small ones (rough
        # terrain) all together, one (triangle, cell) pair each.
        large = columns * rows > 64
        for t in np.flatnonzero(large):
            block = np.minimum(base[t] + step_y[t] * np.arange(rows[t])[:, None]
                               + step_x[t] * np.arange(columns[t]), z_max[t])
            view = tops2d[iy0[t]:iy1[t] + 1, ix0[t]:ix1[t] + 1]
            np.maximum(view, block, out=view)
        sel = np.flatnonzero(~large)
        if len(sel):
            count = columns[sel] * rows[sel]
            tri = np.repeat(sel, count)
            k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
            di, dj = k % columns[tri], k // columns[tri]
            value = np.minimum(base[tri] + step_x[tri] * di + step_y[tri] * dj, z_max[tri])
            np.maximum.at(tops, (iy0[tri] + dj) * nx + ix0[tri] + di, value)
        return tops.reshape(ny, nx)

    def _build_top_pyramid(self) -> None:
        """The top map dilated by 1, 2, 4, ... cells (each cell: the largest value within that
        many cells in x and y), for :meth:`top_height_near`."""
        levels, previous = [], self._tops
        ny, nx = self._tops.shape
        for radius in _TOP_RADII:
            # Dilating by r twice dilates by 2 r: the max of the last level shifted by -r, 0, r.
            shift = max(radius // 2, 1)
            grown = previous.copy()
            if shift < nx:
                np.maximum(grown[:, shift:], previous[:, :-shift], out=grown[:, shift:])
                np.maximum(grown[:, :-shift], previous[:, shift:], out=grown[:, :-shift])
            else:
                grown[:] = np.max(previous, axis=1, keepdims=True)
            previous = grown.copy()
            if shift < ny:
                np.maximum(previous[shift:], grown[:-shift], out=previous[shift:])
                np.maximum(previous[:-shift], grown[shift:], out=previous[:-shift])
            else:
                previous[:] = np.max(grown, axis=0, keepdims=True)
            levels.append(previous)
        self._top_pyramid = np.stack(levels).ravel()
        self._top_cells = nx * ny

    def top_height_near(self, xy, half_extent) -> np.ndarray:
        """A cheap, looser :meth:`top_height`: a bound over squares around points.

        One lookup per point in a precomputed dilation of the top map, so it bounds at least the
        rectangle of ``half_extent`` around each point (at most twice as wide, rounded to
        cells), and is still conservative.

        Parameters
        ----------
        xy
            (N, 2) centres, m.
        half_extent
            (N,) half width of the squares, m (at most ``resolution`` x 2**5).

        Returns
        -------
        numpy.ndarray
            (N,) m, never below :meth:`top_height` of the rectangle; +inf for a square wider
            than the largest dilation or a NaN centre.

        """
        xy = float_array(xy)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f'xy must have shape (N, 2), got {xy.shape}')
        half = np.empty(xy.shape[:1])
        half[...] = float_array(half_extent)  # broadcast by assignment (np.broadcast_to's rules)
        return _tops_near(self._top_pyramid, *self.top_near_grid(), xy, half)

    def top_near_grid(self) -> tuple:
        """The top map's pyramid layout for the compiled :func:`_top_near`: cells per level,
        columns, rows, grid origin x and y (m), inverse resolution (1/m)."""
        ny, nx = self._tops.shape
        return (int(self._top_cells), int(nx), int(ny), float(self._origin[0]),
                float(self._origin[1]), float(self._inverse_resolution))

    def top_height(self, low_xy, high_xy) -> np.ndarray:
        """Upper bound of the environment's height over axis-aligned rectangles.

        Conservative: no point of any mesh (or of the solid under a surface) within a rectangle
        lies higher, so a body whose lowest point is above the bound cannot touch the
        environment. It is exact over horizontal faces and never below the truth elsewhere
        (over a sloped face it is the face's highest point in the ``resolution`` cells the
        rectangle touches; under an overhang it is the overhang's top).

        Parameters
        ----------
        low_xy, high_xy
            (N, 2) lower and upper xy corners of the rectangles, m.

        Returns
        -------
        numpy.ndarray
            (N,) m; -inf where no mesh reaches into the rectangle.

        """
        low_xy = np.asarray(low_xy, dtype=float)
        high_xy = np.asarray(high_xy, dtype=float)
        if low_xy.ndim != 2 or low_xy.shape[1] != 2 or high_xy.shape != low_xy.shape:
            raise ValueError(f'low_xy and high_xy must have the same shape (N, 2), got '
                             f'{low_xy.shape} and {high_xy.shape}')
        tops = self._tops
        ny, nx = tops.shape
        res, origin = self.resolution, self._origin
        if not len(low_xy):
            return np.zeros(0)
        first = np.floor((low_xy - origin) / res - 1e-9)
        last = np.floor((high_xy - origin) / res + 1e-9)
        # NaN or off-grid extents: clamp (off the grid there is no mesh), NaN reads everything.
        bad = ~np.all(np.isfinite(first) & np.isfinite(last), axis=1)
        limit = np.array([nx - 1, ny - 1])
        # Wholly off the grid: no mesh there.
        off = ~bad & np.any((last < 0) | (first > limit), axis=1)
        first = np.where(bad[:, None], 0, np.clip(first, 0, limit)).astype(np.int64)
        last = np.where(bad[:, None], limit, np.clip(last, 0, limit)).astype(np.int64)
        size = last - first + 1
        out = np.full(len(low_xy), -np.inf)
        # Every rectangle read over a window of the largest size, the cells past its own
        # size masked; the rare large ones (NaN, far off) one by one.
        small = np.all(size <= 32, axis=1)
        if np.any(small):
            width, height = np.max(size[small], axis=0)
            di, dj = np.meshgrid(np.arange(width), np.arange(height), indexing='xy')
            di, dj = di.ravel(), dj.ravel()
            f, s = first[small], size[small]
            i = f[:, 0, None] + di
            j = f[:, 1, None] + dj
            inside = (di < s[:, 0, None]) & (dj < s[:, 1, None])
            values = tops[np.minimum(j, ny - 1), np.minimum(i, nx - 1)]
            out[small] = np.max(np.where(inside, values, -np.inf), axis=1)
        for index in np.flatnonzero(~small):
            (i0, j0), (i1, j1) = first[index], last[index]
            out[index] = np.max(tops[j0:j1 + 1, i0:i1 + 1])
        out[off] = -np.inf
        return out

    def _cells(self, xy):
        """Grid cell index of each (N, 2) point, and whether it lies on the grid."""
        xy = np.asarray(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f'xy must have shape (N, 2), got {xy.shape}')
        # x and y together (half the calls): a point is on the grid when clamping it to the
        # grid's extent leaves it where it is (NaN clamps to 0, so it is not).
        grid = (xy - self._origin) * self._inverse_resolution
        clamped = np.fmin(np.fmax(grid, 0.0), self._grid_last)
        inside = clamped == grid
        valid = inside[:, 0] & inside[:, 1]
        # Off the grid (or NaN) the index is clamped into range; those points are not valid.
        index = np.minimum(clamped, self._grid_last - 1.0).astype(np.int64)
        cell = index[:, 1] * (self._shape[1] - 1) + index[:, 0]
        return cell, valid

    def lowest_ground(self, xy) -> np.ndarray:
        """Height of the lowest walkable surface at each point (conservative over its cell).

        Parameters
        ----------
        xy
            (N, 2) horizontal points, m.

        Returns
        -------
        numpy.ndarray
            (N,) m; NaN where there is none.

        """
        cell, valid = self._cells(xy)
        ground = self._ground[cell, 0].copy()
        ground[~valid | ~np.isfinite(ground)] = np.nan
        return ground

    def ground_height(self, xy, z_ref) -> Tuple[np.ndarray, np.ndarray]:
        """Height of the highest walkable surface at or below ``z_ref``, and the room above it.

        A walkable surface is an upward-facing surface with free space above it (§4.2: the
        ground profile under the feet). The answer is conservative over the grid cell that holds
        each point: the highest of the four corner grounds and the lowest of their ceilings.

        Error bound: on horizontal tops the height is exact (float precision), and within one
        ``resolution`` outside a top's edge it may report the top (a foot placed there never
        sinks into the mesh or clips a step edge at a grid node). On sloped faces it
        overestimates by at most slope x ``resolution`` x sqrt(2); features narrower than
        ``resolution`` (spikes, thin ridges between nodes) can be missed. Use
        :class:`collision.BodyCollision` for exact tests.

        Parameters
        ----------
        xy
            (N, 2) horizontal query points, m.
        z_ref
            Scalar or (N,) reference heights, m (e.g. a foot's height plus the largest step up).

        Returns
        -------
        height : numpy.ndarray
            (N,) ground height, m; NaN where there is no walkable surface at or below ``z_ref``
            (off the meshes), or where ``z_ref`` is inside a solid (a wall, a table top), at any
            corner of the cell.
        clearance : numpy.ndarray
            (N,) free height above the ground up to the next surface above it, m; inf if open
            to the sky; NaN where height is NaN.

        """
        xy = np.asarray(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f'xy must have shape (N, 2), got {xy.shape}')
        z = np.asarray(z_ref, dtype=float)
        if z.ndim == 0:
            value = float(z)
            z = np.empty(len(xy))
            z.fill(value)
        elif z.shape != (len(xy),):
            raise ValueError(f'z_ref must be a scalar or shape ({len(xy)},), got {z.shape}')
        return _ground_heights(float_array(xy), float_array(z), float(self._origin[0]),
                               float(self._origin[1]), float(self._inverse_resolution),
                               float(self._grid_last[0]), float(self._grid_last[1]),
                               int(self._shape[1] - 1), self._ground_flat, self._ceiling_flat,
                               int(self._layers))
