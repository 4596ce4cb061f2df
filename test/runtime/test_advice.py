# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The warnings every tool gives of a run's turn-on bias settings and of a verdict against it."""

from denoise_imu_ros.core.modelfile import read_model_file
from denoise_imu_ros.core.schema import RestBiasSettings
from denoise_imu_ros.runtime.advice import blend_warnings, deployment_warning, rest_warnings
from helpers import write_untrained_model
import pytest


@pytest.fixture
def rest_model(tmp_path):
    return read_model_file(write_untrained_model(tmp_path / 'rest.safetensors', {
        'sample_rate_hz': 200.0,
        'rest_bias': RestBiasSettings(prior_rad_s=(0.001, 0.0, 0.0)).to_dict()}))


@pytest.fixture
def raw_model(tmp_path):
    return read_model_file(write_untrained_model(tmp_path / 'raw.safetensors',
                                                 {'sample_rate_hz': 200.0}))


def test_a_rest_bias_model_run_on_the_raw_gyro_is_said_to_be(rest_model):
    assert rest_warnings(rest_model, 'model') == []
    assert rest_warnings(rest_model, 'on') == []
    assert rest_warnings(rest_model, 'off') == [
        'rest_bias off: the model was trained on the gyro less its turn-on bias, it now gets '
        'the raw gyro']


def test_a_raw_gyro_model_given_a_turn_on_bias_says_what_it_can_find(raw_model):
    assert rest_warnings(raw_model, 'model') == rest_warnings(raw_model, 'off') == []
    said, = rest_warnings(raw_model, 'on')
    assert 'stores no turn-on bias settings' in said and 'a 2 deg/s clip' in said


def test_a_clip_wider_than_vqfs_says_which_turns_it_takes_for_stillness(tmp_path):
    wide = read_model_file(write_untrained_model(tmp_path / 'wide.safetensors', {
        'sample_rate_hz': 200.0, 'rest_bias': RestBiasSettings(bias_clip_deg_s=9.0).to_dict()}))
    said, = rest_warnings(wide, 'model')
    assert said.startswith('turn-on bias clip 9 deg/s about the prior: a steady turn')


def test_a_no_model_file_against_its_verdict_is_not_told_about_the_network(tmp_path):
    report = {'deploy': 'network', 'verdict': 'the network beats the calibrated IMU: deploy '
              'the network', 'mean': {'network': {'aoe_deg': 1.0}, 'rest bias': {'aoe_deg': 2.0}}}
    rest = read_model_file(write_untrained_model(tmp_path / 'r.safetensors', {
        'sample_rate_hz': 200.0, 'kind': 'rest bias', 'crossval': report,
        'rest_bias': RestBiasSettings().to_dict()}, calibration_only=True))
    assert deployment_warning(rest) == (
        'r.safetensors runs rest bias (no model), but the cross-recording validation of its '
        'recipe recommends network (rest bias 2.00° against network 1.00° in mean AOE on '
        'unseen recordings)')


def test_a_blended_model_run_without_its_blend_is_said_to_be_what_its_verdict_did_not_judge(
        tmp_path):
    report = {'deploy': 'network', 'verdict': 'deploy the network', 'judged_on': 'aoe_deg',
              'mean': {'network': {'aoe_deg': 4.3}, 'network unblended': {'aoe_deg': 4.48}}}
    blended = read_model_file(write_untrained_model(tmp_path / 'b.safetensors', {
        'sample_rate_hz': 200.0, 'crossval': report,
        'blend': {'weight': 0.5, 'tracking': None}}))
    assert blend_warnings(blended, 'model') == []
    assert blend_warnings(blended, 'off') == [
        'classical_blend off: the network alone, not the output its cross-recording validation '
        'judged, blended with the classical pipeline at weight 0.5 (unseen recordings, mean '
        'AOE: 4.48° alone against 4.30° blended)']
    unblended = read_model_file(write_untrained_model(tmp_path / 'u.safetensors',
                                                      {'sample_rate_hz': 200.0}))
    assert blend_warnings(unblended, 'off') == []
