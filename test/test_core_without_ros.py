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

"""The planning core imports no ROS (STYLE: core is NumPy, trimesh and python-fcl only)."""
import importlib
import pkgutil
import subprocess
import sys


def test_core_modules_import_with_rclpy_blocked():
    code = (
        'import sys, importlib, pkgutil\n'
        "for name in ('rclpy', 'rclpy.node', 'sensor_msgs', 'geometry_msgs', 'std_msgs'):\n"
        '    sys.modules[name] = None\n'
        'import digital_actor_planner.core as core\n'
        'names = [m.name for m in pkgutil.iter_modules(core.__path__)]\n'
        'for n in names:\n'
        "    importlib.import_module('digital_actor_planner.core.' + n)\n"
        'print(len(names))\n')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert int(result.stdout.strip()) >= 1


def test_core_module_list_is_importable_here():
    import digital_actor_planner.core as core
    for module in pkgutil.iter_modules(core.__path__):
        importlib.import_module('digital_actor_planner.core.' + module.name)
