# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The node's settings: one object read from ROS parameters or a params YAML."""

import math

from denoise_imu_ros.core.errors import OptionError
from denoise_imu_ros.runtime.settings import Settings
from helpers import ROOT
import pytest
import yaml


def _file(tmp_path, doc) -> str:
    path = tmp_path / 'params.yaml'
    path.write_text(yaml.safe_dump(doc))
    return str(path)


def _text(tmp_path, text: str) -> str:
    path = tmp_path / 'params.yaml'
    path.write_text(text)
    return str(path)


def test_the_shipped_params_file_holds_every_parameter_at_its_default():
    settings, unknown = Settings.from_params_file(ROOT / 'config' / 'gyro_denoiser.yaml')
    assert settings == Settings() and unknown == []
    written = yaml.safe_load((ROOT / 'config' / 'gyro_denoiser.yaml').read_text())
    assert list(written['/**']['ros__parameters']) == [name for name, _, _ in Settings.specs()]


def test_a_params_file_is_read_as_ros_reads_it(tmp_path):
    """Sections that select the node, in file order; nested names dotted; QoS left to DDS."""
    settings, unknown = Settings.from_params_file(_file(tmp_path, {
        '/**': {'ros__parameters': {'model': 'tumvi', 'max_gap_factor': 5.0,
                                    'qos_overrides': {'/imu/data_raw': {'subscription': {
                                        'depth': 5}}}}},
        '/other_node': {'ros__parameters': {'fixed_frame': 'elsewhere'}},
        '/gyro_denoiser': {'ros__parameters': {'max_gap_factor': 7.0, 'rest_bias': False,
                                               'typo_parameter': 1}}}))
    assert settings == Settings(model='tumvi', max_gap_factor=7.0, rest_bias=False)
    assert unknown == ['typo_parameter']
    assert settings.choice('rest_bias') == 'off' and settings.choice('envelope_guard') == 'model'
    assert settings.with_(rest_bias='on').choice('rest_bias') == 'on'


def test_values_ros_accepts_are_accepted_as_ros_reads_them(tmp_path):
    """Within 1e-6 of a range's end; 1e-2 a float (YAML 1.2, as rcl); every node's own names."""
    settings, unknown = Settings.from_params_file(_text(tmp_path, f"""/**:
  ros__parameters:
    orientation_stddev: {math.pi * (1 + 5e-7)!r}
    rate_tolerance: 1e-2
    use_sim_time: true
"""))
    assert settings.rate_tolerance == 0.01 and unknown == []
    with pytest.raises(OptionError, match='outside'):
        Settings(orientation_stddev=math.pi * (1 + 2e-6))


def test_a_namespaced_node_reads_the_sections_that_select_it(tmp_path):
    path = _file(tmp_path, {'/denoised/gyro_denoiser': {'ros__parameters': {'model': 'tumvi'}},
                            '/gyro_denoiser': {'ros__parameters': {'model': 'broad'}}})
    assert Settings.from_params_file(path, '/denoised/gyro_denoiser')[0].model == 'tumvi'
    assert Settings.from_params_file(path)[0].model == 'broad'


@pytest.mark.parametrize('params, said', [
    ({'max_gap_factor': 3}, r'max_gap_factor must be a float, not a int \(write a decimal'),
    ({'rate_tolerance': 2.0}, r'rate_tolerance = 2.0 is outside \[0.0, 1.0\]'),
    ({'envelope_guard': 'on'}, r"envelope_guard must be 'model' or off, not 'on'"),
    ({'rest_bias': 'sometimes'}, r"rest_bias must be 'model', on or off, not 'sometimes'"),
    ({'fixed_frame': ' '}, 'fixed_frame must name a frame'),
    ({'fusion_tau_acc': 0.0}, 'fusion_tau_acc must be a time constant above 0 s'),
    ({'publish_fused': 'yes'}, 'publish_fused must be a bool, not a str'),
])
def test_a_value_the_node_refuses_is_refused_in_one_line(tmp_path, params, said):
    with pytest.raises(OptionError, match=said):
        Settings.from_params_file(_file(tmp_path, {'/**': {'ros__parameters': params}}))


@pytest.mark.parametrize('doc, said', [
    ({'/other_node': {'ros__parameters': {'model': 'tumvi'}}}, 'no parameters for /gyro_denoiser'),
    ({'/**': {'model': 'tumvi'}}, 'no ros__parameters mapping'),
    (['model', 'tumvi'], 'not a ROS params file'),
])
def test_a_file_that_is_not_the_nodes_params_is_refused(tmp_path, doc, said):
    with pytest.raises(OptionError, match=said):
        Settings.from_params_file(_file(tmp_path, doc))
    with pytest.raises(OptionError, match='No such file'):
        Settings.from_params_file(tmp_path / 'missing.yaml')


@pytest.mark.parametrize('judged, published', [
    (None, (0.02, -0.1, 0.05)), ('bias removed', (0.02, -0.1, 0.05)),
    ('as it came', (0.0, 0.0, 0.0))])
def test_imu_corrected_leaves_the_accelerometer_bias_out_where_it_carries(
        model_file, judged, published):
    from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
    from denoise_imu_ros.pipeline.fusion import FusionSettings
    crossval = {'deploy': 'network', 'verdict': 'v', 'mean': {}, 'folds': []}
    add_metadata(model_file, fusion={'settings': FusionSettings(
        3.0, False, (0.02, -0.1, 0.05)).as_dict()}, **({} if judged is None else {
            'crossval': dict(crossval, accelerometer={'deploy': judged})}))
    loaded = read_model_file(model_file)
    settings = Settings(model=str(model_file))
    assert settings.corrected_accel_bias(loaded) == published
    den = settings.denoiser(loaded)
    assert den.accel_bias == (0.02, -0.1, 0.05)  # the filter and the tilt: the fitted bias
    out = den.process(10**9, [0.0, 0.0, 0.0], [0.1, 0.2, 9.8])
    assert out.accel.tolist() == [0.1 - published[0], 0.2 - published[1], 9.8 - published[2]]
    off = settings.with_(fusion_accel_bias='off')
    assert off.corrected_accel_bias(loaded) == (0.0, 0.0, 0.0)
    assert not settings.fusion(loaded).classical_tilt  # the file's: none stored
    assert settings.with_(fusion_classical_tilt='on').fusion(loaded).classical_tilt


def test_each_messages_accelerometer_variance_only_on_the_accelerometer_it_was_fitted_on(
        model_file):
    """Less the same bias (the file's, its cross-validation's, fusion_accel_bias), no override."""
    from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
    from denoise_imu_ros.pipeline.fusion import FusionSettings
    from denoise_imu_ros.runtime.outputs import Outputs
    variance = {'theta': [-7.5, 1.5, 2.0, -1.5]}
    fitted = {'theta': [-4.4, 0.6, 1.1, 0.1], 'accel_bias_m_s2': [0.02, -0.1, 0.05]}
    add_metadata(model_file, gyro_variance=variance, accel_variance=fitted, fusion={
        'settings': FusionSettings(4.0, False, (0.02, -0.1, 0.05)).as_dict()})
    loaded = read_model_file(model_file)
    out = Outputs(None, print, None, print, 'odom', [], [])
    for settings, carried, fixed in (
            (Settings(), True, None),
            (Settings(fusion_accel_bias='off'), False, None),        # another accelerometer
            (Settings(linear_acceleration_stddev=0.1), False, 0.01),  # the node's override
            (Settings(linear_acceleration_stddev=0.0), False, 0.0)):
        settings.configure(out, loaded)
        assert out.per_sample_accel == carried and out.per_sample_gyro
        assert (out.accel_cov is None) == (fixed is None)
        if fixed is not None:
            assert out.accel_cov[0] == pytest.approx(fixed) and out.accel_cov[1] == 0.0
    add_metadata(model_file, fusion={'settings': FusionSettings(4.0, False, (0.0, 0.1, 0.0)
                                                                ).as_dict()})
    Settings().configure(out, read_model_file(model_file))  # the bias refitted since
    assert not out.per_sample_accel and out.accel_cov is None
