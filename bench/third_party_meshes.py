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
Third-party scenes for the large-scene benchmark and tests, fetched from a registry package.

pybullet's wheel ships ``pybullet_data``: a game level (a samurai monastery, 125 k triangles,
125 m x 121 m), Kiva shelf pods, a table, a mug and a ground plane, under the zlib licence
(its LICENSE.txt is kept beside them). They are not committed: ``fetch`` downloads the wheel
once with ``pip download --no-deps`` (no install: only its data files are read), extracts the
few meshes into ``.cache/third_party/`` (ignored by git) and writes the scene files that use
them. Run: ``.venv/bin/python bench/third_party_meshes.py fetch`` (``./quickstart.sh setup``
does).
"""
import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CACHE = os.path.join(ROOT, '.cache', 'third_party')
PACKAGE = 'pybullet==3.2.7'
MEMBERS = ('pybullet_data/samurai_monastry.obj', 'pybullet_data/plane.obj',
           'pybullet_data/kiva_shelf/meshes/pod_lowres.stl', 'pybullet_data/table/table.obj',
           'pybullet_data/objects/mug.obj')
LICENCE = 'LICENSE.txt'
# What a complete fetch leaves, so that a second run does nothing.
STAMP = os.path.join(CACHE, f'{PACKAGE}.done')

#: Scene files written beside the meshes, by name.
SCENES = {
    # The level is modelled y up: turned +90 degrees about x to stand z up.
    'monastery': ('description: a game level, the samurai monastery of pybullet_data\n'
                  'meshes:\n'
                  '  - {file: pybullet_data/samurai_monastry.obj, '
                  'pose: [0, 0, 0, 1.5707963, 0, 0]}\n'),
}


def _warehouse() -> str:
    """
    Write a warehouse floor of shelf pods, a crate and a mug: about 143 k triangles.

    A 30 m x 30 m floor with two rows of seven shelf pods along a corridor, a crate (the table's
    unit cube) and a mug on it: about 143 k triangles.
    """
    lines = ['description: a warehouse of pybullet_data meshes (plane, Kiva pods, table, mug)',
             'meshes:', '  - {file: pybullet_data/plane.obj}']
    for row in (-1.6, 1.6):
        for i in range(7):
            # Pods are modelled y up, 2.37 m tall on their base.
            lines.append(f'  - {{file: pybullet_data/kiva_shelf/meshes/pod_lowres.stl, '
                         f'pose: [{-9.0 + 3.0 * i:g}, {row:g}, 0, 1.5707963, 0, 0]}}')
    lines.append('  - {file: pybullet_data/table/table.obj, pose: [12, 5, 0.5, 0, 0, 0]}')
    lines.append('  - {file: pybullet_data/objects/mug.obj, pose: [12, 5, 1.0, 0, 0, 0]}')
    lines.append('start: [-12, 0, 0]')
    return '\n'.join(lines) + '\n'


SCENES['warehouse'] = _warehouse()


def scene_path(name: str) -> str:
    """Path of a fetched scene file (it may not exist: see :func:`available`)."""
    return os.path.join(CACHE, f'{name}.yaml')


def available() -> bool:
    """Whether the third-party scenes have been fetched."""
    return os.path.isfile(STAMP)


def fetch() -> None:
    """Download the package once and extract its meshes and licence into the cache."""
    if available():
        return
    os.makedirs(CACHE, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=CACHE) as download:
        subprocess.run([sys.executable, '-m', 'pip', 'download', '-q', '--no-deps',
                        '--only-binary', ':all:', PACKAGE, '-d', download], check=True)
        wheels = [f for f in os.listdir(download) if f.endswith('.whl')]
        if len(wheels) != 1:
            raise RuntimeError(f'expected one wheel of {PACKAGE}, got {wheels}')
        with zipfile.ZipFile(os.path.join(download, wheels[0])) as wheel:
            names = set(wheel.namelist())
            licence = [n for n in names if n.endswith('.dist-info/' + LICENCE)]
            for member in MEMBERS:
                if member not in names:
                    raise RuntimeError(f'{wheels[0]} has no {member}')
                target = os.path.join(CACHE, member)
                os.makedirs(os.path.dirname(target), exist_ok=True)
                with wheel.open(member) as source, open(target, 'wb') as out:
                    shutil.copyfileobj(source, out)
            with wheel.open(licence[0]) as source, \
                    open(os.path.join(CACHE, 'pybullet_data', LICENCE), 'wb') as out:
                shutil.copyfileobj(source, out)
    for name, text in SCENES.items():
        with open(scene_path(name), 'w', encoding='utf-8') as out:
            out.write(text)
    with open(STAMP, 'w', encoding='utf-8') as out:
        out.write(' '.join(MEMBERS) + '\n')


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('command', choices=('fetch', 'where'))
    args = parser.parse_args()
    if args.command == 'fetch':
        try:
            fetch()
        except (OSError, RuntimeError, subprocess.CalledProcessError, zipfile.BadZipFile) as error:
            print(f'third-party meshes not fetched: {error}', file=sys.stderr)
            return 1
    print(CACHE)
    return 0


if __name__ == '__main__':
    sys.exit(main())
