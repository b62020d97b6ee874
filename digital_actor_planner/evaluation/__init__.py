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
Looking at a plan from outside the planner: the independent trajectory judge and pictures.

ROS-free like the core, which it uses but which never uses it: :mod:`trajectory_check` judges
a timed trajectory with geometry of its own (the tests' and benchmarks' verdict on a walk),
:mod:`render` draws key poses and animations with matplotlib.
"""
