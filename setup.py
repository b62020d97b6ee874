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

"""ament_python package: digital_actor_planner."""
from glob import glob
import os

from setuptools import find_packages, setup

package_name = 'digital_actor_planner'


def tree(folder):
    """Map every file below ``folder`` to its share/ install location."""
    pairs = {}
    for path in glob(os.path.join(folder, '**', '*'), recursive=True):
        if os.path.isfile(path):
            target = os.path.join('share', package_name, os.path.dirname(path))
            pairs.setdefault(target, []).append(path)
    return sorted(pairs.items())


setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test', 'test.*', 'bench', 'bench.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ] + tree('launch') + tree('urdf') + tree('config'),
    package_data={package_name: ['data/*']},
    include_package_data=True,
    zip_safe=False,
    maintainer='digital_actor_planner developers',
    maintainer_email='dev@digital-actor.invalid',
    description=('Real-time whole-body motion planning for a mouse-directed humanoid '
                 'digital actor.'),
    license='Apache-2.0',
    python_requires='>=3.11',
    tests_require=['pytest'],
    entry_points={
        'console_scripts': [
            'digital-actor = digital_actor_planner.cli:main',
            'actor_planner = digital_actor_planner.nodes.actor_planner:main',
            'dynamixel_bridge = digital_actor_planner.nodes.dynamixel_bridge:main',
            'actor_viewer = digital_actor_planner.nodes.viewer:main',
        ],
    },
)
