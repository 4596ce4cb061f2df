# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The gravity-aided filters offline: one convention for all three, scores, tuning."""

from denoise_imu_ros.core.metrics import fused_errors
from denoise_imu_ros.core.records import Sequence
from denoise_imu_ros.core.schema import parse_meta
from denoise_imu_ros.evaluation import filters
from denoise_imu_ros.evaluation.filters import eval_filters, Filter, run
import numpy as np
import pytest
from scipy.spatial.transform import Rotation

KINDS = [Filter('vqf', 2.0), Filter('imufusion', gain=0.2), Filter('madgwick', gain=0.033)]


@pytest.mark.parametrize('flt', KINDS, ids=lambda f: f.kind)
def test_every_filter_starts_from_gravity_and_integrates_sample_k_into_stamp_k(flt):
    """The orientation at stamp k includes sample k's rate: each interval at its ends' mean."""
    tilt = Rotation.from_euler('ZYX', [0.0, 0.15, -0.3])
    n = 1000
    rate = np.random.default_rng(1).uniform(-0.5, 0.5, n)  # about the body's vertical axis
    up = tilt.inv().apply([0.0, 0.0, 1.0])
    gyro = np.outer(rate, up)
    accel = np.tile(9.81 * up, (n, 1))
    quat = Rotation.from_quat(run(flt, gyro, accel, 200.0))
    # the vertical is the accelerometer's from the first stamp on, whatever the rotation
    seen = quat.inv().apply([0.0, 0.0, 1.0])
    assert np.degrees(np.arccos(np.clip(seen @ up, -1, 1))).max() < 0.05
    # rotation about the vertical: the gyro's own integral, sample k into stamp k
    turned = (quat[0].inv() * quat).as_rotvec() @ up
    expected = np.concatenate([[0.0], np.cumsum(0.5 * (rate[:-1] + rate[1:]) * 0.005)])
    np.testing.assert_allclose(np.unwrap(turned), expected, atol=2e-3)


def test_fused_errors_align_the_yaw_once_and_never_the_tilt():
    t = np.arange(4000) * 0.005
    gt = Rotation.from_rotvec(np.outer(np.sin(t), [0.2, -0.1, 1.0]))
    offset = Rotation.from_rotvec([0.0, 0.0, 1.1])  # an arbitrary yaw: aligned away
    creep = Rotation.from_rotvec(np.outer(np.radians(0.5) * t / 60, [1.0, 0.0, 0.0]))
    err = fused_errors(offset * creep * gt, gt, np.ones(len(t), bool), t)
    assert err.start == 300  # 1.5 s in
    tilt = 0.5 * t[300:] / 60  # deg: a tilt creeping at 0.5 deg/min is never aligned away
    assert err.tilt == pytest.approx(np.sqrt(np.mean(tilt ** 2)), rel=1e-3)
    assert err.tilt_growth_deg_min == pytest.approx(0.5, rel=1e-3)
    assert err.aoe_yaw < 1e-3 and err.aoe == pytest.approx(err.tilt, rel=1e-2)


def test_eval_uses_the_settings_the_model_files_store():
    net = {'fusion': {'settings': {'tau_acc_s': 7.0, 'bias_estimation': False},
                      'filters': {'raw vqf': Filter('vqf', 1.0).as_dict(),
                                  'calibrated madgwick': Filter('madgwick', gain=0.1).as_dict()}}}
    calib = {'fusion': {'settings': {'tau_acc_s': 4.0, 'bias_estimation': True}}}
    rows = eval_filters(parse_meta(net, 'm'), parse_meta(calib, 'c'))
    assert rows == {'raw + VQF defaults': ('raw', Filter('vqf', 3.0, True)),
                    'raw + VQF': ('raw', Filter('vqf', 1.0)),
                    'rest bias + VQF': ('rest bias', Filter('vqf', 1.0)),
                    'tracker only + VQF': ('tracker only', Filter('vqf', 1.0)),
                    'calibrated + VQF': ('calibrated', Filter('vqf', 4.0, True)),
                    'calibrated + imufusion': ('calibrated', Filter('imufusion', gain=0.5)),
                    'calibrated + Madgwick': ('calibrated', Filter('madgwick', gain=0.1)),
                    'network + VQF': ('network', Filter('vqf', 7.0))}
    rows = eval_filters(parse_meta({}, 'm'), None)
    assert set(rows) == {'raw + VQF defaults', 'raw + VQF', 'rest bias + VQF',
                         'tracker only + VQF', 'network + VQF'}


def _turning_sequence(n: int) -> Sequence:
    """Return a body turning back and forth about a tilted axis, its IMU exact."""
    t = np.arange(n) * 0.005
    gt = Rotation.from_rotvec(np.outer(np.sin(t), [0.3, 0.2, 1.0]))
    omega = (gt[:-1].inv() * gt[1:]).as_rotvec() / 0.005
    accel = gt.inv().apply(np.tile([0, 0, 9.81], (len(t), 1)))
    return Sequence('s', (1e9 + t * 1e9).astype(np.int64), np.hstack([np.vstack(
        [omega, omega[-1:]]), accel]), gt.as_quat(), np.zeros((len(t), 3)),
        np.ones(len(t), bool))


def test_tuning_picks_the_lowest_mean_error_on_the_tails(monkeypatch):
    seq = _turning_sequence(3000)
    biased = seq.imu[:, :3] + [0.0, 0.02, 0.0]  # a gyro bias: a short time constant helps
    monkeypatch.setattr(filters, 'TAU_ACC_GRID_S', (0.5, 50.0))
    report = filters.tune([seq], {'raw': [biased]}, 200.0, {'raw': ('vqf',)})
    chosen = report['raw vqf']
    assert chosen['settings']['tau_acc_s'] == 0.5 and len(chosen['candidates']) == 4
    assert chosen['aoe_deg'] == min(chosen['candidates'].values())
    # a bias the accelerometer does not have is tried, and loses
    offered = filters.tune([seq], {'raw': [biased]}, 200.0, {'raw': ('vqf',)}, (0.0, 0.3, 0.0))
    assert len(offered['raw vqf']['candidates']) == 8
    assert offered['raw vqf']['settings'] == chosen['settings']
    # judged on the tilt (poses whose heading is not trusted): the yaw drift not compared
    drifting = biased + [0.0, 0.0, 0.01]
    by_aoe = filters.tune([seq], {'raw': [drifting]}, 200.0, {'raw': ('vqf',)})['raw vqf']
    by_tilt = filters.tune([seq], {'raw': [drifting]}, 200.0, {'raw': ('vqf',)},
                           key='tilt_deg')['raw vqf']
    assert by_tilt['tilt_deg'] == min(by_tilt['candidates'].values())
    assert by_aoe['aoe_deg'] == min(by_aoe['candidates'].values())
    assert max(by_aoe['candidates'].values()) > max(by_tilt['candidates'].values()) + 0.1


def test_tuning_starts_each_filter_at_its_tail_as_a_run_starts(monkeypatch):
    monkeypatch.setattr(filters, 'TAU_ACC_GRID_S', (50.0,))  # slow: its start shows
    seq = _turning_sequence(4000)
    biased = seq.imu[:, :3] + [0.0, 0.03, 0.01]
    tail = seq.tail(2500)  # the samples before it lead in; the filter does not run there
    chosen = filters.tune([tail], {'raw': [biased[2500:]]}, 200.0, {'raw': ('vqf',)})
    flt = Filter.from_dict(chosen['raw vqf'])
    started = filters.score(tail, filters.run(flt, biased[2500:], tail.imu[:, 3:], 200.0,
                                              tail.stamp_ns))
    warm = filters.score(tail, filters.run(flt, biased, seq.imu[:, 3:], 200.0,
                                           seq.stamp_ns)[2500:])
    assert chosen['raw vqf']['aoe_deg'] == pytest.approx(started.aoe, abs=1e-12)
    assert abs(warm.aoe - started.aoe) > 0.01


def _moving_sequence(bias: np.ndarray, n: int = 6000) -> Sequence:
    """Return a body moving and turning, its accelerometer the specific force plus ``bias``."""
    t = np.arange(n) * 0.005
    gt = Rotation.from_rotvec(np.stack([0.2 * np.sin(0.9 * t), 0.15 * np.cos(0.6 * t),
                                        1.5 * np.sin(0.3 * t)], axis=1))
    pos = np.stack([np.sin(t), np.cos(0.7 * t), 0.2 * np.sin(1.3 * t)], axis=1)
    acc = np.stack([-np.sin(t), -0.49 * np.cos(0.7 * t), -0.338 * np.sin(1.3 * t)], axis=1)
    force = gt.inv().apply(acc + [0.0, 0.0, 9.80665])
    noise = np.random.default_rng(3).normal(0.0, 0.3, (n, 3))
    gyro = np.zeros((n, 3))
    return Sequence('s', (1e9 + t * 1e9).astype(np.int64),
                    np.hstack([gyro, force + bias + noise]), gt.as_quat(), pos,
                    np.ones(n, bool))


def test_the_accelerometer_bias_is_fitted_from_the_poses_before_the_tails():
    bias = np.array([-0.02, 0.12, 0.06])
    seq = _moving_sequence(bias)
    seq.imu[4000:, 3:] += 1.0          # the tail: not looked at
    seq.gt_pos[1000:1200] = 5.0        # a hole, its positions invented: masked
    seq.gt_valid[1000:1200] = False
    fitted, samples = filters.fit_accel_bias([seq], 4000)
    np.testing.assert_allclose(fitted, bias, atol=0.01)
    assert 3500 < samples < 3800       # the hole and the smoothing window around it left out
    upside_down = _moving_sequence(bias)
    upside_down.imu[:, 3:] *= -1       # poses whose world z points down: no fit, not a wrong one
    assert filters.fit_accel_bias([upside_down], 4000) is None


@pytest.mark.parametrize('flt', KINDS, ids=lambda f: f.kind)
def test_every_filter_removes_the_stored_accelerometer_bias(flt):
    from dataclasses import replace
    seq = _moving_sequence(np.zeros(3), 1000)
    gyro = (Rotation.from_quat(seq.gt_quat[:-1]).inv() * Rotation.from_quat(
        seq.gt_quat[1:])).as_rotvec() / 0.005
    gyro = np.vstack([gyro, gyro[-1:]])
    bias = (0.05, -0.1, 0.2)
    with_bias = replace(flt, accel_bias_m_s2=bias)
    assert Filter.from_dict(with_bias.as_dict()) == with_bias
    assert 'accel bias removed' in with_bias.label and 'accel' not in flt.label
    np.testing.assert_allclose(run(with_bias, gyro, seq.imu[:, 3:] + bias, 200.0),
                               run(flt, gyro, seq.imu[:, 3:], 200.0), atol=1e-9)


@pytest.mark.parametrize('stored, message', [
    ({'filter': 'vqf', 'settings': {'tau_acc_s': -1}}, 'tau_acc_s'),
    ({'filter': 'kalman', 'gain': 0.1}, "unknown filter 'kalman'"),
    ({'filter': 'madgwick'}, "'gain'"),
])
def test_stored_filter_settings_out_of_range_are_one_line(stored, message):
    from denoise_imu_ros.core.errors import ModelFileError
    from denoise_imu_ros.evaluation.filters import Filter
    with pytest.raises(ModelFileError, match=f'^fusion.filters.x: inconsistent .*{message}'):
        Filter.from_dict(stored, 'fusion.filters.x')


def test_tune_fusion_says_what_the_model_file_lacks_and_asks_for_data_only_when_missing(
        tmp_path, capsys):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.learn.checkpoint import save_model
    from helpers import SAMPLE, untrained_model
    calib = tmp_path / 'calib.safetensors'
    save_model(calib, untrained_model(calibration_only=True), {'sample_rate_hz': 200.0})
    bare, named = tmp_path / 'bare.safetensors', tmp_path / 'named.safetensors'
    save_model(bare, untrained_model(), {'sample_rate_hz': 200.0})
    save_model(named, untrained_model(), {'sample_rate_hz': 200.0,
                                          'train_sequences': [SAMPLE.name],
                                          'train_config': {'window': 1024}})
    for model, data, said in ((bare, ['--data', str(SAMPLE.parent)], 'no validation tails'),
                              (named, [], 'pass --data')):
        assert main(['tune-fusion', '--model', str(model), '--baseline', str(calib),
                     *data]) == 1
        err = capsys.readouterr().err.strip()
        assert said in err and len(err.splitlines()) == 1
        assert 'pass --data' not in err or not data


@pytest.mark.parametrize('weight, key', [(1.0, 'aoe_deg'), (0.0, 'tilt_deg')])
def test_tune_fusion_judges_as_the_recipe_trusts_the_heading(tmp_path, monkeypatch, weight,
                                                             key):
    from denoise_imu_ros.learn.checkpoint import save_model
    from helpers import SAMPLE, untrained_model
    calib = tmp_path / 'calib.safetensors'
    save_model(calib, untrained_model(calibration_only=True), {'sample_rate_hz': 200.0})
    model = tmp_path / 'm.safetensors'
    save_model(model, untrained_model(), {
        'sample_rate_hz': 200.0, 'train_sequences': [SAMPLE.name],
        'run': {'data': str(SAMPLE.parent)},
        'train_config': {'window': 16000, 'heading_weight': weight}})
    judged = []
    monkeypatch.setattr(filters, 'tune', lambda *args, **kw: judged.append(args[-1]) or {})
    report = filters.tune_model(str(model), str(calib), progress=False)
    assert judged == [key] and report['judged_on'] == key
    assert report['chosen_on'].endswith(
        'the lowest mean AOE' if key == 'aoe_deg' else 'the heading is not judged)')


def test_tune_fusion_says_when_it_replaces_the_filter_crossval_chose(
        tmp_path, monkeypatch, capsys):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.learn.checkpoint import save_model
    from helpers import untrained_model
    calib, model = tmp_path / 'calib.safetensors', tmp_path / 'm.safetensors'
    save_model(calib, untrained_model(calibration_only=True), {'sample_rate_hz': 200.0})
    save_model(model, untrained_model(), {'sample_rate_hz': 200.0, 'fusion': {
        'settings': {'tau_acc_s': 5.0}, 'chosen_on': 'crossval: the folds'}})
    monkeypatch.setattr(filters, 'tune_model', lambda *args, **kw: {})
    monkeypatch.setattr(filters, 'table', lambda report: '')
    monkeypatch.setattr(filters, 'attach', lambda *args: None)
    args = ['tune-fusion', '--model', str(model), '--baseline', str(calib), '--attach']
    assert main(args) == 0
    assert 'replaces the filter crossval chose' in capsys.readouterr().err
    assert main(args[:2] + [str(calib)] + args[3:]) == 0  # a tuned file: nothing to say
    assert 'replaces' not in capsys.readouterr().err


def test_tune_fusion_feeds_each_tail_its_gyro_with_the_stream_before_as_context(
        tmp_path, monkeypatch):
    from denoise_imu_ros.learn.checkpoint import load_model, save_model
    from helpers import SAMPLE, untrained_model
    calib = tmp_path / 'calib.safetensors'
    save_model(calib, untrained_model(calibration_only=True), {'sample_rate_hz': 200.0})
    model = tmp_path / 'm.safetensors'
    save_model(model, untrained_model(), {
        'sample_rate_hz': 200.0, 'train_sequences': [SAMPLE.name],
        'run': {'data': str(SAMPLE.parent)}, 'train_config': {'window': 16000}})
    seen = []
    monkeypatch.setattr(filters, 'tune', lambda *args, **kw: seen.append(args) or {})
    filters.tune_model(str(model), str(calib), progress=False)
    (tail,), gyros = seen[0][0], seen[0][1]
    assert len(tail.lead_in) >= 16000  # the tail starts after the training window
    for source, loaded in (('network', load_model(str(model))),
                           ('calibrated', load_model(str(calib)))):
        # the model ran from the first sample; the filter gets the tail's part alone
        np.testing.assert_array_equal(gyros[source][0],
                                      tail.on_poses(loaded.correct(tail.stream)))
    np.testing.assert_array_equal(gyros['raw'][0], tail.imu[:, :3])


def test_a_bad_stored_filter_is_one_short_line_naming_the_file():
    from denoise_imu_ros.core.errors import ModelFileError
    bad = {'filter': 'vqf', 'settings': {'tau_acc_s': 'long'},
           'candidates': {f'vqf tau_acc {k} s': 1.0 for k in range(100)}}
    meta = parse_meta({'fusion': {'filters': {'raw vqf': bad}}}, 'm')
    with pytest.raises(ModelFileError) as err:
        eval_filters(meta, None, 'my.safetensors')
    said = str(err.value)
    assert said.startswith('my.safetensors: fusion.filters.raw vqf: inconsistent filter')
    assert len(said) < 200 and '\n' not in said
