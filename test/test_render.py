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

"""Pictures of a run: PNG key poses and GIF animation are real, non-blank images of the actor."""
import os
import time

from digital_actor_planner.core.skeleton import Skeleton
from digital_actor_planner.evaluation.render import render_gif, render_png
import numpy as np
from PIL import Image
import pytest
import trimesh
import yaml

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SCENES = os.path.join(ROOT, 'config', 'scenes')


@pytest.fixture(scope='module')
def skeleton():
    return Skeleton()


def course_meshes(name):
    with open(os.path.join(SCENES, f'{name}.yaml')) as stream:
        scene = yaml.safe_load(stream)
    meshes = []
    for entry in scene['meshes']:
        mesh = trimesh.load(os.path.join(SCENES, entry['file']), force='mesh')
        if 'pose' in entry:
            x, y, z, roll, pitch, yaw = entry['pose']
            matrix = trimesh.transformations.euler_matrix(roll, pitch, yaw, 'sxyz')
            matrix[:3, 3] = (x, y, z)
            mesh.apply_transform(matrix)
        meshes.append(mesh)
    return meshes


def standing_run(skeleton, duration, distance, rate=100.0):
    """Return a standing actor translated along +x: times (k,), frames (k, 22)."""
    times = np.arange(0.0, duration + 1e-9, 1.0 / rate)
    frames = np.tile(skeleton.neutral(), (len(times), 1))
    frames[:, skeleton.index['root_x']] = np.linspace(0.0, distance, len(times))
    return times, frames


def shirt_mask(image):
    """Pixels with the actor's blue shirt colour (blue well above red and green)."""
    rgb = np.asarray(image.convert('RGB'), dtype=int)
    return ((rgb[:, :, 2] - rgb[:, :, 0] > 60) & (rgb[:, :, 2] > 120)
            & (rgb[:, :, 2] - rgb[:, :, 1] > 30))


def shirt_pixels(image):
    return int(np.sum(shirt_mask(image)))


def shirt_centre_x(image):
    """Mean column of the shirt pixels, as a fraction of the image width."""
    mask = shirt_mask(image)
    return float(np.mean(np.nonzero(mask)[1])) / mask.shape[1]


def test_png_shows_the_actor_on_the_course(skeleton, tmp_path):
    times, frames = standing_run(skeleton, 2.0, 1.6)
    footsteps = np.array([[0.4 * i, 0.09 * (-1) ** i, 0.0, 0.0] for i in range(5)])
    path = str(tmp_path / 'run.png')
    render_png(path, skeleton, course_meshes('low_beam'), times, frames, footsteps=footsteps,
               n_poses=3, title='low beam', size=(600, 400))
    image = Image.open(path)
    assert image.format == 'PNG'
    assert image.size == (600, 400)
    pixels = np.asarray(image.convert('RGB'), dtype=float)
    assert pixels.std() > 20.0
    assert shirt_pixels(image) > 500
    # The ground is drawn too: the lower half of the picture is not the plain background.
    background = pixels[2, 2]
    lower = pixels[300:, :]
    assert np.mean(np.any(np.abs(lower - background) > 10, axis=-1)) > 0.5


def test_png_of_a_long_run_on_big_terrain_is_fast(skeleton, tmp_path, artifacts_dir):
    # The rough course is a 35 000-face heightfield: clipped and resampled, it stays quick.
    times, frames = standing_run(skeleton, 10.0, 7.0)
    path = os.path.join(artifacts_dir, 'render_rough.png')
    start = time.perf_counter()
    render_png(path, skeleton, course_meshes('rough'), times, frames, title='rough')
    elapsed = time.perf_counter() - start
    assert elapsed < 30.0
    image = Image.open(path)
    assert image.size == (1200, 800)
    assert shirt_pixels(image) > 6 * 300      # six key poses, each clearly visible


def test_gif_follows_the_actor(skeleton, tmp_path):
    times, frames = standing_run(skeleton, 1.0, 0.8)
    path = str(tmp_path / 'run.gif')
    render_gif(path, skeleton, course_meshes('pillars'), times, frames, fps=10,
               size=(320, 240))
    image = Image.open(path)
    assert image.format == 'GIF'
    assert image.size == (320, 240)
    assert image.n_frames == 11
    shots, centres = [], []
    for index in (0, 10):
        image.seek(index)
        shots.append(np.asarray(image.convert('RGB'), dtype=float))
        assert shots[-1].std() > 15.0
        assert shirt_pixels(image) > 150
        centres.append(shirt_centre_x(image))
    # The camera follows: the actor stays in the middle while the course moves past.
    assert np.abs(shots[0] - shots[1]).mean() > 1.0
    assert all(abs(c - 0.5) < 0.15 for c in centres)
    assert abs(centres[0] - centres[1]) < 0.03


def test_gif_with_a_fixed_camera_shows_the_actor_moving(skeleton, tmp_path):
    times, frames = standing_run(skeleton, 1.0, 3.0)
    path = str(tmp_path / 'fixed.gif')
    render_gif(path, skeleton, course_meshes('flat'), times, frames, fps=2, follow=False,
               size=(320, 240))
    image = Image.open(path)
    assert image.n_frames == 3 and image.size == (320, 240)
    centres = []
    for index in (0, 2):
        image.seek(index)
        centres.append(shirt_centre_x(image))
    assert abs(centres[1] - centres[0]) > 0.2


@pytest.mark.parametrize('bad', [
    {'frames': np.zeros((10, 21))},
    {'frames': np.zeros(22)},
    {'times': np.arange(9) * 0.01},
    {'frames': np.full((10, 22), np.nan)},
    {'footsteps': np.zeros((3, 3))},
    {'meshes': ['not a mesh']},
    {'n_poses': 0},
    {'size': (10, 10)},
    {'face_budget': 1},
    {'azimuth': float('nan')},
])
def test_bad_input_raises_and_writes_nothing(skeleton, tmp_path, bad):
    times, frames = standing_run(skeleton, 0.09, 0.1)
    arguments = {'meshes': course_meshes('flat'), 'times': times, 'frames': frames}
    options = {}
    for key, value in bad.items():
        (arguments if key in arguments else options)[key] = value
    path = tmp_path / 'bad.png'
    with pytest.raises(ValueError):
        render_png(str(path), skeleton, arguments['meshes'], arguments['times'],
                   arguments['frames'], **options)
    assert list(tmp_path.iterdir()) == []


def test_bad_gif_rate_raises(skeleton, tmp_path):
    times, frames = standing_run(skeleton, 0.5, 0.1)
    with pytest.raises(ValueError, match='fps'):
        render_gif(str(tmp_path / 'a.gif'), skeleton, course_meshes('flat'), times, frames,
                   fps=0)
    with pytest.raises(ValueError, match='22'):
        render_gif(str(tmp_path / 'a.gif'), skeleton, course_meshes('flat'), times,
                   frames[:, :20])
    assert list(tmp_path.iterdir()) == []
