# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""Pins of the shipped models: provenance, accuracy on the bundled sample, streaming."""

from denoise_imu_ros.core.modelfile import read_model_file, shipped_models
from denoise_imu_ros.core.schema import Blend, NO_MODEL, tracking_from_dict
from denoise_imu_ros.evaluation import evaluate as evaluate_module
from denoise_imu_ros.evaluation.crossval import BLEND_WEIGHTS
from denoise_imu_ros.learn.checkpoint import load_model
from denoise_imu_ros.learn.model import correct_gyro
from denoise_imu_ros.pipeline.rest_bias import HOLD_ABOVE_DEG_S
from denoise_imu_ros.pipeline.streaming import StreamingCorrector
from denoise_imu_ros.runtime.advice import deployment_warning
from helpers import SAMPLE
import numpy as np
import pytest

SAMPLE_DIR = SAMPLE.parent


@pytest.mark.parametrize('name', ['euroc', 'tumvi', 'euroc_calibrated', 'tumvi_calibrated'])
def test_shipped_models_load_by_name_with_their_provenance(name):
    assert name in shipped_models()
    loaded = load_model(name)
    meta = loaded.meta.raw
    for key in ('sample_rate_hz', 'train_sequences', 'train_config', 'validation',
                'code_version', 'receptive_field'):
        assert key in meta
    expected = {'euroc': ['MH_01_easy', 'MH_03_medium', 'MH_05_difficult', 'V1_02_medium',
                          'V2_01_easy', 'V2_03_difficult'],
                'tumvi': ['dataset-room1_512_16', 'dataset-room3_512_16',
                          'dataset-room5_512_16']}[name.split('_')[0]]
    assert meta['train_sequences'] == expected
    assert loaded.model.receptive_field == (1 if 'calibrated' in name else 511)


@pytest.mark.parametrize('name', sorted(shipped_models()))
def test_every_shipped_model_is_trusted_within_the_motion_of_its_training_recordings(name):
    """Its input envelope: its recordings' fastest rotation; a fallback only without rest bias."""
    meta = read_model_file(name).meta
    bounds = meta.input_envelope
    if meta.kind in NO_MODEL:  # nothing learnt: nothing to distrust
        assert bounds is None
        return
    fastest = {'euroc': 2.47, 'tumvi': 4.14, 'broad': 24.46}[name.split('_')[0]]  # rad/s
    assert abs(bounds.gyro_rad_s - fastest) < 0.01
    if meta.rest_bias is not None:
        assert bounds.fallback_rad_s == (0.0, 0.0, 0.0)
    if name.startswith('euroc'):  # the ADIS16448's turn-on bias about z: 4.5 deg/s
        assert -0.08 < bounds.fallback_rad_s[2] < -0.075


def test_shipped_euroc_model_beats_raw_and_calibrated_on_the_shipped_test_sample(tmp_path):
    report = evaluate_module.evaluate('euroc', str(SAMPLE_DIR), [SAMPLE.name],
                                      str(tmp_path), plots=False)
    aoe = {m: r['aoe_deg'] for m, r in report['sequences'][SAMPLE.name].items()}
    assert aoe['network'] < aoe['calibrated'] < aoe['raw']
    fused = {m: r['aoe_deg'] for m, r in report['fused'][SAMPLE.name].items()}
    assert fused['network + VQF'] < min(v for m, v in fused.items() if m != 'network + VQF')
    # gravity bounds the tilt: the fused tilt error stops growing, the open-loop one does not
    growth = {m: r['tilt_growth_deg_min'] for m, r in report['fused'][SAMPLE.name].items()}
    assert abs(growth['network + VQF']) < report['sequences'][SAMPLE.name]['network'][
        'tilt_growth_deg_min']


@pytest.mark.parametrize('name', ['euroc', 'tumvi', 'euroc_calibrated', 'tumvi_calibrated'])
def test_shipped_files_store_filter_settings_chosen_on_training_recordings(name):
    meta = read_model_file(name).meta.raw
    fusion = meta['fusion']
    assert fusion['chosen_on'].startswith(f'validation tails of {meta["train_sequences"][0]}')
    assert fusion['settings']['bias_estimation'] is False
    assert len(fusion['orientation_std_rad']) == 3
    # the accelerometer bias fitted on the training poses, stored where the tails kept it
    fitted = fusion['accel_bias']
    assert fitted['fitted_on'].startswith(f'poses of {meta["train_sequences"][0]}')
    assert fusion['settings']['accel_bias_m_s2'] in (fitted['m_s2'], [0.0, 0.0, 0.0])
    if name.startswith('euroc'):  # the ADIS16448's: about 0.12 m/s^2 on y, 0.7 deg of tilt
        assert fusion['settings']['accel_bias_m_s2'] == fitted['m_s2']
        assert 0.08 < fitted['m_s2'][1] < 0.16


def test_shipped_model_streams_the_whole_sample_exactly():
    from denoise_imu_ros.data.load import load_imu
    imu = load_imu(SAMPLE).imu
    model = load_model('euroc').model
    np.testing.assert_allclose(StreamingCorrector.from_module(model).process(imu),
                               correct_gyro(model, imu), rtol=0, atol=1e-6)


@pytest.mark.parametrize('name', ['euroc', 'tumvi', 'euroc_calibrated', 'tumvi_calibrated'])
def test_every_shipped_model_carries_its_cross_recording_report(name):
    report = load_model(name).meta.raw['crossval']
    assert report['verdict'].startswith('the network ')
    assert set(report['mean']) == {'raw', 'calibrated', 'network'}
    assert len(report['recordings']) == (6 if name.startswith('euroc') else 3)
    assert report['deploy'] in ('network', 'calibration', 'none')
    kind = 'calibration' if name.endswith('_calibrated') else 'network'
    warning = deployment_warning(read_model_file(name))
    assert (warning is None) == (report['deploy'] == kind)
    if name.startswith('tumvi'):  # on unseen rooms neither beats plain integration
        assert report['deploy'] == 'none' and warning.endswith('deploy no correction')


def test_shipped_euroc_is_the_ensemble_of_five_trainings():
    loaded = load_model('euroc')
    assert loaded.model.config.members == 5
    assert sorted(m['seed'] for m in loaded.meta.raw['members']) == [0, 1, 2, 3, 4]


def test_shipped_tumvi_is_the_ensemble_of_eleven_family_trainings_and_its_folds_verdict():
    loaded = load_model('tumvi')
    assert loaded.model.config.members == 11
    assert sorted(m['seed'] for m in loaded.meta.raw['members']) == list(range(11))
    assert loaded.meta.recipe('increments') == [16, 32, 64, 128]
    report = loaded.meta.raw['crossval']  # the folds' ensembles of seeds, as what ships
    assert report['recipe'].endswith('train_tumvi_family.yaml')
    assert report['seeds'] == [0, 1, 2] and set(report['per_seed']) == {'0', '1', '2'}


def test_shipped_broad_is_what_its_session_folds_say_the_classical_pipeline():
    """No learnt row held within 10 % of tracker only on every unseen trial: broad tracks."""
    broad, network = read_model_file('broad'), load_model('broad_network')
    assert broad.meta.kind == 'tracker only' and broad.config.calibration_only
    report = broad.meta.raw['crossval']
    assert report == network.meta.raw['crossval'] == load_model(
        'broad_calibrated').meta.raw['crossval']
    assert report['fold_kind'] == 'leave one power-on session out'
    assert len(report['folds']) == 2 and report['seeds'] == [0, 1, 2]
    assert len(network.meta.train_sequences) == 12  # every trial, the fast ones too
    assert set(report['mean']) == {'raw', 'rest bias', 'tracker only', 'calibrated',
                                   'network unblended', 'network'}
    assert report['deploy'] == 'tracker only' and deployment_warning(broad) is None
    for name in ('broad_network', 'broad_calibrated'):
        assert deployment_warning(read_model_file(name)).endswith('(tracker only)')
    # what differs between recordings (sessions) was learnt apart from the model
    assert report['train_config']['recording_bias'] and network.meta.recipe('recording_bias')
    # each file tracks its output's bias as the held-out sessions chose for its row, and
    # the network blends its output with the classical pipeline's as they chose
    for name, row in (('broad', 'tracker only'), ('broad_calibrated', 'calibrated'),
                      ('broad_network', 'network')):
        chosen = report['tracking']['chosen'][row]
        assert read_model_file(name).meta.bias_tracking == tracking_from_dict(chosen)
    classical = tracking_from_dict(report['tracking']['chosen']['tracker only'])
    assert network.meta.blend == Blend(report['blend']['chosen']['weight'], classical)
    # held through rotation faster than VQF's own attitude follows (BROAD's fast trials)
    assert classical.hold_above_deg_s == HOLD_ABOVE_DEG_S
    assert network.meta.blend.weight in BLEND_WEIGHTS
    # beyond the second-long acceleration of its training trials, the classical alone
    assert 1.0 < network.meta.input_envelope.sustained_accel_m_s2 < 100.0
    assert network.model.config.members == 3
    assert sorted(m['seed'] for m in network.meta.raw['members']) == [0, 1, 2]
    # one estimator, its prior between the two sessions' turn-on biases (rad/s)
    settings = broad.meta.rest_bias
    assert settings == network.meta.rest_bias
    for axis, (b, c) in enumerate(((3.6e-3, 8.6e-3), (2.1e-3, -3.3e-3), (-4.0e-3, -4.4e-3))):
        assert min(b, c) - 3e-4 < settings.prior_rad_s[axis] < max(b, c) + 3e-4
    # imu/data's filter: what the session folds chose for each file's row (validation
    # tails share the training's power-on), the fitted accelerometer bias where they kept it
    for name, row in (('broad', 'tracker only'), ('broad_calibrated', 'calibrated'),
                      ('broad_network', 'network')):
        loaded, chosen = read_model_file(name), report['fusion']['chosen'][row]
        settings = loaded.meta.fusion.chosen
        assert (settings.tau_acc_s, settings.bias_estimation) == (
            chosen['tau_acc_s'], chosen['bias_estimation'])
        assert any(settings.accel_bias_m_s2) == chosen['accel_bias_removed']
        assert loaded.meta.raw['fusion']['chosen_on'].startswith('crossval: ')
    # one power-on's accelerometer bias worsens the other's velocity increments: the
    # published accelerometer stays as it came
    from denoise_imu_ros.runtime.settings import Settings
    accel = report['accelerometer']
    assert accel['deploy'] == 'as it came' and len(accel['recordings']) == 12
    assert accel['mean']['bias removed'] > accel['mean']['as it came']
    for name in ('broad', 'broad_network', 'broad_calibrated'):
        loaded = read_model_file(name)
        assert Settings(model=name).corrected_accel_bias(loaded) == (0.0, 0.0, 0.0)
