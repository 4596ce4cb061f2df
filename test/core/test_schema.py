# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The model file's metadata: typed once on reading, every malformed entry refused in one line."""

from denoise_imu_ros.core.errors import ModelFileError
from denoise_imu_ros.core.modelfile import read_model_file, shipped_models
from denoise_imu_ros.core.schema import (fusion_metadata, FusionSettings, parse_meta,
                                         RestBiasSettings, Validation)
import pytest


def test_absent_entries_are_none_or_the_documented_defaults():
    meta = parse_meta({}, 'm')
    assert meta.sample_rate_hz is None and meta.rest_bias is None and meta.crossval is None
    assert meta.validation == Validation() and meta.fusion.chosen == FusionSettings()
    assert meta.train_sequences == () and meta.training_span is None
    assert parse_meta({'train_config': {'window': 100, 'max_offset': 8}}, 'm').training_span \
        == 108
    assert parse_meta({'train_config': {'window': 100, 'whole_sequences': True}},
                      'm').training_span is None


def test_typed_entries_and_what_this_version_does_not_know_survive_a_copy():
    stored = {'sample_rate_hz': 200, 'dataset': 'euroc', 'train_sequences': ['a', 'b'],
              'rest_bias': RestBiasSettings(prior_rad_s=(0.001, 0.0, 0.0)).to_dict(),
              'fusion': {'settings': FusionSettings(4.0, False, [0.1, -0.2, 0.05]).as_dict(),
                         'orientation_std_rad': [0.01, 0.02, 0.03]},
              'crossval': {'deploy': 'network', 'verdict': 'deploy the network',
                           'mean': {'raw': {'aoe_deg': 9.0}, 'network': {'aoe_deg': 2.0}},
                           'folds': [['a'], ['b']], 'steps': 10},
              'a_future_entry': {'x': 1}}
    meta = parse_meta(stored, 'm')
    assert meta.sample_rate_hz == 200.0 and isinstance(meta.sample_rate_hz, float)
    assert meta.rest_bias.prior_rad_s == (0.001, 0.0, 0.0)
    assert meta.fusion.chosen.accel_bias_m_s2 == (0.1, -0.2, 0.05)
    assert meta.fusion.orientation_std_rad == (0.01, 0.02, 0.03)
    assert meta.crossval.mean_deg == {'raw': 9.0, 'network': 2.0}
    assert meta.crossval.judged_on == 'aoe_deg'  # a report from before the tilt verdict
    assert meta.crossval.held_out == ('a', 'b') and meta.raw is stored
    assert meta.crossval.accel_deploy is None  # a report from before the accelerometer's


def test_a_tracking_held_above_a_rate_is_stored_and_read_back_and_older_files_never_hold():
    from denoise_imu_ros.core.schema import BiasTracking
    held = BiasTracking(0.05, 30.0, 0.05, 400.0)
    assert parse_meta({'bias_tracking': held.as_dict()}, 'm').bias_tracking == held
    older = {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0, 'sigma_init_deg_s': 0.05}
    assert parse_meta({'bias_tracking': older}, 'm').bias_tracking.hold_above_deg_s is None
    assert BiasTracking(0.05, 30.0, 0.05).as_dict() == older  # what an older reader knows
    assert held.describe() == 'sigma 0.05 deg/s, forgetting 30 s, held above 400 deg/s'
    assert BiasTracking(0.05, 30.0, 0.05).describe() == 'sigma 0.05 deg/s, forgetting 30 s'
    # a start that is not sigma is said: the node's log of the shipped broad
    assert BiasTracking(0.05, 30.0, 0.5, 400.0).describe() == (
        'sigma 0.05 deg/s, forgetting 30 s, held above 400 deg/s, started at 0.5 deg/s')


@pytest.mark.parametrize('raw, message', [
    ({'rest_bias': [1, 2]}, 'rest_bias'), ({'rest_bias': {'rest_min_s': 'long'}}, 'rest_bias'),
    ({'rest_bias': {'prior_rad_s': [0.0, 0.0]}}, 'rest_bias'),
    ({'rest_bias': {'threshold': 1.0}}, 'rest_bias'),
    ({'rest_bias': {'prior_rad_s': [0.0, float('nan'), 0.0]}}, 'rest_bias'),
    ({'rest_bias': {'rest_min_s': 0.0}}, 'rest_bias'),
    ({'rest_bias': {'bias_clip_deg_s': True}}, 'rest_bias'),
    # a prior beyond the estimator's own clip (EuRoC's 4.4 deg/s bias written in deg/s)
    ({'rest_bias': {'prior_rad_s': [0.0, 0.0, 4.4], 'bias_clip_deg_s': 9.0}},
     'beyond any MEMS gyro turn-on bias'),
    ({'rest_bias': {'prior_rad_s': [50.0, 0.0, 0.0]}}, r'60 deg/s = 1.047 rad/s\): written in'),
    ({'rest_bias': {'bias_clip_deg_s': 500.0}}, 'beyond any MEMS gyro turn-on bias'),
    ({'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0, 'forget': 9.0}},
     r"bias_tracking has unknown entries \['forget'\]"),
    ({'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0,
                        'hold_above_deg_s': -400.0}}, 'hold_above_deg_s must be a positive'),
    ({'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0,
                        'hold_above_deg_s': '400'}}, 'hold_above_deg_s must be a positive'),
    ({'input_envelope': {'gyro_rad_s': 5.0, 'accel_offset_m_s2': 9.0, 'gyro': 1.0}},
     r"input_envelope has unknown entries \['gyro'\]"),
    ({'input_envelope': {'gyro_rad_s': 5.0, 'accel_offset_m_s2': 9.0,
                         'sustained_accel_m_s2': -1.0}}, 'sustained_accel_m_s2 must be'),
    ({'blend': {'weight': 1.5, 'tracking': None}}, 'weight must be a number from 0 to 1'),
    ({'blend': {'weight': 0.5, 'tracking': {'sigma_motion_deg_s': 0.1}}}, 'inconsistent blend'),
    ({'blend': {'weight': 0.5, 'tracking': 'vqf'}}, 'inconsistent blend'),
    ({'blend': {'weight': 0.5, 'mix': 1}}, r"blend has unknown entries \['mix'\]"),
    ({'fusion': {'settings': {'tau_acc_s': -1.0}}}, 'inconsistent fusion settings'),
    ({'fusion': {'settings': {'tau_acc_s': 'long'}}}, 'inconsistent fusion settings'),
    ({'fusion': {'settings': {'bias_estimation': 'yes'}}}, 'inconsistent fusion settings'),
    ({'fusion': {'settings': {'tau': 3.0}}}, 'inconsistent fusion settings'),
    ({'fusion': {'settings': {'accel_bias_m_s2': [0.1, 0.2]}}}, 'inconsistent fusion'),
    ({'fusion': {'settings': {'accel_bias_m_s2': [0.0, 9.81, 0.0]}}}, 'inconsistent fusion'),
    ({'fusion': {'settings': {'accel_bias_m_s2': [float('nan'), 0, 0]}}}, 'inconsistent fusion'),
    ({'fusion': {'orientation_std_rad': 'small'}}, 'fusion.orientation_std_rad'),
    ({'fusion': {'orientation_std_rad': [0.01, -0.02, 0.03]}}, 'fusion.orientation_std_rad'),
    ({'fusion': {'filters': {'raw vqf': 3}}}, 'fusion.filters'),
    ({'fusion': 'tuned'}, "fusion 'tuned' is not a mapping"),
    ({'crossval': {'deploy': 'everything'}}, 'crossval.deploy'),
    ({'crossval': {'folds': 'a'}}, 'crossval.folds'),
    ({'crossval': {'judged_on': 'aoe_yaw_deg'}}, 'crossval.judged_on'),
    ({'crossval': {'accelerometer': {'deploy': 'calibrated'}}}, 'crossval.accelerometer'),
    ({'train_sequences': 'MH_01'}, 'train_sequences'),
    ({'kind': 3}, 'kind 3 is not a model kind'),
    ({'validation': {'step': 'last'}}, 'validation.step'),
    ({'train_config': {'window': 'x'}}, 'train_config.window'),
])
def test_malformed_entries_are_refused_in_one_line_naming_the_file(raw, message):
    with pytest.raises(ModelFileError, match=message) as err:
        parse_meta(raw, 'm.safetensors')
    assert str(err.value).startswith('m.safetensors: ') and '\n' not in str(err.value)


@pytest.mark.parametrize('name', shipped_models())
def test_every_shipped_model_parses(name):
    meta = read_model_file(name).meta
    assert meta.sample_rate_hz is not None and meta.train_sequences


def test_folds_that_leave_a_power_on_out_set_the_filter_of_the_row_a_model_file_runs():
    """The folds' filter for that row, the file's accelerometer bias where they remove one."""
    chosen = {'tracker only': {'tau_acc_s': 5.0, 'bias_estimation': True,
                               'accel_bias_removed': True, 'classical_tilt': True,
                               'orientation_std_rad': [1, 2, 3]},
              'network': {'tau_acc_s': 3.0, 'bias_estimation': False,
                          'accel_bias_removed': False, 'orientation_std_rad': [4, 5, 6]}}
    report = {'fold_kind': 'leave one power-on session out',
              'fusion': {'chosen': chosen, 'chosen_on': 'the folds'}}
    bias = [0.01, -0.02, 0.03]
    own = {'settings': {'tau_acc_s': 2.0, 'accel_bias_m_s2': bias},
           'filters': {'raw vqf': {'filter': 'vqf'}}, 'chosen_on': 'validation tails'}
    meta = parse_meta({'sample_rate_hz': 200.0, 'fusion': own}, 'test')
    assert not meta.fusion.by_crossval
    got = fusion_metadata(report, 'tracker only', meta)
    assert got['settings'] == {'tau_acc_s': 5.0, 'bias_estimation': True,
                               'accel_bias_m_s2': bias, 'classical_tilt': True}
    assert got['filters'] == own['filters'] and got['orientation_std_rad'] == [1, 2, 3]
    assert got['chosen_on'] == 'crossval: the folds'
    assert parse_meta({'sample_rate_hz': 200.0, 'fusion': got}, 'test').fusion.by_crossval
    network = fusion_metadata(report, 'network', meta)['settings']  # a report without the tilt
    assert network['accel_bias_m_s2'] == [0.0, 0.0, 0.0] and not network['classical_tilt']
    assert fusion_metadata(report, 'calibrated', meta) is None  # no choice for it
    assert fusion_metadata(dict(report, fold_kind='leave recordings out'), 'network',
                           meta) is None  # the tails share the power-on: their choice stands
    assert fusion_metadata({'fold_kind': report['fold_kind']}, 'network', meta) is None
    # a report from a file (user input) that does not hold together is one clear error
    for bad in ({'tau_acc_s': -1.0}, {'orientation_std_rad': 'small'}, {'bias_estimation': 1},
                {'classical_tilt': 'yes'}):
        broken = dict(report, fusion={'chosen': {'network': dict(chosen['network'], **bad)},
                                      'chosen_on': 'the folds'})
        with pytest.raises(ModelFileError, match='crossval.fusion.chosen.network'):
            fusion_metadata(broken, 'network', meta)
