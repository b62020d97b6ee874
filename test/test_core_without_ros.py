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

"""The planning core, the evaluation beside it and the node's real time import no ROS (STYLE)."""
import importlib
import pkgutil
import subprocess
import sys

# The packages that must run without a ROS install: the core, the judge and pictures that
# look at its plans (tests, benchmarks and `digital-actor simulate` run them bare), and the
# planner node's real time (frame buffer, planning processes, stream threads: nodes only adapt).
ROS_FREE = ('core', 'evaluation', 'runtime')


def test_ros_free_modules_import_with_rclpy_blocked():
    code = (
        'import sys, importlib, pkgutil\n'
        "for name in ('rclpy', 'rclpy.node', 'rclpy.serialization', 'rcl_interfaces',\n"
        "             'sensor_msgs', 'geometry_msgs', 'std_msgs', 'visualization_msgs',\n"
        "             'nav_msgs', 'diagnostic_msgs'):\n"
        '    sys.modules[name] = None\n'
        f'for package in {ROS_FREE!r}:\n'
        "    folder = importlib.import_module('digital_actor_planner.' + package)\n"
        '    names = [m.name for m in pkgutil.iter_modules(folder.__path__)]\n'
        '    for n in names:\n'
        "        importlib.import_module(f'digital_actor_planner.{package}.{n}')\n"
        '    print(len(names))\n')
    result = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert all(int(count) >= 1 for count in result.stdout.split()), result.stdout


def test_ros_free_module_lists_are_importable_here():
    for package in ROS_FREE:
        folder = importlib.import_module('digital_actor_planner.' + package)
        for module in pkgutil.iter_modules(folder.__path__):
            importlib.import_module(f'digital_actor_planner.{package}.{module.name}')
