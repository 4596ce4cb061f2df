# SPDX-FileCopyrightText: 2026 denoise_imu_ros authors
# SPDX-License-Identifier: Apache-2.0
"""The turn-on bias from stillness: causal, equal online and offline, refused when malformed."""

import math

from denoise_imu_ros.core.schema import FusionSettings, parse_meta
from denoise_imu_ros.pipeline import rest_bias
from denoise_imu_ros.pipeline.rest_bias import RestBias, RestBiasSettings
import numpy as np
import pytest

RATE = 200.0
BIAS = np.array([0.009, -0.004, 0.006])  # rad/s, a consumer MEMS gyro's turn-on bias


def _imu(still_s: float, moving_s: float, seed: int = 0, turn: float | None = None):
    """Gravity and a constant bias with white noise: still, then moving (or turning)."""
    rng = np.random.default_rng(seed)
    n_still, n_move = int(still_s * RATE), int(moving_s * RATE)
    t = np.arange(n_move) / RATE
    motion = (np.full((n_move, 3), [0.0, 0.0, turn]) if turn is not None
              else np.stack([np.sin(2 * t), np.cos(3 * t), 0.5 * np.sin(t)], 1))
    gyro = np.vstack([np.zeros((n_still, 3)), motion]) + BIAS
    gyro += rng.normal(0, 0.002, gyro.shape)
    accel = np.tile([0.0, 0.0, 9.81], (len(gyro), 1))
    accel[n_still:] += 2.0 * np.sin(np.arange(n_move) / RATE * 5)[:, None]
    accel += rng.normal(0, 0.02, accel.shape)
    return np.hstack([gyro, accel])


def test_online_equals_batch_bit_for_bit():
    imu = _imu(3.0, 5.0)
    settings = RestBiasSettings(prior_rad_s=(0.001, 0.002, 0.003))
    batch = rest_bias.rest_bias_batch(imu, RATE, settings)
    online = RestBias(settings, RATE)
    step = np.array([online.update(s[:3], s[3:]) for s in imu])
    assert np.array_equal(step, batch['bias'])
    assert online.still_samples == batch['rest'].sum() > 0
    online.reset()  # a new run: the prior again
    assert np.array_equal(online.update(imu[0, :3], imu[0, 3:]), batch['bias'][0])


def test_the_estimate_at_a_sample_depends_on_no_later_sample():
    imu = _imu(3.0, 5.0)
    k = int(4.0 * RATE)
    changed = imu.copy()
    changed[k + 1:, :3] += 0.5
    a = rest_bias.rest_bias_batch(imu, RATE, RestBiasSettings())['bias']
    b = rest_bias.rest_bias_batch(changed, RATE, RestBiasSettings())['bias']
    assert np.array_equal(a[:k + 1], b[:k + 1])


def test_a_still_start_finds_the_bias_and_a_moving_start_keeps_the_prior():
    est = rest_bias.rest_bias_batch(_imu(3.0, 5.0), RATE, RestBiasSettings())
    assert np.abs(est['bias'][-1] - BIAS).max() < 6e-4
    still_end = int(3.0 * RATE) - 1
    assert est['sigma'][still_end] < 1e-3 < est['sigma'][0]
    assert est['sigma'][-1] > est['sigma'][still_end]  # less certain as motion goes on
    prior = (0.005, 0.005, 0.005)
    moving = rest_bias.rest_bias_batch(_imu(0.0, 5.0), RATE,
                                       RestBiasSettings(prior_rad_s=prior))
    assert not moving['rest'].any()
    assert np.array_equal(moving['bias'], np.tile(prior, (len(moving['bias']), 1)))


def test_a_steady_turn_faster_than_the_clip_is_never_taken_for_a_bias():
    turn = math.radians(5.0)  # a robot turning in place at 5 deg/s: gyro and accel steady
    est = rest_bias.rest_bias_batch(_imu(0.0, 10.0, turn=turn), RATE, RestBiasSettings())
    assert not est['rest'][int(2 * RATE):].any()
    assert np.abs(est['bias']).max() == 0.0


def test_a_slow_turn_after_a_still_start_keeps_the_still_starts_bias():
    # EuRoC-like: a 4.5 deg/s turn-on bias about z, the prior near it, the clip VQF's 2
    # deg/s about the prior; 3 s still, then turning in place at -5 deg/s for 20 s, the
    # accelerometer steady: the gyro reads -0.5 deg/s, a bias a clip about 0 would take
    bias_z, prior = math.radians(4.5), (0.0, 0.0, math.radians(4.4))
    imu = _imu(3.0, 20.0, turn=math.radians(-5.0))
    imu[:, 2] += bias_z - BIAS[2]
    imu[int(3.0 * RATE):, 3:] = [0.0, 0.0, 9.81]
    settings = RestBiasSettings(prior_rad_s=prior)
    est = rest_bias.rest_bias_batch(imu, RATE, settings)
    assert est['rest'][:int(3.0 * RATE)].any()  # the still start, 0.1 deg/s off the prior
    assert not est['rest'][int(5.0 * RATE):].any()  # the turn: 4.9 deg/s off it
    assert np.abs(np.degrees(est['bias'][:, 2] - bias_z))[int(3.0 * RATE):].max() < 0.05
    online = RestBias(settings, RATE)
    for sample in imu:
        online.update(sample[:3], sample[3:])
    assert online.offset_deg_s < 0.6 and not online.ambiguous  # x: BIAS, prior 0


def test_a_bias_far_out_in_its_clip_is_said_to_be_ambiguous():
    # a turn at 1.5 deg/s from the start, the accelerometer steady: taken for a bias
    imu = _imu(0.0, 10.0, turn=math.radians(1.5))
    imu[:, 3:] = [0.0, 0.0, 9.81]
    online = RestBias(RestBiasSettings(), RATE)
    for sample in imu:
        online.update(sample[:3], sample[3:])
    assert online.still_samples and online.ambiguous
    assert 1.0 < online.offset_deg_s < 2.0


def test_removing_it_subtracts_the_estimate_from_the_gyro_only():
    imu = _imu(3.0, 2.0)
    out = rest_bias.remove_rest_bias(imu, RATE, RestBiasSettings())
    est = rest_bias.rest_bias_batch(imu, RATE, RestBiasSettings())['bias']
    assert np.array_equal(out[:, :3], imu[:, :3] - est)
    assert np.array_equal(out[:, 3:], imu[:, 3:])
    assert rest_bias.remove_rest_bias(imu, RATE, None) is imu


def test_the_nominal_bias_is_the_mean_of_the_recordings_that_were_still():
    prior, still, spread = rest_bias.nominal_bias(
        [_imu(3.0, 2.0, 0), _imu(0.0, 3.0, 1), _imu(3.0, 2.0, 2)], RATE, RestBiasSettings())
    assert still == 2 and 0 <= spread < 6e-4
    assert np.abs(np.array(prior) - BIAS).max() < 6e-4
    assert rest_bias.nominal_bias([_imu(0.0, 3.0)], RATE, RestBiasSettings()) == (None, 0, 0.0)


def test_the_model_file_choice_and_the_switches():
    stored = RestBiasSettings(prior_rad_s=(0.001, 0.0, 0.0))
    meta = parse_meta({'rest_bias': stored.to_dict()}, 'm')
    assert rest_bias.resolve(meta, 'model') == stored
    assert rest_bias.resolve(meta, 'on') == stored
    assert rest_bias.resolve(meta, 'off') is None
    assert rest_bias.resolve(parse_meta({}, 'm'), 'model') is None
    assert rest_bias.resolve(parse_meta({'rest_bias': None}, 'm'), 'on') == RestBiasSettings()
    with pytest.raises(ValueError, match='must be one of model, on, off'):
        rest_bias.resolve(meta, 'sometimes')


def test_the_baseline_rows_use_the_model_settings_or_a_clip_wide_enough_for_any_bias():
    stored = RestBiasSettings(prior_rad_s=(0.001, 0.0, 0.0))
    assert rest_bias.baseline_settings(parse_meta({'rest_bias': stored.to_dict()}, 'm')) == stored
    wide = rest_bias.baseline_settings(parse_meta({}, 'm'))
    assert wide.prior_rad_s == (0.0, 0.0, 0.0) and wide.bias_clip_deg_s == 10.0
    big = _imu(3.0, 2.0) + np.r_[0.0, 0.0, math.radians(4.6), 0.0, 0.0, 0.0]  # EuRoC's z
    assert not rest_bias.rest_bias_batch(big, RATE, RestBiasSettings())['rest'].any()
    found = rest_bias.rest_bias_batch(big, RATE, wide)['bias'][-1]
    assert found[2] == pytest.approx(math.radians(4.6) + BIAS[2], rel=0.02)


def test_a_rest_only_model_runs_anywhere_a_model_does_and_corrects_nothing_else(tmp_path):
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.core.modelfile import add_metadata, read_model_file
    from denoise_imu_ros.runtime.advice import deployment_warning
    from denoise_imu_ros.pipeline.online import OnlineDenoiser
    from helpers import write_untrained_model
    settings = RestBiasSettings(prior_rad_s=(0.001, 0.002, 0.003))
    report = {'deploy': 'rest bias', 'verdict': 'the network does not beat the raw gyro less '
              'its turn-on bias: deploy no learnt correction'}
    net = write_untrained_model(tmp_path / 'net.safetensors', {
        'sample_rate_hz': RATE, 'rest_bias': settings.to_dict(), 'crossval': report})
    assert main(['rest-model', '--like', str(net), '--out', str(tmp_path / 'rest')]) == 0
    rest = read_model_file(tmp_path / 'rest')
    assert rest.config.calibration_only and rest.meta.kind == 'rest bias'
    assert rest.meta.rest_bias == settings and rest.meta.crossval.report == report
    assert deployment_warning(rest) is None  # what the verdict recommends
    assert 'deploy no learnt correction' in deployment_warning(read_model_file(net))
    imu = _imu(3.0, 2.0)
    den = OnlineDenoiser.from_model_file(rest)
    got = np.array([den.process(10**9 + k * 5_000_000, s[:3], s[3:]).gyro
                    for k, s in enumerate(imu)])
    np.testing.assert_allclose(got, rest_bias.remove_rest_bias(imu, RATE, settings)[:, :3],
                               rtol=0, atol=1e-7)
    add_metadata(net, rest_bias=None)
    assert main(['rest-model', '--like', str(net), '--out', str(tmp_path / 'x')]) == 1
    assert not (tmp_path / 'x').exists()


def test_a_tracker_only_model_runs_the_classical_pipeline_as_eval_scores_it(tmp_path):
    """The verdict can deploy no model: the node runs exactly eval's tracker-only row."""
    from denoise_imu_ros.cli import main
    from denoise_imu_ros.core.modelfile import read_model_file
    from denoise_imu_ros.learn.checkpoint import load_model
    from denoise_imu_ros.runtime.advice import deployment_warning, model_kind
    from denoise_imu_ros.pipeline.online import OnlineDenoiser
    from helpers import write_untrained_model
    settings = RestBiasSettings(prior_rad_s=(0.001, 0.002, 0.003))
    chosen = {'sigma_motion_deg_s': 0.1, 'forgetting_s': 100.0, 'sigma_init_deg_s': 0.1,
              'label': 'sigma 0.1 deg/s, forgetting 100 s'}
    fused = {'label': 'vqf tau_acc 5 s, bias estimation on', 'tau_acc_s': 5.0,
             'bias_estimation': True, 'accel_bias_removed': True,
             'orientation_std_rad': [0.01, 0.02, 0.03]}
    report = {'deploy': 'tracker only', 'verdict': 'deploy no learnt correction',
              'mean': {'network': {'aoe_deg': 2.0}, 'tracker only': {'aoe_deg': 1.0}},
              'tracking': {'chosen': {'tracker only': chosen, 'network': None}},
              'fusion': {'chosen': {'tracker only': fused}, 'chosen_on': 'the folds'},
              'fold_kind': 'leave one power-on session out'}
    net = write_untrained_model(tmp_path / 'net.safetensors', {
        'sample_rate_hz': RATE, 'rest_bias': settings.to_dict(), 'crossval': report,
        'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0},
        'fusion': {'settings': {'tau_acc_s': 2.0, 'bias_estimation': False,
                                'accel_bias_m_s2': [0.01, -0.02, 0.03]}}})
    assert main(['rest-model', '--like', str(net), '--tracker-only',
                 '--out', str(tmp_path / 'tracker')]) == 0
    tracker = read_model_file(tmp_path / 'tracker')
    assert model_kind(tracker) == 'tracker only' and tracker.config.calibration_only
    assert tracker.meta.bias_tracking.sigma_motion_deg_s == 0.1  # crossval's, not the model's
    # imu/data's filter too: the classical rows' choice, with the model's accelerometer bias
    assert tracker.meta.fusion.chosen == FusionSettings(5.0, True, (0.01, -0.02, 0.03))
    assert tracker.meta.fusion.orientation_std_rad == (0.01, 0.02, 0.03)
    assert deployment_warning(tracker) is None
    assert '(network 2.00° against tracker only 1.00°' in deployment_warning(
        read_model_file(net))
    imu = _tilted_turns(40.0, np.array([0.004, -0.003, 0.002]))
    den = OnlineDenoiser.from_model_file(tracker)
    got = np.array([den.process(10**9 + k * 5_000_000, s[:3], s[3:]).gyro
                    for k, s in enumerate(imu)])
    expected = rest_bias.tracker_only_gyro(load_model(str(net)), imu)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-7)
    assert np.abs(expected - rest_bias.baseline_gyro(load_model(str(net)), imu)).max() > 1e-4
    np.testing.assert_allclose(load_model(str(tmp_path / 'tracker')).correct(imu), expected,
                               rtol=0, atol=1e-7)


def test_the_classical_rows_tracking_is_the_folds_choice_then_the_blends_then_the_models():
    """The tracker-only row runs what the file says the classical pipeline is, in that order."""
    own = {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0}
    classical = {'sigma_motion_deg_s': 0.03, 'forgetting_s': 300.0}
    folds = {'sigma_motion_deg_s': 0.1, 'forgetting_s': 10.0, 'sigma_init_deg_s': 0.05}
    report = {'deploy': 'tracker only', 'verdict': 'v', 'mean': {},
              'tracking': {'chosen': {'tracker only': folds}}}

    def tracking(**meta):
        got = rest_bias.classical_tracking(parse_meta(dict(meta, sample_rate_hz=RATE), 't'))
        return None if got is None else (got.sigma_motion_deg_s, got.forgetting_s)
    blend = {'weight': 0.5, 'tracking': classical}
    assert tracking(bias_tracking=own, blend=blend, crossval=report) == (0.1, 10.0)
    assert tracking(bias_tracking=own, blend=blend) == (0.03, 300.0)
    assert tracking(bias_tracking=own, blend=dict(blend, tracking=None)) is None
    assert tracking(bias_tracking=own) == (0.05, 30.0)
    assert tracking() == (rest_bias.CLASSICAL_TRACKING.sigma_motion_deg_s,
                          rest_bias.CLASSICAL_TRACKING.forgetting_s)


def _tilted_turns(seconds: float, bias: np.ndarray, seed: int = 0) -> np.ndarray:
    """Return a gyro biased by ``bias`` turning about tilted axes, with true gravity."""
    from denoise_imu_ros.core.rotation import exp, multiply
    from scipy.spatial.transform import Rotation
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * RATE)) / RATE
    rate = np.stack([0.6 * np.sin(0.7 * t), 0.5 * np.cos(0.5 * t), 0.3 * np.sin(0.3 * t)], 1)
    att, quat = (0.0, 0.0, 0.0, 1.0), np.empty((len(t), 4))
    for k, w in enumerate(rate / RATE):
        quat[k], att = att, multiply(att, exp(*w))
    accel = Rotation.from_quat(quat).inv().apply([0.0, 0.0, 9.81])
    return np.hstack([rate + bias + rng.normal(0, 0.002, rate.shape),
                      accel + rng.normal(0, 0.02, accel.shape)])


def test_the_tracked_bias_online_equals_batch_and_finds_a_bias_in_motion():
    from denoise_imu_ros.core.schema import BiasTracking
    settings = BiasTracking(0.05, 30.0)
    bias = np.array([0.004, -0.003, 0.002])  # rad/s, left in a model's output
    imu = _tilted_turns(120.0, bias)
    batch = rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, settings)
    online = rest_bias.BiasTracker(settings, RATE)
    step = np.array([s[:3] - online.update(s[:3], s[3:]) for s in imu])
    assert np.array_equal(step, batch)
    # never still: found in motion alone, through gravity seen from every attitude
    assert np.abs(online.estimate()[0] - bias).max() < 1e-3 < np.abs(bias).max()
    gyro = imu[:, :3]
    assert rest_bias.track_bias(gyro, imu[:, 3:], RATE, None) is gyro
    online.reset()  # a new run: from a bias of 0 again
    assert np.array_equal(imu[0, :3] - online.update(imu[0, :3], imu[0, 3:]), batch[0])


def test_a_held_stretch_leaves_the_estimate_where_it_was_online_as_in_batch():
    from denoise_imu_ros.core.schema import BiasTracking
    settings = BiasTracking(0.05, 30.0)
    imu = _tilted_turns(60.0, np.array([0.004, -0.003, 0.002]), seed=1)
    hold = np.zeros(len(imu), bool)
    hold[2000:5000] = hold[8000:8400] = True
    imu[2000:5000, :3] += 0.3  # what a model beyond its training rates might output
    batch = rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, settings, hold)
    online = rest_bias.BiasTracker(settings, RATE)
    step = np.array([s[:3] - online.update(s[:3], s[3:], h) for s, h in zip(imu, hold)])
    assert np.array_equal(step, batch)
    # after the hold the estimate goes on from where it was before it; learning moves it
    free = rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, settings)
    held, learnt = imu[:, :3] - batch, imu[:, :3] - free
    assert np.abs(held[5000] - held[1999]).max() < 2e-4
    assert np.abs(learnt[5000] - learnt[1999]).max() > 2e-3
    assert np.array_equal(held[:2000], learnt[:2000])


def test_a_tracker_held_above_a_rate_forgets_what_fast_rotation_taught_it_online_as_in_batch():
    from denoise_imu_ros.core.schema import BiasTracking
    held_settings, settings = BiasTracking(0.05, 30.0, 0.05, 400.0), BiasTracking(0.05, 30.0, 0.05)
    imu = _tilted_turns(60.0, np.array([0.004, -0.003, 0.002]), seed=2)
    # a spin the accelerometer does not see: the tracker would take it for a bias
    imu[2000:5000, 2] += math.radians(600.0)
    fast = rest_bias.fast_rotation(imu[:, :3], RATE, 400.0)
    assert fast[2020:5000].all() and not fast[:2000].any() and not fast[5020:].any()
    online_fast = rest_bias.FastRotation(400.0, RATE)
    assert np.array_equal([online_fast.update(g) for g in imu[:, :3]], fast)
    batch = rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, held_settings)
    assert np.array_equal(batch, rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, settings,
                                                      fast))
    online = rest_bias.BiasTracker(held_settings, RATE)
    step = np.array([s[:3] - online.update(s[:3], s[3:]) for s in imu])
    assert np.array_equal(step, batch)
    assert not online.held
    online.reset()
    for sample in imu[:3000]:
        online.update(sample[:3], sample[3:])
    assert online.held  # within the spin: /diagnostics' tracked_bias_held
    online.reset()  # a new run from within the spin: the rates seen before are forgotten
    after = imu[5000:]
    assert np.array_equal([s[:3] - online.update(s[:3], s[3:]) for s in after],
                          after[:, :3] - rest_bias.tracked_bias(after[:, :3], after[:, 3:],
                                                                RATE, held_settings))
    free = rest_bias.track_bias(imu[:, :3], imu[:, 3:], RATE, settings)
    held, learnt = imu[:, :3] - batch, imu[:, :3] - free
    assert np.abs(held[5020] - held[2019]).max() < 2e-4
    assert np.abs(learnt[5020] - learnt[2019]).max() > 2e-3


@pytest.mark.parametrize('n', [0, 1, 10, 11, 19, 20, 21, 45])
def test_the_rate_hold_per_sample_equals_it_over_arrays_at_any_length(n):
    gyro = np.random.default_rng(n).normal(0.0, 4.5, (n, 3))  # rad/s: about the bound
    online = rest_bias.FastRotation(400.0, RATE)  # over 20 samples at 200 Hz
    fast = rest_bias.fast_rotation(gyro, RATE, 400.0)
    assert fast.shape == (n,) and np.array_equal([online.update(g) for g in gyro], fast)


def test_tracking_runs_where_the_model_file_says_unless_switched_off():
    from denoise_imu_ros.core.errors import ModelFileError
    from denoise_imu_ros.core.schema import BiasTracking
    stored = {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0, 'chosen_on': 'tails'}
    meta = parse_meta({'bias_tracking': stored}, 'm')
    assert rest_bias.tracking(meta, 'model') == rest_bias.tracking(meta, 'on') == BiasTracking(
        0.05, 30.0)
    assert rest_bias.tracking(meta, 'off') is None
    assert rest_bias.tracking(parse_meta({}, 'm'), 'on') is None
    for bad in ({'sigma_motion_deg_s': 0.0, 'forgetting_s': 30.0},
                {'sigma_motion_deg_s': 0.05}, 'fast',
                dict(stored, sigma_init_deg_s=0.0), dict(stored, sigma_init_deg_s=-0.1),
                dict(stored, sigma_init_deg_s='wide')):
        with pytest.raises(ModelFileError, match='m: inconsistent'):
            parse_meta({'bias_tracking': bad}, 'm')


def test_a_shaken_start_teaches_the_output_tracker_no_bias_of_a_raw_gyros_size():
    """Accelerations that are not gravity at the start (a drone carried): no bias to learn."""
    from denoise_imu_ros.core.schema import BiasTracking
    from helpers import learnt_on_a_shaken_start
    assert learnt_on_a_shaken_start(BiasTracking(0.05, 30.0, 0.05)) < 0.5
    # a file written before: VQF's 0.5 deg/s, run as it was chosen (here up to the clip)
    old = parse_meta({'bias_tracking': {'sigma_motion_deg_s': 0.05, 'forgetting_s': 30.0}},
                     'm').bias_tracking
    assert old == BiasTracking(0.05, 30.0, 0.5)
    assert learnt_on_a_shaken_start(old) == pytest.approx(2.0)
