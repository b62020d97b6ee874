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

"""One declaration per setting: the core's checks and the node's descriptors agree."""
from dataclasses import replace

from digital_actor_planner.core.actor import ActorConfig
from digital_actor_planner.core.footsteps import FootstepConfig
from digital_actor_planner.core.gait import GaitConfig
from digital_actor_planner.core.settings import ConfigError, declared_settings
from digital_actor_planner.core.upper_body import UpperBodyConfig
import pytest

CONFIGS = (FootstepConfig, GaitConfig, UpperBodyConfig, ActorConfig)


def _outside(declaration):
    """Return values just past each bound of a declared number."""
    step = 1 if declaration.kind is int else 1e-6
    values = []
    if declaration.low is not None:
        values.append(declaration.low if declaration.low_open else declaration.low - step)
    if declaration.high is not None:
        values.append(declaration.high if declaration.high_open else declaration.high + step)
    return values


@pytest.mark.parametrize('config_class', CONFIGS, ids=lambda c: c.__name__)
def test_every_field_is_declared_and_refused_past_its_range_by_name(config_class):
    declared = declared_settings(config_class)
    default = config_class()
    nested = {'footsteps', 'gait', 'upper_body', 'actor'}
    for name in default.__dataclass_fields__:
        assert name in declared or name in nested, f'{config_class.__name__}.{name} undeclared'
    for name, declaration in declared.items():
        assert getattr(default, name) == declaration.default
        for value in _outside(declaration):
            with pytest.raises(ConfigError) as caught:
                replace(default, **{name: value})
            assert caught.value.name == name and caught.value.value == value
            assert name in str(caught.value) and repr(value) in str(caught.value)


def test_actor_config_holds_its_footstep_and_gait_settings_without_copies():
    config = ActorConfig(footsteps=FootstepConfig(window_steps=5), gait=GaitConfig(frame_rate=50))
    assert config.footsteps.window_steps == 5 and config.frame_rate == 50
    assert 'window_steps' not in declared_settings(ActorConfig)
    assert 'frame_rate' not in declared_settings(ActorConfig)
    with pytest.raises(TypeError):
        ActorConfig(window_steps=5)
    with pytest.raises(ConfigError, match='frame_rate') as caught:
        ActorConfig.from_settings(frame_rate=5.0)
    assert caught.value.name == 'frame_rate'
    with pytest.raises(ConfigError, match='no_such_setting'):
        ActorConfig.from_settings(no_such_setting=1)


def test_cross_field_rules_name_the_field():
    for build, name in ((lambda: FootstepConfig(step_length_min=0.9), 'step_length_min'),
                        (lambda: GaitConfig(min_step_time=1.0), 'min_step_time'),
                        (lambda: ActorConfig(max_backward_speed=1.5), 'max_backward_speed'),
                        (lambda: ActorConfig(backward_step_length_min=0.5),
                         'backward_step_length_min')):
        with pytest.raises(ConfigError) as caught:
            build()
        assert caught.value.name == name


def test_every_node_descriptor_states_the_declared_range():
    from digital_actor_planner.nodes.planner_params import parameter_declarations, \
        parameter_settings
    declared = dict(parameter_settings())
    core = {**declared_settings(FootstepConfig), **declared_settings(GaitConfig),
            **declared_settings(ActorConfig)}
    descriptors = {name: descriptor for name, _, descriptor in parameter_declarations()}
    assert set(descriptors) == set(declared)
    for name, declaration in declared.items():
        if name in core:
            assert core[name] is declaration, name
        descriptor = descriptors[name]
        ranges = list(descriptor.floating_point_range) + list(descriptor.integer_range)
        if declaration.low is None or declaration.high is None:
            assert not ranges, name
            continue
        assert len(ranges) == 1, name
        assert (ranges[0].from_value, ranges[0].to_value) == (declaration.low,
                                                              declaration.high), name
        assert (len(descriptor.integer_range) == 1) == (declaration.kind is int), name


def test_node_config_refuses_an_out_of_range_actor_parameter_by_name():
    from digital_actor_planner.nodes.planner_params import ConfigurationError, \
        default_scene_path, read_node_config, validate_node_config
    values = {'scene': default_scene_path()}
    for name, value in (('step_length_max', 1.5), ('window_steps', 9), ('step_intervals', 61),
                        ('max_angular_speed', 0.0), ('max_backward_speed', 1.5)):
        with pytest.raises(ConfigurationError) as caught:
            validate_node_config(read_node_config(dict(values, **{name: value}).get))
        assert caught.value.parameter == name and caught.value.value == value
        assert f"parameter '{name}'" in str(caught.value) and repr(value) in str(caught.value)
