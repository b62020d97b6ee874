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
The environment: meshes in, an FCL BVH and walkable-ground queries out.

The paper (§3.2, §4.2) asks the lower-body planner for the ground profile under the predicted
path and for collision tests of the legs against obstacles. The environment is any set of
triangle meshes in the world frame (z up, metres); the ground is simply one of them. This module
reads mesh files, keeps an FCL broad-phase manager for exact collision tests (used by
:mod:`collision`), and answers "where can a foot stand" with a layered height map on one
lattice over the scene, built in tiles where the queries read it and kept in a bounded cache,
so that memory follows the geometry the actor walks on and not the scene's area.
"""
from __future__ import annotations

from dataclasses import dataclass
import math
import os
from typing import Optional, Sequence, Tuple

import fcl
import numpy as np
import trimesh

from .jit import float_array, kernel

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
# Cells along a side of one tile of the ground map (2.56 m at 2 cm): large enough that a
# tile's halo (the largest dilation, each side) costs about its own area again, small enough
# that the tiles under a few steps of the actor's window are few.
_TILE = 128
# The top map and its dilations, per tile.
_TOP_LEVELS = 1 + len(_TOP_RADII)
_PYRAMID_VALUES = _TOP_LEVELS * _TILE * _TILE
# A tile's memory with one layer of free intervals, bytes.
_TILE_BYTES = (_PYRAMID_VALUES + 2 * _TILE * _TILE) * 8
#: Memory the ground map's tiles may take by default, bytes (about 130 tiles, 850 m2 of
#: single-layer ground: far more than the actor reads around itself in a walk).
DEFAULT_CACHE_BYTES = 160 * 2 ** 20
# A scene of at most this many tiles (a course of 200 m2 or so) has them all built at
# construction, where they cost little and none is built in a walk.
_EAGER_TILES = 32
# The fewest tiles a cache may hold (a query's tiles are built in groups of half of it).
_MIN_CACHE_TILES = 8
# Tiles of the lattice at most (its table of slots is 8 bytes a tile): about 5 km x 5 km.
_MAX_TILES = 1 << 22


@kernel('Tuple((f8[::1], f8[::1]))(f8[:, :], f8[::1], f8, f8, f8, f8, f8, i8, i8[::1], '
        'i8[::1], i8[::1], f8[::1], f8[::1], i8[::1], i8, u1[::1], i8[::1])')
def _ground_heights(xy, z_ref, x0, y0, inverse, last_x, last_y, tiles_x, slot_of, offset,
                    layers, ground, ceiling, stamp, clock, wanted, missed):
    """
    Return :meth:`Environment.ground_height` of each point in one pass.

    :meth:`Environment.ground_height` of each point in one pass (see there): the grid cell holding
    it (node indices up to ``last_x``, ``last_y``), the highest of its tile's grounds at or below
    ``z_ref`` and the ceiling over that.

    The cells are read from the tiles of the cache (:meth:`Environment.ground_grid`): tile
    ``slot_of[t]`` holds ``layers`` intervals a cell from ``offset`` on in ``ground`` and
    ``ceiling``. A point whose tile is not in the cache gets a NaN height and a clearance of
    -inf, its tile is marked in ``wanted`` and counted in ``missed[0]``; a tile read gets
    ``stamp`` = ``clock`` (for the cache's least-recently-used order).
    """
    count = xy.shape[0]
    height = np.full(count, np.nan)
    clearance = np.full(count, np.nan)
    for n in range(count):
        z = z_ref[n]
        gx, gy = (xy[n, 0] - x0) * inverse, (xy[n, 1] - y0) * inverse
        # On the grid when clamping leaves the point where it is (NaN is not).
        if not (0.0 <= gx <= last_x and 0.0 <= gy <= last_y and abs(z) < np.inf):
            continue
        column, row = int(min(gx, last_x - 1.0)), int(min(gy, last_y - 1.0))
        tile = (row // _TILE) * tiles_x + column // _TILE
        slot = slot_of[tile]
        if slot < 0:
            wanted[tile] = 1
            missed[0] += 1
            clearance[n] = -np.inf
            continue
        stamp[slot] = clock
        count_layers = layers[slot]
        cell = offset[slot] + ((row % _TILE) * _TILE + column % _TILE) * count_layers
        if count_layers == 1:
            index = cell
            if not ground[index] <= z + _Z_TOLERANCE:
                continue
        else:
            level = -1
            for layer in range(count_layers):
                if ground[cell + layer] <= z + _Z_TOLERANCE:
                    level += 1
            if level < 0:
                continue
            index = cell + level
        if z > ceiling[index]:
            continue
        height[n] = ground[index]
        clearance[n] = ceiling[index] - ground[index]
    return height, clearance


@kernel('f8(f8[::1], i8[::1], i8[::1], i8, u1[::1], i8[::1], i8, i8, i8, f8, f8, f8, f8, f8, '
        'f8)', inline=True)
def top_near(pyramid, slot_of, stamp, clock, wanted, missed, tiles_x, nx, ny, x0, y0,
             inverse, x, y, half):
    """
    Return :meth:`Environment.top_height_near` of one square, m.

    :meth:`Environment.top_height_near` of one square: the smallest dilation of the top map that
    covers ``half`` (m) read at the cell holding (x, y) (clamped onto the grid of ``nx`` x ``ny``
    cells); +inf where no dilation is wide enough or the centre is NaN.

    The dilations are read from the tiles of the cache (:meth:`Environment.top_near_grid`):
    tile ``slot_of[t]`` holds ``_TOP_LEVELS`` maps of ``_TILE`` x ``_TILE`` cells in
    ``pyramid``. Where the tile is not in the cache the bound is NaN (every comparison with it
    fails, so a caller that clears what lies above the bound clears nothing), the tile is
    marked in ``wanted`` and counted in ``missed[0]``.
    """
    need = np.ceil(half * inverse + 1e-6)
    fx, fy = (x - x0) * inverse, (y - y0) * inverse
    if not need <= _TOP_RADII[-1] or fx != fx or fy != fy:
        return np.inf
    level = 1
    while _TOP_RADII[level - 1] < need:
        level += 1
    column = int(min(max(np.floor(fx), 0.0), nx - 1))
    row = int(min(max(np.floor(fy), 0.0), ny - 1))
    tile = (row // _TILE) * tiles_x + column // _TILE
    slot = slot_of[tile]
    if slot < 0:
        wanted[tile] = 1
        missed[0] += 1
        return np.nan
    stamp[slot] = clock
    return pyramid[((slot * _TOP_LEVELS + level) * _TILE + row % _TILE) * _TILE
                   + column % _TILE]


@kernel('f8[::1](f8[::1], i8[::1], i8[::1], i8, u1[::1], i8[::1], i8, i8, i8, f8, f8, f8, '
        'f8[:, :], f8[::1])')
def _tops_near(pyramid, slot_of, stamp, clock, wanted, missed, tiles_x, nx, ny, x0, y0,
               inverse, xy, half):
    """:func:`top_near` of each (N, 2) centre and (N,) half width."""
    out = np.empty(xy.shape[0])
    for i in range(xy.shape[0]):
        out[i] = top_near(pyramid, slot_of, stamp, clock, wanted, missed, tiles_x, nx, ny,
                          x0, y0, inverse, xy[i, 0], xy[i, 1], half[i])
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


@kernel('Tuple((f8[:, ::1], f8[:, ::1]))(f8[:, :, ::1], f8[:, :, ::1])')
def _intersect_cells(grounds, ceilings):
    """
    Intersect the free intervals of each cell's four corners.

    Intersect the free intervals of each cell's four corners: (4, M, K) grounds and ceilings, each
    corner's intervals disjoint and sorted by ground (empty ones, +inf, last) -> (M, K') the same
    of the cells.

    As :func:`_intersect` three times over, without its (M, K x K) arrays: the pairs of one
    interval of the cell so far and one of the next corner, in that order, meet where their
    common part is not empty; the parts are kept sorted by ground, equal grounds in pair order.
    """
    corners, count, layers = grounds.shape
    room = 4 * layers * layers + 1
    current_ground, current_ceiling = np.empty(room), np.empty(room)
    next_ground, next_ceiling = np.empty(room), np.empty(room)
    out_ground = np.full((count, 4 * layers + 1), np.inf)
    out_ceiling = np.full((count, 4 * layers + 1), np.inf)
    width = 1
    for m in range(count):
        n = 0
        for k in range(layers):
            if grounds[0, m, k] < np.inf:
                current_ground[n], current_ceiling[n] = grounds[0, m, k], ceilings[0, m, k]
                n += 1
        for corner in range(1, corners):
            t = 0
            for a in range(n):
                for b in range(layers):
                    ground = max(current_ground[a], grounds[corner, m, b])
                    ceiling = min(current_ceiling[a], ceilings[corner, m, b])
                    if not (ground < np.inf and ceiling >= ground):
                        continue
                    i = t
                    while i > 0 and next_ground[i - 1] > ground:
                        next_ground[i], next_ceiling[i] = next_ground[i - 1], next_ceiling[i - 1]
                        i -= 1
                    next_ground[i], next_ceiling[i] = ground, ceiling
                    t += 1
            for i in range(t):
                current_ground[i], current_ceiling[i] = next_ground[i], next_ceiling[i]
            n = t
        for i in range(n):
            out_ground[m, i], out_ceiling[m, i] = current_ground[i], current_ceiling[i]
        width = max(width, n)
    return out_ground[:, :width].copy(), out_ceiling[:, :width].copy()


def _intersect_corners(grounds, ceilings):
    """Intersect the free intervals of a cell's four corners, (M, K) each -> (M, K')."""
    return _intersect_cells(np.ascontiguousarray(np.stack(grounds)),
                            np.ascontiguousarray(np.stack(ceilings)))


class SceneError(ValueError):
    """A scene file cannot be used: names the file and the field, line or value at fault."""


# Memory a loaded triangle takes in all (trimesh, FCL's BVH, the triangles as the ground map's
# tiles and the upper body's broad phase read them), with room for the peaks of construction,
# bytes; measured on game levels, terrains and warehouses of 0.1 to 0.5 M triangles.
TRIANGLE_BYTES = 2048
# Mesh file bytes a triangle takes at the least (binary STL: 50; OBJ and PLY take more).
_FILE_BYTES_PER_TRIANGLE = 50


def available_memory() -> int:
    """
    Return the memory the machine can give this process without swapping, bytes.

    Memory the machine can give this process without swapping, bytes (its ``MemAvailable``; where
    that is not known, its physical memory).
    """
    try:
        with open('/proc/meminfo', 'r', encoding='ascii') as meminfo:
            for line in meminfo:
                if line.startswith('MemAvailable:'):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf('SC_PAGE_SIZE') * os.sysconf('SC_PHYS_PAGES'))
    except (AttributeError, ValueError, OSError):
        return 1 << 62


def check_memory(triangles: int, what: str) -> None:
    """
    Refuse geometry of ``triangles`` triangles that would not fit in the available memory.

    Refuse, before allocating, geometry of ``triangles`` triangles that would not fit in the memory
    the machine has available.

    Parameters
    ----------
    triangles
        Triangles to load (at most, where only a file's size is known).
    what
        The start of the message: what holds them (``'scene.obj: a 3 GB file of up to'``).

    Raises
    ------
    SceneError
        Naming ``what``, the memory it needs and the memory available.

    """
    need, have = int(triangles) * TRIANGLE_BYTES, available_memory()
    if need > have:
        raise SceneError(f'{what} {triangles} triangles needs about {need / 2 ** 30:.1f} GB to '
                         f'load, but this machine has {have / 2 ** 30:.1f} GB available')


def load_mesh(path: str) -> trimesh.Trimesh:
    """
    Read one mesh file (STL, OBJ, PLY, GLB/GLTF, DAE) as world-frame triangles.

    Multi-geometry files (a GLB scene) are flattened with their node transforms.

    Raises
    ------
    SceneError
        Missing, unreadable, empty or non-mesh file; a file too large for the memory available
        (judged by its size before it is read); NaN/inf vertices; no triangles, or only
        degenerate ones.

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
    check_memory(size // _FILE_BYTES_PER_TRIANGLE,
                 f'{path}: a mesh file of {size / 2 ** 20:.0f} MB, up to')
    try:
        loaded = trimesh.load(path, force='scene', process=False)
        geometry = list(loaded.dump(concatenate=False)) if loaded.geometry else []
    except MemoryError as error:
        raise SceneError(f'{path}: the machine ran out of memory reading it') from error
    except Exception as error:  # trimesh's loaders raise many exception types
        raise SceneError(f'{path}: not a readable mesh: {error}') from error
    meshes = [g for g in geometry if isinstance(g, trimesh.Trimesh)]
    if not meshes:
        raise SceneError(f'{path}: contains no triangle mesh')
    mesh = meshes[0] if len(meshes) == 1 else trimesh.util.concatenate(meshes)
    _check_mesh(mesh, path)
    return mesh


def _check_mesh(mesh, what: str) -> None:
    """
    Raise SceneError for a mesh with nothing to stand on or to collide with.

    Raise SceneError for a mesh without triangles, with a non-finite vertex, or whose triangles all
    have no area (nothing to stand on or to collide with).
    """
    if not isinstance(mesh, trimesh.Trimesh):
        raise ValueError(f'{what}: expected a trimesh.Trimesh, got {type(mesh).__name__}')
    if len(mesh.faces) == 0:
        raise SceneError(f'{what}: mesh has zero triangles')
    vertices = np.asarray(mesh.vertices, dtype=float)
    if not np.all(np.isfinite(vertices)):
        bad = int(np.flatnonzero(~np.all(np.isfinite(vertices), axis=1))[0])
        raise SceneError(f'{what}: vertex {bad} is not finite: {vertices[bad].tolist()}')
    faces = np.asarray(mesh.faces)
    if faces.min() < 0 or faces.max() >= len(vertices):
        raise SceneError(f'{what}: a triangle refers to a vertex that does not exist '
                         f'(indices {int(faces.min())} to {int(faces.max())} of '
                         f'{len(vertices)} vertices)')
    triangles = vertices[faces]
    doubled_area = np.linalg.norm(np.cross(triangles[:, 1] - triangles[:, 0],
                                           triangles[:, 2] - triangles[:, 0]), axis=1)
    extent = float(np.ptp(vertices, axis=0).max())
    if not np.any(doubled_area > 1e-12 * max(extent, 1e-300) ** 2):
        raise SceneError(f'{what}: degenerate mesh: none of its {len(faces)} triangle(s) has '
                         f'an area')


class Environment:
    """
    Triangle meshes in the world frame with an FCL BVH and a walkable-ground map in tiles.

    Parameters
    ----------
    meshes
        World-frame triangle meshes (z up, m). Closed meshes are solids; an open upward-facing
        surface (a height-field terrain) counts as solid below it.
    names
        One name per mesh (for messages); default ``mesh0``, ``mesh1``, ...
    resolution
        Grid spacing of the ground map, m.
    cache_bytes
        Memory the ground map's tiles may take together, bytes (see Notes).

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
    The ground map is one lattice of ``resolution`` cells over the scene's bounds, cut into
    tiles of ``_TILE`` x ``_TILE`` cells. A tile is rasterised from the triangles over it when
    a query first reads it and kept in a cache of at most ``cache_bytes``, the tiles read
    longest ago dropped first; a small scene (at most ``_EAGER_TILES`` tiles) has them all
    built at construction. Memory therefore follows the triangles and the ground the actor
    walks on, not the scene's area (docs/environment.md).

    """

    def __init__(self, meshes: Sequence[trimesh.Trimesh], names: Optional[Sequence[str]] = None,
                 resolution: float = 0.02, cache_bytes: int = DEFAULT_CACHE_BYTES):
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
        check_memory(sum(len(m.faces) for m in meshes), 'the scene, of')
        if not (isinstance(resolution, (int, float)) and math.isfinite(resolution)
                and resolution > 0):
            raise ValueError(f'resolution must be a positive number of metres, got {resolution!r}')
        if not (isinstance(cache_bytes, int) and cache_bytes >= _MIN_CACHE_TILES * _TILE_BYTES):
            raise ValueError(f'cache_bytes must be an integer of at least '
                             f'{_MIN_CACHE_TILES * _TILE_BYTES}, got {cache_bytes!r}')
        self.meshes = meshes
        self.names = names
        self.resolution = float(resolution)
        self.cache_bytes = int(cache_bytes)
        self.bounds = np.array([np.min([m.bounds[0] for m in meshes], axis=0),
                                np.max([m.bounds[1] for m in meshes], axis=0)])
        self._lay_out_grid()
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
        self._prepare_ground_triangles()
        self._prepare_top_triangles()
        self._open_cache()
        if self._tile_count <= min(_EAGER_TILES, self._slot_limit // 2):
            self._build_tiles(np.arange(self._tile_count))

    def mesh_of(self, geometry) -> int:
        """Index of the mesh whose FCL geometry is ``geometry`` (from a contact), or -1."""
        return self._object_index.get(id(geometry), -1)

    def triangle(self, mesh_index: int, triangle_index: int) -> np.ndarray:
        """(3, 3) world vertices of one triangle of one mesh, m."""
        return self._vertices[mesh_index][self._faces[mesh_index][triangle_index]]

    # -- the lattice, and the triangles as the tiles read them --------------------------
    def _lay_out_grid(self) -> None:
        """One lattice of nodes over the scene's bounds, cut into tiles of _TILE cells."""
        res = self.resolution
        lo, hi = self.bounds[0, :2], self.bounds[1, :2]
        with np.errstate(over='ignore', invalid='ignore'):
            counts = np.ceil((hi - lo) / res) + 1
        cells = np.maximum(counts, 2) - 1
        tiles = np.ceil(cells / _TILE)
        if not (np.all(np.isfinite(tiles)) and tiles[0] * tiles[1] <= _MAX_TILES):
            width, depth = (hi - lo).tolist()
            raise ValueError(f'the scene spans {width:.6g} m x {depth:.6g} m: at a resolution '
                             f'of {res:g} m its ground map would have more than {_MAX_TILES} '
                             f'tiles of {_TILE} cells')
        nx, ny = int(cells[0]) + 1, int(cells[1]) + 1
        self._origin = lo.copy()
        self._inverse_resolution = 1.0 / res
        self._shape = (ny, nx)
        # The last node's x and y index (nx - 1, ny - 1).
        self._grid_last = np.array([nx - 1, ny - 1], dtype=float)
        self._tiles_x, self._tiles_y = int(tiles[0]), int(tiles[1])
        self._tile_count = self._tiles_x * self._tiles_y

    def _prepare_ground_triangles(self) -> None:
        """
        Prepare the nodes each triangle covers and its affine maps over the whole lattice.

        Per triangle, the nodes it covers and the affine maps of its barycentric weights and height
        over them, on the whole lattice, so a tile's values are those of the lattice.
        """
        res, (x0, y0) = self.resolution, self._origin
        ny, nx = self._shape
        parts = []
        for mesh, vertices, faces in zip(self.meshes, self._vertices, self._faces):
            # A closed mesh wound inside out (negative volume) would read as free space inside
            # and solid outside: flip its faces for the depth count.
            if mesh.is_watertight and mesh.volume < 0:
                faces = faces[:, ::-1]
            parts.append(vertices[faces])
        triangles = np.concatenate(parts)
        edge1 = triangles[:, 1] - triangles[:, 0]
        edge2 = triangles[:, 2] - triangles[:, 0]
        normal = np.cross(edge1, edge2)
        norm = np.linalg.norm(normal, axis=1)
        steep = np.abs(normal[:, 2]) <= 1e-9 * np.maximum(norm, 1e-300)
        triangles, edge1, edge2 = triangles[~steep], edge1[~steep], edge2[~steep]
        det = normal[~steep, 2]
        low = triangles[:, :, :2].min(axis=1)
        high = triangles[:, :, :2].max(axis=1)
        ix0 = np.clip(np.ceil((low[:, 0] - x0) / res - 1e-9), 0, nx - 1).astype(np.int64)
        ix1 = np.clip(np.floor((high[:, 0] - x0) / res + 1e-9), -1, nx - 1).astype(np.int64)
        iy0 = np.clip(np.ceil((low[:, 1] - y0) / res - 1e-9), 0, ny - 1).astype(np.int64)
        iy1 = np.clip(np.floor((high[:, 1] - y0) / res + 1e-9), -1, ny - 1).astype(np.int64)
        # Barycentric weights and height are affine in the node indices relative to each
        # triangle's first covered node: w = a * i + b * j + c.
        ox = x0 + ix0 * res - triangles[:, 0, 0]
        oy = y0 + iy0 * res - triangles[:, 0, 1]
        e1x, e1y, e2x, e2y = edge1[:, 0], edge1[:, 1], edge2[:, 0], edge2[:, 1]
        coefficients = np.empty((len(triangles), 9))
        coefficients[:, 0] = res * e2y / det
        coefficients[:, 1] = -res * e2x / det
        coefficients[:, 2] = (ox * e2y - e2x * oy) / det
        coefficients[:, 3] = -res * e1y / det
        coefficients[:, 4] = res * e1x / det
        coefficients[:, 5] = (e1x * oy - ox * e1y) / det
        coefficients[:, 6:9] = (coefficients[:, 0:3] * edge1[:, 2, None]
                                + coefficients[:, 3:6] * edge2[:, 2, None])
        coefficients[:, 8] += triangles[:, 0, 2]
        covers = (ix1 >= ix0) & (iy1 >= iy0)
        self._raster = _Raster(
            triangles=triangles[covers], ix0=ix0[covers], ix1=ix1[covers], iy0=iy0[covers],
            iy1=iy1[covers], coefficients=coefficients[covers],
            sign=np.where(det[covers] > 0, 1, -1).astype(np.int8))

    def _prepare_top_triangles(self) -> None:
        """
        Prepare the cells each triangle's xy box touches and the plane's bound over them.

        Per triangle, the cells its xy box touches and the plane's bound over them (see
        _build_tops): an upper bound of its height over each cell.
        """
        res, (x0, y0) = self.resolution, self._origin
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
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
        # Relative to each triangle's first cell: the plane's maximum over cell (i, j) is
        # base + step_x * i + step_y * j (a little above it for the rounding of the sums).
        base = (triangles[:, 0, 2] + slope_x * (x0 + ix0 * res - triangles[:, 0, 0])
                + slope_y * (y0 + iy0 * res - triangles[:, 0, 1])
                + res * (np.maximum(slope_x, 0.0) + np.maximum(slope_y, 0.0)) + 1e-6)
        self._top_triangles = _TopTriangles(
            ix0=ix0, ix1=ix1, iy0=iy0, iy1=iy1, base=np.where(tilted, base, z_max),
            step_x=np.where(tilted, slope_x * res, 0.0),
            step_y=np.where(tilted, slope_y * res, 0.0), z_max=z_max,
            large=(ix1 - ix0 + 1) * (iy1 - iy0 + 1) > 64)
        self._highest = float(z_max.max())

    # -- the cache of tiles ------------------------------------------------------------------
    def _open_cache(self) -> None:
        """Open an empty cache: no tile built, no slot taken."""
        self._slot_of = np.full(self._tile_count, -1, dtype=np.int64)
        self._wanted = np.zeros(self._tile_count, dtype=np.uint8)
        self._missed = np.zeros(1, dtype=np.int64)
        slots = self.cache_bytes // _TILE_BYTES
        self._slot_limit = int(slots)
        self._tile_in = np.full(slots, -1, dtype=np.int64)
        self._stamp = np.zeros(slots, dtype=np.int64)
        self._offset = np.zeros(slots, dtype=np.int64)
        self._layer_count = np.ones(slots, dtype=np.int64)
        self._pyramid = np.zeros(0)
        self._ground_pool = np.zeros(0)
        self._ceiling_pool = np.zeros(0)
        self._pool_used = 0
        self._live_values = 0
        self._clock = 1

    def cached_bytes(self) -> int:
        """Memory the ground map's cache holds now (its arrays' sizes), bytes."""
        return int(self._pyramid.nbytes + self._ground_pool.nbytes + self._ceiling_pool.nbytes)

    def cached_tiles(self) -> int:
        """How many tiles of the ground map are built and cached now."""
        return int(np.count_nonzero(self._tile_in >= 0))

    def _build_wanted(self) -> None:
        """Build the tiles the last kernel calls found missing."""
        tiles = np.flatnonzero(self._wanted)
        self._wanted[:] = 0
        self._missed[0] = 0
        self._build_tiles(tiles)

    def _build_tiles(self, tiles: np.ndarray) -> None:
        """Build the given tiles (those not in the cache yet), as many as the cache holds."""
        tiles = np.asarray(tiles, dtype=np.int64)
        # The tiles asked for that are cached already stay while the others are built.
        pinned = set(self._slot_of[tiles[self._slot_of[tiles] >= 0]].tolist())
        tiles = tiles[self._slot_of[tiles] < 0]
        for tile in tiles[:self._slot_limit - 1].tolist():
            ground, ceiling = self._build_ground_tile(tile)
            pyramid = self._build_top_tile(tile)
            slot = self._take_slot(ground.size, pinned)
            layers = ground.shape[1]
            self._store_values(slot, ground.ravel(), ceiling.ravel())
            self._layer_count[slot] = layers
            start = slot * _PYRAMID_VALUES
            self._pyramid[start:start + _PYRAMID_VALUES] = pyramid.ravel()
            self._slot_of[tile] = slot
            self._tile_in[slot] = tile
            self._stamp[slot] = self._clock
            pinned.add(slot)

    def _take_slot(self, values: int, pinned: set) -> int:
        """
        Return a free slot for a tile of ``values`` ground values, evicting old tiles.

        A free slot for a tile of ``values`` ground values, evicting the tiles read longest ago
        (but not ``pinned``) while the cache would exceed its bytes.
        """
        def used_bytes():
            taken = int(np.count_nonzero(self._tile_in >= 0))
            return taken * _PYRAMID_VALUES * 8 + self._live_values * 16
        while True:
            free = np.flatnonzero(self._tile_in < 0)
            if len(free) and used_bytes() + _PYRAMID_VALUES * 8 + values * 16 <= self.cache_bytes:
                break
            taken = np.flatnonzero(self._tile_in >= 0)
            taken = np.array([s for s in taken.tolist() if s not in pinned], dtype=np.int64)
            if not len(taken):
                break
            self._evict(int(taken[np.argmin(self._stamp[taken])]))
        free = np.flatnonzero(self._tile_in < 0)
        slot = int(free[0])
        if (slot + 1) * _PYRAMID_VALUES > len(self._pyramid):
            grown = np.full(min(max(2 * len(self._pyramid), (slot + 1) * _PYRAMID_VALUES),
                                self._slot_limit * _PYRAMID_VALUES), np.nan)
            grown[:len(self._pyramid)] = self._pyramid
            self._pyramid = grown
        return slot

    def _evict(self, slot: int) -> None:
        self._slot_of[self._tile_in[slot]] = -1
        self._tile_in[slot] = -1
        self._live_values -= _TILE * _TILE * int(self._layer_count[slot])

    def _store_values(self, slot: int, ground: np.ndarray, ceiling: np.ndarray) -> None:
        """Put a tile's (cells x layers) intervals into the pools, compacting them when full."""
        need = len(ground)
        if self._pool_used + need > len(self._ground_pool):
            # Keep the live tiles' values only, in slot order, with room to grow.
            live = np.flatnonzero(self._tile_in >= 0)
            live = live[live != slot]
            size = max(2 * (self._live_values + need), 4 * need)
            ground_pool, ceiling_pool = np.empty(size), np.empty(size)
            used = 0
            for s in live.tolist():
                n = _TILE * _TILE * int(self._layer_count[s])
                start = int(self._offset[s])
                ground_pool[used:used + n] = self._ground_pool[start:start + n]
                ceiling_pool[used:used + n] = self._ceiling_pool[start:start + n]
                self._offset[s] = used
                used += n
            self._ground_pool, self._ceiling_pool = ground_pool, ceiling_pool
            self._pool_used = used
        start = self._pool_used
        self._ground_pool[start:start + need] = ground
        self._ceiling_pool[start:start + need] = ceiling
        self._offset[slot] = start
        self._pool_used += need
        self._live_values += need

    # -- building one tile -------------------------------------------------------------------
    def _tile_cells(self, tile: int):
        """First cell column and row of a tile, and its columns and rows of cells on the grid."""
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
        column, row = (tile % self._tiles_x) * _TILE, (tile // self._tiles_x) * _TILE
        return column, row, min(_TILE, nx - column), min(_TILE, ny - row)

    def _build_ground_tile(self, tile: int):
        """
        Return a tile's free intervals: (_TILE * _TILE, layers) grounds and ceilings, m.

        Rasterises the triangles over the tile's nodes (a vertical ray per node, all hits);
        walking down each ray from the sky with a depth counter (+1 entering a solid at an
        upward face, -1 leaving at a downward face) gives the free intervals [ground, ceiling)
        a foot can stand in; a cell's intervals are those free at all four of its corners.
        """
        column, row, width, height = self._tile_cells(tile)
        # The tile's nodes: one more than its cells each way.
        i0, i1, j0, j1 = column, column + width, row, row + height
        nodes_x = width + 1
        nodes, heights, signs = self._rasterise(i0, i1, j0, j1)
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
        line = np.repeat(np.arange(len(unique)), per_node)
        hit_z = np.full((len(unique), depth_max), -np.inf)
        hit_sign = np.zeros((len(unique), depth_max), dtype=np.int8)
        hit_z[line, rank] = heights
        hit_sign[line, rank] = signs
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
        layers = grounds.shape[1]
        node_ground = np.full((nodes_x * (height + 1), layers), np.inf)
        node_ceiling = np.full((nodes_x * (height + 1), layers), np.inf)
        node_ground[unique] = grounds
        node_ceiling[unique] = ceilings
        node_ground = node_ground.reshape(height + 1, nodes_x, layers)
        node_ceiling = node_ceiling.reshape(height + 1, nodes_x, layers)
        # Conservative over each cell: a height z is free in the cell when it is free at all four
        # corners, so the cell's free intervals are the intersection of the corners' intervals.
        # Where all four corners hold the same intervals (open floor) that intersection is the
        # corner's own (an identity, so compared exactly); only the others are intersected.
        corners = [(slice(None, -1), slice(None, -1)), (slice(None, -1), slice(1, None)),
                   (slice(1, None), slice(None, -1)), (slice(1, None), slice(1, None))]
        grounds = [node_ground[c].reshape(-1, layers) for c in corners]
        ceilings = [node_ceiling[c].reshape(-1, layers) for c in corners]
        uniform = np.ones(len(grounds[0]), dtype=bool)
        for g, c in zip(grounds[1:], ceilings[1:]):
            uniform &= np.all((g == grounds[0]) & (c == ceilings[0]), axis=1)
        mixed = np.flatnonzero(~uniform)
        cell_ground, cell_ceiling = _intersect_corners(
            [g[mixed] for g in grounds], [c[mixed] for c in ceilings])
        width_layers = max(1, int(np.isfinite(grounds[0][uniform]).sum(axis=1).max(initial=0)),
                           cell_ground.shape[1])
        out_ground = np.full((_TILE, _TILE, width_layers), np.inf)
        out_ceiling = np.full((_TILE, _TILE, width_layers), np.inf)
        tile_ground = np.full((width * height, width_layers), np.inf)
        tile_ceiling = np.full((width * height, width_layers), np.inf)
        keep = min(layers, width_layers)
        tile_ground[uniform, :keep] = grounds[0][uniform][:, :keep]
        tile_ceiling[uniform, :keep] = ceilings[0][uniform][:, :keep]
        tile_ground[mixed, :cell_ground.shape[1]] = cell_ground
        tile_ceiling[mixed, :cell_ground.shape[1]] = cell_ceiling
        out_ground[:height, :width] = tile_ground.reshape(height, width, width_layers)
        out_ceiling[:height, :width] = tile_ceiling.reshape(height, width, width_layers)
        return (out_ground.reshape(_TILE * _TILE, width_layers),
                out_ceiling.reshape(_TILE * _TILE, width_layers))

    def _rasterise(self, i0: int, i1: int, j0: int, j1: int):
        """
        Rasterise the non-vertical triangles at the lattice nodes [i0, i1] x [j0, j1].

        Heights and facing of every non-vertical triangle at the lattice nodes [i0, i1] x [j0, j1]
        it covers.

        Returns (node index within the block, row-major, height m, +1 upward / -1 downward
        facing) of each hit, in triangle order.
        """
        res, (x0, y0) = self.resolution, self._origin
        r = self._raster
        sel = np.flatnonzero((r.ix0 <= i1) & (r.ix1 >= i0) & (r.iy0 <= j1) & (r.iy1 >= j0))
        nodes_x = i1 - i0 + 1
        # Scan line by grid row: each (triangle, row) pair covers the nodes between the
        # triangle's edges on that row, so slivers cost their area, not their bounding box.
        row_first = np.maximum(r.iy0[sel], j0)
        rows = np.minimum(r.iy1[sel], j1) - row_first + 1
        estimate = rows * (np.minimum(r.ix1[sel], i1) - np.maximum(r.ix0[sel], i0) + 3)
        out_nodes, out_z, out_sign = [], [], []
        cumulative = np.cumsum(estimate)
        start = 0
        eps = 1e-9
        while start < len(sel):
            limit = (cumulative[start - 1] if start else 0) + _RASTER_CHUNK
            stop = max(start + 1, int(np.searchsorted(cumulative, limit, side='right')))
            part = np.arange(start, stop)
            start = stop
            n = rows[part]
            pairs = int(n.sum())
            if pairs == 0:
                continue
            local = np.repeat(part, n)
            tri = sel[local]
            # j counts rows from the triangle's first covered node, as on the whole lattice.
            j = (row_first[local] - r.iy0[tri]) + (np.arange(pairs)
                                                   - np.repeat(np.cumsum(n) - n, n))
            y = y0 + (r.iy0[tri] + j) * res
            t = r.triangles[tri]
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
            first = np.maximum(np.maximum(np.ceil((left - x0) / res - 1e-7), r.ix0[tri]), i0)
            last = np.minimum(np.minimum(np.floor((right - x0) / res + 1e-7), r.ix1[tri]), i1)
            ok = np.isfinite(first) & np.isfinite(last) & (last >= first)
            tri, j = tri[ok], j[ok]
            first = first[ok].astype(np.int64) - r.ix0[tri]
            width = last[ok].astype(np.int64) - r.ix0[tri] - first + 1
            total = int(width.sum())
            if total == 0:
                continue
            owner = np.repeat(np.arange(len(tri)), width)
            i = first[owner] + np.arange(total) - np.repeat(np.cumsum(width) - width, width)
            tri, j = tri[owner], j[owner]
            c = r.coefficients[tri]
            w1 = c[:, 0] * i + c[:, 1] * j + c[:, 2]
            w2 = c[:, 3] * i + c[:, 4] * j + c[:, 5]
            inside = (w1 >= -eps) & (w2 >= -eps) & (w1 + w2 <= 1 + eps)
            z = c[:, 6] * i + c[:, 7] * j + c[:, 8]
            node = (r.iy0[tri] + j - j0) * nodes_x + (r.ix0[tri] + i - i0)
            out_nodes.append(node[inside])
            out_z.append(z[inside])
            out_sign.append(r.sign[tri[inside]])
        if not out_nodes:
            return np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int8)
        return np.concatenate(out_nodes), np.concatenate(out_z), np.concatenate(out_sign)

    def _build_top_tile(self, tile: int) -> np.ndarray:
        """
        Return a tile's top map and its dilations: (_TOP_LEVELS, _TILE, _TILE) m.

        Level 0 is the upper bound of every triangle's height over each cell: from each
        triangle whose xy bounding box touches the cell, the lower of the triangle's highest
        vertex and the highest point of its plane over the cell (a plane's maximum over a
        rectangle is at a corner). Every point of every mesh, and of the solid below a surface,
        therefore lies at or below its cell's value; -inf where no triangle reaches. Level
        k > 0 is that map dilated by _TOP_RADII[k - 1] cells (each cell: the largest value
        within that many cells in x and y), for :meth:`top_height_near`; it is built over the
        tile and a halo of the largest radius, so it is the dilation of the whole lattice's map.
        """
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
        column, row, width, height = self._tile_cells(tile)
        halo = _TOP_RADII[-1]
        c0, c1 = max(column - halo, 0), min(column + width + halo, nx)
        r0, r1 = max(row - halo, 0), min(row + height + halo, ny)
        tops = self._top_map(c0, c1, r0, r1)
        region_y, region_x = tops.shape
        out = np.full((_TOP_LEVELS, _TILE, _TILE), -np.inf)
        inner = (slice(row - r0, row - r0 + height), slice(column - c0, column - c0 + width))
        out[0, :height, :width] = tops[inner]
        previous = tops
        for level, radius in enumerate(_TOP_RADII, start=1):
            # Dilating by r twice dilates by 2 r: the max of the last level shifted by -r, 0, r.
            shift = max(radius // 2, 1)
            grown = previous.copy()
            if shift < region_x:
                np.maximum(grown[:, shift:], previous[:, :-shift], out=grown[:, shift:])
                np.maximum(grown[:, :-shift], previous[:, shift:], out=grown[:, :-shift])
            else:
                grown[:] = np.max(previous, axis=1, keepdims=True)
            previous = grown.copy()
            if shift < region_y:
                np.maximum(previous[shift:], grown[:-shift], out=previous[shift:])
                np.maximum(previous[:-shift], grown[shift:], out=previous[:-shift])
            else:
                previous[:] = np.max(grown, axis=0, keepdims=True)
            out[level, :height, :width] = previous[inner]
        return out

    def _top_map(self, c0: int, c1: int, r0: int, r1: int) -> np.ndarray:
        """Level 0 of the top map over cells [c0, c1) x [r0, r1): (r1 - r0, c1 - c0) m."""
        t = self._top_triangles
        tops2d = np.full((r1 - r0, c1 - c0), -np.inf)
        near = (t.ix0 < c1) & (t.ix1 >= c0) & (t.iy0 < r1) & (t.iy1 >= r0)
        # Large triangles (a floor, a wall) one by one as blocks of cells; small ones (rough
        # terrain) all together, one (triangle, cell) pair each.
        for k in np.flatnonzero(near & t.large).tolist():
            a0, a1 = max(t.ix0[k], c0), min(t.ix1[k], c1 - 1)
            b0, b1 = max(t.iy0[k], r0), min(t.iy1[k], r1 - 1)
            di = np.arange(a0 - t.ix0[k], a1 - t.ix0[k] + 1)
            dj = np.arange(b0 - t.iy0[k], b1 - t.iy0[k] + 1)
            block = np.minimum(t.base[k] + t.step_y[k] * dj[:, None] + t.step_x[k] * di,
                               t.z_max[k])
            view = tops2d[b0 - r0:b1 - r0 + 1, a0 - c0:a1 - c0 + 1]
            np.maximum(view, block, out=view)
        sel = np.flatnonzero(near & ~t.large)
        if len(sel):
            columns = t.ix1[sel] - t.ix0[sel] + 1
            count = columns * (t.iy1[sel] - t.iy0[sel] + 1)
            tri = np.repeat(sel, count)
            columns = np.repeat(columns, count)
            k = np.arange(int(count.sum())) - np.repeat(np.cumsum(count) - count, count)
            di, dj = k % columns, k // columns
            i, j = t.ix0[tri] + di - c0, t.iy0[tri] + dj - r0
            inside = (i >= 0) & (i < c1 - c0) & (j >= 0) & (j < r1 - r0)
            tri, di, dj = tri[inside], di[inside], dj[inside]
            value = np.minimum(t.base[tri] + t.step_x[tri] * di + t.step_y[tri] * dj,
                               t.z_max[tri])
            np.maximum.at(tops2d.ravel(), j[inside] * (c1 - c0) + i[inside], value)
        return tops2d

    # -- queries -----------------------------------------------------------------------------
    def _tick(self) -> int:
        """Advance the cache's clock for one query (tiles read get it as their stamp)."""
        self._clock += 1
        return self._clock

    def top_height_near(self, xy, half_extent) -> np.ndarray:
        """
        Return a cheap, looser :meth:`top_height`: a bound over squares around points.

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
        out = _tops_near(*self.top_near_grid(), xy, half)
        while self._missed[0]:
            # Tiles not cached yet: build them and read those points again.
            again = np.flatnonzero(np.isnan(out))
            self._build_wanted()
            out[again] = _tops_near(*self.top_near_grid(), xy[again], half[again])
        return out

    def top_near_grid(self) -> tuple:
        """
        Return the tiled top map's layout for the compiled :func:`top_near`.

        The tiled top map's layout for the compiled :func:`top_near`, from its first argument up
        to the query point: the dilations' pool, slot of each tile, stamps, clock, wanted tiles and
        missed count, tiles a row, columns and rows of cells, grid origin x and y (m), inverse
        resolution (1/m).

        Tiles a previous call found missing are built first.
        """
        if self._missed[0]:
            self._build_wanted()
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
        return (self._pyramid, self._slot_of, self._stamp, self._tick(), self._wanted,
                self._missed, self._tiles_x, nx, ny, float(self._origin[0]),
                float(self._origin[1]), float(self._inverse_resolution))

    def ground_grid(self) -> tuple:
        """
        Return the tiled ground map's layout for the compiled :func:`_ground_heights`.

        The tiled ground map's layout for the compiled :func:`_ground_heights`, after the query
        points and heights: grid origin x and y (m), inverse resolution (1/m), last node indices,
        tiles a row, slot of each tile, offsets and layers of each slot, grounds and ceilings (m),
        stamps, clock, wanted tiles and missed count.
        """
        return (float(self._origin[0]), float(self._origin[1]),
                float(self._inverse_resolution), float(self._grid_last[0]),
                float(self._grid_last[1]), self._tiles_x, self._slot_of, self._offset,
                self._layer_count, self._ground_pool, self._ceiling_pool, self._stamp,
                self._tick(), self._wanted, self._missed)

    def _tiles_of_cells(self, column: np.ndarray, row: np.ndarray) -> np.ndarray:
        return (row // _TILE) * self._tiles_x + column // _TILE

    def _read_cells(self, column: np.ndarray, row: np.ndarray, read) -> np.ndarray:
        """
        Return ``read(slots, local cells)`` for cells given by lattice column and row.

        ``read(slots, local cells)`` for cells given by lattice column and row, with their tiles
        built first (in groups the cache holds at once).
        """
        tiles = self._tiles_of_cells(column, row)
        local = (row % _TILE) * _TILE + column % _TILE
        out = None
        needed = np.unique(tiles)
        group = max(1, self._slot_limit // 2)
        for start in range(0, len(needed), group):
            chunk = needed[start:start + group]
            self._build_tiles(chunk)
            self._stamp[self._slot_of[chunk]] = self._tick()
            mine = np.isin(tiles, chunk)
            values = read(self._slot_of[tiles[mine]], local[mine])
            if out is None:
                out = np.empty(len(tiles), dtype=values.dtype)
            out[mine] = values
        return out if out is not None else np.zeros(0)

    def top_height(self, low_xy, high_xy) -> np.ndarray:
        """
        Upper bound of the environment's height over axis-aligned rectangles.

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
        ny, nx = self._shape[0] - 1, self._shape[1] - 1
        res, origin = self.resolution, self._origin
        out = np.full(len(low_xy), -np.inf)
        if not len(low_xy):
            return out
        first = np.floor((low_xy - origin) / res - 1e-9)
        last = np.floor((high_xy - origin) / res + 1e-9)
        # NaN extents read everything: the highest point of any mesh.
        bad = ~np.all(np.isfinite(first) & np.isfinite(last), axis=1)
        limit = np.array([nx - 1, ny - 1])
        # Wholly off the grid: no mesh there.
        off = ~bad & np.any((last < 0) | (first > limit), axis=1)
        first = np.where(bad[:, None], 0, np.clip(first, 0, limit)).astype(np.int64)
        last = np.where(bad[:, None], 0, np.clip(last, 0, limit)).astype(np.int64)
        pool = _TILE * _TILE
        for index in np.flatnonzero(~bad & ~off).tolist():
            (i0, j0), (i1, j1) = first[index], last[index]
            columns = np.arange(i0 // _TILE, i1 // _TILE + 1)
            rows = np.arange(j0 // _TILE, j1 // _TILE + 1)
            best = -np.inf
            for tile_row in rows.tolist():
                for tile_column in columns.tolist():
                    tile = tile_row * self._tiles_x + tile_column
                    self._build_tiles(np.array([tile]))
                    slot = int(self._slot_of[tile])
                    self._stamp[slot] = self._tick()
                    tops = self._pyramid[slot * _PYRAMID_VALUES:][:pool].reshape(_TILE, _TILE)
                    a0, b0 = tile_column * _TILE, tile_row * _TILE
                    block = tops[max(j0 - b0, 0):min(j1 - b0, _TILE - 1) + 1,
                                 max(i0 - a0, 0):min(i1 - a0, _TILE - 1) + 1]
                    best = max(best, float(block.max()))
            out[index] = best
        out[bad] = self._highest
        return out

    def _cells(self, xy):
        """Lattice cell column and row of each (N, 2) point, and whether it lies on the grid."""
        xy = np.asarray(xy, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:
            raise ValueError(f'xy must have shape (N, 2), got {xy.shape}')
        # x and y together: a point is on the grid when clamping it to the grid's extent
        # leaves it where it is (NaN clamps to 0, so it is not).
        grid = (xy - self._origin) * self._inverse_resolution
        clamped = np.fmin(np.fmax(grid, 0.0), self._grid_last)
        inside = clamped == grid
        valid = inside[:, 0] & inside[:, 1]
        # Off the grid (or NaN) the index is clamped into range; those points are not valid.
        index = np.minimum(clamped, self._grid_last - 1.0).astype(np.int64)
        return index[:, 0], index[:, 1], valid

    def lowest_ground(self, xy) -> np.ndarray:
        """
        Height of the lowest walkable surface at each point (conservative over its cell).

        Parameters
        ----------
        xy
            (N, 2) horizontal points, m.

        Returns
        -------
        numpy.ndarray
            (N,) m; NaN where there is none.

        """
        column, row, valid = self._cells(xy)
        ground = np.full(len(valid), np.nan)
        if np.any(valid):
            ground[valid] = self._read_cells(
                column[valid], row[valid],
                lambda slots, local: self._ground_pool[self._offset[slots]
                                                       + local * self._layer_count[slots]])
        ground[~np.isfinite(ground)] = np.nan
        return ground

    def ground_height(self, xy, z_ref) -> Tuple[np.ndarray, np.ndarray]:
        """
        Height of the highest walkable surface at or below ``z_ref``, and the room above it.

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
        xy, z = float_array(xy), float_array(z)
        height, clearance = _ground_heights(xy, z, *self.ground_grid())
        while self._missed[0]:
            # Tiles not cached yet: build them (as many as the cache holds) and read again.
            again = np.flatnonzero(clearance == -np.inf)
            self._build_wanted()
            height[again], clearance[again] = _ground_heights(xy[again], z[again],
                                                              *self.ground_grid())
        return height, clearance


@dataclass(frozen=True)
class _Raster:
    """
    The non-vertical triangles with the lattice nodes each covers and their affine maps.

    The non-vertical triangles (T, 3, 3) m with the lattice nodes each covers ([ix0, ix1] x [iy0,
    iy1]), the affine maps of their two barycentric weights and height over those nodes' indices
    (T, 9) and their facing (+1 up, -1 down).
    """

    triangles: np.ndarray
    ix0: np.ndarray
    ix1: np.ndarray
    iy0: np.ndarray
    iy1: np.ndarray
    coefficients: np.ndarray
    sign: np.ndarray


@dataclass(frozen=True)
class _TopTriangles:
    """
    Every triangle's cells and the bound of its height over them.

    Every triangle's cells ([ix0, ix1] x [iy0, iy1]) and the bound of its height over cell (i, j)
    of them: min(base + step_x * i + step_y * j, z_max), m; ``large`` ones are added to the top map
    as blocks (the sum taken in the other order).
    """

    ix0: np.ndarray
    ix1: np.ndarray
    iy0: np.ndarray
    iy1: np.ndarray
    base: np.ndarray
    step_x: np.ndarray
    step_y: np.ndarray
    z_max: np.ndarray
    large: np.ndarray
