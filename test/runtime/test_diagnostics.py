# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""What /diagnostics says, from the pipeline's state alone (no DDS)."""

from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
from denoise_imu_ros.pipeline.online import OnlineDenoiser
from denoise_imu_ros.pipeline.rest_bias import RestBiasSettings
from denoise_imu_ros.runtime.diagnostics import Level, status
import numpy as np
import pytest

WITHHELD = {'corrected_withheld': 0, 'attitude_withheld': 0, 'fused_withheld': 0}
STILL = (np.zeros(3), np.array([0.0, 0.0, 9.81]))


def _fed(den, n, period_ns=5_000_000, gyro=None, first_ns=10**9):
    for k in range(n):
        den.process(first_ns + k * period_ns, STILL[0] if gyro is None else gyro, STILL[1])


@pytest.fixture()
def den(model_file):
    return OnlineDenoiser.from_model_file(read_model_file(model_file))


def test_each_state_has_its_level_and_message(den):
    said = status(den, WITHHELD, None, '/imu/data_raw')
    assert (said.level, said.message) == (Level.WARN, 'no input yet')
    assert said.values['seconds_since_input'] == '' and said.values['accepted'] == '0'
    _fed(den, 10)
    said = status(den, WITHHELD, 0.01, '/imu/data_raw')
    assert (said.level, said.message) == (Level.WARN, 'warming up')
    field = den.engine.receptive_field
    assert said.values['buffer_fill'] == f'10/{field}'
    _fed(den, field, first_ns=2 * 10**9)
    said = status(den, WITHHELD, 0.01, '/imu/data_raw', callback_s=[1e-4, 3e-4, 2e-4])
    assert (said.level, said.message) == (Level.OK, 'ok')
    assert said.values['callback_time_p50_us'] == '200.0'
    assert said.values['rest_bias_applied'] == said.values['envelope_guard_applied'] == 'False'
    said = status(den, WITHHELD, 0.01, '/imu/data_raw', 'the verdict says: deploy no model')
    assert (said.level, said.message) == (Level.WARN, 'the verdict says: deploy no model')
    said = status(den, {**WITHHELD, 'fused_withheld': 7}, 2.5, '/ns/imu/data_raw')
    assert (said.level, said.message) == (Level.ERROR, 'no input for 2.5 s on /ns/imu/data_raw')
    assert said.values['input_rate_hz'] == '0.00' and said.values['fused_withheld'] == '7'


def test_a_stream_dropped_whole_says_why_not_that_nothing_came(den):
    """All-zero header stamps: every message arrived and was dropped for its stamp."""
    for _ in range(1600):
        den.process(0, *STILL)
    said = status(den, WITHHELD, 0.01, '/imu/data_raw')
    assert (said.level, said.message) == (Level.ERROR,
                                          'no message accepted: dropped 1600 (zero stamp)')


def test_a_stream_off_the_model_rate_is_an_error(den):
    _fed(den, 100, period_ns=10_000_000)  # 100 Hz into a 200 Hz model
    said = status(den, WITHHELD, 0.01, '/imu/data_raw')
    assert said.level == Level.ERROR and said.message.startswith(
        'input rate 100.0 Hz differs from the model rate 200.0 Hz')


def test_a_turn_on_bias_far_from_its_prior_is_a_warning(model_file):
    """Still at 1.5 deg/s from a prior of 0 within a 2 deg/s clip: maybe a slow turn."""
    add_metadata(model_file, rest_bias=RestBiasSettings().to_dict())
    den = OnlineDenoiser.from_model_file(read_model_file(model_file))
    _fed(den, 1200, gyro=np.radians([0.0, 0.0, 1.5]))
    said = status(den, WITHHELD, 0.01, '/imu/data_raw')
    assert said.level == Level.WARN and said.message.startswith('turn-on bias found at rest 1.49')
    assert said.values['rest_bias_ambiguous'] == 'True'
    assert said.values['rest_bias_source'] == 'stillness'


def test_a_blend_says_its_weight_and_the_samples_given_the_classical_pipeline_alone(model_file):
    """Accelerating longer than in training: the classical pipeline's output alone."""
    add_metadata(model_file, blend={'weight': 0.7, 'tracking': None},
                 input_envelope={'gyro_rad_s': 10.0, 'accel_offset_m_s2': 20.0,
                                 'sustained_accel_m_s2': 1.0})
    den = OnlineDenoiser.from_model_file(read_model_file(model_file))
    said = status(den, WITHHELD, None, '/imu/data_raw')
    assert said.values['classical_blend_applied'] == 'True'
    assert said.values['classical_blend_weight'] == '0.7'
    _fed(den, 50)
    assert status(den, WITHHELD, 0.01, '/imu/data_raw').values['classical_only_samples'] == '0'
    for k in range(100):  # 2.8 m/s^2 off gravity for 0.5 s: 1.4 m/s^2 over the last second
        den.process(2 * 10**9 + k * 5_000_000, STILL[0], np.array([8.0, 0.0, 9.81]))
    assert int(status(den, WITHHELD, 0.01, '/imu/data_raw').values[
        'classical_only_samples']) > 0
